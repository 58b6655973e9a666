"""Dispersion: per-band shear along ``y`` and its adjoint (un-shear, crop)."""

from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ..validate import real_array
from .algebra import Routing, TensorOperator, _normalize_axis, validate_shape, vec_index

__all__ = ["Shear", "parse_shifts", "shear_bands", "unshear_bands"]


#: Most bands and the largest total shift (px) :func:`parse_shifts` takes: beyond them the
#: measurement alone would not fit in memory; refused before allocating.
MAX_BANDS = 10_000
MAX_SHIFT_PX = 65_536


def parse_shifts(shifts, n_bands: int) -> np.ndarray:
    """Per-band shifts from a step (``2`` → ``0, 2, 4, …``) or a sequence.

    Shifts must be finite, ``≥ 0`` and monotone: non-decreasing (dispersion
    runs towards larger column index, SPEC §1) or non-increasing (a mirrored
    prism: the first band is shifted most).  Integral values come back as
    ``int64``, anything fractional as ``float64`` (linear interpolation).
    """
    if isinstance(n_bands, bool) or not isinstance(n_bands, numbers.Integral) or n_bands < 1:
        raise ValueError(f"n_bands must be a positive integer, got {n_bands!r}")
    if n_bands > MAX_BANDS:
        raise ValueError(f"n_bands must be ≤ {MAX_BANDS}, got {n_bands}")
    kinds = np.asarray(shifts).dtype.kind if not isinstance(shifts, (str, bytes)) else "U"
    if kinds not in "iuf" or isinstance(shifts, bool):  # "2" or True would be read as numbers
        raise ValueError(f"shifts must be a number or a sequence of numbers (px), got {shifts!r}")
    if np.ndim(shifts) == 0:
        step = float(np.asarray(shifts))
        if not np.isfinite(step) or step < 0:
            raise ValueError(f"shift step must be a finite number ≥ 0, got {shifts!r}")
        if step * (n_bands - 1) > MAX_SHIFT_PX:  # (before the product can overflow)
            raise ValueError(
                f"a step of {step:g} px over {n_bands} bands shifts the last band by "
                f"{step * (n_bands - 1):g} px; at most {MAX_SHIFT_PX} px"
            )
        s = step * np.arange(n_bands)
    else:
        s = real_array("shifts", shifts, finite=False).reshape(-1)
        if s.size != n_bands:
            raise ValueError(f"expected {n_bands} per-band shifts (one per band), got {s.size}")
    if not np.isfinite(s).all():
        raise ValueError(f"shifts must be finite, got {s.tolist()}")
    if (s < 0).any():
        raise ValueError(f"shifts must be ≥ 0, got {s.tolist()}")
    d = np.diff(s)
    if (d < 0).any() and (d > 0).any():  # neither direction
        first = np.sign(d[np.nonzero(d)[0][0]])
        bad = int(np.nonzero(np.sign(d) == -first)[0][0])
        rel = "<" if s[bad + 1] < s[bad] else ">"
        raise ValueError(
            "shifts must be monotone (non-decreasing, or non-increasing for a mirrored "
            f"dispersion), but band {bad + 1} has shift {s[bad + 1]:g} {rel} {s[bad]:g} of "
            f"band {bad}"
        )
    if s.size and s.max() > MAX_SHIFT_PX:
        raise ValueError(
            f"the largest shift is {s.max():g} px; at most {MAX_SHIFT_PX} px (the measurement "
            "grows by it)"
        )
    if np.all(s == np.round(s)):
        return s.astype(np.int64)
    return s


class Shear(TensorOperator):
    """Shift band ``l`` by ``s_l`` columns: ``Y[:, c + s_l, l] = X[:, c, l]``.

    Parameters
    ----------
    input_shape : tuple of int
        Shape of ``X``; ``axis`` is the dispersion direction (``y``) and
        ``band_axis`` holds the bands.
    shifts : int, float or sequence
        A step (``s_l = step · l``) or one shift per band; non-decreasing,
        ``≥ 0``.  Fractional shifts (calibrated prisms) use linear
        interpolation: ``Y[c + ⌊s⌋] += (1 − t) X[c]``, ``Y[c + ⌊s⌋ + 1] += t X[c]``
        with ``t = s − ⌊s⌋``.
    axis, band_axis : int
        Defaults ``1`` (``y``) and ``2`` (``λ``).

    Notes
    -----
    The output is ``⌈max s⌉`` wider along ``axis``.  The adjoint un-shears:
    ``Xᵀ[:, c, l] = Y[:, c + s_l, l]`` (crop), with the same interpolation
    weights for fractional shifts.  For integer shifts ``A Aᵀ`` is diagonal
    (1 where a band lands, 0 elsewhere); fractional shifts couple neighbouring
    columns (band width 1).
    """

    def __init__(self, input_shape, shifts=1, *, axis: int = 1, band_axis: int = 2):
        shape = validate_shape(input_shape, "input_shape")
        if len(shape) < 2:
            raise ValueError(f"Shear needs at least 2 axes, got input shape {shape}")
        axis = _normalize_axis(axis, len(shape), "axis")
        band_axis = _normalize_axis(band_axis, len(shape), "band_axis")
        if axis == band_axis:
            raise ValueError(f"axis and band_axis must differ, both are {axis}")
        s = parse_shifts(shifts, shape[band_axis])
        self.shifts = s
        self.integer = s.dtype.kind == "i"
        self.axis, self.band_axis = axis, band_axis
        self._floor = np.floor(s).astype(np.int64)
        self._frac = s - self._floor
        extra = int(np.ceil(s.max())) if s.size else 0
        out = list(shape)
        out[axis] += extra
        super().__init__(shape, out)

    # slices ---------------------------------------------------------------------
    def _idx(self, l, start=None, n=None):
        idx = [slice(None)] * len(self.input_shape)
        idx[self.band_axis] = l
        if start is not None:
            idx[self.axis] = slice(start, start + n)
        return tuple(idx)

    def _forward(self, x):
        y = B.zeros_like_shape(self.output_shape, x)
        n = self.input_shape[self.axis]
        for l in range(self.input_shape[self.band_axis]):
            f, t = int(self._floor[l]), float(self._frac[l])
            xl = x[self._idx(l)]
            if t == 0.0:
                y[self._idx(l, f, n)] = xl
            else:
                y[self._idx(l, f, n)] += (1.0 - t) * xl
                y[self._idx(l, f + 1, n)] += t * xl
        return y

    def _adjoint(self, y):
        n = self.input_shape[self.axis]
        parts = []
        for l in range(self.input_shape[self.band_axis]):
            f, t = int(self._floor[l]), float(self._frac[l])
            part = y[self._idx(l, f, n)]
            if t != 0.0:
                part = (1.0 - t) * part + t * y[self._idx(l, f + 1, n)]
            parts.append(part)
        return tl.stack(parts, axis=self.band_axis)

    # structure --------------------------------------------------------------------
    def _key(self, name):
        return (name, self.input_shape, self.axis, self.band_axis, tuple(self.shifts.tolist()))

    def _routing(self):
        nd = len(self.input_shape)
        disp = [(0, 0)] * nd
        spread = [0] * nd
        disp[self.axis] = (int(self._floor.min()), int(self._floor.max()))
        spread[self.axis] = 0 if self.integer else 1
        return Routing(
            self._key("shear"), tuple(range(nd)), tuple(disp), tuple(spread), self.integer
        )

    def _adjoint_routing(self):
        if not self.integer:
            return None
        nd = len(self.input_shape)
        disp = [(0, 0)] * nd
        disp[self.axis] = (-int(self.shifts.max()), -int(self.shifts.min()))
        return Routing(self._key("unshear"), tuple(range(nd)), tuple(disp), (0,) * nd, True)

    def _to_matrix(self):
        cols = vec_index(self.input_shape)
        out_idx = vec_index(self.output_shape)
        grids = np.indices(self.input_shape)
        band = grids[self.band_axis]
        rows_all, cols_all, vals_all = [], [], []
        for extra, weight in ((0, 1.0 - self._frac), (1, self._frac)):
            w = weight[band]
            keep = w != 0
            pos = list(grids)
            pos[self.axis] = grids[self.axis] + self._floor[band] + extra
            rows = out_idx[tuple(p[keep] for p in pos)]
            rows_all.append(rows)
            cols_all.append(cols[keep])
            vals_all.append(w[keep])
        return sp.csr_matrix(
            (np.concatenate(vals_all), (np.concatenate(rows_all), np.concatenate(cols_all))),
            shape=self.shape,
        )


def shear_bands(cube, shifts=1, *, axis: int = 1, band_axis: int = 2):
    """Functional form of :class:`Shear`: disperse ``cube`` band by band."""
    return Shear(tl.shape(cube), shifts, axis=axis, band_axis=band_axis).forward(cube)


def unshear_bands(measurement, n_columns: int, shifts=1, *, axis: int = 1, band_axis: int = 2):
    """Adjoint of :func:`shear_bands`: cut each band back to ``n_columns`` columns."""
    if not (hasattr(measurement, "shape") or isinstance(measurement, (list, tuple))):
        raise ValueError(
            f"measurement must be an array, got {type(measurement).__name__} {measurement!r}"[:200]
        )
    shape = (
        list(tl.shape(measurement)) if tl.is_tensor(measurement) else list(np.shape(measurement))
    )
    if not shape:
        raise ValueError("measurement must be an array with rows and columns, got a scalar")
    shape[_normalize_axis(axis, len(shape))] = validate_shape((n_columns,), "n_columns")[0]
    op = Shear(shape, shifts, axis=axis, band_axis=band_axis)
    return op.adjoint(measurement)
