"""Reconstruction methods behind :func:`tensor_cosdi.reconstruct` (SPEC §5, §6).

So far: the harness (:class:`Result`, the registry), regularised least
squares (``"lsq"``) and GAP-TV (``"gap_tv"``).  The online Tucker dictionary
ADMM (``"otd"``) and WDCT-ADMM are issue 4's remaining work.
"""

from . import gap_tv, lsq  # noqa: F401  (register "gap_tv", "lsq")
from ._base import Result, methods, reconstruct, register_method
from .gap_tv import gap_tv, tv_denoise
from .lsq import operator_scale, regularised_lsq

__all__ = ["Result", "reconstruct", "methods", "register_method", "regularised_lsq", "operator_scale", "gap_tv", "tv_denoise"]
