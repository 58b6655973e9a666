"""The double Amici prism: ray trace, deviation, design and the dispersion shear (SPEC §8, thesis
App. B)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validate import number, real_array
from .glass import _glass

__all__ = ["DoubleAmiciPrism", "NoDesign", "THESIS_FIELD_DEG"]

#: Half field of view of the thesis' lens–detector pair (100 mm, 4 mm detector): ``atan(4 / 200)``
#: in degrees,
#: the ``|θ0| ≤ 2.29°`` range Alg. 8 averages over.
THESIS_FIELD_DEG = float(np.rad2deg(np.arctan(4.0 / 200.0)) * 2)


def _finite(name, value):
    v = real_array("value", value, finite=False)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


class NoDesign(ValueError):
    """No ``φ3`` in the range searched zeroes the deviation (:meth:`DoubleAmiciPrism.design`):
    the inputs are valid, the design does not exist."""


@dataclass(frozen=True)
class DoubleAmiciPrism:
    """A double Amici prism: glass 1 | glass 2 | glass 1, symmetric (thesis Figure 92-95).

    Parameters
    ----------
    phi1, phi3 : float
        The apex angles of the thesis (degrees): the outer wedges have apex
        ``α1 = 180° − (φ1 + φ3)``, the middle wedge ``|α2| = 180° − 2 φ3``.
        The prism built for the thesis has ``φ1 = 85.9°``, ``φ3 = 73.7°``
        (zero deviation near 570 nm).
    glass1, glass2 : str or Glass
        Outer and middle glasses (thesis: N-SK2 and SF4, Eq. 188-189).

    Notes
    -----
    :meth:`deviation` is Alg. 7 (Eq. 172-186) with angles in radians inside:
    ``α1 = π − (φ1 + φ3)``, ``α2 = −(π − 2φ3)``, ``β1 = −α1 − α2/2``, then
    Snell's law at the four faces, ``θ5 = θ4' − β1`` and ``δ = θ0 − θ5``.

    Examples
    --------
    >>> prism = DoubleAmiciPrism(phi1=85.9, phi3=73.7)
    >>> abs(prism.deviation(570.0)) < 0.05
    True
    >>> s = prism.shifts([450, 550, 650], distance_mm=30, pixel_um=6)
    >>> float(s[0]), bool(40 < s[-1] < 80)
    (0.0, True)
    """

    phi1: float = 85.9
    phi3: float = 73.7
    glass1: object = "N-SK2"
    glass2: object = "SF4"

    def __post_init__(self):
        for name in ("phi1", "phi3"):
            v = getattr(self, name)
            if not (
                isinstance(v, (int, float, np.floating, np.integer))
                and not isinstance(v, (bool, np.bool_))
                and np.isfinite(v)
                and 0 < v < 180
            ):
                raise ValueError(f"{name} must be an angle in degrees in (0, 180), got {v!r}")
        if self.phi1 + self.phi3 >= 180:
            raise ValueError(
                "phi1 + phi3 must be < 180° (outer apex α1 = 180° − (φ1 + φ3) > 0), got "
                f"{self.phi1 + self.phi3:g}"
            )
        if not 45 < self.phi3 < 90:
            raise ValueError(
                "phi3 must lie in (45°, 90°) so the middle apex 180° − 2φ3 is in (0°, 90°), got "
                f"{self.phi3:g}"
            )
        _glass(self.glass1), _glass(self.glass2)  # unknown glass names fail here

    @property
    def apex_angles(self) -> tuple[float, float]:
        """``(α1, |α2|)`` in degrees: apex of each outer wedge and of the middle wedge."""
        return 180.0 - (self.phi1 + self.phi3), 180.0 - 2 * self.phi3

    def _trace(self, wavelength_nm, theta0_deg):
        lam = _finite("wavelength_nm", wavelength_nm)
        th0 = np.deg2rad(_finite("theta0", theta0_deg))
        p1, p3 = np.deg2rad(self.phi1), np.deg2rad(self.phi3)
        a1 = np.pi - (p1 + p3)
        a2 = -(np.pi - 2 * p3)
        b1 = -a1 - a2 / 2
        n1 = _glass(self.glass1).index(lam)
        n2 = _glass(self.glass2).index(lam)

        def snell(ratio, angle, face):
            s = ratio * np.sin(angle)
            if np.any(np.abs(s) > 1):
                raise ValueError(
                    f"total internal reflection at face {face} of the prism (φ1={self.phi1:g}°, "
                    f"φ3={self.phi3:g}°): "
                    "no ray leaves for these angles"
                )
            return np.arcsin(s)

        t1p = snell(1 / n1, th0 - b1, 1)
        t2p = snell(n1 / n2, t1p - a1, 2)
        t3p = snell(n2 / n1, t2p - a2, 3)
        t4p = snell(n1, t3p - a1, 4)
        return np.rad2deg(t4p - b1)

    def exit_angle(self, wavelength_nm, theta0=0.0):
        """``θ5`` in degrees: angle of the emerging ray to the optical axis (Equation 184)."""
        out = self._trace(wavelength_nm, theta0)
        return float(out) if np.ndim(out) == 0 else out

    def deviation(self, wavelength_nm, theta0=0.0):
        """Deviation ``δ = θ0 − θ5`` in degrees (Algorithm 7) for incidence ``theta0`` (degrees).

        Broadcasts ``wavelength_nm`` (nm) against ``theta0``.
        """
        out = _finite("theta0", theta0) - self._trace(wavelength_nm, theta0)
        return float(out) if np.ndim(out) == 0 else out

    def mean_deviation(
        self, wavelength_nm, *, field_deg: float = THESIS_FIELD_DEG, n_angles: int = 41
    ):
        """Deviation averaged over incidences ``θ0 ∈ [−field/2, field/2]`` (Algorithm 8), degrees.

        ``field_deg`` is the full angular field (thesis: 2.29°, a 4 mm detector
        behind a 100 mm lens); ``n_angles`` evenly spaced incidences.
        """
        number("field_deg", field_deg, low=0, high=180, high_open=True)
        if (
            isinstance(n_angles, bool)
            or not isinstance(n_angles, (int, np.integer))
            or n_angles < 1
        ):
            raise ValueError(f"n_angles must be a positive integer, got {n_angles!r}")
        lam = _finite("wavelength_nm", wavelength_nm)
        th = np.linspace(-field_deg / 2, field_deg / 2, n_angles) if n_angles > 1 else np.zeros(1)
        d = self.deviation(lam[..., None], th).mean(axis=-1)
        return float(d) if np.ndim(d) == 0 else d

    def dispersion(
        self, wavelength_min_nm: float = 450.0, wavelength_max_nm: float = 650.0, theta0=0.0
    ) -> float:
        """``Δ = δ(λmax) − δ(λmin)`` in degrees (Equation 187)."""
        return float(
            self.deviation(wavelength_max_nm, theta0) - self.deviation(wavelength_min_nm, theta0)
        )

    def shear(self, wavelength_nm, distance_mm: float, *, center_nm: float = 570.0, theta0=0.0):
        """Lateral displacement ``S(λ)`` in mm on a plane ``distance_mm`` behind the prism (Eq.
        191).

        ``S(λ) = x · [tan θ5(λ) − tan θ5(λc)]``: where the ray of wavelength
        ``λ`` lands relative to the ray of the centre wavelength, so
        ``S(λc) = 0`` as the thesis requires.  (Eq. 191 as printed,
        ``x·[tan θ5 + tan(δ(λ) + θ5)]``, is constant in ``λ`` when ``δ = θ0 − θ5``;
        the sentence around it defines the quantity used here.)
        """
        if not (np.isfinite(distance_mm) and distance_mm >= 0):
            raise ValueError(f"distance_mm must be a finite distance ≥ 0, got {distance_mm!r}")
        t = np.deg2rad(self._trace(wavelength_nm, theta0))
        tc = np.deg2rad(self._trace(center_nm, theta0))
        out = distance_mm * (np.tan(t) - np.tan(tc))
        return float(out) if np.ndim(out) == 0 else out

    def shifts(
        self,
        wavelengths_nm,
        distance_mm: float,
        pixel_um: float,
        *,
        theta0=0.0,
        integer: bool = False,
    ):
        """Per-band shifts in pixels for a sensor ``distance_mm`` behind the prism, first band 0.

        ``|S(λ_l) − S(λ_0)| / pixel`` — ready for the ``shifts=`` argument of
        every system (dispersion runs towards larger column index, SPEC §1;
        which physical direction that is, is a mirror choice).

        Parameters
        ----------
        wavelengths_nm : sequence of float
            Band centres, strictly increasing.
        distance_mm : float
            Prism–sensor distance (thesis prototype: 30 mm).
        pixel_um : float
            Pixel pitch (thesis camera: 6 µm).
        integer : bool
            Round to whole pixels (then the shear is an integer shift);
            otherwise fractional shifts (linear interpolation in the shear).

        Raises
        ------
        ValueError
            If ``S`` is not monotonic over the bands (then no non-decreasing
            shift list exists).
        """
        lam = _finite("wavelengths_nm", wavelengths_nm).reshape(-1)
        if lam.size == 0 or np.any(np.diff(lam) <= 0):
            raise ValueError(
                f"wavelengths_nm must be a non-empty, strictly increasing list, got {lam.tolist()}"
            )
        if not (np.isfinite(pixel_um) and pixel_um > 0):
            raise ValueError(f"pixel_um must be a pitch > 0 µm, got {pixel_um!r}")
        s = self.shear(lam, distance_mm, center_nm=float(lam[0]), theta0=theta0) * 1000.0 / pixel_um
        s = np.atleast_1d(s)
        d = np.diff(s)
        if not (np.all(d >= 0) or np.all(d <= 0)):
            raise ValueError(
                "the prism's shear S(λ) is not monotonic over these wavelengths, so no per-band "
                "shift list "
                f"exists; shear in px: {np.round(s, 3).tolist()}"
            )
        s = np.abs(s)
        return np.round(s).astype(np.int64) if integer else s

    @classmethod
    def design(
        cls,
        *,
        phi1: float = 85.9,
        center_nm: float = 570.0,
        glass1="N-SK2",
        glass2="SF4",
        field_deg: float = 0.0,
        phi3_range=(46.0, 89.9),
    ) -> "DoubleAmiciPrism":
        """The prism with apex ``phi1`` whose ``φ3`` makes the deviation zero at ``center_nm``.

        ``field_deg = 0`` zeroes the on-axis deviation (Alg. 7 with θ0 = 0);
        ``field_deg > 0`` zeroes the field-averaged deviation (Alg. 8).
        Solved by Brent's method (``scipy.optimize.brentq``) over ``phi3_range``.

        Examples
        --------
        >>> p = DoubleAmiciPrism.design(phi1=85.9, center_nm=570.0)
        >>> round(p.phi3, 1), abs(p.deviation(570.0)) < 1e-6
        (73.8, True)
        """
        from scipy.optimize import brentq

        from .._units import check_wavelengths_nm

        # the inputs first: an unknown glass or a NaN angle must not read as "no design"
        _glass(glass1), _glass(glass2)
        number("phi1", phi1, low=0, high=180, low_open=True, high_open=True)
        check_wavelengths_nm([center_nm], "center_nm")
        number("field_deg", field_deg, low=0, high=180, high_open=True)
        try:
            lo, hi = (float(v) for v in phi3_range)
        except (TypeError, ValueError):
            raise ValueError(
                f"phi3_range must be two angles (lo, hi), got {phi3_range!r}"
            ) from None
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"phi3_range must be two finite angles lo < hi, got {phi3_range!r}")

        def f(phi3):
            try:
                p = cls(phi1, phi3, glass1, glass2)
                return (
                    p.mean_deviation(center_nm, field_deg=field_deg)
                    if field_deg > 0
                    else p.deviation(center_nm)
                )
            except ValueError:
                return np.nan

        grid = np.linspace(max(lo, 45.0 + 1e-6), min(hi, 90.0 - 1e-6, 180.0 - phi1 - 1e-6), 200)
        vals = np.array([f(p) for p in grid])
        ok = np.isfinite(vals)
        idx = np.nonzero(ok[:-1] & ok[1:] & (np.sign(vals[:-1]) != np.sign(vals[1:])))[0]
        if idx.size == 0:
            raise NoDesign(
                f"no φ3 in {phi3_range} gives zero deviation at {center_nm:g} nm "
                f"for φ1 = {phi1:g}° "
                f"({glass1}/{glass2}); try another phi1"
            )
        phi3 = brentq(f, grid[idx[0]], grid[idx[0] + 1], xtol=1e-12)
        return cls(phi1, float(phi3), glass1, glass2)
