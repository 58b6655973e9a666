"""Orthonormal per-mode bases applied by n-mode products (SPEC §4, §5; thesis Eq. 82, 86).

A datacube is represented as ``F = Θ ×₁ Ψ1 ×₂ Ψ2 … ×_d Ψd`` with square
orthonormal *synthesis* matrices ``Ψn`` (columns are the atoms).  Because
every ``Ψn`` is orthonormal, the analysis is ``Θ = F ×₁ Ψ1ᵀ … ×_d Ψdᵀ`` and
``(ΨᵀAᵀAΨ + μI)⁻¹ = Ψᵀ (AᵀA + μI)⁻¹ Ψ``: the basis never enters a solve.

Per-mode bases: :func:`dct` (DCT-II), :func:`wavelet` (periodised discrete
wavelet transform from PyWavelets, default Symlet-8), :func:`identity`, and
bases learned from data, :func:`svd_basis` (left singular vectors of a
matrix) and :func:`tucker_bases` (HOSVD: eigenvectors of each mode's small
Gram).  :class:`KroneckerBasis` applies one per mode.
"""

from __future__ import annotations

import numbers
import warnings

import numpy as np
import scipy.fft

from . import _backend as B
from .operators import ModeProduct, validate_shape

__all__ = ["dct", "wavelet", "identity", "svd_basis", "tucker_bases", "KroneckerBasis", "is_orthonormal"]


def _size(n) -> int:
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"basis size must be a positive integer, got {n!r}")
    return int(n)


def is_orthonormal(psi, *, atol: float = 1e-10) -> bool:
    """True when ``psi`` is square with ``ΨᵀΨ = I`` within ``atol``."""
    m = np.asarray(B.to_numpy(psi), dtype=np.float64)
    return bool(m.ndim == 2 and m.shape[0] == m.shape[1] and np.abs(m.T @ m - np.eye(m.shape[0])).max() <= atol)


def _polish(m: np.ndarray) -> np.ndarray:
    """The nearest orthonormal matrix (polar factor): removes 1e-13 filter round-off."""
    u, _, vt = np.linalg.svd(m)
    return u @ vt


def identity(n: int) -> np.ndarray:
    """The ``n × n`` identity (no transform along that mode)."""
    return np.eye(_size(n))


def dct(n: int) -> np.ndarray:
    """Orthonormal DCT-II synthesis matrix: column ``k`` is the ``k``-th cosine atom.

    ``Ψᵀ x`` equals ``scipy.fft.dct(x, norm="ortho")``.

    Examples
    --------
    >>> import numpy as np, scipy.fft
    >>> x = np.arange(5.0)
    >>> np.allclose(dct(5).T @ x, scipy.fft.dct(x, norm="ortho"))
    True
    """
    n = _size(n)
    return scipy.fft.dct(np.eye(n), norm="ortho", axis=0).T


def wavelet(n: int, name: str = "sym8", *, level: int | None = None) -> np.ndarray:
    """Orthonormal periodised wavelet synthesis matrix (PyWavelets, default Symlet-8).

    Column ``j`` is the atom whose coefficient sits at position ``j`` of
    ``numpy.concatenate(pywt.wavedec(x, name, mode="periodization", level=level))``.

    Parameters
    ----------
    n : int
        Signal length; ``n`` must be divisible by ``2**level``.
    name : str
        An orthogonal PyWavelets wavelet (``"sym8"``, ``"db4"``, ``"haar"`` …).
    level : int, optional
        Decomposition depth.  Default: the deepest level without boundary
        effects (``pywt.dwt_max_level``) that ``n`` allows (0 — the identity —
        for short axes such as 28 bands with Symlet-8).

    Examples
    --------
    >>> psi = wavelet(64)
    >>> psi.shape, is_orthonormal(psi)
    ((64, 64), True)
    """
    import pywt

    n = _size(n)
    try:
        w = pywt.Wavelet(name)
    except ValueError:
        raise ValueError(f"unknown wavelet {name!r}; see pywt.wavelist(kind='discrete')") from None
    if not w.orthogonal:
        raise ValueError(f"wavelet {name!r} is not orthogonal; its matrix would not be orthonormal")
    if level is None:
        level = pywt.dwt_max_level(n, w.dec_len)
        while level > 0 and n % 2**level:
            level -= 1
    elif isinstance(level, bool) or not isinstance(level, numbers.Integral) or level < 0:
        raise ValueError(f"level must be an integer ≥ 0, got {level!r}")
    if n % 2**level:
        raise ValueError(f"a periodised {level}-level transform needs n divisible by {2**level}, got n = {n}")
    if level == 0:
        return np.eye(n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # deep levels on short signals: boundary wrap-around is intended
        cols = [np.concatenate(pywt.wavedec(e, w, mode="periodization", level=level)) for e in np.eye(n)]
    analysis = np.stack(cols, axis=1)  # coefficients = analysis @ x
    return _polish(analysis.T)


def svd_basis(matrix) -> np.ndarray:
    """Complete orthonormal basis of left singular vectors of ``matrix`` (``m × k``), strongest first.

    Learned spatial bases of SPEC §5 step 2: ``Ψ1, Ψ2`` from the panchromatic
    image ``Z`` are ``svd_basis(Z)`` and ``svd_basis(Z.T)``.  Computed from the
    small Gram ``M Mᵀ`` (``eigh``), which is complete even where ``k < m``.
    """
    m = np.asarray(B.to_numpy(matrix), dtype=np.float64)
    if m.ndim != 2:
        raise ValueError(f"svd_basis needs a 2-D matrix, got shape {m.shape}")
    if not np.isfinite(m).all():
        raise ValueError("svd_basis: the matrix contains NaN or inf")
    vals, vecs = np.linalg.eigh(m @ m.T)
    return _polish(vecs[:, ::-1])


def tucker_bases(tensor, modes=None) -> dict[int, np.ndarray]:
    """Complete HOSVD bases: ``{mode: svd_basis(unfolding(tensor, mode))}`` (thesis Eq. 97).

    Examples
    --------
    >>> import numpy as np
    >>> bases = tucker_bases(np.random.default_rng(0).random((6, 5, 4)), modes=[2])
    >>> bases[2].shape, is_orthonormal(bases[2])
    ((4, 4), True)
    """
    x = B.to_numpy(tensor)
    modes = range(x.ndim) if modes is None else modes
    out = {}
    for m in modes:
        if not -x.ndim <= m < x.ndim:
            raise ValueError(f"mode {m} is not an axis of a tensor of shape {x.shape}")
        m %= x.ndim
        out[m] = svd_basis(np.moveaxis(x, m, 0).reshape(x.shape[m], -1))
    return out


class KroneckerBasis:
    """``Ψ = Ψ1 ⊗ … ⊗ Ψd`` applied by n-mode products: ``F = Θ ×ₙ Ψn`` for the listed modes.

    Parameters
    ----------
    shape : tuple of int
        Shape of ``F`` (and of ``Θ``: the bases are square).
    matrices : dict {mode: (n, n) array} or list of arrays
        Orthonormal synthesis matrices; modes not listed are left as they are.

    Examples
    --------
    >>> import numpy as np
    >>> basis = KroneckerBasis((8, 8, 4), {0: wavelet(8, "haar"), 1: wavelet(8, "haar"), 2: dct(4)})
    >>> F = np.random.default_rng(0).random((8, 8, 4))
    >>> np.allclose(basis.synthesis(basis.analysis(F)), F)
    True
    """

    def __init__(self, shape, matrices):
        self.shape = validate_shape(shape, "shape")
        if not isinstance(matrices, dict):
            matrices = dict(enumerate(matrices))
        mats = {}
        for mode, m in matrices.items():
            if not -len(self.shape) <= mode < len(self.shape):
                raise ValueError(f"mode {mode} is not an axis of shape {self.shape}")
            mode %= len(self.shape)
            m = np.asarray(B.to_numpy(m), dtype=np.float64)
            n = self.shape[mode]
            if m.shape != (n, n):
                raise ValueError(f"basis of mode {mode} must be {n} × {n} (square), got {m.shape}")
            if not is_orthonormal(m):
                err = np.abs(m.T @ m - np.eye(n)).max()
                raise ValueError(f"basis of mode {mode} is not orthonormal: max |ΨᵀΨ − I| = {err:.2e}")
            mats[mode] = m
        self.matrices = mats
        self._op = ModeProduct(self.shape, mats) if mats else None

    def synthesis(self, theta):
        """``F = Θ ×ₙ Ψn`` — coefficients to cube."""
        return theta if self._op is None else self._op.forward(theta)

    def analysis(self, cube):
        """``Θ = F ×ₙ Ψnᵀ`` — cube to coefficients (the inverse, by orthonormality)."""
        return cube if self._op is None else self._op.adjoint(cube)

    def with_mode(self, mode: int, matrix) -> "KroneckerBasis":
        """A copy with the basis of one mode replaced (the OTD basis update)."""
        mats = dict(self.matrices)
        mats[mode] = matrix
        return KroneckerBasis(self.shape, mats)

    def __repr__(self):
        return f"KroneckerBasis(shape={self.shape}, modes={sorted(self.matrices)})"
