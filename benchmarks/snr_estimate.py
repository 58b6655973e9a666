"""The measurement SNR estimate on every system: measurement-only against fit residual.

For every registered system, a real CAVE tuning scene (``--scene``, 64×64,
16 bands, the system's seeded random code) noiseless, at 30 dB and at 20 dB
(noise seed 0): the measurement-only reading
(:func:`tensor_cosdi.noise.estimate_snr_db`), the fit-residual reading and
the estimate (:func:`tensor_cosdi.solvers.snr.estimate_snr`).  The verdict
column is computed: ``ok`` when the estimate is within 3 dB of a noisy truth
and above 32 dB when noiseless.

    python benchmarks/snr_estimate.py [--scene balloons] [--out benchmarks/results/snr_estimate.md]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi.solvers.snr import estimate_snr  # noqa: E402


def verdict(true_snr, est) -> str:
    if true_snr is None:
        return "ok" if est > 32 else "reads noise"
    return "ok" if abs(est - true_snr) < 3 else f"off by {est - true_snr:+.1f} dB"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="balloons", help="a tuning scene of the research data")
    ap.add_argument("--out", default=str(RESULTS / "snr_estimate.md"))
    args = ap.parse_args(argv)
    if args.scene not in tc.datasets.TUNE_SCENES:
        raise SystemExit(f"--scene must be a tuning scene, one of {tc.datasets.TUNE_SCENES}")
    try:
        tc.datasets.data_dir()
    except FileNotFoundError as exc:
        raise SystemExit(f"snr_estimate.py needs the research scenes: {exc}") from None
    lines = [
        f"# Measurement SNR estimates, `cave.{args.scene}`, 64×64, 16 bands, random codes",
        "",
        "| system | true SNR | measurement only dB | fit residual dB | estimate dB | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for name in tc.studies.SYSTEMS:
        for snr in (None, 30, 20):
            p = tc.studies.make_problem(
                name, f"cave.{args.scene}", shape=(64, 64), n_bands=16, snr_db=snr, rng=0
            )
            e = estimate_snr(p.system, p.measurement)
            lines.append(
                f"| {name} | {'noiseless' if snr is None else f'{snr} dB'} | "
                f"{e.from_measurement_db:.1f} | {e.from_residual_db:.1f} | {e.snr_db:.1f} | "
                f"{verdict(snr, e.snr_db)} |"
            )
            print(lines[-1], flush=True)
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
