"""Matrix-free linear operators on tensors (SPEC §2, §4).

Every imager in :mod:`tensor_cosdi.systems` is a composition of these
primitives; each has an exact adjoint and an explicit sparse matrix for tests.
"""

from .algebra import (
    Adjoint,
    Composition,
    Identity,
    OperatorSum,
    Scaled,
    Stack,
    TensorOperator,
    sensing_gain,
    unvec,
    validate_shape,
    vec,
    vec_index,
    weighted_sum,
)
from .blur import Blur, BlurSum
from .codes import Code
from .gram import Pattern, StructureError, check_structure, probe_structure
from .integrate import Replicate, SumAxis
from .layout import LAYOUTS, LightFieldLayout, Pad, Transpose
from .modes import ModeProduct
from .routing import Routing
from .shear import Shear, parse_shifts, shear_bands, unshear_bands
from .woodbury import (
    Diagonal,
    FoldedBanded,
    PixelBlocks,
    RowBanded,
    conjugate_gradient,
    gram_eigenvalues,
)

__all__ = [
    "TensorOperator",
    "sensing_gain",
    "Composition",
    "OperatorSum",
    "Scaled",
    "Adjoint",
    "Stack",
    "Identity",
    "weighted_sum",
    "ModeProduct",
    "Code",
    "Shear",
    "parse_shifts",
    "shear_bands",
    "unshear_bands",
    "SumAxis",
    "Replicate",
    "Blur",
    "BlurSum",
    "Transpose",
    "Pad",
    "LightFieldLayout",
    "LAYOUTS",
    "Diagonal",
    "PixelBlocks",
    "RowBanded",
    "FoldedBanded",
    "Pattern",
    "StructureError",
    "check_structure",
    "probe_structure",
    "conjugate_gradient",
    "gram_eigenvalues",
    "Routing",
    "vec",
    "unvec",
    "vec_index",
    "validate_shape",
]
