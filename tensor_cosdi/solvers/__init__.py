"""Reconstruction methods behind :func:`tensor_cosdi.reconstruct` (SPEC §5, §6).

So far: the harness (:class:`Result`, the registry) and regularised least
squares (``"lsq"``).  The online Tucker dictionary ADMM (``"otd"``), WDCT-ADMM
and GAP-TV are issue 4's remaining work.
"""

from . import lsq  # noqa: F401  (registers "lsq")
from ._base import Result, methods, reconstruct, register_method
from .lsq import operator_scale, regularised_lsq

__all__ = ["Result", "reconstruct", "methods", "register_method", "regularised_lsq", "operator_scale"]
