"""GAP-TV: generalised alternating projection with a total-variation denoiser (baseline, SPEC §5)."""

from __future__ import annotations


import numpy as np
import tensorly as tl
from skimage.restoration import denoise_tv_chambolle

from .. import _backend as B
from ._base import History, check_positive, register_method, relative_change
from ..systems._base import sensing_gain

__all__ = ["gap_tv", "gap_tv_operator", "tv_denoise"]


def tv_denoise(cube, weight: float, *, n_iter: int = 50):
    """Isotropic 2-D TV (Chambolle, scikit-image) of every band/slice: spatial axes 0 and 1.

    Runs on the host: tensors of other backends go through NumPy and back.
    """
    x = np.asarray(B.to_numpy(cube), dtype=np.float64)
    shape = x.shape
    flat = x.reshape(shape[:2] + (-1,))
    out = denoise_tv_chambolle(flat, weight=weight, max_num_iter=n_iter, channel_axis=2)
    return B.tensor_like(out.reshape(shape), cube)


def gap_tv(
    system,
    measurement,
    *,
    max_iter: int = 60,
    tv_weight: float = 0.05,
    accelerate: bool = True,
    tol: float = 1e-4,
    eps: float = 1e-6,
    progress: bool = False,
):
    """GAP-TV (Yuan 2016) for any system: ``x ← D_TV(x + Aᵀ (AAᵀ + εI)⁻¹ (ĝ − A x))``.

    The projection uses the system's structured ``(εI + A Aᵀ)⁻¹`` (a division
    for diagonal ``A Aᵀ``; per-pixel blocks, banded rows or CG otherwise) with
    ``ε = eps · s`` relative to the sensing gain ``s``.  With ``accelerate``
    the measurement is replaced by the running ``ĝ ← ĝ + (g − A x)`` of
    accelerated GAP.  ``tv_weight`` is relative to the largest value of the
    first (least-norm) estimate.  Stops when the relative change of ``x`` is
    below ``tol`` or after ``max_iter`` iterations.  Registered as ``"gap_tv"``.
    """
    tv_weight = check_positive("tv_weight", tv_weight)
    eps = check_positive("eps", eps)
    tol = check_positive("tol", tol)
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer ≥ 1, got {max_iter!r}")
    return gap_tv_operator(system.operator, measurement, max_iter=max_iter, tv_weight=tv_weight,
                           accelerate=accelerate, tol=tol, eps=eps, progress=progress)


def gap_tv_operator(op, measurement, *, max_iter=60, tv_weight=0.05, accelerate=True, tol=1e-4, eps=1e-6,
                    progress=False, desc="GAP-TV", denoiser=None):
    """:func:`gap_tv` for a bare :class:`~tensor_cosdi.operators.TensorOperator` (axes 0, 1 spatial).

    ``denoiser(x, weight)`` replaces the TV step (default :func:`tv_denoise`);
    OTD's subspace panchromatic start uses it.
    """
    denoise = tv_denoise if denoiser is None else denoiser
    from tqdm import tqdm

    g = measurement
    lam = eps * sensing_gain(op, g)
    x = op._adjoint(op.solve_dual(g, lam))  # least-norm start
    weight = tv_weight * max(float(tl.max(tl.abs(x))), np.finfo(float).tiny)
    g_hat = g
    hist = History()
    converged = False
    gnorm = max(float(tl.norm(g)), np.finfo(float).tiny)
    for _ in tqdm(range(max_iter), desc=desc, disable=not progress):
        ax = op._forward(x)
        if accelerate:
            g_hat = g_hat + (g - ax)
        x_new = denoise(x + op._adjoint(op.solve_dual(g_hat - ax, lam)), weight)
        change = relative_change(x_new, x)
        x = x_new
        res = float(tl.norm(op._forward(x) - g)) / gnorm
        hist.record(residual=res, objective=(res * gnorm) ** 2, change=change)
        if change < tol:
            converged = True
            break
    return x, hist, converged


register_method(
    "gap_tv",
    gap_tv,
    {"max_iter": 60, "tv_weight": 0.05, "accelerate": True, "tol": 1e-4, "eps": 1e-6, "progress": False},
    "generalised alternating projection with a TV denoiser",
)
