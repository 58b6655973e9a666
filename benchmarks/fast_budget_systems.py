"""``pnp_fast``'s two budgets on every imager, clean data: the start's ADMM iterations
against more denoiser iterations.

On a clean measurement of a spectral cube ``pnp_fast`` starts from OTD's first stage alone
and runs :data:`~tensor_cosdi.solvers.pnp_gap.FAST_ITER_CLEAN` iterations
(:func:`~tensor_cosdi.solvers.pnp_gap.fast_budget`); elsewhere it keeps
:data:`~tensor_cosdi.solvers.pnp_gap.FAST_WARM_ITER` ADMM iterations of the start and
:data:`~tensor_cosdi.solvers.pnp_gap.FAST_ITER`.  This script runs both
budgets, forced, on each registered imager's seeded problem (``studies.make_problem``,
ColorChecker, 64×64, 16 bands, noiseless), the medians of ``--repeats`` timed runs after
one untimed warm-up (each with no SNR estimate cached, as a user's single call), so the
ratio of seconds is of one run.  It shows where the trade
holds (a cube of three axes) and where the denoiser's per-slice calls make the extra
iterations cost more than the ADMM iterations they replace (more axes).

    python benchmarks/fast_budget_systems.py [--repeats 3]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import IMAGERS, RESULTS, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi.solvers.snr import clear_cache, estimate_snr  # noqa: E402


def budgets():
    import importlib

    m = importlib.import_module("tensor_cosdi.solvers.pnp_gap")
    return m, {
        "first stage alone": {
            "warm_iter": m.FAST_WARM_ITER_CLEAN, "max_iter": m.FAST_ITER_CLEAN,
            "sigma_end": m.FAST_SIGMA_END_CLEAN,
        },
        f"{m.FAST_WARM_ITER} ADMM iterations": {
            "warm_iter": m.FAST_WARM_ITER, "max_iter": m.FAST_ITER, "sigma_end": "auto",
        },
    }  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(RESULTS / "fast_budget_systems.md"))
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be ≥ 1, got {args.repeats}")
    module, runs = budgets()
    names = list(runs)
    lines = [
        "# `pnp_fast`'s clean-data budget on every imager",
        "",
        "ColorChecker 64×64, 16 bands, noiseless (`studies.make_problem`); both budgets "
        f"forced, median of {args.repeats} timed runs each after a warm-up; PSNR with the "
        "cube's peak as data range.  `fast_budget` is what `pnp_fast` chooses by itself.",
        "",
        "| system | cube axes | estimated SNR dB | `fast_budget` | "
        + " | ".join(f"{n}: PSNR dB, s" for n in names)
        + f" | seconds, first stage alone ÷ {module.FAST_WARM_ITER} ADMM | PSNR difference dB |",
        "|---|---|---|---|" + "---|" * len(names) + "---|---|",
    ]
    for name in IMAGERS:
        p = tc.studies.make_problem(name, "colorchecker", snr_db=None)
        snr = estimate_snr(p.system, p.measurement).snr_db
        chosen = module.fast_budget(p.system, p.measurement)
        label = names[0] if chosen["warm_iter"] == 0 else names[1]
        if p.system.panchromatic_exact:  # no first stage to start from
            lines.append(
                f"| {name} | {len(p.system.cube_shape)} | {snr:.1f} | {label} | "
                "no first stage (exact panchromatic image) |" + " — |" * (len(names) + 1)
            )
            continue
        cells, secs, psnrs = [], [], []
        for n in names:
            tc.reconstruct(p.system, p.measurement, "pnp_fast", **runs[n])  # warm-up
            times = []
            for _ in range(args.repeats):
                clear_cache()
                t0 = time.perf_counter()
                r = tc.reconstruct(p.system, p.measurement, "pnp_fast", **runs[n])
                times.append(time.perf_counter() - t0)
            peak = float(np.max(p.cube))
            psnr = tc.metrics.psnr(p.cube, np.asarray(r.cube), data_range=peak)
            secs.append(float(np.median(times)))
            psnrs.append(psnr)
            cells.append(f"{psnr:.2f}, {secs[-1]:.2f}")
        lines.append(
            f"| {name} | {len(p.system.cube_shape)} | {snr:.1f} | {label} | "
            + " | ".join(cells)
            + f" | {secs[0] / secs[1]:.2f} | {psnrs[0] - psnrs[1]:+.2f} |"
        )
        print(lines[-1], flush=True)
    write_results(Path(args.out), lines)


if __name__ == "__main__":
    main()
