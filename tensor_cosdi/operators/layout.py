"""Permutations and embeddings: axis transposes, zero padding / cropping, and the
light-field layouts of SPEC §3.3 (5-D views ↔ interleaved lenslet image, Equation 85,
↔ tiled sub-aperture views, Equation 78 as corrected in SPEC §12)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from .algebra import Routing, TensorOperator, _normalize_axis, validate_shape, vec_index

__all__ = ["Transpose", "Pad", "LightFieldLayout", "LAYOUTS"]

LAYOUTS = ("interleaved", "tiled")


def _permutation_matrix(rows_for_input: np.ndarray, shape_out, n_in) -> sp.csr_matrix:
    cols = np.arange(n_in)
    return sp.csr_matrix(
        (np.ones(n_in), (rows_for_input, cols)), shape=(int(np.prod(shape_out)), n_in)
    )


class Transpose(TensorOperator):
    """Permute axes: ``output axis i`` is ``input axis axes[i]``."""

    def __init__(self, input_shape, axes):
        shape = validate_shape(input_shape, "input_shape")
        axes = tuple(_normalize_axis(a, len(shape)) for a in axes)
        if sorted(axes) != list(range(len(shape))):
            raise ValueError(f"axes must be a permutation of 0..{len(shape) - 1}, got {axes}")
        self.axes = axes
        super().__init__(shape, tuple(shape[a] for a in axes))

    _is_permutation = True

    def _forward(self, x):
        return tl.transpose(x, self.axes)

    def _adjoint(self, y):
        return tl.transpose(y, tuple(np.argsort(self.axes)))

    @property
    def T(self):
        return Transpose(self.output_shape, tuple(int(a) for a in np.argsort(self.axes)))

    def _routing(self):
        nd = len(self.axes)
        axis_map = tuple(self.axes.index(a) for a in range(nd))
        return Routing(
            ("transpose", self.input_shape, self.axes), axis_map, ((0, 0),) * nd, (0,) * nd
        )

    def _to_matrix(self):
        out_idx = vec_index(self.output_shape)
        rows = np.transpose(out_idx, np.argsort(self.axes)).reshape(-1, order="F")
        return _permutation_matrix(rows, self.output_shape, rows.size)


class Pad(TensorOperator):
    """Zero padding along one axis (adjoint: crop).

    ``Pad(shape, axis=1, before=β, after=a)`` places the input ``β`` entries
    further along ``axis`` in an output that is ``β + a`` longer — e.g. the
    reflected arm of CASSI-VSI landing ``β`` columns to the right (SPEC §3.1).
    """

    def __init__(self, input_shape, *, axis: int = 1, before: int = 0, after: int = 0):
        shape = validate_shape(input_shape, "input_shape")
        self.axis = _normalize_axis(axis, len(shape))
        for name, v in (("before", before), ("after", after)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ValueError(f"{name} must be an integer ≥ 0, got {v!r}")
        self.before, self.after = int(before), int(after)
        out = list(shape)
        out[self.axis] += self.before + self.after
        super().__init__(shape, out)

    def _slice(self):
        idx = [slice(None)] * len(self.input_shape)
        idx[self.axis] = slice(self.before, self.before + self.input_shape[self.axis])
        return tuple(idx)

    def _forward(self, x):
        y = B.zeros_like_shape(self.output_shape, x)
        y[self._slice()] = x
        return y

    def _adjoint(self, y):
        return y[self._slice()]

    def _key(self, name):
        return (name, self.input_shape, self.axis, self.before, self.after)

    def _routing(self):
        nd = len(self.input_shape)
        disp = [(0, 0)] * nd
        disp[self.axis] = (self.before, self.before)
        return Routing(self._key("pad"), tuple(range(nd)), tuple(disp), (0,) * nd)

    def _adjoint_routing(self):
        nd = len(self.input_shape)
        disp = [(0, 0)] * nd
        disp[self.axis] = (-self.before, -self.before)
        return Routing(self._key("crop"), tuple(range(nd)), tuple(disp), (0,) * nd)

    def _to_matrix(self):
        out_idx = vec_index(self.output_shape)
        rows = out_idx[self._slice()].reshape(-1, order="F")
        return _permutation_matrix(rows, self.output_shape, rows.size)


class LightFieldLayout(TensorOperator):
    """5-D light field ``(N1, N2, *C, N4, N5)`` → lenslet image ``(N1·N4, N2·N5, *C)``.

    ``C`` are zero or more middle axes (bands, snapshots …); ``N4, N5`` the
    view (angle) axes.

    layout="interleaved" (Eq. 85, the 3-D parameterisation):
        ``F̃[j1, j2, …] = F[j1 // N4, j2 // N5, …, j1 % N4, j2 % N5]`` — the
        pixels under one lenslet hold the views of one scene point, so
        neighbouring pixels of ``F̃`` are the same point seen from
        neighbouring views.
    layout="tiled" (Eq. 78 with the index fixed as in SPEC §12):
        ``F̃[j1, j2, …] = F[j1 % N1, j2 % N2, …, j1 // N1, j2 // N2]`` — each
        view is a contiguous ``N1 × N2`` sub-image.

    Both are permutations: the adjoint is the inverse, and
    ``LightFieldLayout(s, "tiled") @ LightFieldLayout(s, "interleaved").T``
    converts an interleaved image into tiled views.
    """

    def __init__(self, input_shape, layout: str = "interleaved"):
        shape = validate_shape(input_shape, "input_shape")
        if len(shape) < 4:
            raise ValueError(
                f"a light field needs at least 4 axes (N1, N2, …, N4, N5), got input shape {shape}"
            )
        if layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
        self.layout = layout
        N1, N2, N4, N5 = shape[0], shape[1], shape[-2], shape[-1]
        self.mid = shape[2:-2]
        super().__init__(shape, (N1 * N4, N2 * N5) + self.mid)

    def permutation(self) -> tuple[int, ...]:
        """Axis order that, followed by a reshape to ``output_shape``, tiles the views."""
        m = len(self.mid)
        nd = 4 + m
        a4, a5 = nd - 2, nd - 1
        mid = tuple(range(2, 2 + m))
        if self.layout == "interleaved":
            return (0, a4, 1, a5) + mid
        return (a4, 0, a5, 1) + mid

    def split_shape(self) -> tuple[int, ...]:
        """The input shape in :meth:`permutation` order (the sensor image before merging)."""
        s = self.input_shape
        return tuple(s[a] for a in self.permutation())

    def _forward(self, x):
        return tl.reshape(tl.transpose(x, self.permutation()), self.output_shape)

    def _adjoint(self, y):
        order = tuple(np.argsort(self.permutation()))
        return tl.transpose(tl.reshape(y, self.split_shape()), order)

    def _routing(self):
        nd_out = len(self.output_shape)
        key = ("lightfield", self.input_shape, self.layout)
        return Routing(key, (None,) * len(self.input_shape), (None,) * nd_out, (0,) * nd_out, True)

    def _adjoint_routing(self):
        nd_in = len(self.input_shape)
        key = ("lightfield_inverse", self.input_shape, self.layout)
        return Routing(key, (None,) * len(self.output_shape), (None,) * nd_in, (0,) * nd_in, True)

    _is_permutation = True

    def _to_matrix(self):
        out_idx = vec_index(self.output_shape)
        # C-order flat output position of every input entry, via the adjoint's reshaping
        flat_c = np.arange(int(np.prod(self.output_shape))).reshape(self.output_shape)  # C order
        order = tuple(np.argsort(self.permutation()))
        pos_c = np.transpose(flat_c.reshape(self.split_shape()), order)
        # pos_c[input multi-index] = C-order flat output index; convert to vec (F) order
        multi = np.unravel_index(pos_c, self.output_shape)
        rows = out_idx[multi].reshape(-1, order="F")
        return _permutation_matrix(rows, self.output_shape, rows.size)
