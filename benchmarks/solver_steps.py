"""Speed of the steps that every first stage (OTD's, ``pnp_fast``'s start, the SNR estimate's
subspace fit) takes many times, at 256×256×28 float32 (SD-CASSI, the real TSA mask, a tuning
scene), each against the way it was done before, in the same run:

* ``relative_change`` of two Fortran-ordered iterates (the stopping quantity, once an
  iteration of every solver): the compiled one-pass sums (numba, the ``fast`` extra) against
  NumPy's difference and two dot products (``TENSOR_COSDI_JIT=0``);
* the subspace TV of ``subspace_gap_tv`` (8 coefficient images, 3 warm Chambolle steps):
  ``WarmTV`` stepping the planes of a Fortran-ordered iterate as they lie against copying
  them into channel-first planes and back (a transposing copy each way);
* ``fitted_mean_spectrum`` (the light gate's fit, up to three times a reconstruction): band
  slices in the estimate's memory order, no copy per band, the normal equations in float64,
  against a C-ordered cube copied to the measurement's backend once per band with the normal
  equations summed in float32 (the reference loop below);
* a whole first stage (``subspace_gap_tv``, 90 iterations, 3 warm Chambolle steps, as
  ``pnp_fast``'s start): its iterates held as coefficient images against accelerated GAP on
  full cubes with the subspace TV as its prior (``engine.gap``, the general path).

Each row is the median of ``--repeats`` runs, and its ratio to a copy of the cube measured in
the same run.

    python benchmarks/solver_steps.py [--repeats 30] [--scene cloth] [--out FILE]

Needs the research data (``TENSOR_COSDI_DATA``).  Never asserts anything: read the ratios.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from tensor_cosdi import _backend as B
from tensor_cosdi.bases import dct
from tensor_cosdi.solvers import engine
from tensor_cosdi.solvers._base import compiled_change, relative_change
from tensor_cosdi.solvers.denoisers import WarmTV
from tensor_cosdi.solvers.priors import TV
from tensor_cosdi.solvers.subspace import (
    fitted_mean_spectrum,
    pan_atoms_for,
    subspace_denoise,
    subspace_gap_tv,
)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, load_mask, median_ms, problem, write_results  # noqa: E402

ATOMS = 8
TV_STEPS = 3
TV_WEIGHT = 0.05


def numpy_change(new, old):
    """:func:`relative_change` with the compiled loop off (``TENSOR_COSDI_JIT=0``)."""
    saved = os.environ.get("TENSOR_COSDI_JIT")
    os.environ["TENSOR_COSDI_JIT"] = "0"
    try:
        return relative_change(new, old)
    finally:
        os.environ.pop("TENSOR_COSDI_JIT")
        if saved is not None:
            os.environ["TENSOR_COSDI_JIT"] = saved


def copied_planes_tv(warm):
    """The subspace TV's denoiser as it ran on planes copied to channel-first order and back:
    the same warm steps on C-ordered planes, a transposing copy each way."""

    def denoise(coef, weight):
        planes = np.ascontiguousarray(np.moveaxis(coef, 2, 0))
        return np.asfortranarray(warm(np.moveaxis(planes, 0, 2), weight))

    return denoise


def per_band_copies_fit(system, measurement, cube, sums=np.float32):
    """The reference loop of ``fitted_mean_spectrum``: a C-ordered cube copied to the
    measurement's backend once per band, the normal equations summed in ``sums``."""
    from scipy.optimize import nnls

    x = np.maximum(np.asarray(cube, dtype=np.float32), 0.0)
    a = x.sum(axis=2, keepdims=True)
    g = np.asarray(measurement, dtype=np.float32).ravel()
    n = x.shape[2]
    cols = np.empty((g.size, n), dtype=np.float32)
    e = np.zeros(x.shape, dtype=np.float32)
    for band in range(n):
        e[:, :, band : band + 1] = a
        out = system.operator.apply(B.tensor_like(e, measurement))
        cols[:, band] = np.asarray(out).ravel()
        e[:, :, band : band + 1] = 0.0
    cols, g = cols.astype(sums), g.astype(sums)
    s, _ = nnls((cols.T @ cols).astype(np.float64), (cols.T @ g).astype(np.float64))
    return np.maximum(s / s.max(), 1e-3)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--scene", default="cloth", help="a tuning scene (default cloth)")
    ap.add_argument("--out", default=str(RESULTS / "solver_steps.md"))
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error(f"--repeats must be at least 1, got {args.repeats}")
    system, _, g = problem(args.scene, None, load_mask("tsa"))
    g = np.asarray(g, dtype=np.float32)
    x = np.asfortranarray(system.operator.apply_adjoint(g))  # a solver's iterate, its layout
    x2 = np.asfortranarray(x * np.float32(1.001))
    copy_ms = median_ms(lambda: x.copy(order="K"), args.repeats)
    rows = []

    def row(step, way, fn):
        ms = median_ms(fn, args.repeats)
        rows.append(f"| {step} | {way} | {ms:.2f} | {ms / copy_ms:.2f} |")
        return ms

    compiled = compiled_change()
    if compiled:
        row("relative_change", "compiled one-pass sums", lambda: relative_change(x2, x))
    row("relative_change", "NumPy difference and dot products", lambda: numpy_change(x2, x))
    atoms = [dct(x.shape[2])[:, :ATOMS].astype(np.float32)]
    lie, copied = WarmTV(TV_STEPS), WarmTV(TV_STEPS)
    copied_den = copied_planes_tv(copied)
    a = subspace_denoise(x, atoms, [2], lie, TV_WEIGHT)
    b = subspace_denoise(x, atoms, [2], copied_den, TV_WEIGHT)
    tv_gap = float(np.abs(a - b).max() / np.abs(b).max())
    row("subspace TV", "planes stepped as they lie", lambda: subspace_denoise(
        x, atoms, [2], lie, TV_WEIGHT))  # fmt: skip
    row("subspace TV", "planes copied to channel-first and back", lambda: subspace_denoise(
        x, atoms, [2], copied_den, TV_WEIGHT))  # fmt: skip
    new_w = fitted_mean_spectrum(system, g, x, "λ")
    old_w = per_band_copies_fit(system, g, np.ascontiguousarray(x))
    fit_gap = float(np.abs(new_w - old_w).max())
    sums64 = per_band_copies_fit(system, g, np.ascontiguousarray(x), np.float64)
    fit_gap64 = float(np.abs(new_w - sums64).max())
    row("fitted_mean_spectrum", "estimate's order, no copies, float64 sums", lambda: (
        fitted_mean_spectrum(system, g, x, "λ")))  # fmt: skip
    row("fitted_mean_spectrum", "C order, a copy a band, float32 sums", lambda: (
        per_band_copies_fit(system, g, np.ascontiguousarray(x))))  # fmt: skip
    stage_iter = 90
    atoms_k = [dct(x.shape[2])[:, : pan_atoms_for(x.shape[2], "auto")].astype(np.float32)]

    def full_cube_stage():
        warm = WarmTV(TV_STEPS)
        prior = TV(TV_WEIGHT, denoise=lambda v, w: subspace_denoise(v, atoms_k, [2], warm, w))
        return engine.gap(
            system.operator, g, prior, eps=1e-6, max_iter=stage_iter, objective=False
        )[0]

    def coefficient_stage():
        return subspace_gap_tv(
            system, g, max_iter=stage_iter, tv_weight=TV_WEIGHT, tv_steps=TV_STEPS
        )

    a, b = coefficient_stage(), full_cube_stage()
    stage_gap = float(np.abs(a - b).max() / np.abs(b).max())
    stage_repeats = max(1, args.repeats // 6)
    for way, fn in (("coefficient images", coefficient_stage), ("full cubes", full_cube_stage)):
        ms = median_ms(fn, stage_repeats)
        step = f"first stage, {stage_iter} iterations"
        rows.append(f"| {step} | {way} | {ms:.0f} | {ms / copy_ms:.0f} |")
    lines = [
        f"# Solver steps at 256×256×28 float32: {args.scene}, TSA mask",
        "",
        f"A Fortran-ordered iterate (the adjoint of the measurement); a copy of it: "
        f"{copy_ms:.2f} ms.  Median of {args.repeats} runs.",
        "",
        "| step | way | ms | × copy |",
        "|---|---|---|---|",
        *rows,
        "",
        "* subspace TV, the two ways: "
        + (
            "the same result bit for bit."
            if tv_gap == 0
            else f"largest difference {tv_gap:.1e} of the result's peak."
        ),
        f"* fitted_mean_spectrum, the two ways: largest difference {fit_gap:.1e} (the spectra "
        f"have a peak of 1); the reference loop with its normal equations summed in float64: "
        f"{fit_gap64:.1e}.",
        f"* first stage, the two ways: largest difference {stage_gap:.1e} of the cube's peak "
        f"(medians of {stage_repeats} runs).",
    ]
    if not compiled:
        lines.append("* relative_change: numba is not installed, so no compiled row.")
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
