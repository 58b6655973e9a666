"""Image-quality metrics as the thesis computes them (SPEC §9).

PSNR and SSIM per band, averaged over bands; RMSE over all voxels; SAM per
spectrum in degrees, averaged; the combined percentage error of Eq. 49 for
design studies.  Argument names follow scikit-image (``image_true``,
``image_test``, keyword-only options).
"""

from __future__ import annotations

import warnings

import numpy as np
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

from . import _backend as B
from .validate import integer, number, real_array

__all__ = ["psnr", "ssim", "rmse", "sam", "combined_error"]


def _channel_axis(channel_axis, band_axis, ndim: int) -> int:
    """The bands' axis from ``channel_axis`` (scikit-image's name) or the older ``band_axis``
    (deprecated), checked against the images' ``ndim``."""
    if band_axis is not None:
        warnings.warn(
            "band_axis is deprecated; use channel_axis (scikit-image's name)",
            DeprecationWarning,
            stacklevel=3,
        )
        channel_axis = band_axis
    axis = integer("channel_axis", channel_axis)
    if ndim >= 3 and not -ndim <= axis < ndim:
        raise ValueError(f"channel_axis {axis} is out of range for images of {ndim} axes")
    return axis


def psnr(
    image_true, image_test, *, data_range=None, channel_axis: int = 2, band_axis=None
) -> float:
    """PSNR in dB computed per band and averaged over bands.

    Parameters
    ----------
    image_true, image_test : tensors of equal shape ``(Nx, Ny, Nλ, …)``
    data_range : float, optional
        Peak-to-peak range of the true image (default: its max − min).
    channel_axis : int
        Axis of the bands (default 2, SPEC §1; scikit-image's name).
    band_axis : int, optional
        Deprecated name of ``channel_axis``.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.zeros((4, 4, 2)); b = a + 0.1
    >>> round(psnr(a, b, data_range=1.0), 6)
    20.0
    """
    t, e, data_range = _pair(image_true, image_test, data_range)
    axis = _channel_axis(channel_axis, band_axis, t.ndim)
    t = np.moveaxis(t, axis, 0) if t.ndim >= 3 else t[None]
    e = np.moveaxis(e, axis, 0) if e.ndim >= 3 else e[None]
    vals = []
    for tb, eb in zip(t, e):
        if np.array_equal(tb, eb):
            vals.append(np.inf)
        else:
            vals.append(peak_signal_noise_ratio(tb, eb, data_range=data_range))
    return float(np.mean(vals))


def _pair(image_true, image_test, data_range=None):
    t = real_array("image_true", B.to_numpy(image_true), finite=False)
    e = real_array("image_test", B.to_numpy(image_test), finite=False)
    if t.shape != e.shape:
        raise ValueError(f"image_true has shape {t.shape} but image_test has shape {e.shape}")
    if not (np.isfinite(t).all() and np.isfinite(e).all()):
        raise ValueError("image_true and image_test must be finite (NaN or inf found)")
    if data_range is None:
        data_range = float(t.max() - t.min())
        if not data_range > 0:
            raise ValueError(
                "data_range must be positive, got 0.0 (the true image is constant); pass it"
            )
        return t, e, data_range
    # a peak beyond 1e150 would overflow its own square inside scikit-image
    return t, e, number("data_range", data_range, low=0, low_open=True, high=1e150)


def _bands_last_as_images(x: np.ndarray, axis: int) -> np.ndarray:
    """``(…, Nλ)`` cube → stack of 2-D band images ``(n, Nx, Ny)`` (extra axes become more
    images)."""
    if x.ndim == 2:
        return x[None]
    x = np.moveaxis(x, axis, -1)
    x = np.moveaxis(x, (0, 1), (-2, -1))  # (…, Nλ, Nx, Ny)
    return x.reshape((-1,) + x.shape[-2:])


def ssim(
    image_true,
    image_test,
    *,
    data_range=None,
    channel_axis: int = 2,
    win_size: int = 7,
    band_axis=None,
) -> float:
    """Structural similarity per band (scikit-image, Gaussian-free 7×7 window), averaged.

    Images smaller than the window use the largest odd window that fits.
    ``channel_axis``: the bands' axis (``band_axis``: its deprecated name).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.random.default_rng(0).random((16, 16, 3))
    >>> ssim(a, a)
    1.0
    """
    t, e, data_range = _pair(image_true, image_test, data_range)
    axis = _channel_axis(channel_axis, band_axis, t.ndim)
    tb, eb = _bands_last_as_images(t, axis), _bands_last_as_images(e, axis)
    w = min(integer("win_size", win_size, low=3), *tb.shape[1:])
    w -= 1 - w % 2
    if w < 3:
        raise ValueError(f"SSIM needs images of at least 3 × 3 pixels, got {tb.shape[1:]}")
    vals = [structural_similarity(a, b, data_range=data_range, win_size=w) for a, b in zip(tb, eb)]
    return float(np.mean(vals))


def rmse(image_true, image_test) -> float:
    """Root-mean-square error over all voxels.

    Examples
    --------
    >>> import numpy as np
    >>> rmse(np.zeros((2, 2, 2)), np.full((2, 2, 2), 0.5))
    0.5
    """
    t, e, _ = _pair(image_true, image_test, 1.0)
    return float(np.sqrt(np.mean((t - e) ** 2)))


def sam(image_true, image_test, *, channel_axis: int = 2, band_axis=None) -> float:
    """Spectral angle mapper in degrees: the angle between true and estimated spectra, averaged.

    ``θ = arccos(⟨f, f̂⟩ / (‖f‖ ‖f̂‖))`` per pixel (every index except
    ``channel_axis``; ``band_axis``: its deprecated name).  Pixels whose true
    spectrum is zero have no angle and
    are skipped; an estimated spectrum of zero where the truth is not counts
    as 90° (orthogonal: nothing of the spectrum was recovered).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.ones((2, 2, 2)); g = f.copy(); g[..., 1] = 0
    >>> round(sam(f, g), 6)
    45.0
    """
    t, e, _ = _pair(image_true, image_test, 1.0)
    axis = _channel_axis(channel_axis, band_axis, t.ndim)
    t = np.moveaxis(t, axis, -1).reshape(-1, t.shape[axis])
    e = np.moveaxis(e, axis, -1).reshape(-1, e.shape[axis])
    nt, ne = np.linalg.norm(t, axis=1), np.linalg.norm(e, axis=1)
    valid = nt > 0
    if not valid.any():
        raise ValueError("SAM is undefined: every true spectrum is zero")
    cos = np.zeros(t.shape[0])
    ok = valid & (ne > 0)
    cos[ok] = np.sum(t[ok] * e[ok], axis=1) / (nt[ok] * ne[ok])
    angles = np.degrees(np.arccos(np.clip(cos[valid], -1.0, 1.0)))
    return float(np.mean(angles))


def combined_error(psnr_values, ssim_values, rmse_values, sam_values) -> np.ndarray:
    """The combined percentage error of Equation 49 that picks a design (the VSI splitting ratio).

    Each argument is an ``(L1, L2)`` array: ``L1`` scenes × ``L2`` design
    settings.  Per scene, each metric becomes its relative distance to the
    best setting — ``|max − v| / max`` for PSNR and SSIM, ``|min − v| / min``
    for RMSE and SAM — and ``p[ι2] = 100 / (4 L1) Σ_q Σ_ι1 Φq[ι1, ι2]``.

    Returns
    -------
    ndarray of shape (L2,)
        Percentage error per setting; the best design has the smallest.

    Examples
    --------
    >>> import numpy as np
    >>> combined_error([[30, 20]], [[0.9, 0.45]], [[0.1, 0.2]], [[5, 10]]).round(2).tolist()
    [0.0, 70.83]
    """
    named = {"psnr_values": psnr_values, "ssim_values": ssim_values, "rmse_values": rmse_values,
             "sam_values": sam_values}  # fmt: skip
    arrays = [real_array(k, v, finite=False) for k, v in named.items()]
    shape = arrays[0].shape
    if len(shape) != 2 or any(a.shape != shape for a in arrays):
        raise ValueError(
            "combined_error needs four (scenes, settings) arrays of one shape, got "
            + ", ".join(str(a.shape) for a in arrays)
        )
    if not all(np.isfinite(a).all() for a in arrays):
        raise ValueError("combined_error: metric values must be finite")
    terms = []
    for a, best in zip(arrays, (np.max, np.max, np.min, np.min)):
        ref = best(a, axis=1, keepdims=True)
        if (ref == 0).any():
            raise ValueError(
                "combined_error: a scene's best value is 0, so its relative error is undefined"
            )
        terms.append(np.abs(ref - a) / np.abs(ref))
    return 100.0 * np.sum(terms, axis=(0, 1)) / (4 * shape[0])
