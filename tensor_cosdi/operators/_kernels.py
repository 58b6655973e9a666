"""Memory-speed NumPy kernels of the coded shear-and-sum (the CASSI detector), for linear shifts.

When band ``l`` is shifted by ``s·l`` pixels (an integer step ``s ≥ 0``, the
usual prism model), the shear is a *stride*.  Hold the cube with the band
axis slowest and the shifted axis next — memory order ``(λ, y, x)`` for an
``(x, y, λ)`` SD-CASSI cube, i.e. Fortran order.  Then every band is one contiguous slab and lands
on one contiguous block
of the measurement: the forward is two ufunc calls per band on whole slabs
into a measurement that stays in cache, and the adjoint one multiply of a
zero-copy strided view of the measurement (band ``l`` reads from ``s·l``
slices further on, so the view's band stride is ``s`` slices) — no inner
loop over short rows.  Measured (``benchmarks/operators.py``, 256×256×28
float32): the per-band loop over rows of 256 values costs 6-8 copies of
the cube, these ≈ 2.5 (forward) and ≈ 1.4 (adjoint).  A fully strided
forward (multiply into a zero-padded ``W``-slice buffer, then one
reduction over the bands' strided view) measured 5-8 copies: the buffer
does not stay in cache.

The adjoint returns its cube in that layout, so solver iterates stay in it;
a cube in any other layout takes the per-band loop of the caller.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import as_strided

__all__ = ["linear_step", "moved", "shear_sum_forward", "shear_sum_adjoint"]


def linear_step(shifts) -> int | None:
    """``s`` when ``shifts == s·arange(L)`` for an integer ``s ≥ 0``, else ``None``."""
    sh = np.asarray(shifts)
    if sh.size == 0 or not np.issubdtype(sh.dtype, np.integer) and not np.all(sh == np.round(sh)):
        return None
    step = int(sh[1] - sh[0]) if sh.size > 1 else 0
    if sh[0] != 0 or step < 0 or not np.array_equal(sh, step * np.arange(sh.size)):
        return None
    return step


def moved(a, band_axis: int, shift_axis: int):
    """View with the band axis first and the shifted axis second (the others in order)."""
    return np.moveaxis(a, (band_axis, shift_axis), (0, 1))


def shear_sum_forward(x: np.ndarray, weights, band_axis: int, shift_axis: int, step: int):
    """``y[c, …] = Σ_l (w ∘ x)[l, c − step·l, …]`` (axes in input order minus the band axis).

    ``weights`` is already :func:`moved` and contiguous (or ``None``).
    Returns ``None`` when ``x`` is not in the fast layout.  Each band is one
    contiguous slab and its target ``y[step·l : step·l + N]`` one contiguous
    block of the (cache-resident) measurement, so the loop is two ufunc
    calls per band on whole slabs.
    """
    xm = moved(x, band_axis, shift_axis)
    if not xm.flags.c_contiguous:
        return None
    L, n = xm.shape[:2]
    width = n + step * (L - 1)
    out = np.zeros((width,) + xm.shape[2:], dtype=x.dtype)
    tmp = np.empty(xm.shape[1:], dtype=x.dtype) if weights is not None else None
    for l in range(L):
        target = out[step * l : step * l + n]
        if weights is None:
            np.add(target, xm[l], out=target)
        else:
            np.multiply(xm[l], weights[l if weights.shape[0] > 1 else 0], out=tmp)
            np.add(target, tmp, out=target)
    return np.moveaxis(out, 0, shift_axis - (shift_axis > band_axis))


def shear_sum_adjoint(
    y: np.ndarray, weights, band_axis: int, shift_axis: int, step: int, n_bands: int, n: int
) -> np.ndarray:
    """``x[l, c, …] = w · y[c + step·l, …]``, returned in the fast layout (band, shift, rest)."""
    ym = np.ascontiguousarray(np.moveaxis(y, shift_axis - (shift_axis > band_axis), 0))
    view = as_strided(
        ym, (n_bands, n) + ym.shape[1:], (step * ym.strides[0],) + ym.strides, writeable=False
    )
    if weights is None:
        out = view.copy()
    else:
        out = np.empty(np.broadcast_shapes(view.shape, weights.shape), dtype=y.dtype)
        np.multiply(view, weights, out=out)
    return np.moveaxis(out, (0, 1), (band_axis, shift_axis))
