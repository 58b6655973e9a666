"""Depth from a focal stack (SPEC §7, the CASSDI-DFA focal-stack estimate)."""

from __future__ import annotations

import numbers

import numpy as np
from scipy import ndimage

from ..validate import axis_index, number, real_array

__all__ = ["focus_measure", "depth_from_focus"]


def focus_measure(image, *, window: int = 5, sigma: float = 0.0):
    """Local energy of the Laplacian (sharpness) of one image, ``(H, W)``.

    ``(∇²I)²`` averaged over a ``window × window`` box; ``sigma > 0``
    smooths the image first (noise robustness).  Channels of an
    ``(H, W, C)`` image are summed.
    """
    x = real_array("image", image, finite=False)
    if x.ndim == 2:
        x = x[..., None]
    if x.ndim != 3:
        raise ValueError(f"image must be (H, W) or (H, W, C), got {np.shape(image)}")
    if isinstance(window, bool) or not isinstance(window, numbers.Integral) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")
    number("sigma", sigma, low=0, high=max(x.shape[:2]))  # wider than the image: nothing left
    if not np.isfinite(x).all():
        raise ValueError("image must hold finite values")
    out = np.zeros(x.shape[:2])
    for c in range(x.shape[2]):
        img = ndimage.gaussian_filter(x[..., c], sigma) if sigma > 0 else x[..., c]
        out += ndimage.laplace(img, mode="nearest") ** 2
    return ndimage.uniform_filter(out, size=window, mode="nearest")


def depth_from_focus(
    stack, *, axis: int = -1, window: int = 5, sigma: float = 0.0, return_confidence: bool = False
):
    """Fractional index of the sharpest plane per pixel of a focal stack.

    The focus measure (:func:`focus_measure`) of every plane, its maximum
    over the planes, then a parabola through the maximum and its two
    neighbours for a sub-plane position (clipped to ±0.5 plane).

    Parameters
    ----------
    stack : array_like (…, Nz) with spatial axes (H, W[, C])
        Images focused at ``Nz`` planes along ``axis``; e.g. the focal stack
        ``ff (Nx, Ny, Nz)`` of a CASSDI-DFA reconstruction.
    axis : int
        The plane axis.
    window, sigma
        See :func:`focus_measure`.
    return_confidence : bool
        Also return the ratio of the best focus measure to the mean one
        (≈ 1 on textureless pixels, where the estimate is meaningless).

    Returns
    -------
    ndarray (H, W) of plane indices in ``[0, Nz − 1]`` (and the confidence).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy import ndimage
    >>> rng = np.random.default_rng(0)
    >>> sharp = rng.random((32, 32))
    >>> stack = np.stack([ndimage.gaussian_filter(sharp, s) for s in (2.0, 0.0, 2.0)], -1)
    >>> bool(np.mean(np.round(depth_from_focus(stack)) == 1) > 0.95)
    True
    """
    x = real_array("stack", stack, finite=False)
    x = np.moveaxis(x, axis_index("axis", axis, max(x.ndim, 1)), -1) if x.ndim else x
    if x.ndim not in (3, 4):
        raise ValueError(
            f"stack must be (H, W, Nz) or (H, W, C, Nz) along axis={axis}, got {np.shape(stack)}"
        )
    nz = x.shape[-1]
    if nz < 2:
        raise ValueError(f"a focal stack needs ≥ 2 planes, got {nz}")
    if not np.all(np.isfinite(x)):
        raise ValueError("stack contains NaN or inf")
    fm = np.stack([focus_measure(x[..., k], window=window, sigma=sigma) for k in range(nz)], axis=0)
    k = np.argmax(fm, axis=0)
    est = k.astype(np.float64)
    if nz >= 3:
        kk = np.clip(k, 1, nz - 2)
        i, j = np.indices(k.shape)
        c0, c1, c2 = fm[kk - 1, i, j], fm[kk, i, j], fm[kk + 1, i, j]
        den = c0 - 2 * c1 + c2
        with np.errstate(divide="ignore", invalid="ignore"):
            off = np.where(den < 0, 0.5 * (c0 - c2) / den, 0.0)
        est = est + np.where(k == kk, np.clip(off, -0.5, 0.5), 0.0)
    if return_confidence:
        eps = 1e-9 * max(
            float(fm.max()), np.finfo(float).tiny
        )  # textureless pixels: ratio → 1, not 0/0
        conf = (fm.max(axis=0) + eps) / (fm.mean(axis=0) + eps)
        return est, conf
    return est
