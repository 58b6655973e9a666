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

The adjoint returns its cube in that layout, so solver iterates stay in it.

A cube whose band axis is slowest but whose shifted axis is not next
(band-major slabs, memory ``(λ, x, y)``) is read band by band too
(:func:`shear_sum_forward_slabs`): each coded slab goes into a buffer padded
like the measurement, and lands with one contiguous add at the band's flat
offset — one long add per band instead of a short row at a time
(``benchmarks/results/operators.md``, row "band-major").

A cube with the band axis fastest (NumPy's default C order for
``(x, y, λ)``) cannot be read band by band without gathering single values,
so :class:`GatherMatrix` applies the coded shear-and-sum
as one sparse matrix–vector product over the cube's memory buffer: one
row per measurement pixel holding the code values of the voxels that land
on it, with column indices in the cube's own memory order (no transpose).
SciPy's CSR product reads the cube once, in order, and writes each
measurement pixel once.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.lib.stride_tricks import as_strided

__all__ = [
    "linear_step",
    "moved",
    "shear_sum_forward",
    "shear_sum_forward_slabs",
    "shear_sum_adjoint",
    "memory_order",
    "GatherMatrix",
]


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


def shear_sum_forward_slabs(x: np.ndarray, weight_of, band_axis: int, shift_axis: int, step: int):
    """The same sum for a cube whose band axis is slowest in memory but whose shifted axis is
    not next (band-major ``(λ, x, y)`` memory for an ``(x, y, λ)`` cube); ``None`` otherwise.

    The measurement is allocated in the order of the slabs' remaining axes, so shifting a
    band by ``d`` pixels adds ``d`` times the shifted axis' stride to every flat index.  Each
    coded slab is written into a zero-padded buffer laid out like the measurement (the
    padding of the shifted axis is never written), and that buffer is added to the
    measurement's flat buffer at the band's offset: one contiguous add per band instead of
    one short row at a time (the rows of a band slab land ``d`` pixels into rows of the
    longer measurement).  The padding's zeros land on real pixels and change nothing.
    ``weight_of(l)`` is band ``l``'s code in the remaining axes' logical order (``weight_of``
    ``None``: no code); it is called only once the layout qualifies.
    """
    order = memory_order(x)
    if order is None or order[0] != band_axis or order[1] == shift_axis:
        return None
    rest = [a for a in range(x.ndim) if a != band_axis]
    out_axes = [rest.index(a) for a in order[1:]]  # output axes, slowest first in memory
    L = x.shape[band_axis]
    o_shift = rest.index(shift_axis)
    out_shape = [x.shape[a] for a in rest]
    out_shape[o_shift] += step * (L - 1)
    held = [out_shape[a] for a in out_axes]  # the measurement's shape in memory order
    size = int(np.prod(held))
    stride = int(np.prod([out_shape[a] for a in out_axes[out_axes.index(o_shift) + 1 :]]))
    flat = np.zeros(size + step * (L - 1) * stride, dtype=x.dtype)
    pad = np.zeros(held, dtype=x.dtype)  # one band, padded along the shifted axis
    n = x.shape[shift_axis]
    inner = pad[tuple(slice(0, n) if a == o_shift else slice(None) for a in out_axes)]
    inner = np.moveaxis(inner, range(len(out_axes)), out_axes)  # logical order of ``rest``
    pad_flat = pad.reshape(-1)
    for l in range(L):
        slab = x[(slice(None),) * band_axis + (l,)]  # a view
        if weight_of is None:
            np.copyto(inner, slab)
        else:
            np.multiply(slab, weight_of(l), out=inner)
        target = flat[step * l * stride : step * l * stride + size]
        np.add(target, pad_flat, out=target)
    y = flat[:size].reshape(held)
    return np.moveaxis(y, range(len(out_axes)), out_axes)


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


def memory_order(x: np.ndarray) -> tuple[int, ...] | None:
    """The axes of ``x`` from slowest to fastest in memory when its buffer is one dense block
    in some axis order (C, Fortran or any permutation), else ``None``."""
    if x.ndim == 0 or x.size == 0 or any(st < 0 for st in x.strides):
        return None
    order = tuple(sorted(range(x.ndim), key=lambda a: (x.strides[a], x.shape[a]), reverse=True))
    expected = x.itemsize
    for a in reversed(order):
        if x.shape[a] != 1 and x.strides[a] != expected:
            return None
        expected *= x.shape[a]
    return order


class GatherMatrix:
    """The coded shear-and-sum ``y[…, c + s_l, …] += W[…, l, …] x[…, l, …]`` as a CSR matrix
    acting on the memory buffer of a cube in one fixed memory order.

    Parameters
    ----------
    input_shape : tuple of int
        The logical cube shape.
    order : tuple of int
        The cube's axes from slowest to fastest in memory (:func:`memory_order`).
    sum_axis, shift_axis : int
        Band axis (summed) and the axis band ``l`` is shifted along by ``shifts[l]``
        (``shift_axis`` ``None``: no shift).
    shifts : array of int
        Non-negative integer shift of every band.
    weights : ndarray or None
        Code values broadcastable to ``input_shape`` (``None``: all ones).
    dtype : numpy dtype
        The dtype of the cubes it will be applied to (the matrix stores its values in it).

    Notes
    -----
    The matrix holds one entry per voxel: 4 + 4 bytes (float32) or 8 + 4
    (float64) per voxel, plus 4 per measurement pixel.
    """

    def __init__(self, input_shape, order, sum_axis, shift_axis, shifts, weights, dtype):
        shape = tuple(int(n) for n in input_shape)
        n_in = int(np.prod(shape))
        out = list(shape)
        if shift_axis is not None:
            out[shift_axis] += int(np.max(shifts))
        del out[sum_axis]
        self.output_shape = tuple(out)
        n_out = int(np.prod(self.output_shape))
        index = np.int32 if max(n_in, n_out) < 2**31 - 1 else np.int64
        # the memory position of every voxel (logical C order), then its measurement pixel
        mem_strides = np.empty(len(shape), dtype=np.int64)
        step = 1
        for a in reversed(order):
            mem_strides[a] = step
            step *= shape[a]
        grids = np.indices(shape, dtype=index, sparse=True)
        cols = sum(g * index(st) for g, st in zip(grids, mem_strides))
        out_strides = np.ones(len(self.output_shape), dtype=np.int64)
        for a in range(len(self.output_shape) - 2, -1, -1):
            out_strides[a] = out_strides[a + 1] * self.output_shape[a + 1]
        rows = 0
        k = 0
        for a, g in enumerate(grids):
            if a == sum_axis:
                continue
            pos = g
            if a == shift_axis:
                band = grids[sum_axis].reshape(-1)
                pos = g + np.asarray(shifts, dtype=index)[band].reshape(grids[sum_axis].shape)
            rows = rows + pos * index(out_strides[k])
            k += 1
        rows = np.broadcast_to(rows, shape).reshape(-1)
        cols = np.broadcast_to(cols, shape).reshape(-1)
        vals = (
            np.ones(n_in, dtype=dtype)
            if weights is None
            else np.broadcast_to(np.asarray(weights, dtype=dtype), shape).reshape(-1)
        )
        # each (pixel, voxel) pair occurs once, so the conversion has nothing to sum
        self.matrix = sp.coo_matrix((vals, (rows, cols)), shape=(n_out, n_in)).tocsr()
        self.order = tuple(order)

    def forward(self, x: np.ndarray) -> np.ndarray:
        """``y`` for a cube ``x`` held in :attr:`order` (its buffer is read in place)."""
        flat = np.ravel(x, order="K")  # a view: x is one dense block in this order
        return (self.matrix @ flat).reshape(self.output_shape)
