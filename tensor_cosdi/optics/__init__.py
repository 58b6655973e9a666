"""Optics helpers (SPEC §8): glasses, the double Amici prism, Zernike polynomials, PSFs, projected
patterns.

* :func:`refractive_index`, :class:`Glass`, :func:`register_glass` — Sellmeier glasses (N-SK2, SF4,
N-BK7).
* :class:`DoubleAmiciPrism` — ray trace (Alg. 7), field-averaged deviation (Alg. 8), apex-angle
design,
  the shear ``S(λ)`` (Eq. 191) and per-band pixel shifts for any system's ``shifts=``.
* :func:`zernike`, :func:`noll_to_nm` — Noll-ordered, unit-RMS Zernike polynomials.
* :class:`Lens`, :func:`psf`, :func:`psf_stack` — pupil + Zernike + defocus PSFs (Eq. 51-53) for
``CASSDIDFA``.
* :func:`projector_phase`, :func:`phase_shift_patterns`, :func:`gray_code_patterns` —
structured-light patterns.
"""

from .fringes import (
    gray_code_bits,
    gray_code_patterns,
    gray_to_binary,
    phase_shift_patterns,
    projector_phase,
)
from .glass import GLASSES, Glass, refractive_index, register_glass
from .prism import THESIS_FIELD_DEG, DoubleAmiciPrism, NoDesign
from .psf import (
    Lens,
    PSFCropWarning,
    defocus_coefficient,
    psf,
    psf_stack,
    psf_width,
    pupil_psf,
    sweep_psf_stack,
)
from .zernike import NAMES as ZERNIKE_NAMES
from .zernike import noll_to_nm, zernike, zernike_radial

__all__ = [
    "Glass",
    "GLASSES",
    "refractive_index",
    "register_glass",
    "DoubleAmiciPrism",
    "NoDesign",
    "THESIS_FIELD_DEG",
    "zernike",
    "zernike_radial",
    "noll_to_nm",
    "ZERNIKE_NAMES",
    "Lens",
    "psf",
    "psf_stack",
    "pupil_psf",
    "defocus_coefficient",
    "psf_width",
    "PSFCropWarning",
    "sweep_psf_stack",
    "projector_phase",
    "phase_shift_patterns",
    "gray_code_patterns",
    "gray_code_bits",
    "gray_to_binary",
]
