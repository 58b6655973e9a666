"""A Kronecker basis: one per-mode transform per axis of a tensor."""

from __future__ import annotations

import numpy as np

from .. import _backend as B
from ..operators import ModeProduct, validate_shape
from ..validate import real_array
from .matrices import is_orthonormal
from .transforms import Dense, ModeTransform, _memory_view, as_transform

__all__ = ["KroneckerBasis"]


class KroneckerBasis:
    """``Ψ = Ψ1 ⊗ … ⊗ Ψd`` applied mode by mode: ``F = Θ ×ₙ Ψn`` for the listed modes.

    Each mode holds a :class:`ModeTransform`: DCT and wavelets run as fast
    transforms (``scipy.fft``, PyWavelets) and learned matrices as one GEMM
    per mode, on the array's own memory order (a Fortran-ordered cube stays
    Fortran-ordered).  Tensors of other backends go through
    ``tensorly.tenalg`` with the dense matrices.

    Parameters
    ----------
    shape : tuple of int
        Shape of ``F`` (and of ``Θ``: the bases are square).
    matrices : dict {mode: matrix, ModeTransform or name} or list
        Orthonormal synthesis matrices (or transforms, or ``"dct"`` /
        ``"identity"`` / a PyWavelets name); modes not listed are left as they are.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.bases import wavelet
    >>> basis = KroneckerBasis((8, 8, 4), {0: wavelet(8, "haar"), 1: "haar", 2: "dct"})
    >>> F = np.random.default_rng(0).random((8, 8, 4))
    >>> np.allclose(basis.synthesis(basis.analysis(F)), F)
    True
    """

    def __init__(self, shape, matrices):
        self.shape = validate_shape(shape, "shape")
        if not isinstance(matrices, dict):
            matrices = dict(enumerate(matrices))
        trans = {}
        for mode, m in matrices.items():
            if not -len(self.shape) <= mode < len(self.shape):
                raise ValueError(f"mode {mode} is not an axis of shape {self.shape}")
            mode %= len(self.shape)
            n = self.shape[mode]
            if not isinstance(m, (ModeTransform, str)):
                m = real_array(f"the mode-{mode} matrix", B.to_numpy(m), finite=False)
                if m.shape != (n, n):
                    raise ValueError(
                        f"basis of mode {mode} must be {n} × {n} (square), got {m.shape}"
                    )
                if not is_orthonormal(m):
                    err = np.abs(m.T @ m - np.eye(n)).max()
                    raise ValueError(
                        f"basis of mode {mode} is not orthonormal: max |ΨᵀΨ − I| = {err:.2e}"
                    )
            trans[mode] = as_transform(n, m)
        self.transforms = trans
        self._op = None

    @property
    def matrices(self) -> dict:
        """``{mode: Ψn}`` as dense matrices."""
        return {m: t.matrix for m, t in self.transforms.items()}

    def _apply(self, x, synthesis: bool, overwrite: bool = False):
        if not self.transforms:
            return x
        if not isinstance(x, np.ndarray):
            if self._op is None:
                self._op = ModeProduct(self.shape, self.matrices)
            return self._op.forward(x) if synthesis else self._op.adjoint(x)
        v, flipped = _memory_view(x)
        nd = v.ndim
        spare = []  # C-contiguous buffers of v's shape whose contents are dead
        dead = overwrite or (v is not x and not flipped)  # v may be written over once used
        for mode, t in self.transforms.items():
            axis = nd - 1 - mode if flipped else mode
            step = t._synthesis if synthesis else t._analysis
            if isinstance(t, Dense) and spare and spare[-1].dtype == v.dtype:
                new = step(v, axis, out=spare.pop())  # a dense GEMM writes into a dead buffer
            else:
                new = step(v, axis)
            if dead and new is not v:
                spare.append(v)
            v, dead = new, True
        return v.T if flipped else v

    def synthesis(self, theta, *, overwrite: bool = False):
        """``F = Θ ×ₙ Ψn`` — coefficients to cube.  ``overwrite=True`` lets it reuse ``theta``'s
        memory (its contents are then undefined): one cube fewer at the peak."""
        return self._apply(theta, True, overwrite)

    def analysis(self, cube, *, overwrite: bool = False):
        """``Θ = F ×ₙ Ψnᵀ`` — cube to coefficients (the inverse, by orthonormality);
        ``overwrite`` as in :meth:`synthesis`."""
        return self._apply(cube, False, overwrite)

    def with_mode(self, mode: int, matrix) -> KroneckerBasis:
        """A copy with the basis of one mode replaced (the OTD basis update)."""
        trans = dict(self.transforms)
        trans[mode] = matrix
        return KroneckerBasis(self.shape, trans)

    def __repr__(self):
        kinds = {m: t.kind for m, t in sorted(self.transforms.items())}
        return f"KroneckerBasis(shape={self.shape}, modes={kinds})"
