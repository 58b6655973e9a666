"""n-mode products: separable (Kronecker) sensing and per-mode bases (Equation 80, 82)."""

from __future__ import annotations

from functools import reduce

import numpy as np
import scipy.sparse as sp
from tensorly import tenalg

from .. import _backend as B
from ..validate import real_array
from .algebra import TensorOperator, _normalize_axis, validate_shape

__all__ = ["ModeProduct"]


class ModeProduct(TensorOperator):
    """``Y = X ×_{n1} M1 ×_{n2} M2 …`` on any subset of modes.

    Parameters
    ----------
    input_shape : tuple of int
    matrices : sequence of 2-D arrays, or dict ``{mode: matrix}``
        Matrix ``M`` for mode ``n`` has ``input_shape[n]`` columns; the output
        size along ``n`` is its number of rows.
    modes : sequence of int, optional
        The modes of ``matrices`` when it is a sequence (default ``0, 1, …``).

    Notes
    -----
    Forward and adjoint go through ``tensorly.tenalg.multi_mode_dot`` (the
    adjoint with the transposed matrices).  In the column-major ``vec`` of
    SPEC §1 the matrix is ``M_d ⊗ … ⊗ M_1`` (identity for untouched modes).
    With a single mode, ``A Aᵀ`` is one ``M Mᵀ`` block per fibre.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.operators import ModeProduct
    >>> op = ModeProduct((4, 5, 6), {2: np.ones((2, 6))})
    >>> op.output_shape
    (4, 5, 2)
    """

    def __init__(self, input_shape, matrices, modes=None):
        shape = validate_shape(input_shape, "input_shape")
        if isinstance(matrices, dict):
            modes, matrices = list(matrices.keys()), list(matrices.values())
        else:
            matrices = list(matrices)
            modes = list(range(len(matrices))) if modes is None else list(modes)
        if len(modes) != len(matrices) or not matrices:
            raise ValueError(
                f"ModeProduct needs one mode per matrix, got {len(modes)} modes and "
                f"{len(matrices)} matrices"
            )
        modes = [_normalize_axis(m, len(shape), "mode") for m in modes]
        if len(set(modes)) != len(modes):
            raise ValueError(f"modes must be distinct, got {modes}")
        mats = []
        out = list(shape)
        for m, M in zip(modes, matrices):
            M = real_array(f"the mode-{m} matrix", B.to_numpy(M), finite=False)
            if M.ndim != 2 or M.shape[1] != shape[m]:
                raise ValueError(
                    f"matrix for mode {m} must have shape (rows, {shape[m]}) to act on input "
                    f"shape {shape}, got {M.shape}"
                )
            if not np.isfinite(M).all():
                raise ValueError(f"matrix for mode {m} contains NaN or inf")
            mats.append(M)
            out[m] = M.shape[0]
        order = np.argsort(modes)
        self.modes = tuple(modes[i] for i in order)
        self.matrices = tuple(mats[i] for i in order)
        super().__init__(shape, out)

    def _mats(self, like):
        return [self._params.get(f"m{i}", M, like) for i, M in enumerate(self.matrices)]

    def _forward(self, x):
        return tenalg.multi_mode_dot(x, self._mats(x), modes=list(self.modes))

    def _adjoint(self, y):
        return tenalg.multi_mode_dot(y, self._mats(y), modes=list(self.modes), transpose=True)

    @property
    def T(self):
        return ModeProduct(self.output_shape, [M.T for M in self.matrices], self.modes)

    def _gram_pattern(self):
        from .gram import Pattern

        if len(self.modes) == 1:
            return Pattern("blocks", self.modes[0])
        return None

    def _to_matrix(self):
        factors = []
        for n, size in enumerate(self.input_shape):
            if n in self.modes:
                factors.append(sp.csr_matrix(self.matrices[self.modes.index(n)]))
            else:
                factors.append(sp.identity(size, format="csr"))
        # column-major vec: the first mode varies fastest → kron(M_d, …, M_1)
        return reduce(lambda acc, f: sp.kron(f, acc, format="csr"), factors[1:], factors[0])
