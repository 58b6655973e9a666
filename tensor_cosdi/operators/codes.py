"""Hadamard (element-wise) codes: coded apertures, colour codes, per-depth codes."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _backend as B
from .algebra import Routing, TensorOperator, _normalize_axis, validate_shape, vec

__all__ = ["Code"]


class Code(TensorOperator):
    """Element-wise multiplication by a fixed code, ``y = C ∘ x``.

    Parameters
    ----------
    code : array_like
        Real, finite code.  Its axes correspond to the input axes listed in
        ``axes``; each of its sizes equals the input size there or is 1
        (broadcast).  Axes of the input not listed are broadcast over.
    input_shape : tuple of int
        Shape of the tensors the operator acts on.
    axes : sequence of int, optional
        Input axes spanned by the code's axes (default: the leading axes, so
        a ``(Nx, Ny)`` coded aperture applies to every band of a
        ``(Nx, Ny, Nλ)`` cube).

    Notes
    -----
    Forward and adjoint are the same map, ``x ↦ C ∘ x``; ``A Aᵀ = diag(C²)``.
    The explicit matrix is ``diag(vec(C))`` with ``C`` broadcast to
    ``input_shape``.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.operators import Code
    >>> op = Code(np.array([[1.0, 0.0], [0.5, 1.0]]), (2, 2, 3))
    >>> op.forward(np.ones((2, 2, 3)))[:, :, 0].tolist()
    [[1.0, 0.0], [0.5, 1.0]]
    """

    def __init__(self, code, input_shape, *, axes=None):
        shape = validate_shape(input_shape, "input_shape")
        code = np.asarray(B.to_numpy(code))
        if code.dtype.kind not in "biuf":
            raise ValueError(f"code must be a real array, got dtype {code.dtype}")
        code = code.astype(np.float64)
        if code.ndim == 0 or code.ndim > len(shape):
            raise ValueError(
                f"code with shape {code.shape} cannot be applied to input shape {shape}: "
                f"expected 1 to {len(shape)} axes"
            )
        if axes is None:
            axes = tuple(range(code.ndim))
        axes = tuple(_normalize_axis(a, len(shape), "code axis") for a in axes)
        if len(axes) != code.ndim or len(set(axes)) != len(axes):
            raise ValueError(
                f"axes={axes} must list {code.ndim} distinct input axes, one per code axis"
            )
        for a, n in zip(axes, code.shape):
            if n not in (1, shape[a]):
                raise ValueError(
                    f"code shape {code.shape} does not match input shape {shape}: code axis of "
                    f"size {n} maps to input axis {a} of size {shape[a]} (expected {shape[a]} or 1)"
                )
        if not np.isfinite(code).all():
            raise ValueError("code contains NaN or inf")
        full = [1] * len(shape)
        order = np.argsort(axes)
        for i in order:
            full[axes[i]] = code.shape[i]
        self.weights = np.ascontiguousarray(
            np.transpose(code, order).reshape(full)
        )  # broadcastable to input_shape
        self.code = code
        self.axes = axes
        super().__init__(shape, shape)

    def _w(self, like):
        return self._params.get("w", self.weights, like)

    def _forward(self, x):
        return x * self._w(x)

    _adjoint = _forward

    @property
    def T(self):
        return self

    def _routing(self):
        return Routing.identity(len(self.input_shape), ("code", self.input_shape))

    def _to_matrix(self):
        return sp.diags(vec(np.broadcast_to(self.weights, self.input_shape)), format="csr")
