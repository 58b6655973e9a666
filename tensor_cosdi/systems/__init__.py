"""The imagers of SPEC §3, each a frozen composition of :mod:`tensor_cosdi.operators`.

==========================  ==================================================  =================
system                      cube → measurement                                   ``A Aᵀ``
==========================  ==================================================  =================
:class:`SDCASSI`            ``(Nx, Ny, Nλ) → (Nx, Ny+S[, K])``                    diagonal / K×K
:class:`DDCASSI`            ``(Nx, Ny, Nλ) → (Nx, Ny[, K])``                      diagonal / K×K
:class:`DualCameraCASSI`    ``(Nx, Ny, Nλ) → (Nx, Ny+S, 2)``                      none (CG)
:class:`CASSIVSI`           ``(Nx, Ny, Nλ) → (Nx, Ny+S)``                         row-banded
:class:`CASSDIDFA`          ``(Nx, Ny, Nλ, Nz) → (Nx, Ny+S)``                     diagonal (CG with PSFs)
:class:`C3SLFI`             ``(Ñ1, Ñ2, N3) → (Ñ1, Ñ2, K)`` or 5-D                  K×K per pixel
:class:`CS2LI`              ``(Nx, Ny, Nλ, Nt) → (Nx, Ny, Nt)``                   diagonal
:class:`MuCoSDI`            SL / LF / monocular on the dual-disperser core       diagonal
==========================  ==================================================  =================

``S = ⌈max s_l⌉`` is the extra width the dispersion adds.  Every system has
``cube_shape``, ``measurement_shape``, ``axes``, ``wavelengths``, ``operator``,
``forward``, ``adjoint``, ``simulate``, ``panchromatic`` and ``matrix()`` (the
thesis' explicit sensing matrix, for tests), and ``Cls.example(...)`` builds
a seeded instance.
"""

from ._base import System
from .c3slfi import C3SLFI
from .cassdi_dfa import CASSDIDFA
from .cassi import DDCASSI, SDCASSI, DualCameraCASSI
from .cassi_vsi import CASSIVSI
from .cs2li import CS2LI, fringe_cube
from .mu_cosdi import MODALITIES, MuCoSDI

__all__ = [
    "System",
    "SDCASSI",
    "DDCASSI",
    "DualCameraCASSI",
    "CASSIVSI",
    "CASSDIDFA",
    "C3SLFI",
    "CS2LI",
    "MuCoSDI",
    "MODALITIES",
    "fringe_cube",
]
