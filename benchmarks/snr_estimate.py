"""The measurement SNR estimate on every system: measurement-only against fit residual.

For every registered system, a real CAVE tuning scene (``--scene``, 64×64,
16 bands, the system's seeded random code) noiseless, at 30 dB and at 20 dB
(noise seed 0): the measurement-only reading
(:func:`tensor_cosdi.noise.estimate_snr_db`), the fit-residual reading and
the estimate (:func:`tensor_cosdi.solvers.snr.estimate_snr`).  The verdict
column is computed: ``ok`` when the estimate is within 3 dB of a noisy truth
and above 32 dB when noiseless.

A second table reads the same estimate at the real-spectra protocol
(SD-CASSI, 256×256×28, 2 px per band, ``_protocol.problem``) on every tuning
scene, for the TSA mask and the seeded random code: the spread of the
estimate over the scenes and how many get the verdict ``ok``.

    python benchmarks/snr_estimate.py [--scene balloons] [--no-protocol]
                                      [--out benchmarks/results/snr_estimate.md]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import MASKS, RESULTS, load_mask, problem, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi.solvers.pnp_gap import ACCELERATE_ABOVE_DB as CLEAN  # noqa: E402
from tensor_cosdi.solvers.snr import estimate_snr  # noqa: E402


def verdict(true_snr, est) -> str:
    if true_snr is None:
        return "ok" if est > 32 else "reads noise"
    return "ok" if abs(est - true_snr) < 3 else f"off by {est - true_snr:+.1f} dB"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="balloons", help="a tuning scene of the research data")
    ap.add_argument("--out", default=str(RESULTS / "snr_estimate.md"))
    ap.add_argument(
        "--no-protocol", action="store_true", help="skip the 256×256×28 table on the tuning scenes"
    )
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
    if not args.no_protocol:
        lines += protocol_table()
    write_results(args.out, lines)


def protocol_table() -> list[str]:
    """The estimate on every tuning scene at the real-spectra protocol, both codes."""
    scenes = tc.datasets.TUNE_SCENES
    lines = [
        "",
        f"## SD-CASSI 256×256×28, 2 px per band, the {len(scenes)} tuning scenes",
        "",
        f"| code | true SNR | estimate dB: min | median | max | verdict ok "
        f"| read ≥ {CLEAN:g} dB (`pnp_gap`'s accelerated path) |",
        "|---|---|---|---|---|---|---|",
    ]
    for mask in MASKS:
        code = load_mask(mask)
        for snr in (None, 30, 20):
            est = []
            for scene in scenes:
                system, _, g = problem(scene, snr, code)
                est.append(estimate_snr(system, g).snr_db)
            ok = sum(verdict(snr, e) == "ok" for e in est)
            lines.append(
                f"| {mask} | {'noiseless' if snr is None else f'{snr} dB'} | "
                f"{np.min(est):.1f} | {np.median(est):.1f} | {np.max(est):.1f} | "
                f"{ok} of {len(est)} | {sum(e >= CLEAN for e in est)} of {len(est)} |"
            )
            print(lines[-1], flush=True)
    return lines


if __name__ == "__main__":
    main()
