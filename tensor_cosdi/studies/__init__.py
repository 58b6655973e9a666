"""Simulation studies: a seeded (system, scene, measurement) problem for every imager,
comparisons, sweeps on Dask, and the design studies of the thesis.

:func:`make_problem` builds what the demo, the benchmarks and the quality
tests share: one of the five imagers (or a CASSI baseline) with seeded codes,
a scene of :mod:`tensor_cosdi.scenes` shaped for it, and a noisy measurement.
:func:`compare` runs reconstruction methods on a problem and scores them.
"""

from ..optics.design import prism_grid
from .cluster import local_client
from .condition import conditioning, conditioning_design, vsi_arms
from .design import (
    c3slfi_sparsity,
    c3slfi_table,
    colour_code_design,
    cs2li_code_design,
    cs2li_comparison,
)
from .imagers import vsi_comparison, vsi_ratio
from .learned import learned_code, learned_imagers
from .problems import (
    SCENES,
    SYSTEMS,
    Problem,
    compare,
    make_problem,
    reconstruction_run,
    score,
    score_depth,
    spectral_view,
)
from .sweeping import sweep, write_csv
from .zernike import zernike_design

__all__ = [
    "SYSTEMS",
    "SCENES",
    "Problem",
    "make_problem",
    "compare",
    "score",
    "score_depth",
    "spectral_view",
    "sweep",
    "local_client",
    "conditioning",
    "conditioning_design",
    "vsi_arms",
    "prism_grid",
    "colour_code_design",
    "cs2li_code_design",
    "cs2li_comparison",
    "vsi_comparison",
    "vsi_ratio",
    "learned_code",
    "learned_imagers",
    "zernike_design",
    "c3slfi_table",
    "c3slfi_sparsity",
    "reconstruction_run",
    "write_csv",
]
