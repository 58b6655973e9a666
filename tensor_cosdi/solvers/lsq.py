"""Regularised least squares, closed form through the system's structured Woodbury solve."""

from __future__ import annotations

import time

import numpy as np
import tensorly as tl

from ..operators import sensing_gain
from . import engine
from ._base import check_positive, register_method, relative_residual
from .priors import NonNegative, Ridge

__all__ = ["regularised_lsq"]

#: ``nonneg=True``: the ADMM penalty relative to the sensing gain (the x-step is the closed-form
#: solve with ``μ s + ρ``).
NONNEG_RHO = 0.1


def regularised_lsq(
    system, measurement, *, mu: float = 1e-2, nonneg: bool = False, max_iter: int = 100,
    tol: float = 1e-5,
):  # fmt: skip
    """``F = argmin ‖G − A F‖² + μ s ‖F‖² = (AᵀA + μ s I)⁻¹ Aᵀ G`` (SPEC §4, §5 baseline).

    ``s = ‖A 1‖² / ‖1‖²`` (:func:`~tensor_cosdi.operators.sensing_gain`), so ``mu`` is relative.
    One closed-form
    solve where ``A Aᵀ`` has structure (diagonal, per-pixel blocks, banded
    rows), conjugate gradients otherwise.  Registered as method ``"lsq"``.

    ``nonneg=True`` solves the same problem under ``F ≥ 0`` by ADMM
    (:func:`~tensor_cosdi.solvers.engine.admm` with the
    :class:`~tensor_cosdi.solvers.priors.Ridge` prior inside
    :class:`~tensor_cosdi.solvers.priors.NonNegative`; every x-step is the
    same closed-form solve, at most ``max_iter`` of them, stopping at a
    relative change below ``tol``).  Off by default: ``"lsq"`` is the
    linear, closed-form baseline the other methods are measured against;
    ``max_iter`` and ``tol`` are unused then.
    """
    mu = check_positive("mu", mu)
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    max_iter = engine.check_int("max_iter", max_iter, 1)
    tol = check_positive("tol", tol)
    g = measurement
    if nonneg:
        return engine.admm(
            system.operator, g, NonNegative(Ridge(mu)), rho=NONNEG_RHO, max_iter=max_iter,
            tol=tol, desc="non-negative LSQ",
        )  # fmt: skip
    t0 = time.perf_counter()
    lam = mu * sensing_gain(system.operator, g)
    cube = system.operator.solve_normal(system.operator.apply_adjoint(g), lam)
    res = relative_residual(system, cube, g)
    objective = (res * float(tl.norm(g))) ** 2 + lam * float(tl.norm(cube)) ** 2
    history = {
        "objective": [objective],
        "residual": [res],
        "change": [1.0],
        "seconds": [time.perf_counter() - t0],
    }
    return cube, history, True


register_method("lsq", regularised_lsq, summary="regularised least squares, closed form")
