"""OTD's ADMM iteration cost against image size: dense learned spatial bases and blocked ones.

For N in ``--sizes`` (default 256, 512, 1024): an N×N×28 SD-CASSI problem
(a tuning scene upsampled by linear interpolation, seeded random binary
code, 30 dB), starting bases from a short first stage, then the ADMM
(:func:`tensor_cosdi.solvers.otd.tucker_admm`, fixed bases) timed at 5 and
15 iterations; the cost of one iteration is the difference / 10, median of
``--repeats``.  Reported in ns per cube element, so flat means linear in
pixels.  ``spatial_block`` = none (one dense basis per spatial axis: each
transform is an N×N GEMM, cost per element ∝ N) and 256 (blocks of at most
256 pixels, :class:`tensor_cosdi.bases.BlockDense`).

    python benchmarks/otd_scaling.py [--sizes 256,512,1024] [--repeats 3]

Appends the table to ``benchmarks/results/otd_scaling.md``.  Never asserts anything.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from _results import append

ROOT = Path(__file__).resolve().parents[1]


def problem(n: int):
    from scipy.ndimage import zoom

    import tensor_cosdi as tc
    from tensor_cosdi import datasets

    cube, wl = datasets.load_hsi("balloons", "kaist", dtype="float32")
    cube = np.clip(zoom(cube, (n / 256, n / 256, 1), order=1), 0, None).astype(np.float32)
    system = tc.systems.SDCASSI(tc.codes.random_binary((n, n), rng=0), n_bands=28, shifts=2)
    g = np.asarray(system.simulate(cube, snr_db=30, rng=0), dtype=np.float32)
    return system, g / float(np.max(g))


def per_iteration(system, g, block, repeats):
    from tensor_cosdi.solvers.otd import initial_bases, tucker_admm

    bases, _ = initial_bases(system, g, pan_iter=5, spatial_block=block)

    def run(k):
        t = time.perf_counter()
        tucker_admm(system, g, bases, max_iter=k, tol=1e-12, plane_support=False)
        return time.perf_counter() - t

    return statistics.median((run(15) - run(5)) / 10 for _ in range(repeats))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="256,512,1024")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    lines = [
        "| N | spatial_block | s / iteration | ns / element | × the 256² cost per element |",
        "|---|---|---|---|---|",
    ]
    base = {}
    for n in (int(s) for s in args.sizes.split(",")):
        system, g = problem(n)
        for block in (None, 256):
            t = per_iteration(system, g, block, args.repeats)
            ns = t / (n * n * 28) * 1e9
            base.setdefault(block, ns)
            lines.append(
                f"| {n} | {block or 'none (dense)'} | {t:.3f} | {ns:.2f} | {ns / base[block]:.2f} |"
            )
            print(lines[-1], flush=True)
    text = f"\n{time.strftime('%Y-%m-%d')}, 2 cores, float32, median of {args.repeats}:\n\n"
    text += "\n".join(lines) + "\n"
    append(args.out, "otd_scaling.md", text)


if __name__ == "__main__":
    main()
