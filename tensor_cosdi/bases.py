"""Orthonormal per-mode bases applied by n-mode products (SPEC §4, §5; thesis Eq. 82, 86).

A datacube is represented as ``F = Θ ×₁ Ψ1 ×₂ Ψ2 … ×_d Ψd`` with square
orthonormal *synthesis* matrices ``Ψn`` (columns are the atoms).  Because
every ``Ψn`` is orthonormal, the analysis is ``Θ = F ×₁ Ψ1ᵀ … ×_d Ψdᵀ`` and
``(ΨᵀAᵀAΨ + μI)⁻¹ = Ψᵀ (AᵀA + μI)⁻¹ Ψ``: the basis never enters a solve.

Per-mode bases: :func:`dct` (DCT-II), :func:`wavelet` (periodised discrete
wavelet transform from PyWavelets, default Symlet-8), :func:`identity`, and
bases learned from data, :func:`svd_basis` (left singular vectors of a
matrix) and :func:`tucker_bases` (HOSVD: eigenvectors of each mode's small
Gram).  :class:`KroneckerBasis` applies one per mode, DCT and wavelets as
fast transforms (:class:`DCT` through ``scipy.fft``, :class:`Wavelet` through
PyWavelets' multilevel transform) and learned matrices as GEMMs
(:class:`Dense`); the matrix functions above are the dense oracles.
"""

from __future__ import annotations

import numbers
import warnings
from functools import cached_property

import numpy as np
import scipy.fft

from . import _backend as B
from .operators import ModeProduct, validate_shape

__all__ = [
    *("dct", "wavelet", "wavelet_level", "AUTO_COARSEST", "identity", "svd_basis"),
    *("tucker_bases", "KroneckerBasis"),
    *("is_orthonormal", "ModeTransform", "Dense", "DCT", "Wavelet", "as_transform"),
    *("BlockDense", "block_hosvd", "block_sizes"),
]


def _size(n) -> int:
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"basis size must be a positive integer, got {n!r}")
    return int(n)


def is_orthonormal(psi, *, atol: float = 1e-10) -> bool:
    """True when ``psi`` is square with ``ΨᵀΨ = I`` within ``atol``."""
    m = np.asarray(B.to_numpy(psi), dtype=np.float64)
    return bool(
        m.ndim == 2
        and m.shape[0] == m.shape[1]
        and np.abs(m.T @ m - np.eye(m.shape[0])).max() <= atol
    )


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


#: ``level="auto"`` of :func:`wavelet`: the deepest periodised level whose approximation band
#: still holds at least this many coefficients.  WDCT-ADMM, SD-CASSI, 16 bands, 30 dB, four
#: tuning scenes (balloons, cd, clay, feathers): at 64×64 levels 2 (``"boundary"``) / 3 / 4 /
#: 5 / 6 give 19.43 / 21.45 / 24.04 / 25.05 / 26.30 dB; at 96×96 levels 2 / 3 / 4 / 5 give
#: 18.89 / 21.37 / 24.03 / 25.13 dB — the deepest transform wins.
AUTO_COARSEST = 1


def wavelet_level(n: int, name: str = "sym8", level="auto") -> int:
    """The decomposition depth :func:`wavelet` uses for length ``n`` (see its ``level``).

    Examples
    --------
    >>> wavelet_level(64), wavelet_level(96), wavelet_level(64, level="boundary")
    (6, 5, 2)
    """
    import pywt

    n = _size(n)
    if isinstance(level, str):
        if level == "auto":  # as deep as periodisation allows, down to AUTO_COARSEST coefficients
            depth = 0
            while n % 2 ** (depth + 1) == 0 and n // 2 ** (depth + 1) >= AUTO_COARSEST:
                depth += 1
            return depth
        if level == "boundary":  # no atom wider than the signal (PyWavelets' maximum)
            depth = pywt.dwt_max_level(n, pywt.Wavelet(name).dec_len)
            while depth > 0 and n % 2**depth:
                depth -= 1
            return depth
        raise ValueError(f"level must be 'auto', 'boundary' or an integer ≥ 0, got {level!r}")
    if level is None:  # the former default
        return wavelet_level(n, name, "boundary")
    if isinstance(level, bool) or not isinstance(level, numbers.Integral) or level < 0:
        raise ValueError(f"level must be 'auto', 'boundary' or an integer ≥ 0, got {level!r}")
    if n % 2**level:
        raise ValueError(
            f"a periodised {level}-level transform needs n divisible by {2**level}, got n = {n}"
        )
    return int(level)


def wavelet(n: int, name: str = "sym8", *, level="auto") -> np.ndarray:
    """Orthonormal periodised wavelet synthesis matrix (PyWavelets, default Symlet-8).

    Column ``j`` is the atom whose coefficient sits at position ``j`` of
    ``numpy.concatenate(pywt.wavedec(x, name, mode="periodization", level=level))``.

    Parameters
    ----------
    n : int
        Signal length; ``n`` must be divisible by ``2**level``.
    name : str
        An orthogonal PyWavelets wavelet (``"sym8"``, ``"db4"``, ``"haar"`` …).
    level : int, "auto" or "boundary"
        Decomposition depth.  ``"auto"`` (default): as deep as the periodised
        transform allows while the coarsest band keeps :data:`AUTO_COARSEST`
        coefficients (6 levels at 64, 5 at 96, 8 at 256).  ``"boundary"``: the
        deepest level whose atoms are no wider than the signal
        (``pywt.dwt_max_level``; 1–2 levels of Symlet-8 at 32–96, 0 — the
        identity — at 28): far too shallow to make an image sparse, so a
        wavelet baseline with it loses several dB.  ``None`` means
        ``"boundary"``.

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
    level = wavelet_level(n, name, level)
    if level == 0:
        return np.eye(n)
    with warnings.catch_warnings():
        warnings.simplefilter(
            "ignore"
        )  # deep levels on short signals: boundary wrap-around is intended
        cols = [
            np.concatenate(pywt.wavedec(e, w, mode="periodization", level=level)) for e in np.eye(n)
        ]
    analysis = np.stack(cols, axis=1)  # coefficients = analysis @ x
    return _polish(analysis.T)


def svd_basis(matrix) -> np.ndarray:
    """Complete orthonormal basis of left singular vectors of ``matrix`` (``m × k``), strongest
    first.

    Learned spatial bases of SPEC §5 step 2: ``Ψ1, Ψ2`` from the panchromatic
    image ``Z`` are ``svd_basis(Z)`` and ``svd_basis(Z.T)``.  Computed from the
    small Gram ``M Mᵀ`` (``eigh``), which is complete even where ``k < m``.
    """
    m = np.asarray(B.to_numpy(matrix), dtype=np.float64)
    if m.ndim != 2:
        raise ValueError(f"svd_basis needs a 2-D matrix, got shape {m.shape}")
    return _gram_basis(m @ m.T, "svd_basis: the matrix contains NaN or inf")


def _gram_basis(gram, nonfinite: str) -> np.ndarray:
    """Eigenvectors of a Gram matrix, strongest first, polished to orthonormal."""
    if not np.isfinite(gram).all():
        raise ValueError(nonfinite)
    vals, vecs = np.linalg.eigh(gram)
    return _polish(vecs[:, ::-1])


#: Elements per block when :func:`unfolding_gram` streams a tensor (1/16 of a 256²×28 cube).
_GRAM_BLOCK = 1 << 17


def unfolding_gram(x: np.ndarray, mode: int) -> np.ndarray:
    """``X₍ₘ₎ X₍ₘ₎ᵀ`` of the mode-``mode`` unfolding in float64, streamed in blocks: no copy of
    the tensor (an unfolding of a non-leading mode and a float64 cast would cost three).  A
    PyTorch tensor on a GPU is summed there (:func:`tensor_cosdi._backend.unfolding_gram`)."""
    if not isinstance(x, np.ndarray):
        if B.on_accelerator(x) and hasattr(x, "detach"):
            return B.unfolding_gram(x, mode)
        x = np.asarray(B.to_numpy(x))
    n = x.shape[mode]
    pre, post = int(np.prod(x.shape[:mode])), int(np.prod(x.shape[mode + 1 :]))
    v = np.ascontiguousarray(x).reshape(pre, n, post)
    gram = np.zeros((n, n))
    cols = min(post, max(1, _GRAM_BLOCK // n))
    rows = max(1, _GRAM_BLOCK // (n * cols))
    for p0 in range(0, pre, rows):
        for c0 in range(0, post, cols):
            blk = v[p0 : p0 + rows, :, c0 : c0 + cols].astype(np.float64)  # a small copy
            blk = blk.transpose(1, 0, 2).reshape(n, -1)
            gram += blk @ blk.T
    return gram


def tucker_bases(tensor, modes=None) -> dict[int, np.ndarray]:
    """Complete HOSVD bases: ``{mode: svd_basis(unfolding(tensor, mode))}`` (thesis Eq. 97).

    Examples
    --------
    >>> import numpy as np
    >>> bases = tucker_bases(np.random.default_rng(0).random((6, 5, 4)), modes=[2])
    >>> bases[2].shape, is_orthonormal(bases[2])
    ((4, 4), True)
    """
    shape = np.shape(tensor)  # the tensor stays where it is (a GPU, say): see unfolding_gram
    modes = range(len(shape)) if modes is None else modes
    out = {}
    for m in modes:
        if not -len(shape) <= m < len(shape):
            raise ValueError(f"mode {m} is not an axis of a tensor of shape {shape}")
        m %= len(shape)
        gram = unfolding_gram(tensor, m)
        out[m] = _gram_basis(gram, "tucker_bases: the tensor contains NaN or inf")
    return out


# ---- fast per-mode transforms ----------------------------------------------------------
def _memory_view(x):
    """``(view, flipped)``: ``x`` itself if C-contiguous, ``x.T`` if only F-contiguous.

    Transforms work on the C-contiguous view and return C-contiguous arrays,
    so a Fortran-ordered cube (the layout the CASSI adjoint returns) stays
    Fortran-ordered through analysis and synthesis.
    """
    if not x.flags.c_contiguous and x.flags.f_contiguous:
        return x.T, True
    return np.ascontiguousarray(x), False


class ModeTransform:
    """An orthonormal ``n × n`` transform along one axis: ``analysis`` applies ``Ψᵀ``, ``synthesis``
    ``Ψ``.

    Subclasses implement ``_analysis(x, axis)`` / ``_synthesis(x, axis)`` on
    C-contiguous NumPy arrays (returning C-contiguous arrays of the same
    shape and dtype); :attr:`matrix` is the dense ``Ψ`` (the test oracle, and
    what other backends use through ``tensorly.tenalg.mode_dot``).
    """

    kind = "dense"

    def __init__(self, n: int):
        self.n = _size(n)

    @property
    def matrix(self) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _analysis(self, x, axis):  # pragma: no cover - abstract
        raise NotImplementedError

    def _synthesis(self, x, axis):  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}(n={self.n})"


def _dense_along(x: np.ndarray, m: np.ndarray, axis: int, out=None) -> np.ndarray:
    """``y = x ×_axis m`` (``y[…, i, …] = Σ_j m[i, j] x[…, j, …]``) as one (batched) GEMM, C order
    kept; into ``out`` (a C-contiguous array of ``x``'s shape and dtype, not ``x``) if given."""
    n = x.shape[axis]
    pre, post = int(np.prod(x.shape[:axis])), int(np.prod(x.shape[axis + 1 :]))
    if post == 1:
        y = np.matmul(x.reshape(pre, n), m.T, out=None if out is None else out.reshape(pre, n))
    elif pre == 1:
        y = np.matmul(m, x.reshape(n, post), out=None if out is None else out.reshape(n, post))
    else:
        shape = (pre, n, post)
        y = np.matmul(m, x.reshape(shape), out=None if out is None else out.reshape(shape))
    return y.reshape(x.shape)


class Dense(ModeTransform):
    """A given orthonormal matrix (learned bases: SVD / HOSVD), applied as one GEMM."""

    def __init__(self, matrix):
        m = np.asarray(B.to_numpy(matrix), dtype=np.float64)
        if m.ndim != 2 or m.shape[0] != m.shape[1]:
            raise ValueError(f"a basis matrix must be square, got shape {m.shape}")
        super().__init__(m.shape[0])
        self._m = m
        self._typed_cache: dict = {}

    @property
    def matrix(self):
        return self._m

    def _typed(self, transpose: bool, dtype):
        """``Ψ`` or ``Ψᵀ`` as a contiguous array of ``dtype`` (converted once)."""
        key = (transpose, np.dtype(dtype).str)
        hit = self._typed_cache.get(key)
        if hit is None:
            hit = self._typed_cache[key] = np.ascontiguousarray(
                self._m.T if transpose else self._m, dtype=dtype
            )
        return hit

    def _analysis(self, x, axis, out=None):
        return _dense_along(x, self._typed(True, x.dtype), axis, out)

    def _synthesis(self, x, axis, out=None):
        return _dense_along(x, self._typed(False, x.dtype), axis, out)


class DCT(ModeTransform):
    """Orthonormal DCT-II along an axis by ``scipy.fft`` (``O(n log n)``; :func:`dct` is its
    matrix)."""

    kind = "dct"

    @cached_property
    def matrix(self):
        return dct(self.n)

    def _analysis(self, x, axis):
        return scipy.fft.dct(x, type=2, axis=axis, norm="ortho")

    def _synthesis(self, x, axis):
        return scipy.fft.idct(x, type=2, axis=axis, norm="ortho")


class Wavelet(Dense):
    """Periodised orthogonal DWT along an axis (PyWavelets builds it; :func:`wavelet` is its
    matrix).

    Applied as one GEMM with the dense matrix, not by ``pywt.wavedec`` along
    the axis: measured on a 28-band float32 cube (2 cores, OpenBLAS), the
    Symlet-8 analysis along one spatial axis took 11 / 52 / 158 / 580 ms by
    PyWavelets against 1.5 / 8.6 / 44 / 377 ms by GEMM for n = 128 / 256 /
    512 / 1024 — the matrix is faster at every size this library runs.
    """

    kind = "wavelet"

    def __init__(self, n: int, name: str = "sym8", *, level="auto"):
        super().__init__(wavelet(n, name, level=level))  # validates n, name and level
        self.name = name
        self.level = wavelet_level(n, name, level)

    def __repr__(self):
        return f"Wavelet(n={self.n}, {self.name!r}, level={self.level})"


def as_transform(n: int, spec) -> ModeTransform:
    """A :class:`ModeTransform` from a transform, a matrix, or a name ``"dct"``, ``"identity"``, a
    wavelet."""
    if isinstance(spec, ModeTransform):
        if spec.n != n:
            raise ValueError(f"transform of size {spec.n} given for a mode of size {n}")
        return spec
    if isinstance(spec, str):
        if spec == "dct":
            return DCT(n)
        if spec == "identity":
            return Dense(np.eye(n))
        return Wavelet(n, spec)
    return Dense(spec)


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
                m = np.asarray(B.to_numpy(m), dtype=np.float64)
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


from ._block_basis import BlockDense, block_hosvd, block_sizes  # noqa: E402, F401  (on Dense)
