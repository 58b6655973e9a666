"""The imagers of SPEC §3, each a frozen composition of :mod:`tensor_cosdi.operators`.

==========================  ==================================================  =================
system                      cube → measurement                                   ``A Aᵀ``
==========================  ==================================================  =================
:class:`SDCASSI`            ``(Nx, Ny, Nλ) → (Nx, Ny+S[, K])``                    diagonal / K×K
:class:`DDCASSI`            ``(Nx, Ny, Nλ) → (Nx, Ny[, K])``                      diagonal / K×K
:class:`DualCameraCASSI`    ``(Nx, Ny, Nλ) → (Nx, Ny+S, 2)``                      folded banded
:class:`CASSIVSI`           ``(Nx, Ny, Nλ) → (Nx, Ny+S)``                         row-banded
:class:`CASSDIDFA`          ``(Nx, Ny, Nλ, Nz) → (Nx, Ny+S)``                     diagonal; PSFs: CG
:class:`C3SLFI`             ``(Ñ1, Ñ2, N3) → (Ñ1, Ñ2, K)`` or 5-D                  K×K per pixel
:class:`LytroCASSI`         ``(Ñ1, Ñ2, N3) → (Ñ1, Ñ2+S, K+3)``                     folded banded
:class:`CS2LI`              ``(Nx, Ny, Nλ, Nt) → (Nx, Ny, Nt)``                   diagonal
:class:`MuCoSDI`            SL / LF / monocular on the dual-disperser core       diagonal
==========================  ==================================================  =================

``S = ⌈max s_l⌉`` is the extra width the dispersion adds.  Every system has
``cube_shape``, ``measurement_shape``, ``axes``, ``wavelengths``, ``operator``,
``forward``, ``adjoint``, ``simulate``, ``panchromatic`` and ``matrix()`` (the
thesis' explicit sensing matrix, for tests), and ``Cls.example(...)`` builds
a seeded instance.  :data:`REGISTRY` names them all (``"sd_cassi"``,
``"dd_cassi"``, ``"dual_camera_cassi"``, ``"cassi_vsi"``, ``"cassdi_dfa"``,
``"c3slfi"``, ``"lytro_cassi"``, ``"cs2li"``, ``"mu_cosdi"``); each class also carries its
bundle state, frame order, depth channel and seeded problem
(see :class:`System`).
"""

from ._base import System, wavelengths_for
from ._roles import Problem
from .c3slfi import C3SLFI
from .cassdi_dfa import CASSDIDFA
from .cassi import DDCASSI, SDCASSI, DualCameraCASSI
from .cassi_vsi import CASSIVSI
from .cs2li import CS2LI, fringe_cube
from .lytro_cassi import LytroCASSI
from .mu_cosdi import MODALITIES, MuCoSDI
from .registry import REGISTRY, SystemRegistry

for _cls in (
    SDCASSI,
    DDCASSI,
    DualCameraCASSI,
    CASSIVSI,
    CASSDIDFA,
    C3SLFI,
    LytroCASSI,
    CS2LI,
    MuCoSDI,
):
    REGISTRY.register_class(_cls, builtin=True)
del _cls

__all__ = [
    "wavelengths_for",
    "REGISTRY",
    "SystemRegistry",
    "Problem",
    "System",
    "SDCASSI",
    "DDCASSI",
    "DualCameraCASSI",
    "CASSIVSI",
    "CASSDIDFA",
    "C3SLFI",
    "LytroCASSI",
    "CS2LI",
    "MuCoSDI",
    "MODALITIES",
    "fringe_cube",
]
