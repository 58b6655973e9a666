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

from ..validate import number, real_array

__all__ = [
    "disparity_from_views",
    "disparity_cost_volume",
    "occlusion_cost_volume",
    "guided_filter",
    "depth_from_disparity",
    "textured_mask",
    "DISPARITY_METHODS",
]

#: :func:`occlusion_cost_volume`: a half-plane of views replaces all views where its mean
#: difference is below this share of theirs.  Chosen on the tuning set of
#: ``benchmarks/lf_depth.py`` (photographs only, seeds 0-3, 96×96, 5×5 views; MAE / bad-0.07):
#: 0.054 px / 5.4 % at 0.25 (radius 2); 0.15: 0.059 / 5.3 %; 0.4 (radius 4): 0.084 / 7.6 %;
#: 1.0 (half-planes only where strictly better): 0.092 / 11.0 %.
HALF_RATIO = 0.25
#: :func:`disparity_from_views`' ``radius`` (the guided filter's box is ``2·radius + 1``
#: wide).  The whole tuning set (photographs and CAVE tuning scenes, seeds 0-5, 96×96): radius
#: 1 / 2 / 3 give MAE 0.107 / 0.116 / 0.128 px, bad-0.07 12.1 / 12.1 / 12.8 %.  Adding a
#: coarse (radius 6 or 10) aggregate to the costs, or filling low-confidence pixels from
#: confident ones by normalised guided filtering, raised both (0.112-0.25 px).
GUIDED_RADIUS = 1
#: ``method`` of :func:`disparity_from_views`.
DISPARITY_METHODS = ("occlusion", "ssd")


def _views(views):
    L = real_array("views", views, finite=False)
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


#: Most candidate disparities :func:`disparity_from_views` tries (each warps every view).
MAX_CANDIDATES = 2001


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
    d = _check_candidates(disparities)
    order = _check_order(order)
    if isinstance(window, bool) or not isinstance(window, numbers.Integral) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")
    centre = L[U // 2, V // 2]
    cost = np.zeros((d.size, H, W))
    for (u, v), (oy, ox) in _offsets(U, V):
        coeffs = _spline(L[u, v], order)
        for i, di in enumerate(d):
            # I[u, v](y − (u − uc)d, x − (v − vc)d) should equal the centre view at (y, x)
            cost[i] += ((_shift(coeffs, (oy * di, ox * di), order) - centre) ** 2).sum(axis=-1)
    if window > 1:
        cost = ndimage.uniform_filter(cost, size=(1, window, window), mode="nearest")
        if shiftable:
            cost = ndimage.minimum_filter(cost, size=(1, window, window), mode="nearest")
    return cost


def _check_candidates(disparities):
    d = real_array("disparities", disparities, finite=False).reshape(-1)
    if d.size < 3 or not np.all(np.isfinite(d)) or np.any(np.diff(d) <= 0):
        raise ValueError("disparities must be ≥ 3 finite, strictly increasing candidates")
    return d


def _offsets(U, V):
    """The non-centre views ``(u, v)`` and their offsets ``(u − uc, v − vc)``."""
    uc, vc = U // 2, V // 2
    return [((u, v), (u - uc, v - vc)) for u in range(U) for v in range(V) if (u, v) != (uc, vc)]


def _view_groups(offsets):
    """Boolean masks over ``offsets``: every view, then the four half-planes of the grid (the
    views above, below, left and right of the centre, the centre's row or column included)."""
    oy = np.array([o[0] for _, o in offsets])
    ox = np.array([o[1] for _, o in offsets])
    groups = [np.ones(oy.size, bool), oy <= 0, oy >= 0, ox <= 0, ox >= 0]
    return [g for g in groups if g.sum() >= 1]


def occlusion_cost_volume(views, disparities, *, order: int = 3, half_ratio: float = HALF_RATIO):
    """Occlusion-aware matching cost of every candidate disparity: ``(costs, group)``.

    For each candidate ``d`` every view is shifted onto the centre view
    (spline of ``order``) and its absolute difference to the centre view,
    summed over channels, is taken per pixel.  The cost of a pixel is the
    least, over five sets of views — all of them and the four half-planes of
    the view grid (above, below, left, right of the centre) — of the set's
    mean difference: a pixel beside a nearer object is hidden in the views on
    that object's side, and one half-plane of views still sees it (the
    idea of Wang, Efros and Ramamoorthi's occlusion-aware light-field depth,
    ICCV 2015).  A half-plane is taken only where its mean is below
    ``half_ratio`` times the mean of all views: elsewhere the half-planes'
    smaller samples would only add noise.

    Returns
    -------
    costs : ndarray (D, H, W)
    group : ndarray (D, H, W) of int
        The set that gave each cost (0: all views; 1-4: above, below, left,
        right).
    """
    L = _views(views)
    U, V, H, W, C = L.shape
    d = _check_candidates(disparities)
    order = _check_order(order)
    if isinstance(half_ratio, bool) or not (np.isfinite(half_ratio) and 0 < half_ratio <= 1):
        raise ValueError(f"half_ratio must be in (0, 1], got {half_ratio!r}")
    centre = L[U // 2, V // 2]
    offsets = _offsets(U, V)
    groups = _view_groups(offsets)
    diffs = np.empty((len(offsets), H, W))
    costs = np.empty((d.size, H, W))
    group = np.empty((d.size, H, W), dtype=np.int8)
    coeffs = [_spline(L[u, v], order) for (u, v), _ in offsets]
    for i, di in enumerate(d):
        for k, (_, (oy, ox)) in enumerate(offsets):
            shifted = _shift(coeffs[k], (oy * di, ox * di), order)
            diffs[k] = np.abs(shifted - centre).sum(axis=-1)
        per_group = np.stack([diffs[g].mean(axis=0) for g in groups])
        scaled = per_group.copy()
        scaled[1:] /= half_ratio  # a half-plane wins only where clearly better than all views
        group[i] = np.argmin(scaled, axis=0)
        costs[i] = np.take_along_axis(per_group, group[i][None].astype(np.intp), 0)[0]
    return costs, group


def _check_order(order):
    if isinstance(order, bool) or not isinstance(order, numbers.Integral) or not 1 <= order <= 5:
        raise ValueError(f"order must be an integer spline order in 1…5, got {order!r}")
    return int(order)


def _spline(img, order):
    """Per-channel spline coefficients of an (H, W, C) image (the image itself for order 1)."""
    if order == 1:
        return img
    channels = [ndimage.spline_filter(img[..., c], order=order) for c in range(img.shape[-1])]
    return np.stack(channels, -1)


def _shift(coeffs, shift, order):
    """``I(y − sy, x − sx)`` from spline coefficients: the view brought onto the centre view
    for a constant disparity (edges repeated)."""
    sy, sx = shift
    return np.stack(
        [
            ndimage.shift(coeffs[..., c], (sy, sx), order=order, mode="nearest", prefilter=False)
            for c in range(coeffs.shape[-1])
        ],
        -1,
    )


def guided_filter(guide, src, *, radius: int = 4, eps: float = 1e-4):
    """He, Sun and Tang's guided filter (ECCV 2010) of ``src`` (..., H, W) with a grey guide
    (H, W): an edge-aware box average, here of cost slices (every leading index filtered alike).

    ``eps`` is relative to the guide's squared range: where the guide varies
    less than about ``√eps`` of its range within the ``(2·radius + 1)²`` box,
    the output is the box mean; across an edge of the guide it follows the
    guide, so costs are not averaged over a depth edge that is also a
    colour edge.
    """
    I = real_array("guide", guide, finite=False)
    p = real_array("src", src, finite=False)
    if I.ndim != 2 or p.shape[-2:] != I.shape:
        raise ValueError(f"guide must be (H, W) and src (…, H, W); got {I.shape} and {p.shape}")
    if isinstance(radius, bool) or not isinstance(radius, numbers.Integral) or radius < 0:
        raise ValueError(f"radius must be an integer ≥ 0, got {radius!r}")
    number("eps", eps, low=0, low_open=True)
    if not (np.isfinite(I).all() and np.isfinite(p).all()):
        raise ValueError("guide and src must hold finite values (NaN would spread over boxes)")
    if radius == 0:
        return p.copy()
    size = (1,) * (p.ndim - 2) + (2 * radius + 1,) * 2

    def box(x):
        return ndimage.uniform_filter(x, size=size[-x.ndim :], mode="reflect")

    span = float(I.max() - I.min())
    e = eps * (span * span if span > 0 else 1.0)
    mean_i = box(I)
    var_i = box(I * I) - mean_i * mean_i
    mean_p = box(p)
    a = (box(I * p) - mean_i * mean_p) / (var_i + e)
    b = mean_p - a * mean_i
    return box(a) * I + box(b)


def disparity_from_views(
    views,
    *,
    max_disparity: float = 2.0,
    step: float = 0.1,
    method: str = "occlusion",
    window: int = 5,
    order: int = 3,
    shiftable: bool = True,
    radius: int = GUIDED_RADIUS,
    eps: float = 1e-4,
    half_ratio: float = HALF_RATIO,
):
    """Disparity (pixels per view step) of the centre view from a light field's views.

    ``method="occlusion"`` (default): the occlusion-aware cost volume of
    :func:`occlusion_cost_volume` over candidates ``−max_disparity …
    max_disparity`` every ``step``, each cost slice filtered by the guided
    filter with the centre view as guide (:func:`guided_filter`: costs are
    not averaged across colour edges), the best candidate per pixel refined
    by a parabola through its neighbours' costs.  ``method="ssd"``: the plain sum of squared
    differences to the centre view over every view in a ``window`` box
    (shiftable), best candidate and parabola
    (:func:`disparity_cost_volume`).

    ``benchmarks/results/lf_depth.md`` compares the two on rendered
    light fields of real textures with occlusions and slanted planes
    (:func:`tensor_cosdi.scenes.layered_light_field`).

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
    method : {"occlusion", "ssd"}
    window, shiftable
        ``"ssd"`` only: side of the box the cost is averaged over, and
        shiftable windows (see :func:`disparity_cost_volume`).
    order : int
        Spline order of the warps (3: cubic).
    radius, eps
        ``"occlusion"`` only: the guided filter's box radius and
        regulariser (:func:`guided_filter`).
    half_ratio : float
        ``"occlusion"`` only: see :func:`occlusion_cost_volume`.

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
    if method not in DISPARITY_METHODS:
        raise ValueError(f"method must be one of {DISPARITY_METHODS}, got {method!r}")
    for name, value in (("max_disparity", max_disparity), ("step", step)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(f"{name} must be a number, got {value!r}")
    if not (np.isfinite(max_disparity) and max_disparity > 0):
        raise ValueError(f"max_disparity must be > 0, got {max_disparity!r}")
    if not (np.isfinite(step) and 0 < step <= max_disparity):
        raise ValueError(f"step must be in (0, max_disparity], got {step!r}")
    if isinstance(window, bool) or not isinstance(window, numbers.Integral) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")  # every method
    half = np.floor(max_disparity / step + 1e-9)  # a float: 1e308 / 0.1 is no integer
    if 2 * half + 1 > MAX_CANDIDATES:
        raise ValueError(
            f"max_disparity={max_disparity:g} with step={step:g} asks for {2 * half + 1:.3g} "
            f"candidate disparities; at most {MAX_CANDIDATES} (raise step or lower max_disparity)"
        )
    n = int(half)
    cand = step * np.arange(-n, n + 1)
    if method == "ssd":
        cost = disparity_cost_volume(views, cand, window=window, order=order, shiftable=shiftable)
    else:
        L = _views(views)
        raw, _ = occlusion_cost_volume(L, cand, order=order, half_ratio=half_ratio)
        guide = L[L.shape[0] // 2, L.shape[1] // 2].mean(axis=-1)
        cost = guided_filter(guide, raw, radius=radius, eps=eps)
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
    x = real_array("image", image, finite=False)
    if x.ndim == 3:
        x = x.mean(axis=-1)
    if x.ndim != 2:
        raise ValueError(f"image must be (H, W) or (H, W, C), got {np.shape(image)}")
    if not np.isfinite(x).all():
        raise ValueError("image must hold finite values")
    number("threshold", threshold, low=0, high=1)
    number("sigma", sigma, low=0, high=max(x.shape))  # wider than the image: nothing left
    g = ndimage.gaussian_gradient_magnitude(x, sigma)
    return g >= threshold * max(g.max(), np.finfo(float).tiny)


def depth_from_disparity(disparity, *, baseline_mm: float, focal_px: float, offset: float = 0.0):
    """Depth ``z = f·b / (d − d0)`` (mm) from disparity ``d`` (px per view step).

    ``baseline_mm`` is the distance between neighbouring viewpoints,
    ``focal_px`` the focal length in pixels, ``offset = d0`` the disparity of
    the plane at infinity (for a lenslet camera focused at a finite
    distance, the disparity of the focal plane is 0 and ``d0`` is negative;
    calibrate it with a far target).  Pixels with ``d ≤ d0`` get ``inf``; a NaN disparity (an
    invalid pixel) stays NaN.
    """
    fb = number("baseline_mm", baseline_mm, low=0, low_open=True) * number(
        "focal_px", focal_px, low=0, low_open=True
    )
    d0 = number("offset", offset)
    d = real_array("disparity", disparity, finite=False)
    if np.isinf(d).any():
        raise ValueError(
            f"disparity holds {int(np.isinf(d).sum())} infinite values; expected finite pixels "
            "per view step (NaN marks an invalid pixel)"
        )
    d = d - d0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z = np.where(d > 0, fb / np.where(d > 0, d, 1.0), np.inf)
    return np.where(np.isnan(d), np.nan, z)
