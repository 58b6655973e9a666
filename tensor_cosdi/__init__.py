"""tensor_cosdi — compressive spectral and spectral-depth imaging on TensorLy.

The public API, re-exported.  See ``SPEC.md``/``DESIGN.md`` in the project
docs for the systems and the operator protocol.
"""

from . import (
    bases,
    codes,
    colour,
    datasets,
    depth,
    io,
    metrics,
    noise,
    operators,
    optics,
    plot,
    scenes,
    solvers,
    studies,
    systems,
    testing,
    validate,
)
from ._version import __version__
from .operators import TensorOperator
from .solvers import Result, reconstruct, reconstruct_tiled

__all__ = [
    "plot",
    "optics",
    "depth",
    "io",
    "operators",
    "systems",
    "codes",
    "colour",
    "datasets",
    "bases",
    "testing",
    "metrics",
    "noise",
    "scenes",
    "studies",
    "TensorOperator",
    "reconstruct",
    "reconstruct_tiled",
    "Result",
    "solvers",
    "validate",
    "__version__",
]
