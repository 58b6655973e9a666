"""Reconstruction methods behind :func:`tensor_cosdi.reconstruct` (SPEC §5, §6).

So far: the harness (:class:`Result`, the registry), regularised least
squares (``"lsq"``) and GAP-TV (``"gap_tv"``).  The online Tucker dictionary
ADMM (``"otd"``) and WDCT-ADMM are issue 4's remaining work.
"""

from ._base import Result, methods, reconstruct, register_method
from .gap_tv import gap_tv, tv_denoise  # importing a method module registers it
from .lsq import regularised_lsq

__all__ = ["Result", "reconstruct", "methods", "register_method", "regularised_lsq", "gap_tv", "tv_denoise"]
