"""Depth from the views of a (spectral) light field (SPEC §7).

Disparity convention (the public API contract, and :func:`tensor_cosdi.scenes.light_field`):
for views ``I[u, v]`` around the centre view ``(uc, vc) = (U // 2, V // 2)``,

``I[u, v](y − (u − uc)·d, x − (v − vc)·d) = I[uc, vc](y, x)``

with ``d`` in pixels per view step, ``y`` along the first spatial axis and
``x`` along the second.
"""

from __future__ import annotations

import numbers

import numpy as np
from scipy import ndimage

__all__ = ["disparity_from_views", "disparity_cost_volume", "depth_from_disparity", "textured_mask"]


def _views(views):
    L = np.asarray(views, dtype=np.float64)
    if L.ndim == 4:
        L = L[..., None]
    if L.ndim != 5:
        raise ValueError(
            f"views must have shape (U, V, H, W) or (U, V, H, W, C), got {np.shape(views)}"
        )
    if min(L.shape[:2]) < 1 or L.shape[0] * L.shape[1] < 2:
        raise ValueError(f"need at least two views, got a {L.shape[0]}×{L.shape[1]} grid")
    if not np.all(np.isfinite(L)):
        raise ValueError("views contain NaN or inf")
    return L


def disparity_cost_volume(
    views, disparities, *, window: int = 5, order: int = 3, shiftable: bool = True
):
    """Matching cost of every candidate disparity: ``(D, H, W)``.

    For each candidate ``d`` every view is warped onto the centre view
    (spline interpolation of ``order``), the squared differences to the
    centre view are summed over views and channels and averaged over a
    ``window × window`` box; with ``shiftable`` the box may sit anywhere
    over the pixel (the minimum of the box costs around it), so a pixel next
    to a depth edge is matched with the side it belongs to.
    """
    L = _views(views)
    U, V, H, W, C = L.shape
    uc, vc = U // 2, V // 2
    d = np.asarray(disparities, dtype=np.float64).reshape(-1)
    if d.size < 3 or not np.all(np.isfinite(d)) or np.any(np.diff(d) <= 0):
        raise ValueError("disparities must be ≥ 3 finite, strictly increasing candidates")
    if isinstance(window, bool) or not isinstance(window, numbers.Integral) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")
    centre = L[uc, vc]
    yy, xx = np.meshgrid(
        np.arange(H, dtype=np.float64), np.arange(W, dtype=np.float64), indexing="ij"
    )
    cost = np.zeros((d.size, H, W))
    for u in range(U):
        for v in range(V):
            if u == uc and v == vc:
                continue
            img = L[u, v]
            coeffs = [
                ndimage.spline_filter(img[..., c], order=order) if order > 1 else img[..., c]
                for c in range(C)
            ]
            for i, di in enumerate(d):
                coords = [yy - (u - uc) * di, xx - (v - vc) * di]
                # I[u, v](y − (u − uc)d, x − (v − vc)d) should equal the centre view at (y, x)
                for c in range(C):
                    w = ndimage.map_coordinates(
                        coeffs[c], coords, order=order, mode="nearest", prefilter=False
                    )
                    cost[i] += (w - centre[..., c]) ** 2
    if window > 1:
        cost = ndimage.uniform_filter(cost, size=(1, window, window), mode="nearest")
        if shiftable:
            cost = ndimage.minimum_filter(cost, size=(1, window, window), mode="nearest")
    return cost


def disparity_from_views(
    views,
    *,
    max_disparity: float = 2.0,
    step: float = 0.1,
    window: int = 5,
    order: int = 3,
    shiftable: bool = True,
):
    """Disparity (pixels per view step) of the centre view from a light field's views.

    A shift-and-compare cost volume (:func:`disparity_cost_volume`) over
    candidates ``−max_disparity … max_disparity`` every ``step``, the best
    candidate per pixel, refined to sub-pixel precision by a parabola
    through the costs of its neighbours.

    Parameters
    ----------
    views : array_like (U, V, H, W) or (U, V, H, W, C)
        ``C`` channels (e.g. spectral bands) are all used.  Get the views of
        a reconstructed C3SLFI cube with ``system.to_5d(cube)`` moved to
        ``(U, V, H, W, Nλ)``, of a Mu-CoSDI ``"lf"`` cube with ``to_views``.
    max_disparity : float
        Largest ``|d|`` searched.
    step : float
        Candidate spacing.
    window : int
        Side of the box the cost is averaged over.
    order : int
        Spline order of the warps (3: cubic).
    shiftable : bool
        Shiftable windows (see :func:`disparity_cost_volume`).

    Returns
    -------
    ndarray (H, W), in ``[−max_disparity, max_disparity]``.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi import scenes
    >>> img = scenes.photo("astronaut", (32, 32), [550.0])
    >>> lf = scenes.light_field(img, np.full((32, 32), 0.5), views=(3, 3))   # (H, W, C, U, V)
    >>> d = disparity_from_views(np.moveaxis(lf, (3, 4), (0, 1)), max_disparity=1.0)
    >>> bool(abs(np.median(d[8:-8, 8:-8]) - 0.5) < 0.02)
    True
    """
    if not (np.isfinite(max_disparity) and max_disparity > 0):
        raise ValueError(f"max_disparity must be > 0, got {max_disparity!r}")
    if not (np.isfinite(step) and 0 < step <= max_disparity):
        raise ValueError(f"step must be in (0, max_disparity], got {step!r}")
    n = int(np.floor(max_disparity / step + 1e-9))
    cand = step * np.arange(-n, n + 1)
    cost = disparity_cost_volume(views, cand, window=window, order=order, shiftable=shiftable)
    k = np.argmin(cost, axis=0)
    kk = np.clip(k, 1, cand.size - 2)
    H, W = k.shape
    i, j = np.indices((H, W))
    c0, c1, c2 = cost[kk - 1, i, j], cost[kk, i, j], cost[kk + 1, i, j]
    den = c0 - 2 * c1 + c2
    with np.errstate(divide="ignore", invalid="ignore"):
        off = np.where(den > 0, 0.5 * (c0 - c2) / den, 0.0)
    off = np.where(k == kk, np.clip(off, -0.5, 0.5), 0.0)
    return cand[k] + off * step


def textured_mask(image, *, threshold: float = 0.05, sigma: float = 1.0):
    """Pixels with enough texture for a disparity/focus estimate: gradient magnitude ≥
    ``threshold``·max.

    ``image`` (H, W) or (H, W, C) (channels averaged); Gaussian-smoothed
    gradient of scale ``sigma``.
    """
    x = np.asarray(image, dtype=np.float64)
    if x.ndim == 3:
        x = x.mean(axis=-1)
    if x.ndim != 2:
        raise ValueError(f"image must be (H, W) or (H, W, C), got {np.shape(image)}")
    g = ndimage.gaussian_gradient_magnitude(x, sigma)
    return g >= threshold * max(g.max(), np.finfo(float).tiny)


def depth_from_disparity(disparity, *, baseline_mm: float, focal_px: float, offset: float = 0.0):
    """Depth ``z = f·b / (d − d0)`` (mm) from disparity ``d`` (px per view step).

    ``baseline_mm`` is the distance between neighbouring viewpoints,
    ``focal_px`` the focal length in pixels, ``offset = d0`` the disparity of
    the plane at infinity (for a lenslet camera focused at a finite
    distance, the disparity of the focal plane is 0 and ``d0`` is negative;
    calibrate it with a far target).  Pixels with ``d ≤ d0`` get ``inf``.
    """
    for name, v in (("baseline_mm", baseline_mm), ("focal_px", focal_px)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be > 0, got {v!r}")
    d = np.asarray(disparity, dtype=np.float64) - offset
    with np.errstate(divide="ignore"):
        return np.where(d > 0, focal_px * baseline_mm / np.where(d > 0, d, 1.0), np.inf)
