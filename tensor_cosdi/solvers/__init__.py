"""Reconstruction methods behind :func:`tensor_cosdi.reconstruct` (SPEC §5, §6).

The harness (:class:`Result`, the :data:`METHODS` registry), one engine
per splitting (:mod:`~tensor_cosdi.solvers.engine`: ADMM, GAP, FISTA) with
priors as parts (:mod:`~tensor_cosdi.solvers.priors`), and four methods that work on
every system: the online Tucker dictionary ADMM (``"otd"``), ADMM in the
fixed WDCT basis (``"wdct"``), GAP-TV (``"gap_tv"``) and regularised least
squares (``"lsq"``).
"""

from . import denoisers, engine, priors
from ._base import (
    METHODS,
    Method,
    MethodOutput,
    Result,
    SlowSolveWarning,
    methods,
    reconstruct,
    register_method,
    require_system,
    signature_defaults,
)
from .avsi import avsi
from .dcosnet import dcosnet
from .dfa import multiresolution_dfa
from .dictionary import PatchDictionary, dictionary_admm, train_dictionary
from .gap_tv import gap_tv, tv_denoise  # importing a method module registers it
from .lsq import regularised_lsq
from .lytro import lytro_cassi, lytro_dictionary
from .nonlocal_prior import nonlocal_tucker
from .otd import online_tucker_admm, tucker_admm, wdct_admm
from .pnp import pnp_admm, pnp_admm_operator
from .pnp_gap import pnp_fast, pnp_gap
from .split_blur import split_tv
from .tiled import reconstruct_tiled
from .twist import twist_tv

__all__ = [
    "Result",
    "reconstruct",
    "reconstruct_tiled",
    "methods",
    "MethodOutput",
    "SlowSolveWarning",
    "register_method",
    "require_system",
    "signature_defaults",
    "METHODS",
    "Method",
    "engine",
    "priors",
    "regularised_lsq",
    "gap_tv",
    "tv_denoise",
    "online_tucker_admm",
    "wdct_admm",
    "tucker_admm",
    "avsi",
    "pnp_admm",
    "pnp_admm_operator",
    "pnp_gap",
    "pnp_fast",
    "split_tv",
    "dcosnet",
    "twist_tv",
    "dictionary_admm",
    "train_dictionary",
    "lytro_cassi",
    "lytro_dictionary",
    "PatchDictionary",
    "denoisers",
    "multiresolution_dfa",
    "nonlocal_tucker",
]
