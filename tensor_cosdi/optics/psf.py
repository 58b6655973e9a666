"""Incoherent PSFs from a pupil, Zernike aberrations and defocus (SPEC §8, thesis Equation 51-53).

The field in the image plane is the Fraunhofer transform of the pupil
function, evaluated directly at the sensor's pixel positions by two small
matrix DFTs (no FFT padding, so any pixel pitch and wavelength is sampled
exactly):

``E(x, y) = Σ_{u,v} A(u, v) exp(j 2π W(u, v)) exp(j Ω (u² + v²)/r²) exp(−j 2π (x u + y v)/(λ z_i))``

``PSF = |E|²`` averaged over ``supersample²`` points per pixel and normalised
to sum 1.  ``W = Σ_j a_j Z_j`` in waves (unit-RMS Noll Zernikes), and the
defocus coefficient ``Ω = (π/λ)(1/z + 1/z_i − 1/f) r²`` (Eq. 51/53) with the
sensor at ``z_i`` focused on ``focus_mm`` (``1/z_i = 1/f − 1/focus``).
"""

from __future__ import annotations

import numbers

import numpy as np

from .._units import check_wavelengths_nm
from ..validate import integer, number, real_array
from .zernike import zernike as _zernike

__all__ = [
    "Lens", "pupil_psf", "psf", "psf_stack", "sweep_psf_stack", "defocus_coefficient",
    "psf_width", "PSFCropWarning",
]  # fmt: skip


class PSFCropWarning(UserWarning):
    """A PSF crop holds too little of the PSF's light: renormalised to the crop, it is a different
    PSF from the optics'."""


#: Most pupil samples across a PSF's pupil (a defocus or aberration that needs more is refused:
#: the pupil grid alone would hold more than 16 M complex values).
MAX_PUPIL_SAMPLES = 4096
#: Most sub-samples per pixel side.
MAX_SUPERSAMPLE = 64


def _pos(name, v, allow_inf=False):
    """A number > 0 (``inf`` too with ``allow_inf``); booleans and strings are errors."""
    if allow_inf and isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)):
        if float(v) == np.inf:
            return np.inf
    return number(name, v, low=0, low_open=True)


def _aberrations(zernikes) -> dict[int, float]:
    if zernikes is None:
        return {}
    if not isinstance(zernikes, dict):
        raise ValueError(
            f"zernike must be a dict {{Noll index: coefficient in waves}}, got {zernikes!r}"
        )
    out = {}
    for j, a in zernikes.items():
        if isinstance(j, bool) or not isinstance(j, numbers.Integral) or j < 1:
            raise ValueError(f"Zernike keys are Noll indices ≥ 1, got {j!r}")
        a = float(a)
        if not np.isfinite(a):
            raise ValueError(f"Zernike coefficient of Z{j} must be finite, got {a!r}")
        out[int(j)] = a
    return out


class Lens:
    """An imaging lens with a circular pupil: what :func:`psf` needs to know.

    Parameters
    ----------
    focal_mm : float
        Focal length.
    aperture_radius_mm : float
        Pupil radius ``r`` (f-number = focal / (2 r)).
    focus_mm : float
        Object distance in focus (``inf`` allowed); fixes the sensor distance
        ``z_i`` by the thin-lens law.
    pixel_um : float
        Sensor pixel pitch.

    Examples
    --------
    >>> lens = Lens(focal_mm=50, aperture_radius_mm=2.5, focus_mm=1000, pixel_um=6)
    >>> round(lens.image_distance_mm, 3)
    52.632
    """

    def __init__(
        self,
        *,
        focal_mm: float = 50.0,
        aperture_radius_mm: float = 2.5,
        focus_mm: float = 1000.0,
        pixel_um: float = 6.0,
    ):
        self.focal_mm = _pos("focal_mm", focal_mm)
        self.aperture_radius_mm = _pos("aperture_radius_mm", aperture_radius_mm)
        self.focus_mm = _pos("focus_mm", focus_mm, allow_inf=True)
        self.pixel_um = _pos("pixel_um", pixel_um)
        if self.focus_mm <= self.focal_mm:
            raise ValueError(
                f"focus_mm ({self.focus_mm:g}) must exceed focal_mm ({self.focal_mm:g}) to form a "
                f"real image"
            )
        self.image_distance_mm = 1.0 / (1.0 / self.focal_mm - 1.0 / self.focus_mm)

    def __repr__(self):
        return (
            f"Lens(focal_mm={self.focal_mm:g}, aperture_radius_mm={self.aperture_radius_mm:g}, "
            f"focus_mm={self.focus_mm:g}, pixel_um={self.pixel_um:g})"
        )


def _wavelength(wavelength_nm) -> float:
    """One wavelength in nm (checked for its unit) as millimetres."""
    w = number("wavelength_nm", wavelength_nm)
    return float(check_wavelengths_nm([w], "wavelength_nm")[0]) * 1e-6


def defocus_coefficient(lens: Lens, wavelength_nm: float, depth_mm: float) -> float:
    """``Ω = (π/λ)(1/z + 1/z_i − 1/f) r²`` in radians at the pupil edge (Equation 51)."""
    lam = _wavelength(wavelength_nm)
    z = _pos("depth_mm", depth_mm, allow_inf=True)
    return float(
        np.pi
        / lam
        * (1.0 / z + 1.0 / lens.image_distance_mm - 1.0 / lens.focal_mm)
        * lens.aperture_radius_mm**2
    )


def pupil_psf(
    wavelength_nm: float,
    *,
    lens: Lens,
    size: int = 15,
    omega: float = 0.0,
    zernike=None,
    pupil_samples: int | None = None,
    supersample: int = 3,
    return_share: bool = False,
):
    """PSF (``size × size``, sums to 1) of ``lens`` at one wavelength for a defocus ``omega`` (rad)
    and aberrations.

    ``zernike`` maps Noll indices to coefficients in waves (e.g. ``{6: 0.9}``,
    the thesis' vertical astigmatism).  ``pupil_samples`` points across the
    pupil diameter (default: enough to sample the pupil phase at ≤ 1 rad
    per step, at least 64).  ``return_share=True`` also returns the share of
    the PSF's light inside the crop, before it is renormalised: the crop's
    intensity against the whole image plane's, which Parseval's theorem
    gives from the pupil (accurate to ≈ 2 %: 0.99 for a 41-pixel crop of an
    in-focus f/16.7 PSF, 0.22 for a 9-pixel crop of 0.9 wave of Z6).
    """
    if (
        isinstance(size, bool)
        or not isinstance(size, numbers.Integral)
        or size < 1
        or size % 2 == 0
    ):
        raise ValueError(f"size must be an odd integer ≥ 1 (the PSF is centred), got {size!r}")
    if (
        isinstance(supersample, bool)
        or not isinstance(supersample, numbers.Integral)
        or not 1 <= supersample <= MAX_SUPERSAMPLE
    ):
        raise ValueError(
            f"supersample must be an integer in 1…{MAX_SUPERSAMPLE}, got {supersample!r}"
        )
    lam = _wavelength(wavelength_nm)
    omega = number("omega", omega)
    ab = _aberrations(zernike)
    if pupil_samples is None:
        slope = 2 * abs(omega) + 2 * np.pi * sum(abs(a) for a in ab.values()) * 8
        if slope > MAX_PUPIL_SAMPLES:
            raise ValueError(
                f"a defocus of {omega:.3g} rad (and these aberrations) needs {slope:.3g} pupil "
                f"samples; at most {MAX_PUPIL_SAMPLES}: the point is too far out of focus for a "
                "pupil-sampled PSF (is depth_mm in millimetres, beyond the lens' focal length?)"
            )
        pupil_samples = int(max(64, np.ceil(slope)))
    else:
        pupil_samples = integer("pupil_samples", pupil_samples, low=2, high=MAX_PUPIL_SAMPLES)
    r = lens.aperture_radius_mm
    u = (np.arange(pupil_samples) + 0.5) / pupil_samples * 2 - 1  # normalised, (-1, 1)
    U, V = np.meshgrid(u, u, indexing="ij")
    rho = np.hypot(U, V)
    inside = rho <= 1
    theta = np.arctan2(V, U)
    W = np.zeros_like(rho)
    for j, a in ab.items():
        W += a * _zernike(j, np.minimum(rho, 1.0), theta)
    pupil = inside * np.exp(1j * (2 * np.pi * W + omega * rho**2))
    # pixel sub-sample positions on the sensor (mm), centred on the middle pixel
    p = lens.pixel_um * 1e-3
    sub = (np.arange(size * supersample) - (size * supersample - 1) / 2) * p / supersample
    k = -2j * np.pi / (lam * lens.image_distance_mm)
    M = np.exp(k * np.outer(sub, u * r))  # (positions, pupil samples)
    E = M @ pupil @ M.T
    I = np.abs(E) ** 2
    I = I.reshape(size, supersample, size, supersample).mean(axis=(1, 3))
    s = I.sum()
    if not s > 0:
        raise ValueError("the PSF vanished on this grid; increase size")
    if not return_share:
        return I / s
    du = 2 * r / pupil_samples  # pupil sample spacing (mm): ∫|E|² = (λ zᵢ)² Σ|P|² / du²
    total = (lam * lens.image_distance_mm) ** 2 * float(np.sum(np.abs(pupil) ** 2)) / du**2
    return I / s, float(s * p**2 / total)


def psf(
    wavelength_nm: float,
    depth_mm: float,
    *,
    lens: Lens | None = None,
    zernike=None,
    size: int = 15,
    supersample: int = 3,
    pupil_samples: int | None = None,
    return_share: bool = False,
):
    """PSF of a point at ``depth_mm`` imaged at ``wavelength_nm`` (nm) through ``lens`` with
    aberrations (``return_share``: see :func:`pupil_psf`).

    Parameters
    ----------
    wavelength_nm, depth_mm : float
    lens : Lens, optional
        Default :class:`Lens` () (50 mm, f/10, focused at 1 m, 6 µm pixels).
    zernike : dict {Noll index: waves}, optional
        Fixed aberration (e.g. the deformable mirror's ``{6: 0.9}``).
    size : odd int
        Side of the PSF in pixels.

    Returns
    -------
    ndarray (size, size), non-negative, sums to 1.

    Examples
    --------
    >>> lens = Lens(focal_mm=50, aperture_radius_mm=2.5, focus_mm=1000, pixel_um=6)
    >>> h = psf(550, 1000, lens=lens, size=11)
    >>> h.shape, round(float(h.sum()), 12), bool(h[5, 5] == h.max())
    ((11, 11), 1.0, True)
    """
    lens = Lens() if lens is None else lens
    omega = defocus_coefficient(lens, wavelength_nm, depth_mm)
    return pupil_psf(
        wavelength_nm,
        lens=lens,
        size=size,
        omega=omega,
        zernike=zernike,
        pupil_samples=pupil_samples,
        supersample=supersample,
        return_share=return_share,
    )


def psf_stack(
    wavelengths_nm,
    depths_mm,
    *,
    lens: Lens | None = None,
    zernike=None,
    size: int = 15,
    supersample: int = 3,
    min_share: float | None = 0.9,
) -> np.ndarray:
    """PSFs of every (band, depth plane) pair, shaped ``(size, size, Nλ, Nz)`` for
    :class:`~tensor_cosdi.systems.CASSDIDFA`.

    Each PSF is renormalised to its crop; where a crop holds less than
    ``min_share`` of a PSF's light (:func:`pupil_psf`'s ``return_share``) a
    :class:`PSFCropWarning` says so — that renormalised PSF is not the
    optics' (a 9-pixel crop of 0.9 wave of Z6 holds 9-22 % of it).
    ``min_share=None`` checks nothing.

    Depth plane ``z`` of the cube is the scene at ``depths_mm[z]``; the fixed
    aberration ``zernike`` (thesis: ``{6: 0.9}``, vertical astigmatism,
    Sec. 4.3.1) is added to every PSF.  ``zernike=None`` gives the pure-defocus
    "CASSDI-DFD" baseline.

    Examples
    --------
    >>> P = psf_stack([500, 600], [800, 1000, 1300], size=41, zernike={6: 0.9})
    >>> P.shape, bool(np.allclose(P.sum(axis=(0, 1)), 1))
    ((41, 41, 2, 3), True)
    """
    lam, dep = _lists(wavelengths_nm=wavelengths_nm, depths_mm=depths_mm)
    out = _psf_grid(lens, lam, dep, None, zernike, size, supersample, min_share, "psf_stack")
    return out[..., 0]


def sweep_psf_stack(
    wavelengths_nm, depths_mm, focus_mm, *, lens: Lens | None = None, zernike=None,
    size: int = 41, supersample: int = 3, min_share: float | None = 0.9,
) -> np.ndarray:  # fmt: skip
    """PSFs of a focal sweep, ``(size, size, Nλ, Nz, K)`` for
    :class:`~tensor_cosdi.systems.CASSDIDFA`: at step ``k`` the deformable
    mirror refocuses the lens on ``focus_mm[k]`` (it adds the defocus ``−Ω(λ,
    focus_mm[k])``, Z4) on top of the fixed aberration ``zernike``; a point
    at ``depths_mm[z]`` then has the defocus ``Ω(λ, depths_mm[z]) − Ω(λ,
    focus_mm[k])``.

    ``min_share`` as for :func:`psf_stack`.

    Examples
    --------
    >>> P = sweep_psf_stack([550], [900, 1200], [900, 1200], size=21)
    >>> P.shape, bool(P[10, 10, 0, 0, 0] > P[10, 10, 0, 0, 1])  # plane 0 sharpest at step 0
    ((21, 21, 1, 2, 2), True)
    """
    lam, dep, foc = _lists(wavelengths_nm=wavelengths_nm, depths_mm=depths_mm, focus_mm=focus_mm)
    return _psf_grid(lens, lam, dep, foc, zernike, size, supersample, min_share, "sweep_psf_stack")


def _lists(**named):
    """The named sequences as non-empty 1-D float arrays, or a ``ValueError`` naming them."""
    out = [np.atleast_1d(real_array(k, v, finite=False)) for k, v in named.items()]
    if any(v.ndim != 1 or not v.size for v in out):
        raise ValueError(f"{' and '.join(named)} must be non-empty 1-D lists")
    return out


def _psf_grid(lens, lam, dep, foc, zernike, size, supersample, min_share, caller):
    """PSFs ``(size, size, Nλ, Nz, K)`` of the planes ``dep`` with the lens refocused on each of
    ``foc`` by the mirror (``None``: not refocused, ``K = 1``); a :class:`PSFCropWarning` when
    a crop holds less than ``min_share`` of a PSF's light."""
    lens = Lens() if lens is None else lens
    steps = [None] if foc is None else list(foc)
    out = np.empty((size, size, lam.size, dep.size, len(steps)))
    worst = (2.0, None, None)
    for i, w in enumerate(lam):
        for k, f in enumerate(steps):
            for z, d in enumerate(dep):
                omega = defocus_coefficient(lens, w, d)
                if f is not None:
                    omega -= defocus_coefficient(lens, w, f)
                out[:, :, i, z, k], share = pupil_psf(
                    w, lens=lens, size=size, omega=omega, zernike=zernike,
                    supersample=supersample, return_share=True,
                )  # fmt: skip
                worst = min(worst, (share, w, d), key=lambda t: t[0])
    if min_share is not None and worst[0] < min_share:
        import warnings

        warnings.warn(
            f"{caller}: a {size}×{size} crop holds {worst[0]:.0%} of the PSF's light at "
            f"{worst[1]:g} nm, {worst[2]:g} mm (below min_share={min_share}); renormalised to the "
            "crop it is a different PSF — pass a larger size (or min_share=None)",
            PSFCropWarning,
            stacklevel=3,
        )
    return out


def psf_width(h) -> float:
    """RMS radius of a PSF in pixels, ``sqrt(Σ h · |x − x̄|²) / sqrt(Σ h)``."""
    h = real_array("the PSF", h)
    if h.ndim != 2 or not h.sum() > 0:
        raise ValueError(f"psf_width needs a 2-D PSF with positive sum, got shape {h.shape}")
    h = h / h.sum()
    i, j = np.indices(h.shape)
    ci, cj = (h * i).sum(), (h * j).sum()
    return float(np.sqrt((h * ((i - ci) ** 2 + (j - cj) ** 2)).sum()))
