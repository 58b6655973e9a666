"""Integration over an axis (the detector sums bands, focal steps, snapshots) and
its adjoint, replication (the thesis' decimator transpose ``Dᵀ``, Equation 46, 62)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ._kernels import (
    GatherMatrix,
    linear_step,
    memory_order,
    moved,
    shear_sum_adjoint,
    shear_sum_forward,
    shear_sum_forward_slabs,
)
from .algebra import Routing, TensorOperator, _normalize_axis, validate_shape, vec_index
from .codes import Code
from .shear import Shear

__all__ = ["SumAxis", "Replicate"]


class SumAxis(TensorOperator):
    """Sum over one axis: ``y = Σ_a x[..., a, ...]`` (the axis disappears).

    Notes
    -----
    Adjoint: replicate ``y`` along the removed axis (:class:`Replicate`).
    ``A Aᵀ = n I`` with ``n`` the length of the summed axis.  In a composition
    ``SumAxis ∘ Shear ∘ Code`` (the CASSI detector) the three run as one fused
    pass over the cube.
    """

    def __init__(self, input_shape, axis: int):
        shape = validate_shape(input_shape, "input_shape")
        if len(shape) < 2:
            raise ValueError(f"SumAxis needs at least 2 axes, got input shape {shape}")
        self.axis = _normalize_axis(axis, len(shape))
        out = shape[: self.axis] + shape[self.axis + 1 :]
        super().__init__(shape, out)

    def _forward(self, x):
        return tl.sum(x, axis=self.axis)

    def _adjoint(self, y):
        n = self.input_shape[self.axis]
        return tl.stack([y] * n, axis=self.axis)

    @property
    def T(self):
        return Replicate(self.output_shape, self.axis, self.input_shape[self.axis])

    def _routing(self):
        nd = len(self.input_shape)
        axis_map = tuple(None if a == self.axis else a - (a > self.axis) for a in range(nd))
        return Routing(
            ("sum", self.input_shape, self.axis),
            axis_map,
            ((0, 0),) * (nd - 1),
            (0,) * (nd - 1),
            True,
        )

    def _to_matrix(self):
        idx = vec_index(self.output_shape)
        rows = np.expand_dims(idx, self.axis)
        rows = np.broadcast_to(rows, self.input_shape).reshape(-1, order="F")
        n = rows.size
        return sp.csr_matrix((np.ones(n), (rows, np.arange(n))), shape=self.shape)

    def _fuse_with(self, inner):
        if isinstance(inner, Shear) and inner.integer and inner.band_axis == self.axis:
            return _CodedShearSum(inner.input_shape, self.axis, inner.axis, inner.shifts, None)
        if isinstance(inner, Code):
            return _CodedShearSum(inner.input_shape, self.axis, None, None, inner.weights)
        return None


class Replicate(TensorOperator):
    """Copy a tensor ``n`` times along a new axis inserted at ``axis``.

    This is the decimator transpose ``Dᵀ = 1 ⊗ I`` of the thesis (Eq. 46, 62,
    65, 68); the adjoint sums over the new axis.  ``A Aᵀ`` couples the ``n``
    copies of each entry: one ``n × n`` block of ones per pixel.
    """

    def __init__(self, input_shape, axis: int, n: int):
        shape = validate_shape(input_shape, "input_shape")
        (n,) = validate_shape((n,), "n")
        self.axis = _normalize_axis(axis, len(shape) + 1)
        out = shape[: self.axis] + (n,) + shape[self.axis :]
        super().__init__(shape, out)
        self.n = n

    def _forward(self, x):
        return tl.stack([x] * self.n, axis=self.axis)

    def _adjoint(self, y):
        return tl.sum(y, axis=self.axis)

    @property
    def T(self):
        return SumAxis(self.output_shape, self.axis)

    def _gram_pattern(self):
        from .gram import Pattern

        return Pattern("blocks", self.axis)

    def _to_matrix(self):
        return sp.csr_matrix(self.T.to_matrix().T)


#: Above this many voxels the forward on a cube outside the band-major layout keeps the
#: per-band loop instead of building a sparse gather matrix (8-12 bytes per voxel).
GATHER_MAX_VOXELS = 2**25
#: The dtypes SciPy's sparse product takes (a float16 cube keeps the per-band loop).
GATHER_DTYPES = (np.dtype(np.float32), np.dtype(np.float64))


class _CodedShearSum(TensorOperator):
    """Fused ``SumAxis(band) ∘ Shear ∘ Code`` kernel (execution plans only).

    ``y = Σ_l shift_{s_l}(W[..., l, ...] ∘ x[..., l, ...])`` in one loop over
    the bands; each band slice is read once.  The adjoint writes its result
    band-major in memory (``x[..., l, ...]`` contiguous), the layout in which
    the forward loop reads contiguous slices, so iterates of a solver stay
    in the fast layout.
    """

    def __init__(self, input_shape, sum_axis, shift_axis, shifts, weights):
        shape = tuple(input_shape)
        self.sum_axis = sum_axis
        self.shift_axis = shift_axis
        nb = shape[sum_axis]
        self.shifts = np.zeros(nb, dtype=np.int64) if shifts is None else np.asarray(shifts)
        self.weights = weights
        out = list(shape)
        if shift_axis is not None:
            out[shift_axis] += int(self.shifts.max())
        del out[sum_axis]
        super().__init__(shape, out)
        # output axis that receives the shear
        self._oshift = None if shift_axis is None else shift_axis - (shift_axis > sum_axis)
        if weights is not None and weights.shape[sum_axis] == 1:
            self._wslices = [np.take(weights, 0, axis=sum_axis)] * nb
        elif weights is not None:
            self._wslices = [np.take(weights, l, axis=sum_axis) for l in range(nb)]
        else:
            self._wslices = None
        # linear integer shifts s·l: the strided kernels of _kernels.py (NumPy tensors)
        self._step = None if shift_axis is None else linear_step(self.shifts)
        self._gathers: dict = {}  # (memory order, dtype) → GatherMatrix

    def _fuse_with(self, inner):
        if isinstance(inner, Code):
            w = inner.weights if self.weights is None else self.weights * inner.weights
            return _CodedShearSum(self.input_shape, self.sum_axis, self.shift_axis, self.shifts, w)
        return None

    def _band(self, l):
        return (slice(None),) * self.sum_axis + (l,)

    def _oslice(self, l):
        if self._oshift is None:
            return ...
        n = self.input_shape[self.shift_axis]
        s = int(self.shifts[l])
        return (slice(None),) * self._oshift + (slice(s, s + n),)

    def _w(self, l, like):
        return self._params.get(f"w{l}", self._wslices[l], like)

    def _w_moved(self, like):
        if self.weights is None:
            return None
        w = moved(self.weights, self.sum_axis, self.shift_axis)
        return self._params.get("w_moved", w, like)  # contiguous, in like's dtype

    def _forward(self, x):
        numpy = isinstance(x, np.ndarray)
        if numpy and self._step is not None:
            y = shear_sum_forward(x, self._w_moved(x), self.sum_axis, self.shift_axis, self._step)
            if y is not None:
                return y
            w_of = None if self._wslices is None else (lambda l: self._w(l, x))
            y = shear_sum_forward_slabs(x, w_of, self.sum_axis, self.shift_axis, self._step)
            if y is not None:
                return y
        if numpy and x.dtype in GATHER_DTYPES and x.size <= GATHER_MAX_VOXELS:
            order = memory_order(x)
            # the band axis fastest in memory (NumPy's C order for (x, y, λ)): band slices are
            # strided single values, so one sparse product over the buffer (≈ 7 copies against
            # ≈ 19 for the loop; benchmarks/operators.py)
            if order is not None and order[-1] == self.sum_axis:
                return self._gather(order, x.dtype).forward(x)
        y = B.zeros_like_shape(self.output_shape, x)
        nb = self.input_shape[self.sum_axis]
        tmp = None
        for l in range(nb):
            xl = x[self._band(l)]
            if self._wslices is not None:
                w = self._w(l, x)
                if numpy:
                    if tmp is None:
                        tmp = np.empty(np.broadcast_shapes(xl.shape, w.shape), dtype=y.dtype)
                    np.multiply(xl, w, out=tmp)
                    xl = tmp
                else:
                    xl = xl * w
            y[self._oslice(l)] += xl
        return y

    def _gather(self, order, dtype) -> GatherMatrix:
        key = (order, np.dtype(dtype).str)
        hit = self._gathers.get(key)
        if hit is None:
            w = None if self.weights is None else np.asarray(self.weights)
            hit = GatherMatrix(
                self.input_shape, order, self.sum_axis, self.shift_axis, self.shifts, w, dtype
            )
            if len(self._gathers) >= 2:  # at most two layouts; clear() and setting one key are
                self._gathers.clear()  # atomic, and callers keep the matrices they hold
            self._gathers[key] = hit
        return hit

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_gathers"] = {}  # rebuilt where it is needed, not shipped to Dask workers
        return state

    def _adjoint(self, y):
        nb = self.input_shape[self.sum_axis]
        if isinstance(y, np.ndarray) and self._step is not None:
            return shear_sum_adjoint(
                y,
                self._w_moved(y),
                self.sum_axis,
                self.shift_axis,
                self._step,
                nb,
                self.input_shape[self.shift_axis],
            )
        rest = self.input_shape[: self.sum_axis] + self.input_shape[self.sum_axis + 1 :]
        out = (
            B.zeros_like_shape((nb,) + rest, y)
            if not isinstance(y, np.ndarray)
            else np.empty((nb,) + rest, dtype=y.dtype)
        )
        for l in range(nb):
            yl = y[self._oslice(l)]
            if self._wslices is None:
                out[l] = yl
            elif isinstance(y, np.ndarray):
                np.multiply(yl, self._w(l, y), out=out[l])
            else:
                out[l] = yl * self._w(l, y)
        return tl.moveaxis(out, 0, self.sum_axis)
