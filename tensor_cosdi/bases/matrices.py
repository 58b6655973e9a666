"""Orthonormal matrices of one axis: identity, DCT-II and periodised wavelets (the dense
oracles of :mod:`tensor_cosdi.bases.transforms`)."""

from __future__ import annotations

import numbers
import warnings

import numpy as np
import scipy.fft

from .. import _backend as B
from ..validate import number, real_array

__all__ = ["is_orthonormal", "identity", "dct", "wavelet", "wavelet_level", "AUTO_COARSEST"]


#: Largest side of a dense basis matrix (16384² float64 is 2 GiB).
MAX_BASIS_SIZE = 16384


def _size(n) -> int:
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or not 1 <= n <= MAX_BASIS_SIZE:
        raise ValueError(
            f"basis size n must be a positive integer ≤ {MAX_BASIS_SIZE} (a dense n × n matrix), "
            f"got {n!r}"
        )
    return int(n)


def _orthogonal_wavelet(name: str):
    """The PyWavelets wavelet ``name``, or a ``ValueError`` unless it is an orthogonal one."""
    import pywt

    if not isinstance(name, str):
        raise ValueError(
            f"the wavelet must be a PyWavelets name such as 'sym8', got {type(name).__name__} "
            f"{name!r}"
        )
    try:
        w = pywt.Wavelet(name)
    except ValueError:
        raise ValueError(f"unknown wavelet {name!r}; see pywt.wavelist(kind='discrete')") from None
    if not w.orthogonal:
        raise ValueError(f"wavelet {name!r} is not orthogonal; its matrix would not be orthonormal")
    return w


def is_orthonormal(psi, *, atol: float = 1e-10) -> bool:
    """True when ``psi`` is square with ``ΨᵀΨ = I`` within ``atol`` (a NaN entry: False)."""
    m = real_array("psi", B.to_numpy(psi), finite=False)
    atol = number("atol", atol, low=0)
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
    n = _size(n)
    w = _orthogonal_wavelet(name)
    if isinstance(level, str):
        if level == "auto":  # as deep as periodisation allows, down to AUTO_COARSEST coefficients
            depth = 0
            while n % 2 ** (depth + 1) == 0 and n // 2 ** (depth + 1) >= AUTO_COARSEST:
                depth += 1
            return depth
        if level == "boundary":  # no atom wider than the signal (PyWavelets' maximum)
            import pywt

            depth = pywt.dwt_max_level(n, w.dec_len)
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
    w = _orthogonal_wavelet(name)
    level = wavelet_level(n, name, level)
    if level == 0:
        return np.eye(n)
    with warnings.catch_warnings():
        # deep levels on short signals: boundary wrap-around is intended
        warnings.simplefilter("ignore")
        cols = [
            np.concatenate(pywt.wavedec(e, w, mode="periodization", level=level)) for e in np.eye(n)
        ]
    analysis = np.stack(cols, axis=1)  # coefficients = analysis @ x
    return _polish(analysis.T)
