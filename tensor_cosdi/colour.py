"""Colour previews of spectral cubes (SPEC §9) through colour-science."""

from __future__ import annotations

import warnings

import numpy as np

from . import _backend as B
from . import validate
from .validate import real_array

__all__ = ["to_srgb", "rgb_to_cube", "reflectance", "radiance"]


def colour_science():
    """The ``colour`` package, imported without its side effects on the caller: it warns when
    matplotlib is absent, and its import switches NumPy's print options to the 1.13 legacy
    format for the whole process (colour-science 0.4.x) — restored here."""
    state = np.get_printoptions()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import colour
    finally:
        np.set_printoptions(**state)
    return colour


def to_srgb(
    cube, wavelengths, *, band_axis: int = 2, illuminant: str = "D65", white_balance: bool = True
):
    """sRGB preview of a reflectance cube: CIE 1931 2° observer under ``illuminant``.

    ``XYZ = Σ_l R_l S(λ_l) x̄ȳz̄(λ_l) Δλ_l`` with the colour-matching
    functions and illuminant of colour-science sampled at the band centres,
    normalised so that a perfect white has ``Y = 1``; then the sRGB
    primaries and transfer curve (``colour.XYZ_to_sRGB``).  A cube covers
    only part of the visible range (450–650 nm by default), so with
    ``white_balance`` (default) the linear channels are scaled so that a
    flat unit reflectance maps to white.  The result is clipped to
    ``[0, 1]`` — it is a display preview, not data.

    Parameters
    ----------
    cube : tensor of shape (..., Nλ, ...)
        Reflectance (or radiance relative to a white reference) per band.
    wavelengths : array_like of shape (Nλ,)
        Band centres in nm within 360–830.
    band_axis : int
        Axis of ``cube`` holding the bands (default 2, SPEC §1).
    illuminant : str
        A key of ``colour.SDS_ILLUMINANTS``.

    Returns
    -------
    ndarray of shape ``cube.shape`` without ``band_axis``, plus a last axis of 3.

    Examples
    --------
    >>> import numpy as np
    >>> to_srgb(np.ones((2, 2, 5)), [450, 500, 550, 600, 650])[0, 0].round(6).tolist()
    [1.0, 1.0, 1.0]
    """
    colour = colour_science()
    c = validate.real_array("cube", B.to_numpy(cube), finite=False)
    band_axis = validate.integer("band_axis", band_axis, low=-c.ndim, high=c.ndim - 1)
    c = np.moveaxis(c, band_axis, -1)
    wl = validate.real_array("wavelengths", wavelengths, finite=False)
    if wl.ndim != 1:
        raise ValueError(f"wavelengths must be 1-D (one per band), got shape {wl.shape}")
    if wl.size != c.shape[-1]:
        raise ValueError(f"expected {c.shape[-1]} wavelengths (one per band), got {wl.size}")
    if not np.isfinite(c).all():
        raise ValueError("the cube holds NaN or infinite values; an image of them has no colour")
    if not np.isfinite(wl).all() or wl.min() < 360 or wl.max() > 830 or (np.diff(wl) <= 0).any():
        raise ValueError(f"wavelengths must increase strictly within 360–830 nm, got {wl.tolist()}")
    if not isinstance(illuminant, str) or illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(f"unknown illuminant {illuminant!r}; e.g. 'D65', 'A', 'D50'")
    white_balance = validate.flag("white_balance", white_balance)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    xyz_bar = np.stack(
        [np.interp(wl, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)], axis=1
    )
    ill = colour.SDS_ILLUMINANTS[illuminant]
    S = np.interp(wl, ill.wavelengths, ill.values)
    dl = np.gradient(wl) if wl.size > 1 else np.ones(1)
    weights = xyz_bar * (S * dl)[:, None]  # (Nλ, 3)
    weights = weights / np.sum(weights[:, 1])  # perfect white: Y = 1 over the band range
    xyz = c @ weights
    if white_balance:
        white = colour.XYZ_to_sRGB(weights.sum(0), apply_cctf_encoding=False)
        linear = colour.XYZ_to_sRGB(xyz, apply_cctf_encoding=False) / white
        rgb = colour.cctf_encoding(np.clip(linear, 0.0, 1.0), function="sRGB")
    else:
        rgb = colour.XYZ_to_sRGB(xyz)
    return np.clip(real_array("rgb", rgb, finite=False), 0.0, 1.0)


def rgb_to_cube(rgb, wavelengths, *, encoded: bool = True):
    """Reflectance spectra for sRGB colours (spectral upsampling, Mallett & Yuksel 2019).

    Every linear sRGB colour is the weighted sum of three smooth, non-negative
    basis spectra (``colour.recovery.MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019``)
    that sum to one at every wavelength: ``R(λ) = r·b_r(λ) + g·b_g(λ) +
    b·b_b(λ)``.  So a colour in ``[0, 1]³`` gives a reflectance in ``[0, 1]``,
    white gives a flat 1, and the map is linear and fast (one matrix product).

    Parameters
    ----------
    rgb : array_like of shape (..., 3)
        sRGB colours in ``[0, 1]`` (uint8 images: divide by 255 first).
    wavelengths : array_like of shape (Nλ,)
        Band centres in nm within 380–780.
    encoded : bool
        ``True`` (default) when ``rgb`` carries the sRGB transfer curve (as
        photographs do); it is decoded to linear light first.

    Returns
    -------
    ndarray of shape (..., Nλ)

    Examples
    --------
    >>> rgb_to_cube([1.0, 1.0, 1.0], [450, 550, 650]).round(4).tolist()
    [1.0, 1.0, 1.0]
    """
    colour = colour_science()
    x = validate.real_array("rgb", B.to_numpy(rgb), finite=False)
    encoded = validate.flag("encoded", encoded)
    if x.ndim == 0 or x.shape[-1] != 3:
        raise ValueError(f"rgb must have a last axis of 3 (R, G, B), got shape {x.shape}")
    if not np.isfinite(x).all():
        raise ValueError("rgb contains NaN or inf")
    if x.min() < 0 or x.max() > 1:
        raise ValueError(
            f"rgb must lie in [0, 1] (divide uint8 images by 255), got values in [{x.min():g}, "
            f"{x.max():g}]"
        )
    wl = validate.real_array("wavelengths", wavelengths, finite=False)
    if wl.ndim != 1:
        raise ValueError(f"wavelengths must be 1-D (one per band), got shape {wl.shape}")
    if wl.size == 0 or not np.isfinite(wl).all() or wl.min() < 380 or wl.max() > 780:
        raise ValueError(f"wavelengths must be finite nm within 380–780, got {wl.tolist()}")
    linear = colour.cctf_decoding(x, function="sRGB") if encoded else x
    basis = colour.recovery.MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019
    b = np.stack(
        [np.interp(wl, basis.wavelengths, basis.values[:, i]) for i in range(3)]
    )  # (3, Nλ)
    return real_array("linear", linear, finite=False) @ b


def reflectance(cube, white, dark=0.0):
    """Reflectance from a radiance cube and a white reference (thesis Equation 171):
    ``(X − dark) / (W − dark)``.

    Parameters
    ----------
    cube : tensor
        Reconstruction (or capture) of the scene.
    white : tensor broadcastable to ``cube``
        Reconstruction of a white reference (a spectralon) under the same light.
    dark : float or tensor broadcastable to ``cube``
        Dark count (sensor offset).

    Raises
    ------
    ValueError
        Where ``white − dark`` is not positive (the ratio would be undefined
        or flip sign), or where an input holds NaN or ±inf; the message counts the
        offending entries.

    Examples
    --------
    >>> import numpy as np
    >>> reflectance(np.array([3.0, 5.0]), np.array([5.0, 9.0]), dark=1.0).tolist()
    [0.5, 0.5]
    """
    x = real_array("cube", B.to_numpy(cube))
    w = real_array("white", B.to_numpy(white))
    if isinstance(dark, (bool, np.bool_)):
        raise ValueError(f"dark must be a dark count (a number or an array), got {dark!r}")
    d = real_array("dark", B.to_numpy(dark))
    try:
        denom = np.broadcast_to(w - d, np.broadcast_shapes(x.shape, w.shape, d.shape))
    except ValueError:
        raise ValueError(
            f"white {w.shape} and dark {d.shape} must broadcast to the cube's shape {x.shape}"
        ) from None
    bad = ~(denom > 0)
    if bad.any():
        raise ValueError(
            f"white − dark must be > 0 everywhere; {int(bad.sum())} of {bad.size} entries are not "
            "(is the dark frame brighter than the white reference?)"
        )
    return B.tensor_like((x - d) / denom, cube)


def radiance(cube, wavelengths, illuminant: str = "D65", *, band_axis: int = 2):
    """A reflectance cube lit by a CIE illuminant, scaled to a peak of 1.

    ``L_l = R_l S(λ_l) / max(R S)`` with ``S`` the illuminant's spectral power
    distribution of colour-science (``colour.SDS_ILLUMINANTS``) interpolated
    at the band centres.  Databases of reflectance (CAVE) and of radiance
    (KAIST, scenes captured under their own light, each scaled to a peak of
    1) differ by this factor: it simulates the second kind from the first.

    Parameters
    ----------
    cube : tensor of shape (..., Nλ, ...)
        Non-negative reflectance per band, not all zero.
    wavelengths : array_like of shape (Nλ,)
        Band centres in nm, strictly increasing within the illuminant's
        tabulated range.
    illuminant : str
        A key of ``colour.SDS_ILLUMINANTS`` (``"D65"`` daylight, ``"A"``
        tungsten, ``"FL2"`` fluorescent, ``"LED-B3"`` white LED, …).
    band_axis : int
        Axis of ``cube`` holding the bands (default 2, SPEC §1).

    Returns
    -------
    ndarray of ``cube``'s shape, float64, peak 1.

    Examples
    --------
    >>> import numpy as np
    >>> lit = radiance(np.ones((1, 1, 3)), [450, 550, 650], "A")
    >>> lit.round(3).ravel().tolist()  # tungsten light rises toward the red
    [0.2, 0.563, 1.0]
    """
    colour = colour_science()
    c = real_array("cube", B.to_numpy(cube), finite=False)
    if c.ndim == 0:
        raise ValueError("cube must have a band axis, got a scalar")
    if c.size == 0:
        raise ValueError(f"cube is empty (shape {c.shape}): nothing to light")
    axis = validate.integer("band_axis", band_axis, low=-c.ndim, high=c.ndim - 1) % c.ndim
    wl = real_array("wavelengths", wavelengths, finite=False).reshape(-1)
    if wl.size != c.shape[axis]:
        raise ValueError(
            f"expected {c.shape[axis]} wavelengths (one per band of axis {axis}), got {wl.size}"
        )
    # exact keys only: colour-science's mapping also matches other spellings of a key
    if not isinstance(illuminant, str) or illuminant not in list(colour.SDS_ILLUMINANTS):
        raise ValueError(f"unknown illuminant {illuminant!r}; e.g. 'D65', 'A', 'FL2', 'LED-B3'")
    ill = colour.SDS_ILLUMINANTS[illuminant]
    lo, hi = float(ill.wavelengths[0]), float(ill.wavelengths[-1])
    if not np.isfinite(wl).all() or wl.min() < lo or wl.max() > hi or (np.diff(wl) <= 0).any():
        raise ValueError(
            f"wavelengths must increase strictly within {lo:g}–{hi:g} nm (the tabulated range "
            f"of {illuminant!r}), got {wl.tolist()}"
        )
    if not np.isfinite(c).all():
        raise ValueError("cube contains NaN or inf")
    if c.min() < 0:
        raise ValueError(f"cube must be a non-negative reflectance, got a minimum of {c.min():g}")
    shape = [1] * c.ndim
    shape[axis] = wl.size
    lit = c * np.interp(wl, ill.wavelengths, ill.values).reshape(shape)
    peak = lit.max()
    if not peak > 0:
        raise ValueError("cube is all zero under this illuminant: nothing to scale to a peak of 1")
    return lit / peak
