"""Online Tucker dictionary ADMM (thesis Algorithm 5, generalised to every system; SPEC §5) and
WDCT-ADMM.

Both methods solve, for a cube written in a Kronecker basis
``F = Θ ×₁ Ψ1 ×₂ Ψ2 … ×_d Ψd`` of square orthonormal matrices,

    min_Θ ‖G − A(Θ ×ₙ Ψn)‖² + λ‖Θ‖₁ (+ β‖Θ − Θ_prev‖² across basis updates)

by ADMM with the split ``Ω = Θ`` (Eq. 98-106):

* Θ-step (Eq. 101): ``Θ = Ψᵀ (AᵀA + μI)⁻¹ (AᵀG + μ Ψ(Ω + ν))`` — the
  basis never enters the solve because it is orthonormal (SPEC §4), so it
  is the system's closed-form ``solve_normal`` (a division, per-pixel
  ``K × K`` blocks or banded rows; CG only where ``A Aᵀ`` has no structure);
* Ω-step: the exact proximal step of SPEC §12 (which corrects Eq. 106),
  ``Ω = soft((βΩ_prev + μ(Θ − ν)) / (β + μ), λ / (2(β + μ)))``;
* dual step: ``ν ← ν − (Θ − Ω)``.

They differ in the bases.  **OTD** (``"otd"``) learns them: the spatial
pair from the SVD of the panchromatic estimate ``Z`` (Eq. 91-95; Lemma 1
where the codes are complementary), the other modes start as DCT and are
replaced every ``update_every`` iterations by the HOSVD basis of the current
estimate's mode-n unfolding (Eq. 97, Alg. 5 steps 16-18).  **WDCT**
(``"wdct"``) keeps Symlet-8 ⊗ Symlet-8 ⊗ DCT fixed (the thesis' baseline).
"""

from __future__ import annotations

import numpy as np
import tensorly as tl

from ..bases import DCT, Dense, Wavelet, block_hosvd, block_sizes, tucker_bases
from ..validate import flag, imager, integer, number
from . import engine
from ._base import History, check_positive, register_method
from .panchromatic import (  # noqa: F401  (stage 1 of OTD, re-exported here)
    FIT_TV_STEPS,
    PAN_WEIGHTS,
    has_many_bands,
    pan_weight_for,
    panchromatic_estimate,
    subspace_gap_tv,
)
from .priors import FixedBasis, NonNegative, TuckerDictionary, omega_step, with_plane_support
from .snr import CLEAN_ABOVE_DB

__all__ = [
    "online_tucker_admm",
    "wdct_admm",
    "initial_bases",
    "panchromatic_estimate",
    "tucker_admm",
    "lam_schedule",
    "theta_step",
    "omega_step",
    "subspace_gap_tv",
    "fast_start",
    "fast_start_iterations",
]

SPATIAL_BASES = ("panchromatic", "wavelet", "dct")

#: OTD's ``max_iter="auto"``: ADMM iterations after a first-stage estimate (True) or from an exact
#: panchromatic image (False); see :func:`online_tucker_admm`.
OTD_MAX_ITER = {True: 45, False: 60}


_check_int = engine.check_int


#: OTD's ``pan_tv_steps``: warm-started Chambolle steps per iteration of its first stage.
#: Cross-validated 10 / 15 / 20 with one setting for every condition (8 tuning scenes as they are
#: and magnified 4×, 4 folds, TSA mask and a random code, noiseless and 30 dB;
#: ``benchmarks/results/cv_otd_pan_tv_steps.md``): every fold chose 20; tuning means TSA
#: noiseless 31.79 / 31.89 / 31.93 dB, random noiseless 34.74 / 34.75 / 34.77, at 30 dB within
#: 0.02 dB; with the 8 scenes also lit by CIE LED-B3, A and FL11 (32 views, TSA, noiseless;
#: ``cv_otd_pan_tv_steps_lit.md``) every fold chose 20 again, 35.11 → 35.15 dB.  On the report
#: scenes (``real_spectra.md``) every cell moved by +0.00 to +0.07 dB; that table's medians
#: (2 cores, compiled TV steps, the 30-line GAP-TV timed in the same run) put a noiseless cube
#: at 0.54-0.55× GAP-TV's seconds (0.69-0.72× when the plain stage that fits the spectrum took
#: 20 steps instead of :data:`~.panchromatic.FIT_TV_STEPS`, 0.60-0.62× before the first stages'
#: steps of ``benchmarks/results/solver_steps.md``), a noisy one at 0.42-0.46×.
#: :func:`~tensor_cosdi.solvers.pnp_gap.pnp_gap`'s OTD start keeps 10
#: (:data:`~tensor_cosdi.solvers.pnp_gap.START_PAN_TV_STEPS`), the value its own defaults were
#: chosen with.
PAN_TV_STEPS = 20


def initial_bases(
    system,
    measurement,
    *,
    spatial: str = "panchromatic",
    wavelet_name: str = "sym8",
    wavelet_level="auto",
    pan_iter: int = 60,
    pan_atoms="auto",
    pan_weight="auto",
    pan_tv_steps: int | None = PAN_TV_STEPS,
    pan_spectrum: str = "flat",
    pan_fit_tv_steps: int | None = FIT_TV_STEPS,
    spatial_block: int | None = None,
    progress: bool = False,
):
    """The starting per-mode bases ``{mode: ModeTransform}`` of OTD (or WDCT), and a starting cube.

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``
    spatial : {"panchromatic", "wavelet", "dct"}
        ``"panchromatic"``: modes 0 and 1 are the singular vectors of the
        panchromatic estimate ``Z`` (:func:`panchromatic_estimate`; SPEC §5
        steps 1-2; for a ``Z`` with more than two axes, the HOSVD bases of
        its first two modes).  ``"wavelet"``: periodised ``wavelet_name`` on
        both (the WDCT baseline).  ``"dct"``: 2-D DCT.
    wavelet_name : str
        A PyWavelets orthogonal wavelet (default Symlet-8).
    wavelet_level : int, "auto" or "boundary"
        Its depth (:func:`tensor_cosdi.bases.wavelet`; ``"auto"``: as deep as
        the periodised transform allows).
    pan_iter, pan_atoms, pan_weight, pan_tv_steps, pan_spectrum, pan_fit_tv_steps
        See :func:`panchromatic_estimate` (``pan_weight``: TV weight of the
        subspace GAP-TV, relative; ``"auto"`` follows the measurement's
        estimated SNR, :data:`PAN_WEIGHTS`; ``pan_atoms``: spectral DCT atoms,
        ``"auto"`` by the band count, :func:`~.subspace.pan_atoms_for`).
    spatial_block : int or None
        With ``"panchromatic"``: a spatial axis longer than this gets a
        block-diagonal basis, one learned block per run of at most
        ``spatial_block`` pixels (:class:`~tensor_cosdi.bases.BlockDense`),
        so the transforms cost the same per pixel at any size.  ``None``: one
        dense basis per axis.

    Returns
    -------
    bases : dict
        Every mode of ``system.cube_shape`` as a
        :class:`~tensor_cosdi.bases.ModeTransform` (``.matrix`` is the dense
        ``Ψn``); modes ≥ 2 are DCT (SPEC §5 step 3).
    start : tensor or None
        The cube estimated on the way to ``Z``, if any.
    """
    if spatial not in SPATIAL_BASES:
        raise ValueError(f"spatial must be one of {SPATIAL_BASES}, got {spatial!r}")
    shape = system.cube_shape
    mats = {m: DCT(n) for m, n in enumerate(shape) if m >= 2}
    start = None
    if spatial == "panchromatic":
        z, start = panchromatic_estimate(
            system,
            measurement,
            pan_iter=pan_iter,
            pan_atoms=pan_atoms,
            pan_weight=pan_weight,
            pan_tv_steps=pan_tv_steps,
            pan_spectrum=pan_spectrum,
            pan_fit_tv_steps=pan_fit_tv_steps,
            progress=progress,
        )
        for m in (0, 1):
            n = shape[m]
            if spatial_block is not None and n > _check_int("spatial_block", spatial_block, 2):
                mats[m] = block_hosvd(z, m, block_sizes(n, spatial_block))
            else:
                mats[m] = Dense(tucker_bases(z, modes=[m])[m])
    elif spatial == "wavelet":
        mats[0], mats[1] = (Wavelet(n, wavelet_name, level=wavelet_level) for n in shape[:2])
    else:
        mats[0], mats[1] = DCT(shape[0]), DCT(shape[1])
    return mats, start


def theta_step(operator, basis, atg, w, mu):
    """Θ-step (Equation 101): ``Θ = argmin ‖G − AΨΘ‖² + μ‖Θ − w‖²``, with ``w = Ω + ν`` and ``atg =
    AᵀG``.

    ``Θ = Ψᵀ (AᵀA + μI)⁻¹ (AᵀG + μ Ψ w)``: orthonormal ``Ψ`` leaves the
    structured ``solve_normal`` of ``A`` (SPEC §4).  Returns ``(F, Θ)`` with
    ``F = Ψ Θ``.
    """
    f = operator.solve_normal(atg + mu * basis.synthesis(w), mu)
    return f, basis.analysis(f)  # basis: a tensor_cosdi.bases.KroneckerBasis


def tucker_admm(
    system,
    measurement,
    bases: dict,
    *,
    start=None,
    update_modes=(),
    max_iter: int = 60,
    update_every: int = 10,
    mu: float = 0.2,
    lam: float | str = 0.1,
    beta: float = 0.0,
    tol: float = 1e-4,
    weights=None,
    plane_support="auto",
    nonneg: bool = False,
    progress: bool = False,
    desc: str = "ADMM",
):
    """ADMM in a Kronecker basis, the engine call behind ``"otd"`` and ``"wdct"`` (see the module
    notes).

    :func:`tensor_cosdi.solvers.engine.admm` with a
    :class:`~tensor_cosdi.solvers.priors.TuckerDictionary` prior (a
    :class:`~tensor_cosdi.solvers.priors.FixedBasis` when nothing is re-learned).

    Parameters
    ----------
    bases : dict {mode: (n, n) orthonormal ndarray or ModeTransform}
        Starting synthesis bases (modes not listed: identity).
    start : tensor of ``system.cube_shape`` or ``[tensor]`` (handed over), optional
        Starting cube (default: regularised least squares with weight ``mu``).
    update_modes : sequence of int
        Modes whose basis is re-learned (HOSVD of the estimate's unfolding)
        every ``update_every`` iterations.
    mu, beta : float
        ADMM penalty and proximal weight, relative to the sensing gain
        ``s = ‖A 1‖²/‖1‖²``.
    lam : float or "auto"
        Sparsity weight: the soft threshold is ``lam·c/(mu + beta)`` in the
        cube's units, ``c`` the RMS of the starting cube (ℓ1 weight
        ``lam·s·c`` in ``½‖A x − g‖² + λ‖Θ‖₁``).  Noisier data want more;
        ``"auto"`` follows the measurement's estimated SNR
        (:func:`tensor_cosdi.solvers.snr.estimate_snr`) through
        :data:`LAM_SCHEDULE` (or, where a panchromatic axis has 24 bands
        or more, :data:`LAM_SCHEDULE_MANY`; log-linear between the anchors,
        constant beyond), with the anchors the system replaces
        (``otd_lam_anchors``: CS2LI with a colour code) — :func:`lam_schedule`.
    weights : array of ``system.cube_shape``, optional
        Per-coefficient ℓ1 weights (``λ‖w ∘ Θ‖₁``), e.g. larger on atoms
        known to carry noise.
    tol : float
        Stop when the relative change of ``F`` between iterations is below.
    plane_support : "auto", False or int
        On depth-plane systems (CASSDI-DFA) keep one plane per pixel
        (:class:`~tensor_cosdi.solvers.priors.PlaneSupport`) from iteration
        ``max_iter // 6`` ("auto") or the given one: on 64×64×8×3 DFA scenes
        at 30 dB 18.67 / 19.32 → 19.02 / 20.17 dB, SSIM 0.19 / 0.24 → 0.55 / 0.56.
    nonneg : bool
        Project each z-step onto ``x ≥ 0``
        (:class:`~tensor_cosdi.solvers.priors.NonNegative`).  OTD, four tuning
        scenes of fold 3 (feathers, flowers, egyptian_statue, paints; TSA mask,
        256×256×28): noiseless +0.50 / +0.30 / +0.05 / 0.00 dB, 30 dB −0.01 /
        +0.19 / +0.35 / −0.01 dB, at the same time.  Turn it off for signed
        cubes (a difference of two captures, a mean-removed cube).

    Returns
    -------
    cube, history, converged
    """
    mu = check_positive("mu", mu)
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    if isinstance(lam, str):
        if lam != "auto":
            raise ValueError(f"lam must be a number > 0 or 'auto', got {lam!r}")
        from ..noise import snr_schedule
        from .snr import estimate_snr

        table = lam_schedule(system)
        lam = snr_schedule(estimate_snr(system, measurement).snr_db, table)
    lam = check_positive("lam", lam)
    tol = check_positive("tol", tol)
    if not (np.isfinite(beta) and beta >= 0):
        raise ValueError(f"beta must be a finite number ≥ 0, got {beta!r}")
    max_iter = _check_int("max_iter", max_iter, 1)
    update_every = _check_int("update_every", update_every, 0)
    if update_modes and update_every:
        prior = TuckerDictionary(
            bases,
            lam=lam,
            mu=mu,
            beta=float(beta),
            weights=weights,
            update_modes=update_modes,
            update_every=update_every,
        )
    else:
        prior = FixedBasis(bases, lam=lam, mu=mu, beta=float(beta), weights=weights)
    prior = with_plane_support(prior, system, plane_support, max_iter, max_iter // 6)
    if nonneg:
        prior = NonNegative(prior)
    return engine.admm(
        system.operator,
        measurement,
        prior,
        rho=mu,
        start=start,
        max_iter=max_iter,
        tol=tol,
        progress=progress,
        desc=desc,
    )


#: ``lam="auto"`` (OTD's default): the ℓ1 weight against the estimated SNR (dB).  Chosen by 4-fold
#: cross-validation over the 28 tuning scenes (256×256×28 SD-CASSI, TSA mask and a random binary
#: code; ``benchmarks/results/cv_otd.md``): out of {0.03, 0.1, 0.3}, 23 of the 24 fold choices
#: were 0.03 noiseless, 0.1 at 30 dB and 0.3 at 20 dB (one fold, random code at 30 dB, chose
#: 0.03); the schedule is within 0.14 dB of the best fixed value in every condition.  With the
#: non-negative z-step (``nonneg=True``) the same cross-validation on 12 of the scenes chose the
#: same three values on all of them (``benchmarks/results/nonneg.md``).
LAM_SCHEDULE = {40.0: 0.03, 30.0: 0.1, 20.0: 0.3}
#: The same from :data:`~tensor_cosdi.solvers.subspace.MANY_BANDS` bands on, where the first
#: stage has eight atoms.  Noiseless, cross-validated again on all 28 tuning scenes as they are
#: and magnified 4× (TSA mask; ``benchmarks/results/otd_lam_clean_zoom4.md``): 0.00375 / 0.0075
#: / 0.015 / 0.03 → 33.48 / 33.53 / 33.45 / 33.21 dB, every fold chose 0.0075 (a finer grid
#: below the earlier grid's lowest value, 0.03).
LAM_SCHEDULE_MANY = {40.0: 0.0075, 30.0: 0.1, 20.0: 0.3}


def lam_schedule(system) -> dict:
    """The ``{SNR dB: weight}`` anchors of OTD's ``lam="auto"`` on ``system``:
    :data:`LAM_SCHEDULE` (:data:`LAM_SCHEDULE_MANY` from 24 bands on) with the anchors the
    system's ``otd_lam_anchors`` replaces.

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> lam_schedule(tc.systems.SDCASSI.example())
    {40.0: 0.03, 30.0: 0.1, 20.0: 0.3}
    >>> lam_schedule(tc.systems.CS2LI.example())
    {40.0: 0.03, 30.0: 0.03, 20.0: 0.1}
    """
    table = dict(LAM_SCHEDULE_MANY if has_many_bands(system) else LAM_SCHEDULE)
    extra = getattr(system, "otd_lam_anchors", None)
    if extra is None:
        return table
    name = type(system).__name__
    if not isinstance(extra, dict) or not extra:
        raise ValueError(
            f"{name}.otd_lam_anchors must be None or a non-empty dict {{SNR dB: weight}}, "
            f"got {extra!r}"
        )
    for snr, weight in extra.items():
        snr = number(f"{name}.otd_lam_anchors' SNR", snr)
        table[snr] = number(f"{name}.otd_lam_anchors' weight", weight, low=0, low_open=True)
    return table


def online_tucker_admm(
    system,
    measurement,
    *,
    update_every: int = 10,
    spatial: str = "panchromatic",
    update_spatial: bool = True,
    max_iter="auto",
    admm_iter="auto",
    pan_iter: int = 90,
    pan_atoms="auto",
    pan_weight="auto",
    pan_tv_steps=PAN_TV_STEPS,
    pan_spectrum="auto",
    pan_fit_tv_steps=FIT_TV_STEPS,
    spatial_block=None,
    lam="auto",
    mu: float = 0.2,
    beta: float = 0.0,
    tol: float = 1e-4,
    weights=None,
    plane_support="auto",
    nonneg: bool = True,
    progress: bool = False,
):
    """OTD: online Tucker dictionary ADMM (thesis Algorithm 5 for every system, SPEC §5).
    Registered as ``"otd"``.

    Steps (SPEC §5): the panchromatic estimate ``Z`` (exact where the
    system allows, else :func:`subspace_gap_tv`, which also gives the
    starting cube); spatial bases = singular vectors of ``Z``; DCT on the
    other modes; ADMM with the closed-form Θ-step and the exact Ω-step;
    every ``update_every`` iterations (0: never) the bases are re-learned
    by HOSVD of the current estimate — the non-spatial modes as in Alg. 5,
    and with ``update_spatial`` (default) the spatial pair too, which
    corrects an inexact ``Z`` (on 64×64×16 scenes at 30 dB it gained 0.3 to
    2.3 dB on SD-CASSI, CASSI-VSI, CS2LI and CASSDI-DFA).  ``max_iter``,
    ``mu``, ``lam``, ``beta``, ``tol``, ``progress``: see
    :func:`tucker_admm` (``lam="auto"``, the default: :data:`LAM_SCHEDULE`;
    ``max_iter="auto"``: :data:`OTD_MAX_ITER`, 45 after
    a first-stage estimate, 60 where ``Z`` is exact and ADMM does all the
    work; an integer ``max_iter`` also caps the first stage's ``pan_iter``);
    ``admm_iter``: the ADMM stage's iterations alone, leaving the first stage
    as it is (``"auto"``: ``max_iter``'s; never more than an integer
    ``max_iter``; 0: no ADMM stage, the first stage's cube itself, which only a
    system without an exact panchromatic image and ``pan_iter ≥ 1`` has);
    ``pan_*``: see :func:`panchromatic_estimate`;
    ``spatial_block``: see :func:`initial_bases`; ``nonneg``: see
    :func:`tucker_admm` (on by default: a cube of light is non-negative).  For C3SLFI, "OTD-3D" is
    this method on a 3-D system and "OTD-5D" on ``system.as_5d()``.

    Defaults (tuning scenes of :mod:`tensor_cosdi.datasets`, SD-CASSI, TSA
    mask, 256×256×28; mean PSNR noiseless / 30 dB, median seconds): the
    warm-started TV of the first stage (``pan_tv_steps=10``) took 60 + 60
    iterations from 27.02 / 26.02 dB in 7.4 / 8.3 s to 27.19 / 26.42 dB in
    4.7 / 4.1 s; a longer first stage buys more than ADMM iterations do
    (``pan_iter``/``max_iter`` 90/45: 27.28 / 26.88 dB in 4.1 / 4.4 s;
    120/40: 27.54 / 26.71 dB in 5.3 s; 30/60: 26.17 / 25.81 dB).  Where ``Z``
    is exact (dual-camera CASSI at 96×96×16, 30 dB) 45 ADMM iterations lost
    0.3-0.4 dB against 60, hence "auto".  ``pan_tv_steps``: :data:`PAN_TV_STEPS`
    (20, cross-validated against 10 and 15).

    ``pan_spectrum="auto"`` (from 24 bands, on a clean measurement: the first stage also tried with
    its spectral atoms weighted by the scene's fitted mean spectrum, kept unless its residual
    exceeds the plain stage's by more than :data:`~.panchromatic.FITTED_MARGIN`): 4-fold
    cross-validation over 8 tuning scenes as they are and lit by CIE LED-B3 and A
    (``benchmarks/results/cv_otd_pan_spectrum.md``, run with the second stage at both noise levels):
    noiseless 31.32 → 31.99 dB over the 24 views, every fold chose it; at 30 dB a tie (30.28 both);
    at 20 dB it lost, so noisy data do not fit the spectrum twice
    (:data:`~.panchromatic.FITTED_SPECTRUM_ABOVE_DB`).  There ``"auto"`` is ``"gated"``: one stage
    whose atoms follow the fitted spectrum part-way through only under a lamp's lines, shut below an
    estimated 25 dB; with tuning views lit by FL11 added, 30 dB 31.94 → 33.95 dB over 32 views,
    every fold (``benchmarks/results/cv_otd_noisy_gate.md``).  On clean data it costs a second first
    stage, about 2.8 s at 256×256×28 (medians 5.6 → 8.4 s a cube over that run), less since
    the plain stage that fits the spectrum takes ``pan_fit_tv_steps``
    (:data:`~.panchromatic.FIT_TV_STEPS`, 5) Chambolle steps an iteration instead of 20:
    medians 9.22 → 8.39 s a cube on 32 tuning views, TSA, at 35.21 → 35.19 dB
    (``benchmarks/results/cv_otd_pan_fit_tv_steps.md``);
    ``pan_spectrum="flat"`` is the faster, single first stage.  ``"fitted_z"`` (the spatial bases
    from the weighted atoms' estimate, the start from the plain one's) gained 0.06 dB at 30 dB in
    the same cross-validation and lost 0.47 at 20 dB (``benchmarks/results/cv_otd_fitted_z.md``).

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(32, 32), n_bands=8)
    >>> res = tc.reconstruct(p.system, p.measurement, "otd")
    >>> res.cube.shape, res.method
    ((32, 32, 8), 'otd')
    """
    if isinstance(max_iter, str) and max_iter != "auto":  # checked before the first stage runs
        raise ValueError(f"max_iter must be an integer ≥ 1 or 'auto', got {max_iter!r}")
    if isinstance(admm_iter, str):
        if admm_iter != "auto":
            raise ValueError(f"admm_iter must be an integer ≥ 0 or 'auto', got {admm_iter!r}")
    else:
        admm_iter = integer("admm_iter", admm_iter, low=0)
    if max_iter != "auto":  # a given cap bounds the first stage too
        max_iter = integer("max_iter", max_iter, low=1)
        pan_iter = min(integer("pan_iter", pan_iter, low=0), max_iter)
    if admm_iter == 0 and (system.panchromatic_exact or integer("pan_iter", pan_iter, low=0) == 0):
        why = "pan_iter=0" if not system.panchromatic_exact else (
            f"{type(system).__name__}'s panchromatic image is exact"
        )  # fmt: skip
        raise ValueError(
            f"admm_iter=0 returns the first stage's cube, and there is none here ({why}); "
            "use admm_iter ≥ 1"
        )
    bases, start = initial_bases(
        system,
        measurement,
        spatial=spatial,
        pan_iter=pan_iter,
        pan_atoms=pan_atoms,
        pan_weight=pan_weight,
        pan_tv_steps=pan_tv_steps,
        pan_spectrum=pan_spectrum,
        pan_fit_tv_steps=pan_fit_tv_steps,
        spatial_block=spatial_block,
        progress=bool(progress),
    )
    if admm_iter == 0:  # the first stage's cube, no ADMM stage (projected as ADMM's would be)
        return (tl.clip(start, 0, None) if flag("nonneg", nonneg) else start), History(), False
    if max_iter == "auto":
        max_iter = OTD_MAX_ITER[start is not None]
    if not isinstance(admm_iter, str):
        max_iter = min(max_iter, admm_iter)
    update = tuple(m for m in range(0 if update_spatial else 2, len(system.cube_shape)))
    start = [start] if start is not None else None  # handed over: ADMM frees it after iteration 1
    return tucker_admm(
        system,
        measurement,
        bases,
        start=start,
        update_modes=update,
        update_every=update_every,
        max_iter=max_iter,
        lam=lam,
        mu=mu,
        beta=beta,
        tol=tol,
        weights=weights,
        plane_support=plane_support,
        nonneg=nonneg,
        progress=progress,
        desc="OTD stage 2: ADMM",
    )


def wdct_admm(
    system,
    measurement,
    *,
    wavelet_name: str = "sym8",
    wavelet_level="auto",
    max_iter: int = 60,
    mu: float = 0.05,
    lam: float | str = 0.1,
    beta: float = 0.0,
    tol: float = 1e-4,
    weights=None,
    plane_support=False,
    nonneg: bool = True,
    progress: bool = False,
):
    """WDCT-ADMM: the same ADMM with the fixed basis Symlet-8 ⊗ Symlet-8 ⊗ DCT (thesis baseline).

    Registered as ``"wdct"``; every mode beyond the two spatial ones is DCT.  ``wavelet_level``
    is the spatial wavelet's depth (:func:`tensor_cosdi.bases.wavelet`; default as deep as the
    periodised transform allows); the other options as :func:`tucker_admm`.  ``plane_support``
    is off: the fixed-basis baseline's CASSDI-DFA estimate is too poor to pick planes from
    (−0.5 to −0.7 dB).  ``nonneg`` (on) as for OTD: on the same four scenes noiseless
    +0.12 / −0.01 / +0.34 / −0.06 dB, 30 dB +0.11 / 0.00 / +0.35 / −0.07 dB.
    """
    bases, _ = initial_bases(
        system, measurement, spatial="wavelet", wavelet_name=wavelet_name,
        wavelet_level=wavelet_level,
    )  # fmt: skip
    return tucker_admm(
        system, measurement, bases, max_iter=max_iter, mu=mu, lam=lam, beta=beta, tol=tol,
        weights=weights, plane_support=plane_support, nonneg=nonneg, progress=progress,
        desc="WDCT",
    )  # fmt: skip


#: :func:`~tensor_cosdi.solvers.pnp_gap.pnp_fast`'s ``pan_tv_steps`` (:func:`fast_start`): 3
#: warm-started Chambolle steps per iteration of its start's first stage instead of 10. First
#: measured against 10 and 5 (8 tuning scenes as they are and magnified 4×, 4 folds, TSA mask;
#: ``benchmarks/results/pnp_fast_tv_steps_zoom4.md``: 10 / 5 / 3 steps → 33.50 / 33.50 / 33.42 dB
#: noiseless, 31.42 / 31.44 / 31.43 at 30 dB, median 6.8 / 4.9 / 4.4 s on one thread), then
#: cross-validated against 5 with each budget, timed as a user's single call (the SNR fit included),
#: TSA mask and a random code: noisy data (30 and 20 dB,
#: ``benchmarks/results/cv_pnp_fast_noisy_tv.md``) within 0.01 dB, median 5.11-5.29 → 4.47-4.55 s a
#: cube; clean data (``benchmarks/results/cv_pnp_fast_clean_tv.md``, 66 or 72 iterations, the 5-s
#: budget: only candidates whose median time fits it compete) every fold chose 3 steps and 66
#: iterations: 35.14 → 35.06 dB through the TSA mask, 37.69 → 37.68 through the random code, median
#: 5.16 → 4.67 s (TSA), 5.61 → 5.09 s (random: its 16 views include clean ones the SNR estimate
#: reads noisy, which take ADMM iterations).
FAST_PAN_TV_STEPS = 3

#: :func:`~tensor_cosdi.solvers.pnp_gap.pnp_fast`'s ``pan_spectrum`` (:func:`fast_start`):
#: ``"gated"``, one first stage whose atoms are weighted by the fitted mean spectrum part-way
#: through where the measurement's spectrum has sharp lines
#: (:func:`~tensor_cosdi.solvers.panchromatic.gate_above`), at no extra cost. 8 tuning scenes as
#: they are and lit by A, LED-B3 and FL11, 4 folds, TSA
#: (``benchmarks/results/cv_pnp_fast_gated.md``): noiseless 34.87 → 37.48 dB over the 32 views,
#: every fold chose it (FL11 +7.1 to +14.4 dB a view; an unlit scene whose spectrum reads rough,
#: clay, −0.26); the report scenes' gates stay shut (their rows unchanged).  That run kept the gate
#: shut on noisy data: open there at the clean threshold it lost 0.10 dB at 30 dB (−6.4 to +4.3 dB a
#: view; that file at commit f6a84f8).  A higher threshold on noisy data, shut below an estimated 25
#: dB, and a floor on the weights were then cross-validated together
#: (:data:`~tensor_cosdi.solvers.panchromatic.GATE_ABOVE_CLEAN`,
#: ``benchmarks/results/light_gate.md``): 30 dB +1.49 dB over the same kind of 32 views.
FAST_PAN_SPECTRUM = "gated"
#: :func:`pnp_fast`'s ``warm_iter`` on noisy data: OTD's ADMM stage cut from 45 iterations to
#: 10.  On noisy data the stage does the first denoising (dropped altogether, 30 dB on face:
#: 34.4 → 30.1 dB), but 10 iterations do what 20 did: 8 tuning scenes as they are and magnified
#: 4×, 4 folds, 30 and 20 dB, TSA mask and a random code
#: (``benchmarks/results/cv_pnp_fast_noisy_start.md``): tuning means 32.08 / 29.41 / 35.50 /
#: 31.67 dB with 20 iterations, 32.08 / 29.39 / 35.49 / 31.68 with 10, median 5.51-5.80 →
#: 5.11-5.29 s a cube; every fold chose 10 (ties within 0.05 dB won by the faster).  Its first
#: stage keeps OTD's 90 iterations (``pan_iter``): 12 tuning scenes, 4 folds
#: (``benchmarks/results/cv_pnp_fast_pan.md``), 60 lose 0.16 dB clean and 0.15 dB at 30 dB,
#: 20 lose 2.9 and 1.2 dB.
FAST_WARM_ITER = 10
#: ``accelerate="auto"``: accelerated GAP only above this estimated SNR (dB).  Tuning scenes
#: (balloons, clay; TSA mask; OTD start, σ 0.1): noiseless, accelerated 31.45 dB against 29.68
#: plain; at 30 dB accelerated GAP lets the noise through the small code sums (18.6 dB), plain GAP
#: with ``ε = 0.1`` gives 28.29 dB (0.05: 24.4 accelerated; 0.2: 28.21; 0.5: 28.03).
ACCELERATE_ABOVE_DB = CLEAN_ABOVE_DB


def fast_start(system, measurement, *, admm_iter=0, progress: bool = False):
    """The cube :func:`~tensor_cosdi.solvers.pnp_gap.pnp_fast` starts from: OTD's first stage
    (its TV at :data:`FAST_PAN_TV_STEPS` steps an iteration and its atoms weighted by the
    scene's spectrum where that has sharp lines, :data:`FAST_PAN_SPECTRUM`), then ``admm_iter``
    ADMM iterations of :func:`online_tucker_admm`.  ``admm_iter=0`` is pnp_fast's start on a
    clean measurement; ``"auto"`` is its start on any measurement: 0 where the estimated SNR
    (:func:`~tensor_cosdi.solvers.snr.estimate_snr`) is :data:`ACCELERATE_ABOVE_DB` or more,
    :data:`FAST_WARM_ITER` below.  D-CoSNet weights trained with ``start="fast"`` begin from
    the first, ``start="adaptive"`` from the second (``tensor-cosdi train-dcosnet --start``).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
        A system with a first stage (``system.panchromatic_exact`` false; otherwise a
        ``ValueError``).
    measurement : tensor of ``system.measurement_shape``
    admm_iter : int ≥ 0 or "auto"
        ADMM iterations after the first stage (default 0: the first stage's cube alone).
    progress : bool
        A progress bar.

    Returns
    -------
    tensor of ``system.cube_shape``

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)
    >>> fast_start(p.system, p.measurement).shape == p.system.cube_shape
    True
    """
    if imager(system, "panchromatic_exact").panchromatic_exact:
        raise ValueError(
            f"fast_start is the first stage's cube, and {type(system).__name__} has none (its "
            "panchromatic image is exact): start such a system otherwise (e.g. OTD, "
            "D-CoSNet weights trained with start='zero')"
        )
    admm_iter = fast_start_iterations(system, measurement, admm_iter)
    cube, _, _ = online_tucker_admm(
        system, measurement, admm_iter=admm_iter, pan_tv_steps=FAST_PAN_TV_STEPS,
        pan_spectrum=FAST_PAN_SPECTRUM, progress=progress,
    )  # fmt: skip
    return cube


def fast_start_iterations(system, measurement, admm_iter="auto") -> int:
    """:func:`fast_start`'s ADMM iterations: ``admm_iter`` itself (an integer ≥ 0), or for
    ``"auto"`` 0 where the estimated SNR of ``measurement`` is :data:`ACCELERATE_ABOVE_DB` or
    more and :data:`FAST_WARM_ITER` below (the reading is cached: a later solver reuses it).

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=20)
    >>> fast_start_iterations(p.system, p.measurement), fast_start_iterations(p.system, None, 3)
    (10, 3)
    """
    if isinstance(admm_iter, str):
        if admm_iter != "auto":
            raise ValueError(f"admm_iter must be 'auto' or an integer ≥ 0, got {admm_iter!r}")
        from .snr import estimate_snr

        snr = estimate_snr(system, measurement).snr_db
        return 0 if snr >= ACCELERATE_ABOVE_DB else FAST_WARM_ITER
    return integer("admm_iter", admm_iter, low=0)


register_method(
    "otd", online_tucker_admm, summary="online Tucker dictionary ADMM (thesis Alg. 5, every system)"
)
register_method("wdct", wdct_admm, summary="ADMM in the fixed Symlet-8 ⊗ Symlet-8 ⊗ DCT basis")
