"""Optical glasses by their Sellmeier equations (SPEC §8, thesis Equation 188-189)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._registry import Registry
from ..validate import real_array

__all__ = ["Glass", "GLASSES", "register_glass", "refractive_index"]


@dataclass(frozen=True)
class Glass:
    """A glass described by a three-term Sellmeier equation.

    ``n(λ)² = 1 + Σ_i B_i λ² / (λ² − C_i)`` with ``λ`` in micrometres.

    Attributes
    ----------
    name : str
    B : tuple of 3 floats
    C : tuple of 3 floats, µm²
    """

    name: str
    B: tuple
    C: tuple

    def __post_init__(self):
        if len(self.B) != len(self.C) or not self.B:
            raise ValueError(
                f"glass {self.name!r}: B and C must have the same non-zero length, got {self.B}, "
                f"{self.C}"
            )
        if not all(np.isfinite(v) for v in (*self.B, *self.C)):
            raise ValueError(f"glass {self.name!r}: Sellmeier coefficients must be finite")

    def index(self, wavelength_nm):
        """Refractive index at ``wavelength_nm`` (scalar or array, nanometres)."""
        from .._units import check_wavelengths_nm

        lam = check_wavelengths_nm(wavelength_nm, "wavelength_nm")
        l2 = (lam / 1000.0) ** 2
        n2 = 1.0 + sum(b * l2 / (l2 - c) for b, c in zip(self.B, self.C))
        if np.any(n2 <= 0):
            raise ValueError(
                f"glass {self.name!r}: the Sellmeier model is invalid at {wavelength_nm!r} nm "
                "(n² ≤ 0)"
            )
        out = np.sqrt(n2)
        return float(out) if out.ndim == 0 else out


GLASSES = Registry("glass")
"""``NAME → Glass`` (upper-case names), read-only; add yours with :func:`register_glass`."""


def register_glass(name: str, B, C, *, replace: bool = False, _builtin: bool = False) -> Glass:
    """Add a glass (Sellmeier ``B``, ``C`` with ``λ`` in µm) under ``name`` and return it.

    Names are case-insensitive; a name that exists needs ``replace=True`` and
    the catalogue glasses of the library (N-SK2, SF4, N-BK7) cannot be replaced.

    Examples
    --------
    >>> g = register_glass("my-BK7", (1.03961212, 0.231792344, 1.01046945),
    ...                    (0.00600069867, 0.0200179144, 103.560653), replace=True)
    >>> round(g.index(587.6), 4)
    1.5168
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"a glass needs a non-empty name, got {name!r}")
    for what, coeffs in (("B", B), ("C", C)):
        vals = real_array("coeffs", coeffs, finite=False)
        if vals.shape != (3,) or not np.isfinite(vals).all():
            raise ValueError(
                f"glass {name!r}: Sellmeier {what} must be 3 finite numbers, got {coeffs!r}"
            )
    glass = Glass(name, tuple(float(b) for b in B), tuple(float(c) for c in C))
    GLASSES.register(name.upper(), glass, replace=replace, builtin=_builtin)
    return glass


# Thesis Eq. 188 (first and third prisms) and Eq. 189 (middle prism); the Schott catalogue values.
_CATALOGUE = {
    "N-SK2": ((1.28189012, 0.257738258, 0.96818604), (0.0072719164, 0.0242823527, 110.377773)),
    "SF4": ((1.61957826, 0.339493189, 1.02566931), (0.0125502104, 0.0544559822, 117.652222)),
    "N-BK7": ((1.03961212, 0.231792344, 1.01046945), (0.00600069867, 0.0200179144, 103.560653)),
    # more Schott glasses for prism design grids (each gives its catalogue n_d at 587.56 nm to
    # 1e-5: N-SK16 1.62041, N-F2 1.62005, N-SF5 1.67271, N-SF11 1.78472)
    "N-SK16": ((1.34317774, 0.241144399, 0.994317969), (0.00704687339, 0.0229005, 92.7508526)),
    "N-F2": ((1.39757037, 0.159201403, 1.2686543), (0.00995906143, 0.0546931752, 119.248346)),
    "N-SF5": ((1.52481889, 0.187085527, 1.42729015), (0.011254756, 0.0588995392, 129.141675)),
    "N-SF11": ((1.73759695, 0.313747346, 1.89878101), (0.013188707, 0.0623068142, 155.23629)),
}
for _name, (_b, _c) in _CATALOGUE.items():
    register_glass(_name, _b, _c, _builtin=True)
del _name, _b, _c


def _glass(glass) -> Glass:
    if isinstance(glass, Glass):
        return glass
    try:
        return GLASSES[str(glass).upper()]
    except KeyError:  # UnknownNameError; reworded with the hint
        raise ValueError(
            f"unknown glass {glass!r}; known glasses: {sorted(g.name for g in GLASSES.values())} "
            "(add one with register_glass)"
        ) from None


def refractive_index(glass, wavelength_nm):
    """Refractive index of ``glass`` (a name such as ``"N-SK2"``, ``"SF4"``, or a :class:`Glass`).

    Parameters
    ----------
    glass : str or Glass
    wavelength_nm : float or array_like
        Wavelengths in nanometres.

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> round(refractive_index("SF4", 587.56), 4)
    1.7552
    >>> refractive_index("N-SK2", [450, 650]).round(4).tolist()
    [1.6189, 1.6044]
    """
    return _glass(glass).index(wavelength_nm)
