"""ADMM-TV for CASSDI-DFA with PSFs, the blur split off so every step is closed form (SPEC §4).

With PSFs, ``A = H B``: ``B`` blurs every (band, plane) slice, ``H`` codes,
shears and sums (``H Hᵀ`` diagonal).  ``A Aᵀ`` has no cheap structure, so
the other methods solve their x-steps by conjugate gradients.  Here the
blurred cube gets its own variable.  ``B`` is the linear convolution of the
cube zero-padded to ``(Nx + h − 1, Ny + w − 1)``, cropped at the PSF's
centre (:class:`~tensor_cosdi.operators.Blur`); on that padded grid it is a
circular convolution ``C``, diagonal in Fourier space.  So the unknown is
the padded cube ``w`` (its border is scene just outside the frame, whose
blur reaches in; the cube is ``w``'s top-left ``Nx × Ny``), and::

    min ½‖g − H P v‖² + τ TV(z)   s.t.  v = C w,  w = z

(``P`` the crop at the PSF's centre) is solved by scaled ADMM:

* ``v ← (PᵀHᵀHP + ρ₁I)⁻¹(PᵀHᵀg + ρ₁(Cw − u₁))`` — inside the crop the
  system's closed-form diagonal Woodbury (``solve_normal`` of ``H``),
  outside it a division by ``ρ₁``;
* ``w ← (ρ₁CᵀC + ρ₂I)⁻¹(ρ₁Cᵀ(v + u₁) + ρ₂(z − u₂))`` — one division per
  Fourier coefficient;
* ``z ← TV-denoise(w + u₂, τ/ρ₂)`` (Chambolle, warm-started);
* ``u₁ ← u₁ + v − Cw``, ``u₂ ← u₂ + w − z``.
"""

from __future__ import annotations

import numpy as np
import tensorly as tl

from .. import _backend as B
from ..operators import sensing_gain
from . import engine
from ._base import (
    check_positive,
    register_method,
    relative_change,
    relative_residual,
    require_system,
)
from .denoisers import WarmTV
from .priors import robust_peak

__all__ = ["split_tv", "padded_blur"]


def padded_blur(psfs, shape, like):
    """``(conv, pad, centre, power)``: the circular convolution ``C`` by ``psfs`` (h, w, …) on the
    grid ``pad = (Nx + h − 1, Ny + w − 1)`` (``conv(x, adjoint=False)``), the PSF's centre,
    and ``|Ĉ|²``.  A cube zero-padded at the top-left, convolved and cropped at ``centre`` is
    :class:`~tensor_cosdi.operators.Blur`'s output (tested)."""
    h, w = psfs.shape[:2]
    pad = (shape[0] + h - 1, shape[1] + w - 1)
    spec = B.rfftn(B.tensor_like(psfs, like), s=pad, axes=(0, 1))  # (…, Nλ or 1, Nz or 1)

    def conv(x, adjoint=False):
        X = B.rfftn(x, s=pad, axes=(0, 1))
        return B.irfftn(X * (tl.conj(spec) if adjoint else spec), s=pad, axes=(0, 1))

    return conv, pad, (h // 2, w // 2), tl.abs(spec) ** 2


def split_tv(
    system,
    measurement,
    *,
    max_iter: int = 80,
    tv_weight: float = 0.05,
    rho1: float = 0.05,
    rho2: float = 0.05,
    tv_steps: int = 10,
    tol: float = 1e-5,
    nonneg: bool = True,
    progress: bool = False,
):
    """ADMM-TV for a :class:`~tensor_cosdi.systems.CASSDIDFA` with (4-D) PSFs, every step in
    closed form (module docstring).  Registered as ``"split_tv"``.

    Parameters
    ----------
    tv_weight : float
        TV strength relative to the robust peak (99.9th percentile) of the
        start, the least-norm solution of the unblurred system.
    rho1, rho2 : float
        Penalties of ``v = C w`` and ``w = z``, relative to the sensing
        gain ``‖H 1‖² / ‖1‖²``.
    tv_steps : int
        Chambolle steps per iteration (the dual is carried over).
    nonneg : bool
        ``z ← max(TV-denoise(w + u₂), 0)`` (a cube of light) and the
        returned cube clipped at 0; ``False`` for signed cubes.
    max_iter, tol, progress
        Iteration cap, relative-change stop, tqdm bar.

    Examples
    --------
    >>> import numpy as np, tensor_cosdi as tc
    >>> dfa = tc.systems.CASSDIDFA.example((16, 16, 4, 2), psf_size=5)
    >>> g = dfa.forward(np.random.default_rng(0).random(dfa.cube_shape))
    >>> tc.reconstruct(dfa, g, "split_tv", max_iter=5).cube.shape
    (16, 16, 4, 2)
    """
    from ..systems import CASSDIDFA

    require_system("split_tv", system)
    if system.psfs is None or system.sweep:
        raise ValueError(
            "split_tv reconstructs a CASSDIDFA with 4-D PSFs (band, plane); without PSFs use "
            f"'gap_tv' or 'otd' (closed form already), got {type(system).__name__}"
            + (" with a focal sweep" if getattr(system, "sweep", False) else "")
        )
    tv_weight, rho1, rho2, tol = (
        check_positive(n, v)
        for n, v in (("tv_weight", tv_weight), ("rho1", rho1), ("rho2", rho2), ("tol", tol))
    )
    max_iter = engine.check_int("max_iter", max_iter, 1)
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    tv = WarmTV(engine.check_int("tv_steps", tv_steps, 1))
    g = measurement
    nx, ny, nl, nz = system.cube_shape
    H = CASSDIDFA(
        system.codes, n_bands=nl, shifts=system.shifts, wavelengths=system.wavelengths
    ).operator
    conv, pad, (c0, c1), power = padded_blur(system.psfs, (nx, ny), g)

    def embed(x, at):  # P ᵀ (or E): the cube placed in a zero padded grid
        out = B.zeros_like_shape(pad + (nl, nz), x)
        out[at[0] : at[0] + nx, at[1] : at[1] + ny] = x
        return out

    s = sensing_gain(H, g)
    r1, r2 = rho1 * s, rho2 * s
    f0 = H.solve_normal(H.apply_adjoint(g), 1e-6 * s)  # the unblurred least-norm start
    tau = tv_weight * robust_peak(f0)
    w = embed(f0, (0, 0))
    z, u1, u2 = w, B.zeros_like_shape(pad + (nl, nz), g), B.zeros_like_shape(pad + (nl, nz), g)
    htg = embed(H.apply_adjoint(g), (c0, c1))
    loop = engine.Loop(max_iter, tol, progress=progress, desc="split-TV")
    gnorm = max(float(tl.norm(g)), np.finfo(float).tiny)
    cube, cw = f0, conv(w)
    for it in loop:
        r = htg + r1 * (cw - u1)
        v = r / r1  # outside the crop H sees nothing: (ρ₁ I)⁻¹
        inner = H.solve_normal(r[c0 : c0 + nx, c1 : c1 + ny], r1)
        v[c0 : c0 + nx, c1 : c1 + ny] = inner
        rhs = r1 * conv(v + u1, adjoint=True) + r2 * (z - u2)
        w = B.irfftn(B.rfftn(rhs, s=pad, axes=(0, 1)) / (r1 * power + r2), s=pad, axes=(0, 1))
        z = tv(w + u2, tau / r2)
        if nonneg:
            z = tl.clip(z, 0, None)
        cw = conv(w)  # used by this dual step and the next v-step
        u1 = u1 + v - cw
        u2 = u2 + w - z
        new = w[:nx, :ny]
        change = relative_change(new, cube)
        cube = new
        if loop.record(
            it,
            residual_norm=relative_residual(system, cube, g) * gnorm,
            gnorm=gnorm,
            change=change,
            prior_term=0.0,
        ):
            break
    if nonneg:  # a new array, not a view of the padded grid
        return tl.clip(cube, 0, None), loop.history, loop.converged
    return tl.copy(cube), loop.history, loop.converged  # not a view of the padded grid


register_method(
    "split_tv",
    split_tv,
    summary="ADMM-TV for CASSDI-DFA with PSFs, the blur split off: every step closed form "
    "(SPEC §4)",
    systems=("cassdi_dfa",),
    solves=False,
)
