"""tensor_cosdi — compressive spectral and spectral-depth imaging on TensorLy.

The public API, re-exported.  Sub-packages load on first use (``tc.systems``,
``tc.reconstruct`` …), so ``import tensor_cosdi`` is quick and a command-line
call pays only for what it touches.  The library logs to the ``"tensor_cosdi"``
logger (a ``NullHandler`` until the application configures logging).
"""

from __future__ import annotations

import importlib
import logging

from ._version import __version__

logging.getLogger(__name__).addHandler(logging.NullHandler())

_SUBPACKAGES = (
    "bases",
    "codes",
    "colour",
    "datasets",
    "depth",
    "io",
    "metrics",
    "noise",
    "operators",
    "optics",
    "plot",
    "scenes",
    "solvers",
    "studies",
    "systems",
    "testing",
    "validate",
)
#: Names re-exported from a sub-package: ``name → sub-package``.
_FROM = {
    "TensorOperator": "operators",
    "reconstruct": "solvers",
    "reconstruct_tiled": "solvers",
    "Result": "solvers",
}

__all__ = [*_SUBPACKAGES, *_FROM, "__version__"]


def __getattr__(name: str):
    if name in _SUBPACKAGES:
        module = importlib.import_module(f".{name}", __name__)
    elif name in _FROM:
        module = getattr(importlib.import_module(f".{_FROM[name]}", __name__), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = module  # later look-ups skip this function
    return module


def __dir__():
    return sorted({*globals(), *__all__})
