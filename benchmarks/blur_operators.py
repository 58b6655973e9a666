"""Speed of the blur operators of CASSDI-DFA against running their factors one by one.

At the findings' CASSDI-DFA size (64×64 pixels, 16 bands, 3 depth planes, one
41×41 PSF per band and plane, float64), prints the median time of:

* the DFA solver's grayscale stage ``Blur ∘ Replicate(z) ∘ Replicate(λ)`` and
  its focal-stack stage ``Blur ∘ Replicate(λ)``, as their composition runs
  them (fused: one FFT of the input for all copies; the adjoint sums the
  copies in the Fourier domain) and factor by factor;
* the focal sweep's ``BlurSum`` (every plane seen at every one of 3 focal
  steps) against ``SumAxis ∘ Blur ∘ Replicate`` factor by factor;
* ``Blur`` alone against SciPy's ``fftconvolve(mode="same")`` on the same
  slices (an outside reference for the transform size);
* the three compositions on float32 input against the same on float64 (what
  ``dtype="float32"`` of the DFA design studies buys).

Each ratio is taken within the run (medians of ``--repeats``).

    python benchmarks/blur_operators.py [--repeats 30] [--out FILE]

The table and the run's provenance go to ``benchmarks/results/blur_operators.md``.
Never asserts anything: read the ratios.
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

import numpy as np
import scipy.signal

from tensor_cosdi.operators import Blur, BlurSum, Replicate, SumAxis

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, write_results  # noqa: E402
from operators import median_seconds  # noqa: E402


def by_factors(op, x, adjoint=False):
    """``op`` (a composition) applied one factor at a time, none fused."""
    factors = op.factors if adjoint else op.factors[::-1]
    for f in factors:
        x = f.apply_adjoint(x) if adjoint else f.apply(x)
    return x


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--out", default=str(RESULTS / "blur_operators.md"), help="results file")
    args = ap.parse_args(argv)
    r = args.repeats
    nx, ny, nl, nz, k, steps = 64, 64, 16, 3, 41, 3
    rng = np.random.default_rng(0)
    psfs = rng.random((k, k, nl, nz))
    psfs /= psfs.sum(axis=(0, 1))
    cube = (nx, ny, nl, nz)
    blur = Blur(cube, psfs)
    stages = {
        "grayscale stage: Blur ∘ Replicate(z) ∘ Replicate(λ)": blur
        @ Replicate((nx, ny, nl), 3, nz)
        @ Replicate((nx, ny), 2, nl),
        "focal-stack stage: Blur ∘ Replicate(λ)": blur @ Replicate((nx, ny, nz), 2, nl),
    }
    sweep_psfs = rng.random((k, k, nl, nz, steps))
    sweep = BlurSum(cube, sweep_psfs, sum_axis=3)
    stack = cube + (steps,)
    sweep_factors = SumAxis(stack, 3) @ Blur(stack, sweep_psfs) @ Replicate(cube, len(cube), steps)
    rows = []  # (operator, direction, fused ms, by-factor ms, agreement)
    for name, op in stages.items():
        x = rng.standard_normal(op.input_shape)
        y = rng.standard_normal(op.output_shape)
        for direction, fast, slow in (
            ("forward", lambda: op.apply(x), lambda: by_factors(op, x)),
            ("adjoint", lambda: op.apply_adjoint(y), lambda: by_factors(op, y, adjoint=True)),
        ):
            err = float(np.abs(fast() - slow()).max())
            rows.append((name, direction, median_seconds(fast, r), median_seconds(slow, r), err))
    x = rng.standard_normal(cube)
    y = rng.standard_normal(sweep.output_shape)
    for direction, fast, slow in (
        ("forward", lambda: sweep.apply(x), lambda: by_factors(sweep_factors, x)),
        (
            "adjoint",
            lambda: sweep.apply_adjoint(y),
            lambda: by_factors(sweep_factors, y, adjoint=True),
        ),
    ):
        err = float(np.abs(fast() - slow()).max())
        rows.append((f"focal sweep: BlurSum, {steps} steps", direction, median_seconds(fast, r),
                     median_seconds(slow, r), err))  # fmt: skip
    x = rng.standard_normal(cube)
    ref = lambda: scipy.signal.fftconvolve(x, psfs, mode="same", axes=(0, 1))  # noqa: E731
    err = float(np.abs(blur.apply(x) - ref()).max())
    fast = median_seconds(lambda: blur.apply(x), r)
    rows.append(("Blur (against SciPy fftconvolve 'same')", "forward", fast,
                 median_seconds(ref, r), err))  # fmt: skip
    for name, op in (*stages.items(), (f"focal sweep: BlurSum, {steps} steps", sweep)):
        x = rng.standard_normal(op.input_shape)
        y = rng.standard_normal(op.output_shape)
        x32, y32 = x.astype(np.float32), y.astype(np.float32)
        for direction, single, double in (
            ("forward", lambda: op.apply(x32), lambda: op.apply(x)),
            ("adjoint", lambda: op.apply_adjoint(y32), lambda: op.apply_adjoint(y)),
        ):
            err = float(np.abs(single() - double()).max())
            rows.append((f"{name}, float32 (against float64)", direction,
                         median_seconds(single, r), median_seconds(double, r), err))  # fmt: skip

    lines = [
        f"CASSDI-DFA blur operators: {nx}×{ny} pixels, {nl} bands, {nz} planes, one {k}×{k} PSF "
        f"per band and plane (focal sweep: per plane and step, {steps} steps), float64; "
        f"median of {r} repeats; {platform.processor() or platform.machine()}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}",
        "",
        "| operator | direction | as run, ms | reference, ms | reference / as run "
        "| max abs difference |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for name, direction, fast, slow, err in rows:
        lines.append(
            f"| {name} | {direction} | {fast * 1e3:.2f} | {slow * 1e3:.2f} | "
            f"{slow / fast:.2f} | {err:.1e} |"
        )
    lines += [
        "",
        "The reference is the factors run one by one; for the SciPy row SciPy's convolution, "
        "which transforms the PSFs at every call (the operators keep their spectra); for the "
        "float32 rows the same operator on the float64 input (the difference is float32's "
        "rounding).",
        "",
    ]
    for name, direction, fast, slow, err in rows:
        faster = "faster" if fast < slow else "slower"
        lines.append(f"* {name}, {direction}: {max(slow, fast) / min(slow, fast):.2f}× {faster} "
                     f"than the reference; the results agree to {err:.1e}.")  # fmt: skip
    write_results(args.out, lines)
    return rows


if __name__ == "__main__":
    main()
