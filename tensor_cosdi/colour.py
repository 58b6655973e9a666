"""Colour previews of spectral cubes (SPEC §9) through colour-science."""

from __future__ import annotations

import warnings

import numpy as np

from . import _backend as B

__all__ = ["to_srgb"]


def _colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # colour warns when matplotlib is absent
        import colour
    return colour


def to_srgb(cube, wavelengths, *, band_axis: int = 2, illuminant: str = "D65", white_balance: bool = True):
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
    colour = _colour()
    c = np.moveaxis(np.asarray(B.to_numpy(cube), dtype=np.float64), band_axis, -1)
    wl = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    if wl.size != c.shape[-1]:
        raise ValueError(f"expected {c.shape[-1]} wavelengths (one per band), got {wl.size}")
    if not np.isfinite(wl).all() or wl.min() < 360 or wl.max() > 830 or (np.diff(wl) <= 0).any():
        raise ValueError(f"wavelengths must increase strictly within 360–830 nm, got {wl.tolist()}")
    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(f"unknown illuminant {illuminant!r}; e.g. 'D65', 'A', 'D50'")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    xyz_bar = np.stack([np.interp(wl, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)], axis=1)
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
    return np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)
