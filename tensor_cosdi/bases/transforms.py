"""Per-mode transforms applied by n-mode products: dense GEMMs (:class:`Dense`, also
block-diagonal: :class:`BlockDense`), fast DCT (:class:`DCT`) and wavelets (:class:`Wavelet`)."""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.fft

from .. import _backend as B
from ..validate import real_array
from .matrices import _size, dct, wavelet, wavelet_level

__all__ = ["ModeTransform", "Dense", "BlockDense", "DCT", "Wavelet", "as_transform"]


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
        m = np.asarray(B.to_numpy(matrix))
        if m.dtype.kind not in "iuf":
            raise ValueError(f"a basis matrix must hold real numbers, got dtype {m.dtype}")
        m = m.astype(np.float64)
        if m.ndim != 2 or m.shape[0] != m.shape[1]:
            raise ValueError(f"a basis matrix must be square, got shape {m.shape}")
        if not np.isfinite(m).all():
            raise ValueError("a basis matrix must hold finite values (it holds NaN or inf)")
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
    out = Dense(spec)
    if out.n != n:
        raise ValueError(f"matrix of size {out.n} given for a mode of size {n}")
    return out


class BlockDense(Dense):
    """A block-diagonal orthonormal transform: block ``k`` acts on its own run of indices.

    ``matrix`` is the dense block-diagonal ``Ψ`` (the oracle and the other
    backends' path); NumPy arrays go one GEMM per block.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.bases import BlockDense, dct
    >>> t = BlockDense([dct(3), dct(2)])
    >>> t.sizes, t.matrix.shape
    ([3, 2], (5, 5))
    """

    kind = "block_dense"

    def __init__(self, blocks):
        from scipy.linalg import block_diag

        mats = [real_array("a block", B.to_numpy(b), finite=False) for b in blocks]
        if not mats or any(m.ndim != 2 or m.shape[0] != m.shape[1] for m in mats):
            raise ValueError(
                f"BlockDense needs square blocks, got shapes {[m.shape for m in mats]}"
            )
        super().__init__(block_diag(*mats))
        self.blocks = [Dense(m) for m in mats]
        self.sizes = [m.shape[0] for m in mats]
        self._edges = np.cumsum([0] + self.sizes)

    def _along(self, x, axis, out, transpose):
        n = x.shape[axis]
        pre, post = int(np.prod(x.shape[:axis])), int(np.prod(x.shape[axis + 1 :]))
        v = x.reshape(pre, n, post)
        o = np.empty_like(v) if out is None else out.reshape(pre, n, post)
        for blk, a, b in zip(self.blocks, self._edges[:-1], self._edges[1:]):
            m = blk._typed(transpose, x.dtype)
            if post == 1:
                np.matmul(v[:, a:b, 0], m.T, out=o[:, a:b, 0])
            else:
                np.matmul(m, v[:, a:b, :], out=o[:, a:b, :])
        return o.reshape(x.shape)

    def _analysis(self, x, axis, out=None):
        return self._along(x, axis, out, True)

    def _synthesis(self, x, axis, out=None):
        return self._along(x, axis, out, False)

    def __repr__(self):
        return f"BlockDense(sizes={self.sizes})"
