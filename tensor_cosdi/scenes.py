"""Seeded scenes built from real measured data that installs with the dependencies.

For now: a ColorChecker scene from colour-science's measured reflectances
(the reconstruction issue adds photographs, spectral-depth, light-field and
structured-light scenes).
"""

from __future__ import annotations

import warnings

import numpy as np

from .operators import validate_shape

__all__ = ["default_wavelengths", "colorchecker"]


def default_wavelengths(n_bands: int = 28, start: float = 450.0, stop: float = 650.0) -> np.ndarray:
    """``n_bands`` evenly spaced wavelengths in nm (default 28 bands, 450–650 nm)."""
    (n_bands,) = validate_shape((n_bands,), "n_bands")
    if not (np.isfinite(start) and np.isfinite(stop) and 0 < start < stop):
        raise ValueError(f"need 0 < start < stop (nm), got start={start}, stop={stop}")
    return np.linspace(start, stop, n_bands)


def _import_colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # colour warns when matplotlib is absent
        import colour
    return colour


def colorchecker(shape=(64, 96), wavelengths=None, *, chart: str = "ColorChecker N Ohta", dtype="float64"):
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
    wl = default_wavelengths() if wavelengths is None else np.asarray(wavelengths, dtype=float)
    if wl.ndim != 1 or wl.size == 0 or not np.isfinite(wl).all():
        raise ValueError(f"wavelengths must be a non-empty 1-D array of finite nm, got {wl!r}")
    if wl.min() < 380 or wl.max() > 780:
        raise ValueError(
            f"wavelengths must lie within the measured 380–780 nm, got {wl.min():g}–{wl.max():g} nm"
        )
    colour = _import_colour()
    charts = colour.SDS_COLOURCHECKERS
    if chart not in charts:
        raise ValueError(f"unknown chart {chart!r}; choose one of {sorted(charts)}")
    sds = list(charts[chart].values())
    spectra = np.stack([np.asarray(sd[wl], dtype=float) for sd in sds])  # (24, Nλ)
    rows = np.minimum((np.arange(nx) * 4) // nx, 3)
    cols = np.minimum((np.arange(ny) * 6) // ny, 5)
    patch = rows[:, None] * 6 + cols[None, :]
    return spectra[patch].astype(dtype)
