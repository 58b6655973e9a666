"""Unit checks shared by every entry that takes wavelengths."""

from __future__ import annotations

import numpy as np

from .validate import real_array

#: Plausible band centres in nm (200 nm UV to 20 µm thermal infrared); outside is a unit error.
WAVELENGTH_RANGE_NM = (200.0, 20000.0)


def check_wavelengths_nm(values, what: str = "wavelengths") -> np.ndarray:
    """``values`` as a float array of nanometres, or a ``ValueError`` naming the unit.

    Values must be finite and lie in :data:`WAVELENGTH_RANGE_NM`; values
    below 30 are called out as micrometres (the usual slip).
    """
    wl = real_array(what, values, finite=False)
    lo, hi = WAVELENGTH_RANGE_NM
    if wl.size == 0:
        raise ValueError(f"{what}: no values")
    if not np.all(np.isfinite(wl)) or wl.min() < lo or wl.max() > hi:
        finite = wl[np.isfinite(wl)]
        shown = f"{finite.min():g}–{finite.max():g}" if finite.size else "no finite values"
        if finite.size < wl.size:
            shown += f" and {wl.size - finite.size} NaN or infinite"
        micro = finite.size and finite.max() < 30
        hint = " (they look like micrometres: multiply by 1000)" if micro else ""
        raise ValueError(f"{what} must be nanometres in {lo:g}–{hi:g}, got {shown}{hint}")
    return wl
