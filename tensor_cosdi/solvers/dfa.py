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
from ..bases import KroneckerBasis
from ..operators import Code, Replicate, SumAxis
from . import engine
from ._base import (
    History,
    check_positive,
    register_method,
    relative_change,
    relative_residual,
    require_system,
)
from .priors import TV, rms, robust_peak, soft

_check_int = engine.check_int

__all__ = [
    "multiresolution_dfa", "fista_tv", "admm_stage", "finite_differences",
    "finite_differences_adjoint", "FORMS",
]  # fmt: skip

#: ``form`` of :func:`multiresolution_dfa`: FISTA-TV with hard ties (default) or the printed
#: ADMM of Alg. 2-4.
FORMS = ("fista", "admm")


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


def finite_differences(x):
    """Forward differences along axes 0 and 1 (0 past the last row / column): the ``T`` of
    Eq. 63 (``‖fg‖_TV = ‖T fg‖₁``), stacked on a new last axis.

    Examples
    --------
    >>> import numpy as np
    >>> finite_differences(np.array([[0.0, 1.0], [3.0, 5.0]]))[..., 0].tolist()
    [[3.0, 4.0], [0.0, 0.0]]
    """
    d0 = tl.concatenate([x[1:] - x[:-1], 0 * x[-1:]], axis=0)
    d1 = tl.concatenate([x[:, 1:] - x[:, :-1], 0 * x[:, -1:]], axis=1)
    return tl.stack([d0, d1], axis=-1)


def finite_differences_adjoint(p):
    """``Tᵀ p`` for :func:`finite_differences` (the negative divergence)."""
    p0, p1 = p[..., 0], p[..., 1]
    z0, z1 = 0 * p0[:1], 0 * p1[:, :1]
    a0 = tl.concatenate([z0, p0[:-1]], axis=0) - tl.concatenate([p0[:-1], z0], axis=0)
    a1 = tl.concatenate([z1, p1[:, :-1]], axis=1) - tl.concatenate([p1[:, :-1], z1], axis=1)
    return a0 + a1


def admm_stage(
    op, g, start, *, basis, tv=None, couplings=(), rho=0.5, lam=0.1, max_iter=60, cg_iter=3,
    tol=1e-4, desc="ADMM", progress=False,
):  # fmt: skip
    """One stage of the thesis' DFA reconstruction as printed (Alg. 2-4, Eq. 64, 67, 70):

    ``min ½‖g − A x‖² + Σ (σ/2)‖b − C x‖² + τ_θ‖θ‖₁ + τ_w‖w‖₁`` s.t. ``θ = Ψᵀx``, ``w = T x``

    by ADMM with scaled duals (``θ ← soft(Ψᵀx + ν, τ_θ/α)``, ``ν ← ν + Ψᵀx − θ``, the same for
    ``w``).  The x-step ``(AᵀA + Σ σ CᵀC + α I + α TᵀT) x = Aᵀg + Σ σ Cᵀb + α Ψ(θ − ν) +
    α Tᵀ(w − ν_w)`` runs ``cg_iter`` conjugate-gradient steps from the last ``x`` (the printed
    algorithms invert the matrix explicitly, with ``TᵀT ≈ I``; here ``TᵀT`` is kept exact).

    Parameters
    ----------
    op : TensorOperator
        ``A``, from the stage's unknown to the measurement.
    g, start
        The measurement and the first ``x``.
    basis : dict {mode: transform}
        ``Ψ`` (:class:`~tensor_cosdi.bases.KroneckerBasis` of ``start``'s shape).
    tv : float, optional
        ``τ_w / α`` relative to the robust peak of ``start``; ``None``: no ``w`` split
        (Alg. 3-4).
    couplings : sequence of ``(C, b, sigma)``
        Quadratic ties ``(σ/2)‖b − C x‖²``, ``σ = sigma · ‖A‖²`` (Eq. 66, 69).
    rho, lam
        ``α = rho · ‖A‖²``; ``τ_θ / α = lam · RMS(start)``.
    max_iter, cg_iter, tol
        ADMM iterations, CG steps per x-step, and the stop on the relative change.
        The defaults are :func:`multiresolution_dfa`'s (``form="admm"``).

    Returns
    -------
    x, history, converged
    """
    L = engine.lipschitz(op, start)
    alpha = rho * L
    ties = [(C, b, sigma * L) for C, b, sigma in couplings]
    psi = KroneckerBasis(tuple(tl.shape(start)), basis)
    t_theta = lam * rms(start)
    t_w = None if tv is None else tv * robust_peak(start)

    def normal(v):
        out = op.apply_adjoint(op.apply(v)) + alpha * v
        for C, _, sig in ties:
            out = out + sig * C.apply_adjoint(C.apply(v))
        if t_w is not None:
            out = out + alpha * finite_differences_adjoint(finite_differences(v))
        return out

    solve = engine.cg_solver(normal, rtol=1e-12, maxiter=cg_iter)  # warm-started, inexact
    rhs0 = op.apply_adjoint(g)
    for C, b, sig in ties:
        rhs0 = rhs0 + sig * C.apply_adjoint(b)
    x = start
    theta = psi.analysis(x)
    nu = tl.zeros_like(theta)
    w = None if t_w is None else finite_differences(x)
    nu_w = None if t_w is None else tl.zeros_like(w)
    loop = engine.Loop(max_iter, tol, progress=progress, desc=desc)
    gnorm = max(float(tl.norm(g)), np.finfo(float).tiny)
    for it in loop:
        rhs = rhs0 + alpha * psi.synthesis(theta - nu)
        if t_w is not None:
            rhs = rhs + alpha * finite_differences_adjoint(w - nu_w)
        x_new = solve(rhs, x)
        change = relative_change(x_new, x)
        x = x_new
        a = psi.analysis(x)
        theta = soft(a + nu, t_theta)
        nu = nu + a - theta
        term = t_theta * float(tl.sum(tl.abs(theta)))
        if t_w is not None:
            d = finite_differences(x)
            w = soft(d + nu_w, t_w)
            nu_w = nu_w + d - w
            term += t_w * float(tl.sum(tl.abs(w)))
        if loop.record(
            it, residual_norm=float(tl.norm(op.apply(x) - g)), gnorm=gnorm, change=change,
            prior_term=alpha * term,
        ):  # fmt: skip
            break
    return x, loop.history, loop.converged


def multiresolution_dfa(
    system,
    measurement,
    *,
    max_iter: int = 60,
    tv_weight: float = 0.05,
    tol: float = 1e-4,
    nonneg: bool = True,
    form: str = "fista",
    rho: float = 0.5,
    lam: float = 0.1,
    tv: float = 0.05,
    sigma: float = 0.1,
    cg_iter: int = 3,
    progress: bool = False,
):
    """Multiresolution DFA (thesis Algorithm 2-4) for a :class:`~tensor_cosdi.systems.CASSDIDFA`.
    Registered as ``"dfa"``.

    Parameters
    ----------
    max_iter, tv_weight, tol
        Per stage, as in :func:`fista_tv` (``tv_weight``: the FISTA form only).
    form : {"fista", "admm"}
        ``"fista"`` (default): each stage FISTA-TV, the stages tied by projections
        (``Σ_z ff = fg``, ``Σ_l fs = fg``).  ``"admm"``: the stages as the thesis prints
        them (:func:`admm_stage`): Alg. 2 with TV and wavelet splits, Alg. 3-4 with a
        Symlet-8 ⊗ Symlet-8 ⊗ DCT split and the quadratic ties of Eq. 66 and 69 instead of
        projections.  ``benchmarks/results/thesis_findings.md`` compares the two on the
        report scenes (64×64×16×3, 41-px PSFs, 30 dB, three seeds): the printed form
        gets 0.05 fewer depth planes right in every seed and −0.08 ± 0.10 dB of PSNR
        (inconclusive), so FISTA stays the default.
    rho, lam, tv, sigma, cg_iter
        The ADMM form's penalty (relative to ``‖A‖²``), wavelet threshold (relative to the
        start's RMS), TV threshold (relative to its robust peak; stage 1), tie weight
        (relative to ``‖A‖²``) and CG steps per x-step (see :func:`admm_stage`).  Chosen on
        two tuning scenes (balloons, clay; 64×64×16×3, 41-px pure-defocus PSFs, 30 dB) from
        ρ 0.1 / 0.5 / 1 / 2, λ 0.02-0.3, TV 0.01-0.1, σ 0.1-10: balloons 15.55 dB against
        15.01 at the first guess (λ 0.02, TV 0.02, σ 1) and FISTA's 15.84; clay 20.44
        against FISTA's 19.16 (depth 0.73 against 0.79 planes right).
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
    if form not in FORMS:
        raise ValueError(f"form must be one of {FORMS}, got {form!r}")
    rho, lam, tv, sigma = (
        check_positive(n, v) for n, v in (("rho", rho), ("lam", lam), ("tv", tv), ("sigma", sigma))
    )
    cg_iter = _check_int("cg_iter", cg_iter, 1)
    g = measurement
    op = system.operator
    nx, ny, nl, nz = system.cube_shape
    kw = dict(max_iter=max_iter, tv_weight=tv_weight, tol=tol, progress=progress)
    hist = History()
    add = hist.extend

    # 1. all-in-focus grayscale
    # the scale outside the composition, so that a blur meets the copies it blurs (fused)
    a_g = (1.0 / (nl * nz)) * (op @ Replicate((nx, ny, nl), 3, nz) @ Replicate((nx, ny), 2, nl))
    fg0 = a_g.solve_normal(
        a_g.apply_adjoint(g),
        1e-2 * float(tl.norm(a_g.apply(B.tensor_like(np.ones((nx, ny)), g)))) ** 2 / (nx * ny),
    )
    spatial = {0: "sym8", 1: "sym8"}
    if form == "admm":
        akw = dict(rho=rho, lam=lam, max_iter=max_iter, cg_iter=cg_iter, tol=tol, progress=progress)
        fg, h, c1 = admm_stage(a_g, g, fg0, basis=spatial, tv=tv, desc="DFA fg (Alg. 2)", **akw)
    else:
        fg, h, c1 = fista_tv(a_g, g, fg0, desc="DFA fg", **kw)
    if nonneg:
        fg = tl.clip(fg, 0, None)
    add(h)
    # 2. focal stack tied to fg
    a_f = (1.0 / nl) * (op @ Replicate((nx, ny, nz), 2, nl))

    def tie_stack(x):
        return x + ((fg - tl.sum(x, axis=2)) / nz)[..., None]

    ff0 = Replicate((nx, ny), 2, nz).apply(fg / nz)
    if form == "admm":  # Eq. 66: σ‖fg − Σ_z ff‖² instead of the projection
        tie = [(SumAxis((nx, ny, nz), 2), fg, sigma)]
        ff, h, c2 = admm_stage(
            a_f, g, ff0, basis={**spatial, 2: "dct"}, couplings=tie,
            desc="DFA ff (Alg. 3)", **akw,
        )  # fmt: skip
    else:
        ff, h, c2 = fista_tv(a_f, g, ff0, project=tie_stack, desc="DFA ff", **kw)
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
    if form == "admm":  # Eq. 69: ‖Σ_z ff − Σ_l fs‖² and ‖fg − Σ_l fs‖² instead of the projection
        to_gray = SumAxis((nx, ny, nl), 2)
        ties = [(to_gray, total, sigma), (to_gray, fg, sigma)]
        fs, h, c3 = admm_stage(
            op @ lift_s, g, fs0, basis={**spatial, 2: "dct"}, couplings=ties,
            desc="DFA fs (Alg. 4)", **akw,
        )  # fmt: skip
    else:
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
