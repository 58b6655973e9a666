"""The thesis' multiresolution reconstruction for CASSDI-DFA (Algorithm 2-4, SPEC §3.2, §6).

Three sub-problems on decimated unknowns, each a TV-regularised least-squares
problem solved by FISTA (gradient step ``x + Aᵀ(g − A x)/L``, TV proximal
step from scikit-image, Nesterov momentum; ``L`` by power iteration) on the
system's operator composed with a lifting to the 4-D cube
``(Nx, Ny, Nλ, Nz)``:

1. **all-in-focus grayscale** ``fg (Nx, Ny)`` (Alg. 2): the cube is
   ``fg / (Nλ Nz)`` replicated over bands and depths;
2. **focal stack** ``ff (Nx, Ny, Nz)`` (Alg. 3): the cube is ``ff / Nλ``
   replicated over bands, started from ``fg / Nz`` and tied to ``fg``
   (``Σ_z ff = fg``, enforced by projection after each GAP step);
3. **all-in-focus spectral** ``fs (Nx, Ny, Nλ)`` (Alg. 4): with the depth
   weights ``w = ff / Σ_z ff`` the cube is ``fs ⊗ w`` — linear in ``fs`` —
   started from ``fg / Nλ`` and tied to ``fg`` (``Σ_l fs = fg``).

The cube is ``fs ⊗ w``.  The depth map is the plane of largest weight
``argmax_z w`` — in the discrete model (Eq. 57-58) ``ff[:, :, z]`` is the
part of the scene *at* depth ``z``, a layer decomposition rather than a set
of differently focused images, so the focus measure of
:func:`tensor_cosdi.depth.depth_from_focus` (for real focal stacks) would
respond to the layer edges instead (the thesis uses a U-Net here).  The
printed algorithms' explicit ``n × n`` inverses are replaced by gradient
steps: the lifted operators have no cheap ``A Aᵀ`` structure, and GAP's
``(εI + A Aᵀ)⁻¹`` by CG at every iteration took 146 s at 64×64×16×3.
"""

from __future__ import annotations

import numpy as np
import tensorly as tl

from .. import _backend as B
from ..operators import Code, Replicate
from . import engine
from ._base import (
    History,
    check_positive,
    register_method,
    relative_residual,
    require_system,
)
from .priors import TV

_check_int = engine.check_int

__all__ = ["multiresolution_dfa", "fista_tv"]


def fista_tv(
    op,
    g,
    start,
    *,
    max_iter: int = 60,
    tv_weight: float = 0.05,
    tol: float = 1e-4,
    project=None,
    desc: str = "FISTA-TV",
    progress: bool = False,
):
    """``min ½‖g − A x‖² + TV(x)`` by FISTA from ``start``; ``project(x)`` (optional) after each TV
    step.

    :func:`tensor_cosdi.solvers.engine.fista` with the
    :class:`~tensor_cosdi.solvers.priors.TV` prior; ``tv_weight / 10`` is
    relative to the robust peak of ``start`` (its 99.9th percentile).  Returns
    ``(x, history, converged)``.
    """
    return engine.fista(
        op,
        g,
        TV(tv_weight / 10),
        start,
        max_iter=max_iter,
        tol=tol,
        project=project,
        progress=progress,
        desc=desc,
    )


def multiresolution_dfa(
    system,
    measurement,
    *,
    max_iter: int = 60,
    tv_weight: float = 0.05,
    tol: float = 1e-4,
    nonneg: bool = True,
    progress: bool = False,
):
    """Multiresolution DFA (thesis Algorithm 2-4) for a :class:`~tensor_cosdi.systems.CASSDIDFA`.
    Registered as ``"dfa"``.

    Parameters
    ----------
    max_iter, tv_weight, tol
        Per stage, as in :func:`fista_tv`.
    nonneg : bool
        Clip the grayscale and spectral stages' estimates at 0 (a cube of
        light).  The focal stack is clipped either way: the depth weights
        ``ff / Σ_z ff`` are a partition of unity only for a non-negative stack.

    Returns
    -------
    cube, history, converged, depth
        ``depth`` (Nx, Ny): index of the depth plane per pixel (float).

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("cassdi_dfa", "chelsea", shape=(32, 32), n_bands=8)
    >>> res = tc.reconstruct(p.system, p.measurement, "dfa", max_iter=10)
    >>> res.cube.shape, res.depth.shape
    ((32, 32, 8, 3), (32, 32))
    """
    require_system("dfa", system)
    tv_weight, tol = (check_positive(n, v) for n, v in (("tv_weight", tv_weight), ("tol", tol)))
    max_iter = _check_int("max_iter", max_iter, 1)
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    g = measurement
    op = system.operator
    nx, ny, nl, nz = system.cube_shape
    kw = dict(max_iter=max_iter, tv_weight=tv_weight, tol=tol, progress=progress)
    hist = History()
    add = hist.extend

    # 1. all-in-focus grayscale
    lift_g = (1.0 / (nl * nz)) * (Replicate((nx, ny, nl), 3, nz) @ Replicate((nx, ny), 2, nl))
    a_g = op @ lift_g
    fg0 = a_g.solve_normal(
        a_g.apply_adjoint(g),
        1e-2 * float(tl.norm(a_g.apply(B.tensor_like(np.ones((nx, ny)), g)))) ** 2 / (nx * ny),
    )
    fg, h, c1 = fista_tv(a_g, g, fg0, desc="DFA fg", **kw)
    if nonneg:
        fg = tl.clip(fg, 0, None)
    add(h)
    # 2. focal stack tied to fg
    lift_f = (1.0 / nl) * Replicate((nx, ny, nz), 2, nl)

    def tie_stack(x):
        return x + ((fg - tl.sum(x, axis=2)) / nz)[..., None]

    ff0 = Replicate((nx, ny), 2, nz).apply(fg / nz)
    ff, h, c2 = fista_tv(op @ lift_f, g, ff0, project=tie_stack, desc="DFA ff", **kw)
    ff = tl.clip(ff, 0, None)
    add(h)
    # 3. all-in-focus spectral with the depth weights of the focal stack
    total = tl.sum(ff, axis=2)
    tiny = 1e-6 * max(float(tl.max(total)), np.finfo(float).tiny)
    w = ff / (total[..., None] + tiny)
    lift_s = Code(w, system.cube_shape, axes=(0, 1, 3)) @ Replicate((nx, ny, nl), 3, nz)

    def tie_bands(x):
        return x + ((fg - tl.sum(x, axis=2)) / nl)[..., None]

    fs0 = Replicate((nx, ny), 2, nl).apply(fg / nl)
    fs, h, c3 = fista_tv(op @ lift_s, g, fs0, project=tie_bands, desc="DFA fs", **kw)
    if nonneg:
        fs = tl.clip(fs, 0, None)
    add(h)
    cube = lift_s.apply(fs)
    hist["residual"][-1] = relative_residual(system, cube, g)
    depth = np.argmax(B.to_numpy(w), axis=2).astype(np.float64)
    return cube, hist, bool(c1 and c2 and c3), B.tensor_like(depth, g)


register_method(
    "dfa",
    multiresolution_dfa,
    summary="multiresolution CASSDI-DFA (thesis Alg. 2-4): grayscale, focal stack, spectral; "
    "depth map",
    systems=("cassdi_dfa",),
    solves=False,  # FISTA stages; one decimated solve for the start
)
