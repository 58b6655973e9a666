"""One reconstruction engine per splitting — ADMM, GAP (accelerated) and FISTA — with priors as
parts.

Every iterative method of :func:`tensor_cosdi.reconstruct` is one of these
loops with a prior (:mod:`tensor_cosdi.solvers.priors`) plugged in:

==========  =====================================================================
engine      iteration (``x`` cube, ``z`` prior variable, ``u`` scaled dual)
==========  =====================================================================
``admm``    ``x ← (AᵀA + ρI)⁻¹(Aᵀg + ρ(z − u))`` (the system's structured
            ``solve_normal``), ``z ← prox(x + u)``, ``u ← u + x − z``
``gap``     ``ĝ ← ĝ + (g − A x)`` (accelerated), ``x ← prox(x + Aᵀ(AAᵀ + εI)⁻¹(ĝ − A x))``
            (the structured ``solve_dual``)
``fista``   ``x ← prox(y + Aᵀ(g − A y)/L)``, Nesterov momentum on ``y``
``twist``   ``x ← (1 − α) x₋₁ + (α − β) x + β prox(x + Aᵀ(g − A x)/L)`` (two-step IST)
==========  =====================================================================

The data step is always the operator's structured solve (diagonal,
per-pixel blocks, banded rows, or CG where ``A Aᵀ`` has no structure);
``admm`` takes a ``normal_solve`` only for coupled problems (PnP's tie).
The loop bookkeeping — iteration cap, relative-change tolerance, tqdm bar,
per-iteration history and timing — is :class:`Loop`, written once.

**One objective convention.**  Every history records
``½‖A x − g‖² + λ R(x)`` with ``λ R`` the prior's :meth:`~priors.Prior.objective`
(``0`` for implicit, plug-and-play priors).  Prior strengths are given
relative to the data, in one place, :meth:`~priors.Prior.setup`: a sparsity
weight ``lam`` is a threshold of ``lam · RMS(start)`` cube units at the
engine's penalty (``λ = lam · RMS(start) · s`` for ADMM with ``ρ = mu · s``),
a TV or denoiser weight ``w`` a denoising strength of ``w · P₉₉.₉|start|``
(the 99.9th percentile, :func:`~priors.robust_peak` — not the maximum, which
one noisy pixel of the start sets); penalties (``ρ``, ``ε``) are relative to the sensing gain
``s = ‖A 1‖² / ‖1‖²`` (:func:`~tensor_cosdi.operators.sensing_gain`),
so no option depends on the measurement's scale.
"""

from __future__ import annotations

import math

import numpy as np
import tensorly as tl

from ..operators import sensing_gain
from ..validate import integer, number
from ._base import History, relative_change

__all__ = [
    "Loop", "admm", "gap", "fista", "twist", "least_norm", "lipschitz", "check_int", "check_relax",
    "check_guard",
]  # fmt: skip


def check_int(name, value, low):
    """``value`` as an int ≥ ``low`` or a ``ValueError`` naming ``name``
    (:func:`tensor_cosdi.validate.integer`)."""
    return integer(name, value, low=low)


class Loop:
    """The bookkeeping every engine shares: cap, tolerance, progress bar, history.

    ``for it in loop:`` yields iteration indices; :meth:`record` appends one
    row of the history and returns ``True`` when the relative change fell
    below ``tol`` (after the first iteration), which also sets
    :attr:`converged`.
    """

    def __init__(
        self,
        max_iter: int,
        tol: float,
        *,
        progress: bool = False,
        desc: str = "",
        objective: bool = True,
    ):
        self.max_iter = check_int("max_iter", max_iter, 1)
        self.objective = bool(objective)  # False: internal stages skip the prior term (NaN)
        self.tol = float(tol)
        self.progress = bool(progress)
        self.desc = desc
        self.history = History()
        self.converged = False

    def __iter__(self):
        from tqdm import tqdm

        return iter(
            tqdm(range(self.max_iter), desc=self.desc, disable=not self.progress, leave=False)
        )

    def record(
        self, it: int, *, residual_norm: float, gnorm: float, change: float, prior_term: float
    ) -> bool:
        self.history.record(
            residual=residual_norm / gnorm,
            change=change,
            objective=0.5 * residual_norm**2 + prior_term,
        )
        if change < self.tol and it > 0:
            self.converged = True
        return self.converged


def check_relax(relax, *, auto: bool = False):
    """ADMM's over-relaxation as a float in (0, 2), or ``"auto"`` where ``auto`` allows it;
    anything else is a one-line ``ValueError``."""
    if auto and isinstance(relax, str) and relax == "auto":
        return relax
    numeric = isinstance(relax, (int, float, np.floating)) and not isinstance(relax, bool)
    if not (numeric and 0 < relax < 2):
        what = "'auto' or a number" if auto else "a number"
        raise ValueError(f"relax must be {what} in (0, 2), got {relax!r}")
    return float(relax)


def check_guard(guard):
    """:func:`gap`'s divergence guard as a finite float ratio > 1, or ``None`` (off); anything
    else is a one-line ``ValueError`` (:func:`tensor_cosdi.validate.number`)."""
    return None if guard is None else number("guard", guard, low=1, low_open=True)


def _gnorm(g) -> float:
    return max(float(tl.norm(g)), np.finfo(float).tiny)


def admm(
    op,
    g,
    prior,
    *,
    rho: float,
    start=None,
    max_iter: int = 60,
    tol: float = 1e-4,
    normal_solve=None,
    progress: bool = False,
    desc: str = "ADMM",
    objective: bool = True,
    relax: float = 1.0,
):
    """ADMM for ``min ½‖A x − g‖² + R(x)`` with the split ``z = x``.  Returns ``(z, history,
    converged)``.

    Parameters
    ----------
    op : TensorOperator
    g : tensor of ``op.output_shape``
    prior : :class:`~tensor_cosdi.solvers.priors.Prior`
    rho : float
        Penalty relative to the sensing gain (``ρ = rho · s``).
    start : tensor or one-element list, optional
        Starting ``x`` (default: ``(AᵀA + ρI)⁻¹ Aᵀ g``).  A list ``[x0]`` hands
        the cube over: ``admm`` empties the list, so the caller holds no
        reference and the start's memory is freed after the first iteration.
    normal_solve : callable ``(b, x_prev) -> x``, optional
        Replaces ``(AᵀA + ρI)⁻¹ b`` (coupled problems; default the
        operator's structured ``solve_normal``).
    objective : bool
        Record the prior term of the objective (``False``: NaN, for internal
        stages whose history is discarded; TV costs a pass over the cube).
    relax : float
        Over-relaxation ``α`` in (0, 2): the z- and u-steps take
        ``x̂ = α x + (1 − α) z`` in place of ``x`` (Boyd et al. 2011, §3.4.3);
        1 is plain ADMM.  Above 1 it moves further along each x-step at no
        extra cost per iteration (one more cube held).
    """
    relax = check_relax(relax)
    r = rho * sensing_gain(op, g)
    solve = normal_solve if normal_solve is not None else (lambda b, x0: op.solve_normal(b, r))
    atg = op.apply_adjoint(g)
    if isinstance(start, list):
        start = start.pop() if len(start) == 1 else _bad_handoff(start)
    x = solve(atg, None) if start is None else _layout_like(start, atg)
    del start
    prior.setup(x, penalty=r, gain=r / rho)
    z = prior.prox(x)
    u = tl.zeros_like(z)
    loop = Loop(max_iter, tol, progress=progress, desc=desc, objective=objective)
    gnorm = _gnorm(g)
    inplace = isinstance(u, np.ndarray)  # NumPy: update in place, no cube-sized temporaries
    for it in loop:
        if inplace:
            b = np.subtract(z, u)
            b *= r
            b += atg
        else:
            b = atg + r * (z - u)
        z_last = z if relax != 1.0 else None
        z = None  # the last z is not needed any more (its memory is reused)
        x_new = solve(b, x)
        del b
        change = relative_change(x_new, x)
        x = x_new
        xr = x if z_last is None else relax * x + (1.0 - relax) * z_last
        del z_last
        if inplace:  # the prior may keep or return its input: it gets a fresh array
            z = prior.prox(xr + u)
            u += xr
            u -= z
        else:
            z = prior.prox(xr + u)
            u = u + (xr - z)
        del xr
        if loop.record(
            it,
            residual_norm=float(tl.norm(op.apply(z) - g)),
            gnorm=gnorm,
            change=change,
            prior_term=prior.objective(z) if loop.objective else float("nan"),
        ):
            break
        if it + 1 < loop.max_iter:
            prior.update(x, it + 1)
    return z, loop.history, loop.converged


def _layout_like(x, ref):
    """``x`` in ``ref``'s memory order (NumPy; C or Fortran order, else ``x`` as it is): the
    operator's adjoint returns its fast layout (Fortran order for the shear kernels), and a
    start in the other order would keep every iterate there — the coded shear of a C-ordered
    SD-CASSI cube runs 5× slower."""
    if not (isinstance(x, np.ndarray) and isinstance(ref, np.ndarray)):
        return x
    if ref.flags.f_contiguous and not ref.flags.c_contiguous and not x.flags.f_contiguous:
        return np.asfortranarray(x)
    if ref.flags.c_contiguous and not ref.flags.f_contiguous and not x.flags.c_contiguous:
        return np.ascontiguousarray(x)
    return x


def _bad_handoff(start):
    raise ValueError(f"start as a list hands one cube over: [x0], got a list of {len(start)}")


def least_norm(op, g, eps: float = 1e-6):
    """``Aᵀ(AAᵀ + εI)⁻¹ g`` with ``ε = eps · s`` (the structured dual solve): the start of GAP and
    TwIST."""
    return op.apply_adjoint(op.solve_dual(g, eps * sensing_gain(op, g)))


def gap(
    op,
    g,
    prior,
    *,
    eps: float = 1e-6,
    accelerate: bool = True,
    start=None,
    max_iter: int = 60,
    tol: float = 1e-4,
    progress: bool = False,
    desc: str = "GAP",
    objective: bool = True,
    guard: float | None = None,
    step=None,
):
    """(Accelerated) generalised alternating projection.  Returns ``(x, history, converged)``.

    ``ε = eps · s``; the default start is the least-norm ``Aᵀ(AAᵀ + εI)⁻¹ g``.
    One forward per iteration: ``A x`` of the new iterate serves the
    residual and the next projection.

    ``guard`` (accelerated only): stop when ``‖A x − g‖`` has risen three
    iterations in a row and stands above ``guard`` times the lowest residual
    so far, and return the iterate that had it (a single overshoot is normal
    for accelerated GAP).  Accelerated GAP feeds the residual back into ``ĝ``; when the
    prior cannot express the scene (a plug-and-play denoiser at a low level),
    that feedback grows instead of shrinking and the iterates diverge — the
    residual is the signal, and it needs no ground truth.

    ``step`` (optional): a callable ``(x, w) -> (x_new, change)`` that takes the place of
    ``x_new = prior.prox(x + w)`` and its ``relative_change(x_new, x)``, for a prior that keeps
    the iterate in a form of its own between iterations (the subspace first stage holds
    coefficient images: :func:`~tensor_cosdi.solvers.subspace.subspace_gap_tv`); ``prior``
    still gets ``setup`` and ``update`` as usual.
    """
    guard = check_guard(guard)
    if step is not None and not callable(step):
        raise ValueError(f"step must be a callable (x, w) -> (x_new, change), got {step!r}")
    best, rises, last = (np.inf, None), 0, np.inf
    lam = eps * sensing_gain(op, g)
    x = least_norm(op, g, eps) if start is None else start
    prior.setup(x, penalty=1.0, gain=lam / eps)
    g_hat = g
    ax = op.apply(x)
    loop = Loop(max_iter, tol, progress=progress, desc=desc, objective=objective)
    gnorm = _gnorm(g)
    for it in loop:
        if accelerate:
            g_hat = g_hat + (g - ax)
        w = op.apply_adjoint(op.solve_dual(g_hat - ax, lam))
        if step is None:
            v = x + w
            del w  # freed before the prox runs, as the one-expression form did
            x_new = prior.prox(v)
            del v
            change = relative_change(x_new, x)
        else:
            x_new, change = step(x, w)
            del w
        x = x_new
        ax = op.apply(x)
        res = float(tl.norm(ax - g))
        done = loop.record(
            it,
            residual_norm=res,
            gnorm=gnorm,
            change=change,
            prior_term=prior.objective(x) if loop.objective else float("nan"),
        )
        if guard is not None and accelerate:
            rises, last = (rises + 1 if res > last else 0), res
            if res < best[0]:
                best = (res, x)
            elif rises >= 3 and res > guard * best[0]:  # diverging: return the best iterate
                x, loop.converged = best[1], False
                break
        if done:
            break
        if it + 1 < loop.max_iter:
            prior.update(x, it + 1)
    return x, loop.history, loop.converged


def lipschitz(op, like, *, n_iter: int = 20, seed: int = 0) -> float:
    """``1.05 ‖A‖²`` by ``n_iter`` power iterations on ``AᵀA`` (the FISTA step bound;
    :meth:`~tensor_cosdi.operators.TensorOperator.lipschitz`)."""
    return op.lipschitz(like, n_iter=n_iter, seed=seed)


def fista(
    op,
    g,
    prior,
    start,
    *,
    max_iter: int = 60,
    tol: float = 1e-4,
    project=None,
    L: float | None = None,
    progress: bool = False,
    desc: str = "FISTA",
    objective: bool = True,
):
    """FISTA for ``min ½‖A x − g‖² + R(x)`` from ``start``; ``project(x)`` (optional) after each
    prox.

    ``L`` defaults to :func:`lipschitz`.  Returns ``(x, history, converged)``.
    """
    L = lipschitz(op, g) if L is None else float(L)
    prior.setup(start, penalty=L, gain=L)
    x, y, t = start, start, 1.0
    loop = Loop(max_iter, tol, progress=progress, desc=desc, objective=objective)
    gnorm = _gnorm(g)
    for it in loop:
        x_new = prior.prox(y + op.apply_adjoint(g - op.apply(y)) / L)
        if project is not None:
            x_new = project(x_new)
        t_new = (1 + math.sqrt(1 + 4 * t * t)) / 2  # a Python float: keeps float32 iterates float32
        y = x_new + ((t - 1) / t_new) * (x_new - x)
        change = relative_change(x_new, x)
        x, t = x_new, t_new
        if loop.record(
            it,
            residual_norm=float(tl.norm(op.apply(x) - g)),
            gnorm=gnorm,
            change=change,
            prior_term=prior.objective(x) if loop.objective else float("nan"),
        ):
            break
        if it + 1 < loop.max_iter:
            prior.update(x, it + 1)
    return x, loop.history, loop.converged


def twist(
    op,
    g,
    prior,
    start=None,
    *,
    lam1: float = 1e-4,
    monotone: bool = True,
    max_iter: int = 80,
    tol: float = 1e-4,
    L: float | None = None,
    progress: bool = False,
    desc: str = "TwIST",
):
    """TwIST (two-step iterative shrinkage/thresholding, Bioucas-Dias & Figueiredo 2007) from
    ``start`` (default :func:`least_norm`).  Returns ``(x, history, converged)``.

    ``Γ(x) = prox(x + Aᵀ(g − A x)/L)`` (``L`` from :func:`lipschitz`), then
    ``x_{t+1} = (1 − α) x_{t−1} + (α − β) x_t + β Γ(x_t)`` with the paper's
    parameters for the spectrum of ``AᵀA/L`` in ``[lam1, 1]``:
    ``ρ₀ = (1 − lam1)/(1 + lam1)``, ``α = 2/(1 + √(1 − ρ₀²))``,
    ``β = 2α/(1 + lam1)``.  ``monotone``: a two-step update that raises the
    objective ``½‖A x − g‖² + R(x)`` is replaced by the IST step ``Γ(x_t)``
    (already computed), so the recorded objective never rises by more than
    an inexact prox allows.
    """
    L = lipschitz(op, g) if L is None else float(L)
    if not 0 < lam1 < 1:
        raise ValueError(f"lam1 must lie in (0, 1) (the smallest eigenvalue of AᵀA/L), got {lam1}")
    rho0 = (1 - lam1) / (1 + lam1)
    alpha = 2 / (1 + math.sqrt(1 - rho0 * rho0))  # Python floats keep float32 iterates float32
    beta = 2 * alpha / (1 + lam1)
    start = least_norm(op, g) if start is None else start
    prior.setup(start, penalty=L, gain=L)

    def terms(x, ax):  # (data term, prior term)
        return 0.5 * float(tl.norm(ax - g)) ** 2, prior.objective(x)

    x = prior.prox(start + op.apply_adjoint(g - op.apply(start)) / L)
    x_prev, ax = start, op.apply(x)
    f = sum(terms(x, ax)) if monotone else float("nan")
    loop = Loop(max_iter, tol, progress=progress, desc=desc)
    gnorm = _gnorm(g)
    for it in loop:
        step = prior.prox(x + op.apply_adjoint(g - ax) / L)
        x_new = (1 - alpha) * x_prev + (alpha - beta) * x + beta * step
        ax_new = op.apply(x_new)
        data, reg = terms(x_new, ax_new)
        if monotone and data + reg > f:  # fall back to the IST step
            x_new, ax_new = step, op.apply(step)
            data, reg = terms(x_new, ax_new)
        change = relative_change(x_new, x)
        x_prev, x, ax, f = x, x_new, ax_new, data + reg
        if loop.record(
            it,
            residual_norm=float(tl.norm(ax - g)),
            gnorm=gnorm,
            change=change,
            prior_term=reg,
        ):
            break
        if it + 1 < loop.max_iter:
            prior.update(x, it + 1)
    return x, loop.history, loop.converged


def cg_solver(normal, *, rtol: float = 1e-6, maxiter: int = 20):
    """A warm-started CG ``(b, x0) -> x`` for :func:`admm`'s ``normal_solve`` (inexact ADMM)."""
    from ..operators.woodbury import conjugate_gradient

    def solve(b, x0):  # a few CG steps per ADMM iteration is the design: no warning
        return conjugate_gradient(normal, b, x0=x0, rtol=rtol, maxiter=maxiter, warn=False)

    return solve
