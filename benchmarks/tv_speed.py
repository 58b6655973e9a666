"""Speed of the warm-started Chambolle TV steps (``solvers.denoisers.WarmTV``) that OTD's first
stage, the SNR estimate's subspace fit and the split-TV solver run every iteration.

For float32 images of 256×256 with 6 planes (the six spectral atoms of a 28-band first stage)
and 28 planes (every band of a 28-band cube), prints the median time of 5 steps:

* ``one plane at a time``: ``WarmTV``'s NumPy step loop (each plane takes all its steps before
  the next, every temporary a reused buffer), on one thread (``OMP_NUM_THREADS=1``) and with
  the planes split over its thread pool;
* ``compiled``: ``WarmTV`` with the numba kernel (the ``fast`` extra; one sweep over the
  plane a step), on one thread and on its thread pool (rows left out without numba);
* ``all planes per operation``: the reference, the same arithmetic with each NumPy operation
  over every plane at once and fresh temporaries,

each as a ratio to a copy of the planes measured in the same run, and whether the two give the
same primal and dual bit for bit.

    python benchmarks/tv_speed.py [--repeats 30] [--out FILE]

The table and the run's provenance go to ``benchmarks/results/tv_speed.md``.  Never asserts
anything: read the ratios.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from tensor_cosdi.solvers.denoisers import WarmTV, compiled_tv

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, write_results  # noqa: E402
from _protocol import median_ms as _median_ms  # noqa: E402

STEPS = 5
WEIGHT = 0.3


def all_planes_steps(f, p, out, w, n_iter):
    """The reference: Chambolle's step with every operation over all planes at once."""
    g, d = np.zeros_like(p), np.empty_like(f)
    tau = 0.25
    for _ in range(n_iter):
        np.add(p[0], p[1], out=d)
        np.negative(d, out=d)
        d[:, 1:] += p[0][:, :-1]
        d[:, :, 1:] += p[1][:, :, :-1]
        np.add(f, d, out=out)
        np.subtract(out[:, 1:], out[:, :-1], out=g[0][:, :-1])
        np.subtract(out[:, :, 1:], out[:, :, :-1], out=g[1][:, :, :-1])
        norm = np.sqrt(g[0] * g[0] + g[1] * g[1])
        norm *= tau / w
        norm += 1.0
        p -= tau * g
        p /= norm


def median_ms(fn, repeats, threads=None):
    """Median milliseconds of ``fn``; ``threads``: the ``OMP_NUM_THREADS`` the library's TV
    reads while it runs (``""``: unset, every CPU)."""
    saved = os.environ.get("OMP_NUM_THREADS")
    if threads is not None:
        os.environ.pop("OMP_NUM_THREADS", None)
        if threads:
            os.environ["OMP_NUM_THREADS"] = threads
    try:
        return _median_ms(fn, repeats)
    finally:
        os.environ.pop("OMP_NUM_THREADS", None)
        if saved is not None:
            os.environ["OMP_NUM_THREADS"] = saved


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--out", default=str(RESULTS / "tv_speed.md"))
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be ≥ 1, got {args.repeats}")
    rng = np.random.default_rng(0)
    compiled = compiled_tv()
    jit_text = "no compiled rows (numba not installed, or TENSOR_COSDI_JIT=0)"
    if compiled:
        import numba

        jit_text = f"numba {numba.__version__}"
    lines = [
        "# Warm-started Chambolle TV steps",
        "",
        f"{STEPS} steps, weight {WEIGHT}, float32 256×256 planes; median of {args.repeats} "
        "runs, ms and × a copy of the planes in the same run; `same`: primal and dual "
        f"equal to the reference's bit for bit; {jit_text}.",
        "",
        "| planes | variant | ms | × copy | same |",
        "|---|---|---|---|---|",
    ]
    for planes in (6, 28):
        f = rng.random((planes, 256, 256), dtype=np.float32)
        image = np.ascontiguousarray(np.moveaxis(f, 0, 2))  # (H, W, planes), as WarmTV takes
        copy_ms = median_ms(lambda: np.copy(f), args.repeats)
        p_ref, out_ref = np.zeros((2, *f.shape), np.float32), np.empty_like(f)
        all_planes_steps(f, p_ref, out_ref, WEIGHT, STEPS)  # one cold call each, then compare
        flags = {}
        for label, mode in (("numpy", False), ("compiled", True)):
            if mode and not compiled:
                continue
            cold = WarmTV(STEPS, compiled=mode)
            out = cold(image, WEIGHT)
            same = np.array_equal(np.moveaxis(out, 2, 0), out_ref) and np.array_equal(cold.p, p_ref)
            flags[label] = "yes" if same else "NO"
        single, pooled = WarmTV(STEPS, compiled=False), WarmTV(STEPS, compiled=False)
        cpus = os.cpu_count()
        variants = [
            ("all planes per operation (reference), 1 thread",
             lambda: all_planes_steps(f, p_ref, out_ref, WEIGHT, STEPS), "—", None),
            ("one plane at a time (WarmTV, NumPy), 1 thread",
             lambda: single(image, WEIGHT), flags["numpy"], "1"),
            (f"one plane at a time (WarmTV, NumPy), its thread pool ({cpus} CPUs)",
             lambda: pooled(image, WEIGHT), flags["numpy"], ""),
        ]  # fmt: skip
        if compiled:
            jit_single, jit_pooled = WarmTV(STEPS, compiled=True), WarmTV(STEPS, compiled=True)
            variants += [
                ("compiled kernel (WarmTV, numba), 1 thread",
                 lambda: jit_single(image, WEIGHT), flags["compiled"], "1"),
                (f"compiled kernel (WarmTV, numba), its thread pool ({cpus} CPUs)",
                 lambda: jit_pooled(image, WEIGHT), flags["compiled"], ""),
            ]  # fmt: skip
        for name, fn, shown, threads in variants:
            ms = median_ms(fn, args.repeats, threads)
            lines.append(f"| {planes} | {name} | {ms:.2f} | {ms / copy_ms:.1f} | {shown} |")
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
