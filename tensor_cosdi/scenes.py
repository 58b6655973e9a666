"""Seeded scenes built from real measured data that installs with the dependencies.

* :func:`colorchecker` — the 24 measured reflectances of colour-science;
* :func:`photo` — RGB photographs shipped with scikit-image turned into
  spectra by colour-science's spectral upsampling (:func:`~tensor_cosdi.colour.rgb_to_cube`);
* :func:`motorcycle` — the Middlebury motorcycle stereo pair with its
  disparity (scikit-image): a spectral cube plus a depth map, and
  :func:`depth_planes` / :func:`depth_layers` to turn them into the
  ``(Nx, Ny, Nλ, Nz)`` cube of CASSDI-DFA;
* :func:`light_field` — a spectral light field ``(Nx, Ny, Nλ, U, V)``
  rendered from a cube and a disparity map (per-view shifts);
  :func:`layered_light_field` — views of textured, slanted planes that
  occlude each other, with their true disparity (ground truth for
  light-field depth);
* :func:`structured_light` — a seeded height map, its deformed fringe phase
  and a reflectance, ready for :func:`tensor_cosdi.systems.fringe_cube`;
* :func:`cave` — a *real* hyperspectral scene (CAVE, 31 measured bands) of
  the ``hsi_train`` data folder (:func:`tensor_cosdi.datasets.data_dir`; not
  shipped with the package), registered as ``"cave.<name>"``.  Judge
  spectral priors on these: the photo scenes' spectra live in a 3-D
  subspace, which flatters them.

All take any spatial size and any band list (default 28 bands, 450–650 nm).
:data:`SCENES` names the spectral scenes every imager's
``example_problem`` can view (``scene_cube(name, shape, wavelengths)``);
:func:`register_scene` adds your own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _backend as B
from . import validate
from ._registry import Registry
from ._units import check_wavelengths_nm
from .operators import validate_shape
from .validate import real_array

__all__ = [
    "default_wavelengths",
    "colorchecker",
    "photo",
    "PHOTOS",
    "motorcycle",
    "depth_planes",
    "depth_layers",
    "light_field",
    "LightFieldLayer",
    "layered_light_field",
    "structured_light",
    "StructuredLightScene",
    "SCENES",
    "register_scene",
    "scene_cube",
    "cave",
]

PHOTOS = ("astronaut", "chelsea", "coffee", "rocket")
"""RGB photographs of ``skimage.data`` that :func:`photo` accepts."""


def default_wavelengths(n_bands: int = 28, start: float = 450.0, stop: float = 650.0) -> np.ndarray:
    """``n_bands`` evenly spaced wavelengths in nm (default 28 bands, 450–650 nm)."""
    (n_bands,) = validate_shape((n_bands,), "n_bands")
    check_wavelengths_nm([start, stop], "start and stop")  # names micrometres
    if not start < stop:
        raise ValueError(f"need start < stop (nm), got start={start}, stop={stop}")
    return np.linspace(start, stop, n_bands)


def _wavelengths(wavelengths) -> np.ndarray:
    if wavelengths is None:
        wl = default_wavelengths()
    else:
        wl = real_array("wavelengths", wavelengths, finite=False)
    if wl.ndim != 1 or wl.size == 0 or not np.isfinite(wl).all():
        raise ValueError(
            f"wavelengths must be a non-empty 1-D array of finite nm, got {wl.tolist()}"
        )
    if wl.min() < 380 or wl.max() > 780:
        raise ValueError(
            f"wavelengths must lie within the measured 380–780 nm, got {wl.min():g}–{wl.max():g} nm"
        )
    return wl


def colorchecker(
    shape=(64, 96), wavelengths=None, *, chart: str = "ColorChecker N Ohta", dtype="float64"
):
    """The 24-patch ColorChecker as a spectral cube of measured reflectances.

    Parameters
    ----------
    shape : (Nx, Ny)
        Spatial size; the 4 × 6 patches tile it (patch borders at
        ``round(i · Nx / 4)``, ``round(j · Ny / 6)``).
    wavelengths : array_like, optional
        Band centres in nm within 380–780 (default :func:`default_wavelengths`).
    chart : str
        A key of ``colour.SDS_COLOURCHECKERS``.

    Returns
    -------
    cube : ndarray of shape (Nx, Ny, Nλ)
        Reflectance in [0, 1], interpolated from the measured spectra.

    Examples
    --------
    >>> cube = colorchecker((8, 12), [450, 550, 650])
    >>> cube.shape
    (8, 12, 3)
    """
    nx, ny = validate_shape(shape, "shape")
    wl = _wavelengths(wavelengths)
    from .colour import colour_science

    colour = colour_science()
    charts = colour.SDS_COLOURCHECKERS
    if chart not in charts:
        raise ValueError(f"unknown chart {chart!r}; choose one of {sorted(charts)}")
    sds = list(charts[chart].values())
    spectra = np.stack([np.asarray(sd[wl], dtype=float) for sd in sds])  # (24, Nλ)
    rows = np.minimum((np.arange(nx) * 4) // nx, 3)
    cols = np.minimum((np.arange(ny) * 6) // ny, 5)
    patch = rows[:, None] * 6 + cols[None, :]
    return spectra[patch].astype(dtype)


def _fit(image: np.ndarray, shape) -> np.ndarray:
    """Centre-crop ``image`` to the aspect ratio of ``shape``, then resize (anti-aliased)."""
    from skimage.transform import resize

    nx, ny = shape
    h, w = image.shape[:2]
    if h * ny > w * nx:  # too tall: crop rows
        hh = max(1, round(w * nx / ny))
        top = (h - hh) // 2
        image = image[top : top + hh]
    else:
        ww = max(1, round(h * ny / nx))
        left = (w - ww) // 2
        image = image[:, left : left + ww]
    return resize(
        image, (nx, ny) + image.shape[2:], order=1, anti_aliasing=True, preserve_range=True
    )


def photo(name: str = "chelsea", shape=(64, 64), wavelengths=None, *, dtype="float64"):
    """An RGB photograph of scikit-image as a spectral reflectance cube.

    The image is centre-cropped to the aspect ratio of ``shape``, resized
    with anti-aliasing and upsampled to spectra with
    :func:`tensor_cosdi.colour.rgb_to_cube` (Mallett–Yuksel basis of
    colour-science: smooth, non-negative, white → flat 1).

    Parameters
    ----------
    name : str
        One of :data:`PHOTOS` (``skimage.data`` images that ship with it).
    shape : (Nx, Ny)
    wavelengths : array_like, optional
        Band centres in nm within 380–780 (default :func:`default_wavelengths`).

    Returns
    -------
    cube : ndarray of shape (Nx, Ny, Nλ), values in [0, 1]

    Examples
    --------
    >>> photo("astronaut", (16, 16), [450, 550, 650]).shape
    (16, 16, 3)
    """
    from skimage import data

    from .colour import rgb_to_cube

    if name not in PHOTOS:
        raise ValueError(f"unknown photo {name!r}; choose one of {PHOTOS}")
    nx, ny = validate_shape(shape, "shape")
    wl = _wavelengths(wavelengths)
    rgb = _fit(getattr(data, name)().astype(np.float64) / 255.0, (nx, ny))
    return np.clip(rgb_to_cube(np.clip(rgb, 0.0, 1.0), wl), 0.0, 1.0).astype(dtype)


def motorcycle(shape=(64, 96), wavelengths=None, *, dtype="float64"):
    """The Middlebury motorcycle (scikit-image) as a spectral cube with its disparity.

    The left view of ``skimage.data.stereo_motorcycle`` becomes spectra as in
    :func:`photo`; its ground-truth disparity map (pixels of the original
    741-pixel-wide pair) is resized the same way and rescaled to the new
    width.  Invalid disparities (occlusions, marked ``inf`` in the data) are
    filled from their nearest valid neighbour.  Larger disparity = nearer.

    Returns
    -------
    cube : ndarray of shape (Nx, Ny, Nλ)
    disparity : ndarray of shape (Nx, Ny)
        In pixels at the new size (for a stereo baseline like the original).

    Examples
    --------
    >>> cube, disparity = motorcycle((24, 36), [500, 600])
    >>> cube.shape, disparity.shape, bool(disparity.min() > 0)
    ((24, 36, 2), (24, 36), True)
    """
    from scipy import ndimage
    from skimage import data

    from .colour import rgb_to_cube

    nx, ny = validate_shape(shape, "shape")
    wl = _wavelengths(wavelengths)
    left, _, disp = data.stereo_motorcycle()
    disp = real_array("disp", disp, finite=False)
    invalid = ~np.isfinite(disp) | (disp <= 0)
    if invalid.any():
        idx = ndimage.distance_transform_edt(invalid, return_distances=False, return_indices=True)
        disp = disp[tuple(idx)]
    width = left.shape[1]
    rgb = _fit(left.astype(np.float64) / 255.0, (nx, ny))
    cube = np.clip(rgb_to_cube(np.clip(rgb, 0.0, 1.0), wl), 0.0, 1.0).astype(dtype)
    cropped_width = min(width, round(left.shape[0] * ny / nx))
    disparity = _fit(disp, (nx, ny)) * (ny / cropped_width)
    return cube, disparity.astype(dtype)


def depth_planes(depth, n_planes: int, *, near_is_large: bool = True) -> np.ndarray:
    """Quantise a depth (or disparity) map into ``n_planes`` equal-width planes: index per pixel.

    Plane 0 is the nearest: with ``near_is_large`` (disparity) the largest
    values go to plane 0; with ``False`` (metric depth) the smallest do.

    Examples
    --------
    >>> depth_planes([[10.0, 7.0], [1.0, 2.0]], 2).tolist()
    [[0, 0], [1, 1]]
    """
    d = real_array("depth", B.to_numpy(depth), finite=False)
    n_planes = validate.integer("n_planes", n_planes, low=1)
    near_is_large = validate.flag("near_is_large", near_is_large)
    if d.ndim != 2 or not np.isfinite(d).all():
        raise ValueError(f"depth must be a finite 2-D map, got shape {d.shape}")
    lo, hi = d.min(), d.max()
    t = (d - lo) / (hi - lo) if hi > lo else np.zeros_like(d)
    if near_is_large:
        t = 1.0 - t
    return np.minimum((t * n_planes).astype(int), n_planes - 1)


def depth_layers(cube, planes, n_planes: int):
    """A spectral-depth cube ``(Nx, Ny, Nλ, Nz)``: each pixel's spectrum sits in its depth plane
    only.

    This is the cube ``F`` that :class:`~tensor_cosdi.systems.CASSDIDFA` senses
    (SPEC §3.2); summing it over ``z`` gives ``cube`` back.

    Examples
    --------
    >>> import numpy as np
    >>> F = depth_layers(np.ones((2, 2, 3)), np.array([[0, 1], [1, 1]]), 2)
    >>> F.shape, F.sum(axis=3).tolist() == np.ones((2, 2, 3)).tolist()
    ((2, 2, 3, 2), True)
    """
    c = np.asarray(B.to_numpy(cube))
    p = np.asarray(planes)
    (n_planes,) = validate_shape((n_planes,), "n_planes")
    if c.ndim != 3 or p.shape != c.shape[:2]:
        raise ValueError(f"need cube (Nx, Ny, Nλ) and planes (Nx, Ny); got {c.shape} and {p.shape}")
    if not np.issubdtype(p.dtype, np.integer) or p.min() < 0 or p.max() >= n_planes:
        raise ValueError(
            f"planes must be integers in [0, {n_planes - 1}], got {p.dtype} in [{p.min()}, "
            f"{p.max()}]"
        )
    onehot = (p[..., None] == np.arange(n_planes)).astype(c.dtype)  # (Nx, Ny, Nz)
    return c[..., None] * onehot[:, :, None, :]


def light_field(cube, disparity, views=(5, 5)):
    """A spectral light field ``(Nx, Ny, Nλ, U, V)`` rendered from a cube and a disparity map.

    View ``(u, v)`` sees the centre view ``(uc, vc) = (U // 2, V // 2)``
    displaced by the disparity ``d`` per view step, the convention of
    :func:`tensor_cosdi.depth.disparity_from_views`::

        L[u, v](x − (u − uc)·d, y − (v − vc)·d) = cube(x, y)

    rendered by backward warping (bilinear, edges repeated) with ``d``
    taken at the target pixel — exact for piecewise-constant disparity away
    from its edges.

    Parameters
    ----------
    cube : array of shape (Nx, Ny, Nλ)
        The centre view.
    disparity : array of shape (Nx, Ny) or float
        Pixels of shift per view step.
    views : (U, V)

    Examples
    --------
    >>> import numpy as np
    >>> L = light_field(np.random.default_rng(0).random((8, 8, 2)), 1.0, views=(3, 3))
    >>> L.shape, bool(np.allclose(L[2:6, 2:6, :, 2, 1], L[3:7, 2:6, :, 1, 1]))
    ((8, 8, 2, 3, 3), True)
    """
    from scipy import ndimage

    c = real_array("cube", B.to_numpy(cube))
    if c.ndim != 3:
        raise ValueError(f"cube must have shape (Nx, Ny, Nλ), got {c.shape}")
    U, V = validate_shape(views, "views")
    if isinstance(disparity, (bool, np.bool_)):
        raise ValueError(f"disparity must be pixels per view step, got {disparity!r}")
    try:
        d = np.broadcast_to(real_array("disparity", disparity, finite=False), c.shape[:2])
    except ValueError as exc:
        if "disparity" in str(exc):
            raise
        raise ValueError(
            f"disparity must be a number or an (Nx, Ny) = {c.shape[:2]} map, got shape "
            f"{np.shape(disparity)}"
        ) from None
    if not np.isfinite(d).all():
        raise ValueError("disparity contains NaN or inf")
    xx, yy = np.meshgrid(np.arange(c.shape[0]), np.arange(c.shape[1]), indexing="ij")
    out = np.empty(c.shape + (U, V))
    for u in range(U):
        for v in range(V):
            coords = [xx + (u - U // 2) * d, yy + (v - V // 2) * d]
            for band in range(c.shape[2]):
                out[:, :, band, u, v] = ndimage.map_coordinates(
                    c[:, :, band], coords, order=1, mode="nearest"
                )
    return out


@dataclass(frozen=True)
class LightFieldLayer:
    """One textured plane of :func:`layered_light_field`.

    Attributes
    ----------
    texture : ndarray (H, W) or (H, W, C)
        What the centre view sees of the plane, in centre-view pixels.
    disparity : float or (float, float, float)
        ``d`` or ``(d, gy, gx)``: the plane's disparity (pixels per view
        step) at the image centre and its gradient along the two spatial
        axes (per pixel): ``d(y, x) = d + gy·(y − yc) + gx·(x − xc)``.
    mask : ndarray (H, W) of bool, optional
        Where the plane is, in centre-view pixels (``None``: everywhere, and
        beyond the image border; a background).
    """

    texture: np.ndarray
    disparity: float | tuple = 0.0
    mask: np.ndarray | None = None


def layered_light_field(layers, views=(5, 5), *, supersample: int = 3):
    """Views of planes that occlude each other, and the centre view's true disparity.

    Every plane (:class:`LightFieldLayer`) is drawn in every view where the
    convention of :func:`tensor_cosdi.depth.disparity_from_views` puts it,
    ``I[u, v](y − (u − uc)·d, x − (v − vc)·d) = I[uc, vc](y, x)``, solved
    exactly for a slanted plane; where planes overlap the one of larger
    disparity (the nearer) hides the others.  Each pixel is the mean of
    ``supersample × supersample`` samples (edges blend as a camera's pixels
    do); the disparity is the visible plane's at the pixel centre.

    Parameters
    ----------
    layers : sequence of LightFieldLayer
        All of one spatial shape and channel count; the first is usually a
        background (``mask=None``).  A pixel no plane covers is an error.
    views : (U, V)
    supersample : int
        Odd, ≥ 1: samples per pixel and axis.

    Returns
    -------
    views : ndarray (U, V, H, W, C)
    disparity : ndarray (H, W)
        Of the centre view ``(U // 2, V // 2)``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> back = LightFieldLayer(rng.random((24, 24)), (-0.5, 0.0, 0.02))
    >>> disc = np.hypot(*np.mgrid[-12:12, -12:12]) < 6
    >>> front = LightFieldLayer(rng.random((24, 24)), 1.0, disc)
    >>> lf, d = layered_light_field([back, front], views=(3, 3))
    >>> lf.shape, float(d[12, 12]), round(float(d[12, 0]), 2)
    ((3, 3, 24, 24, 1), 1.0, -0.73)
    """
    from scipy import ndimage

    from .validate import integer

    U, V = validate_shape(views, "views")
    s = integer("supersample", supersample, low=1)
    if s % 2 == 0:
        raise ValueError(f"supersample must be odd (a sample at each pixel centre), got {s}")
    layers = list(layers)
    if not layers or not all(isinstance(a, LightFieldLayer) for a in layers):
        raise ValueError("layers must be a non-empty sequence of LightFieldLayer")
    tex = []
    for i, layer in enumerate(layers):
        t = np.asarray(layer.texture, dtype=np.float64)
        t = t[..., None] if t.ndim == 2 else t
        if t.ndim != 3 or not np.isfinite(t).all():
            raise ValueError(f"layer {i}: texture must be a finite (H, W) or (H, W, C) array")
        tex.append(t)
    H, W, C = tex[0].shape
    if any(t.shape != (H, W, C) for t in tex):
        raise ValueError(f"every layer's texture must have the shape {(H, W, C)}")
    planes, masks = [], []
    for i, layer in enumerate(layers):
        d = np.atleast_1d(np.asarray(layer.disparity, dtype=np.float64))
        if d.shape not in ((1,), (3,)) or not np.isfinite(d).all():
            raise ValueError(
                f"layer {i}: disparity must be d or (d, gy, gx), got {layer.disparity!r}"
            )
        planes.append(np.concatenate([d, [0.0, 0.0]]) if d.size == 1 else d)
        if layer.mask is not None:
            m = np.asarray(layer.mask)
            if m.shape != (H, W) or m.dtype != bool:
                raise ValueError(f"layer {i}: mask must be a boolean array of shape {(H, W)}")
        masks.append(layer.mask)
    centre = np.array([(H - 1) / 2, (W - 1) / 2])
    sub = (np.arange(s) - (s - 1) / 2) / s  # sample offsets within a pixel
    py = (np.arange(H)[:, None] + sub[None, :]).reshape(-1)
    px = (np.arange(W)[:, None] + sub[None, :]).reshape(-1)
    PY, PX = np.meshgrid(py - centre[0], px - centre[1], indexing="ij")
    out = np.empty((U, V, H, W, C))
    truth = None
    for u in range(U):
        for v in range(V):
            o = np.array([u - U // 2, v - V // 2], dtype=np.float64)
            best = np.full(PY.shape, -np.inf)
            colour = np.zeros(PY.shape + (C,))
            for (a, gy, gx), t, m in zip(planes, tex, masks):
                den = 1.0 - (gy * o[0] + gx * o[1])
                if den <= 0.05:
                    raise ValueError("a layer's disparity slope is too steep for these views")
                wy, wx = PY + o[0] * a, PX + o[1] * a  # q = w + o (g·w) / (1 − g·o)
                k = (gy * wy + gx * wx) / den
                qy, qx = wy + o[0] * k + centre[0], wx + o[1] * k + centre[1]
                d = a + gy * (qy - centre[0]) + gx * (qx - centre[1])
                if m is None:
                    cover = np.ones(PY.shape, bool)
                else:
                    iy, ix = np.rint(qy).astype(int), np.rint(qx).astype(int)
                    inside = (iy >= 0) & (iy < H) & (ix >= 0) & (ix < W)
                    cover = np.zeros(PY.shape, bool)
                    cover[inside] = m[iy[inside], ix[inside]]
                win = cover & (d > best)
                if not win.any():
                    continue
                best[win] = d[win]
                coords = [qy[win], qx[win]]
                for c in range(C):
                    colour[win, c] = ndimage.map_coordinates(
                        t[..., c], coords, order=1, mode="nearest"
                    )
            if not np.isfinite(best).all():
                raise ValueError(f"view {(u, v)}: some pixels see no layer (add a background)")
            out[u, v] = colour.reshape(H, s, W, s, C).mean(axis=(1, 3))
            if u == U // 2 and v == V // 2:
                truth = best[s // 2 :: s, s // 2 :: s]
    return out, truth


@dataclass(frozen=True)
class StructuredLightScene:
    """A structured-light scene: what :func:`structured_light` returns.

    Attributes
    ----------
    reflectance : ndarray (Nx, Ny, Nλ)
    height : ndarray (Nx, Ny)
        Surface height above the reference plane (arbitrary units, ≥ 0).
    phase : ndarray (Nx, Ny, n_freq)
        Unwrapped fringe phase per frequency: reference-plane phase
        ``2π ν_f y / Ny`` plus ``phase_per_height · ν_f / ν_0 · height``.
    frequencies : tuple of float
        Fringe periods across the width, ``ν_f``.
    phase_per_height : float
        The calibration: phase change (rad) per unit height at ``ν_0``.
    """

    reflectance: np.ndarray
    height: np.ndarray
    phase: np.ndarray
    frequencies: tuple
    phase_per_height: float


#: Most Gaussian bumps a :func:`structured_light` height map sums (each is a full-image pass).
MAX_BUMPS = 1000


def structured_light(
    shape=(64, 64),
    wavelengths=None,
    *,
    frequencies=(4.0,),
    phase_per_height: float = 2.0,
    n_bumps: int = 3,
    photo_name: str = "coffee",
    fringe_axis: int = 1,
    rng=0,
) -> StructuredLightScene:
    """A seeded structured-light scene: smooth height map, deformed fringe phase, reflectance.

    The height is a sum of ``n_bumps`` Gaussian bumps (seeded positions,
    widths and heights in ``[0.5, 1]``) on a flat reference plane; the
    fringe phase of frequency ``ν`` is the reference-plane phase
    ``2πν·y/Ny`` shifted by ``phase_per_height · (ν/ν_0) · height``
    (a linear phase-to-height calibration, SPEC §7).  The reflectance is
    :func:`photo` ``photo_name``.  Feed ``reflectance`` and ``phase`` to
    :func:`tensor_cosdi.systems.fringe_cube` for the CS2LI cube.

    ``fringe_axis`` is the axis the fringe phase runs along: 1 (default,
    ``y`` above) is the axis CASSI disperses along, 0 runs it along ``x``
    (``2πν·x/Nx``), fringes across the dispersion.

    Examples
    --------
    >>> scene = structured_light((16, 16), [500, 600], frequencies=(2.0, 3.0))
    >>> scene.reflectance.shape, scene.phase.shape
    ((16, 16, 2), (16, 16, 2))
    >>> flat = structured_light((16, 16), [500], n_bumps=1, phase_per_height=1e-9, fringe_axis=0)
    >>> bool(np.ptp(flat.phase[:, 0, 0]) > 5 and np.ptp(flat.phase[0, :, 0]) < 1e-6)
    True
    """
    from ._backend import default_rng

    nx, ny = validate_shape(shape, "shape")
    freqs = tuple(real_array("frequencies", frequencies, finite=False).reshape(-1).tolist())
    if not freqs or not all(np.isfinite(f) and f > 0 for f in freqs):
        raise ValueError(f"frequencies must be positive numbers, got {frequencies!r}")
    validate.number("phase_per_height", phase_per_height, low=0, low_open=True)
    n_bumps = validate.integer("n_bumps", n_bumps, low=1, high=MAX_BUMPS)
    gen = default_rng(rng)
    xx, yy = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny), indexing="ij")
    height = np.zeros((nx, ny))
    for _ in range(n_bumps):
        cx, cy = gen.uniform(0.2, 0.8, 2)
        width = gen.uniform(0.1, 0.25)
        height += gen.uniform(0.5, 1.0) * np.exp(
            -((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * width**2)
        )
    if isinstance(fringe_axis, bool) or fringe_axis not in (0, 1):
        raise ValueError(f"fringe_axis must be 0 or 1, got {fringe_axis!r}")
    if fringe_axis == 1:
        ref = 2 * np.pi * np.arange(ny)[None, :] / ny
    else:
        ref = 2 * np.pi * np.arange(nx)[:, None] / nx
    phase = np.stack([f * ref + phase_per_height * (f / freqs[0]) * height for f in freqs], axis=-1)
    phase = np.broadcast_to(phase, (nx, ny, len(freqs))).copy()
    reflectance = photo(photo_name, (nx, ny), wavelengths)
    return StructuredLightScene(reflectance, height, phase, freqs, float(phase_per_height))


# ---- the scene registry ---------------------------------------------------------------
SCENES = Registry("scene")
"""``name → builder(shape, wavelengths) -> (Nx, Ny, Nλ) reflectance``: what ``example_problem``
accepts."""


def register_scene(name: str, builder, *, replace: bool = False) -> None:
    """Make ``builder(shape, wavelengths)`` (an ``(Nx, Ny, Nλ)`` reflectance in [0, 1]) a named
    scene."""
    if not callable(builder):
        raise ValueError(
            f"a scene builder must be callable (shape, wavelengths) -> cube, got {builder!r}"
        )
    SCENES.register(name, builder, replace=replace)


def scene_cube(name: str, shape, wavelengths) -> np.ndarray:
    """The reflectance cube of the named scene at ``shape`` and ``wavelengths``."""
    return SCENES[name](shape, wavelengths)


SCENES.register("colorchecker", lambda shape, wl: colorchecker(shape, wl), builtin=True)
for _name in PHOTOS:
    SCENES.register(_name, lambda shape, wl, _n=_name: photo(_n, shape, wl), builtin=True)
SCENES.register("motorcycle", lambda shape, wl: motorcycle(shape, wl)[0], builtin=True)


def _register_cave():
    from .datasets import HSI_SCENES, cave

    for name in HSI_SCENES:
        SCENES.register(
            f"cave.{name}", lambda shape, wl, _n=name: cave(_n, shape, wl), builtin=True
        )


_register_cave()
del _name

from .datasets import cave  # noqa: E402 - the real scenes' builder, named here with the others
