"""Plug-and-play reconstruction for every system: GAP or ADMM with any denoiser, its level
annealed.

On clean data, accelerated GAP: ``ĝ ← ĝ + (g − A x)``,
``x ← D_σₜ(x + Aᵀ(AAᵀ + εI)⁻¹(ĝ − A x))`` (:func:`tensor_cosdi.solvers.engine.gap`).
On noisy data, ADMM: ``x ← (AᵀA + ρI)⁻¹(Aᵀg + ρ(z − u))`` through the
system's closed-form ``solve_normal``, ``z ← max(D_σₜ(x + u), 0)``,
``u ← u + x − z`` (:func:`tensor_cosdi.solvers.engine.admm`).  Both use a
:class:`~tensor_cosdi.solvers.priors.Denoiser` prior whose ``σ`` falls
geometrically from ``sigma`` to ``sigma_end`` (relative to the start's
robust peak on clean data, to its mean brightness on noisy data:
:data:`SIGMA_SCALE`) over the iterations, started from OTD.  The splitting,
acceleration, ``ε``, ``ρ``, ``sigma_end`` and the iteration count follow
the measurement's estimated SNR unless given.

Why ADMM on noisy data (8 tuning scenes, 30 dB, OTD start 26.88 dB,
the learned denoiser): plain GAP with ``ε = 0.1`` reached 27.39 dB in 20
iterations and no more with more; ADMM reached 28.02 dB in 20 and 29.63 dB
in 80 iterations (``ρ`` 0.15, ``σ`` 0.1 → 0.04).  ADMM needs the
non-negativity: the TSA mask has a patch of 1-3 % transmission, whose
voxels the data barely constrain; there the network's negative excursions
fed the dual variable, and on ``clay`` PnP-ADMM fell from 32.6 dB to
18.8 dB (8.5 dB at a fixed ``σ``) — with ``z ≥ 0`` it climbs to 34.0 dB and
stays.
The default denoiser is the learned spectral one (``"spectral_net"``, needs
torch: ``pip install "tensor_cosdi[torch]"``); ``"tv"``, ``"wavelet"`` or
any registered denoiser or callable ``(x, sigma) -> x`` work without it.
"""

from __future__ import annotations

import functools

import numpy as np

from ..noise import snr_schedule
from . import engine
from ._base import check_positive, register_method
from .denoisers import resolve, self_ensemble, spectral_net
from .otd import (  # pnp_fast's start, defined with it
    ACCELERATE_ABOVE_DB,
    FAST_PAN_SPECTRUM,
    FAST_PAN_TV_STEPS,
    FAST_WARM_ITER,
)
from .panchromatic import PAN_SPECTRA
from .priors import LEVEL_SCALES, Denoiser

__all__ = ["pnp_gap", "pnp_fast", "fast_settings", "fast_budget", "float32_on_cpu"]

WARM_STARTS = ("gap_tv", "otd", "dcosnet", "none")
#: ``warm="otd"`` with ``pan_tv_steps="auto"``: 10 Chambolle steps per iteration of the start's
#: first stage, the value :func:`pnp_gap`'s defaults were cross-validated with.  OTD's own
#: (:data:`~tensor_cosdi.solvers.otd.PAN_TV_STEPS`, 20) was chosen on OTD's cube, which here
#: only starts 80 or more denoiser iterations; :func:`pnp_fast` takes 3
#: (:data:`~tensor_cosdi.solvers.otd.FAST_PAN_TV_STEPS`).
START_PAN_TV_STEPS = 10
#: ``warm="gap_tv"`` with ``warm_iter="auto"``: GAP-TV iterations of the start.
GAP_TV_WARM_ITER = 80
#: ``warm="otd"`` with ``warm_iter="auto"`` on a clean measurement (accelerated GAP): OTD's
#: first stage alone, no ADMM stage (elsewhere OTD's own 45 iterations).  200 accelerated
#: iterations wash the start's ADMM stage out: 8 tuning scenes as they are and magnified 4×,
#: 4 folds, noiseless, TSA, bfloat16 (``benchmarks/results/cv_pnp_gap_first_stage.md``):
#: tuning mean 36.26 dB after OTD's ADMM stage, 36.28 without it, every fold chose it; median
#: 13.34 → 10.85 s a cube.
WARM_ITER_CLEAN = 0
#: :func:`pnp_fast`'s ``max_iter``: 46 against 40 gained 0.20 dB clean and 0.11 dB at 30 dB on 12
#: tuning scenes, 4 folds (``benchmarks/results/cv_pnp_fast_budget.md``; every fold chose 46) for
#: six more denoiser calls, which fit the 5-s budget once its start's TV took 5 steps (and
#: still do, timed with the SNR fit, at 3 steps and 10 ADMM iterations of the start).
FAST_ITER = 46
#: :func:`pnp_fast` on a clean measurement (accelerated GAP) from OTD's first stage
#: (:func:`fast_budget`): that stage's cube alone (``warm_iter=0``), 66 iterations and the
#: level ending at 0.04.  On clean data the start's 20 ADMM iterations bought 0.01-0.05 dB
#: for about 0.8 s; 20 more denoiser iterations cost about as much and buy 0.7 dB.
#: Cross-validated over ``warm_iter`` 0 / 20 × ``max_iter`` 46 / 66 / 76 × ``sigma_end``
#: 0.04 / 0.05 on 8 tuning scenes as they are and magnified 4×, 4 folds, noiseless, TSA mask,
#: among the candidates no slower than the budget in use
#: (``benchmarks/results/cv_pnp_fast_first_stage_budget.md``; every fold chose this): tuning
#: mean 34.46 dB at the earlier budget (20 / 46 / 0.05, median 4.63 s a cube) → 35.14 dB
#: (4.52 s).  76 iterations gave 35.33 dB at a median of 4.91 s, past the budget.  Those
#: seconds left out the SNR fit (0.4-0.7 s at 256×256×28, cached from an earlier method's call
#: on the same measurement); timed with it, 66 iterations at 5 TV steps took 5.16 s and at
#: :data:`FAST_PAN_TV_STEPS` 4.67 s, which is why the start's TV takes 3.
FAST_WARM_ITER_CLEAN = 0
FAST_ITER_CLEAN = 66
FAST_SIGMA_END_CLEAN = 0.04
#: :func:`fast_budget` on noisy data where the network runs in float32 on a CPU
#: (:func:`float32_on_cpu`): a denoiser call takes about twice as long as in bfloat16 there, and
#: the budgets above take 7.3-9.4 s a cube on 2 cores (the report scenes:
#: ``benchmarks/results/pnp_fast_float32_budget_30db.md``, ``..._clean.md``).
#: Iterations and the start's ADMM iterations against the estimated SNR (log-linear, rounded),
#: cross-validated on such a CPU among the candidates whose median time a cube, timed as a
#: user's single call, fits the 5-s budget: 8 tuning scenes, 4 folds, TSA mask and a random
#: code (``benchmarks/results/cv_pnp_fast_float32_noisy.md``; 18 / 22 / 26 / 30 iterations
#: × 5 / 10 ADMM iterations of the start), each SNR on its own as the other SNR-anchored
#: budgets (:data:`ADMM_ITER`).  At 30 dB every fold through the TSA mask and three of four
#: through the random code chose 22 and 5, as did all 8 scenes for each code (tuning means
#: 29.97 and 33.10 dB against 30.15 and 33.22 for 30 iterations, which took 5.6 and 6.0 s); at
#: 20 dB every fold chose 18, with 10 ADMM iterations the better of the two on both codes
#: (28.01 and 30.51 dB).
FAST_ITER_FLOAT32 = {28.5: 22, 19.5: 18}
FAST_WARM_ITER_FLOAT32 = {28.5: 5, 19.5: 10}
#: The last level of those short runs on the RMS scale (a cube of three axes,
#: ``sigma_scale="auto"``), against the estimated SNR: with 22 iterations the level stays
#: higher than :data:`SIGMA_END_ADMM_SHORT`'s 0.04 at 30 dB.  Cross-validated at 30 dB over
#: 0.04 / 0.055 / 0.07 / 0.09 on the 8 tuning scenes as they are, magnified 4× and lit by
#: CIE FL2 (24 views), TSA mask and a random code
#: (``benchmarks/results/cv_pnp_fast_float32_sigma_end.md``): tuning means 32.30 / 32.36 /
#: 32.29 / 32.14 dB (TSA) and 36.07 / 36.24 / 36.06 / 35.65 (random); one setting for both
#: codes chose 0.055 on every fold.  Checked again with the network fine-tuned on 256×256
#: patches (``cv_pnp_fast_float32_sigma_end_ft256.md``, the same 24 views): 0.04 / 0.055 / 0.07
#: → 32.30 / 32.34 / 32.24 dB (TSA) and 36.15 / 36.31 / 36.13 (random), every fold 0.055.
#: The 20-dB anchor is :data:`SIGMA_END_ADMM_SHORT`'s.
FAST_SIGMA_END_FLOAT32 = {28.5: 0.055, 19.5: 0.2}
#: :func:`fast_budget` on clean data where the network runs in float32 on a CPU: the first
#: stage's cube alone, as :data:`FAST_WARM_ITER_CLEAN`, and 28 iterations ending at 0.04,
#: cross-validated in the same way over 24 / 28 / 32 iterations × a last level of 0.04 /
#: 0.05 / 0.06 (``benchmarks/results/cv_pnp_fast_float32_clean.md``): one setting for both
#: codes, two folds of four (the other two chose 32, which took 5.0-5.6 s); tuning means
#: 30.62 and 33.85 dB against 30.85 and 34.03 for the best candidate of each code.  What the
#: float32 budgets cost on the report scenes on such a CPU, both budgets in one run
#: (``benchmarks/results/pnp_fast_float32_budget_30db.md``, ``..._clean.md``): TSA mask 30.91 →
#: 30.75 dB at 30 dB and 32.68 → 31.22 noiseless, random code 33.72 → 33.84 and 35.94 → 34.76,
#: 0.56-0.64× the seconds (median 7.31-9.41 → 4.57-5.40 s a cube); lit by CIE FL2
#: (``..._fl2_30db.md``, ``..._fl2_clean.md``) 32.45 → 31.20 and 35.49 → 33.59 dB.  The last
#: level again over 0.025 / 0.03 / 0.04 on the 8 tuning scenes as they are and magnified 4×
#: (``cv_pnp_fast_float32_clean_sigma_end.md``): one setting for both codes kept 0.04 on every
#: fold (tuning means TSA 33.06 / 33.10 / 33.14 dB, random code 37.09 / 37.06 / 36.98).
FAST_CLEAN_FLOAT32 = {"warm_iter": 0, "max_iter": 28, "sigma_end": 0.04}
#: ``sigma_end="auto"``: the last denoiser level against the estimated SNR (dB → relative σ).
#: Noiseless, 8 tuning scenes, TSA mask, accelerated: 100 iterations ending at 0.015 give
#: 30.71 dB (80 at 0.01: 29.99; 80 at 0.015: 30.32; 120 at 0.01: 30.47; 40 at 0.01: 28.93).
#: The 40-dB anchor is 0.03, cross-validated on all 28 tuning scenes as they are and magnified
#: 4× (4 folds, noiseless, TSA mask, accelerated;
#: ``benchmarks/results/pnp_gap_sigma_clean_zoom4.md``): 0.01 / 0.015 / 0.02 / 0.03 / 0.04 →
#: 36.60 / 36.84 / 36.97 / 37.08 / 37.07 dB, two folds 0.03 and two 0.04.
SIGMA_END = {40.0: 0.03, 30.0: 0.03, 20.0: 0.08}
#: ``sigma_end="auto"`` for a short run (``max_iter`` ≤ :data:`SHORT_RUN`, e.g. :func:`pnp_fast`):
#: with fewer steps the level must stay higher.  Cross-validated with ``pnp_fast``'s settings
#: (40 iterations, one call each, OTD start with 20 ADMM iterations) on 12 tuning scenes in 4
#: folds, TSA mask: 0.05 noiseless (three folds of four; the fourth 0.06, a tie) and 0.05
#: at 30 dB (every fold), from 0.015-0.1 (``benchmarks/results/cv_pnp_fast_sigma.md``: tuning
#: means 30.55 dB noiseless at the long run's 0.015 against 30.94, 29.51 against 29.54 dB at
#: 30 dB); the 20-dB anchors are the long run's.  Plain GAP without acceleration keeps
#: :data:`SIGMA_END` (its 20-iteration default was chosen with it: σ_end 0.05 cost 0.2 dB).
SHORT_RUN = 50
SIGMA_END_SHORT = {40.0: 0.05, 30.0: 0.05, 20.0: 0.08}
#: At 30 dB with ADMM, 0.07, cross-validated on 8 tuning scenes as they are and magnified 4×
#: (``benchmarks/results/pnp_fast_sigma_30db_zoom4.md``: 0.05 / 0.07 / 0.1 → 31.37 / 31.43 /
#: 31.20 dB, three folds of four).
#: Both anchors are on :data:`SIGMA_SCALE`'s RMS scale since it was cross-validated: 0.04 at
#: 30 dB (``benchmarks/results/cv_pnp_fast_sigma_scale.md``), 0.2 at 20 dB
#: (``cv_pnp_fast_sigma_scale_20db.md``).
SIGMA_END_ADMM_SHORT = {28.5: 0.04, 19.5: 0.2}
#: :data:`SIGMA_END_ADMM_SHORT` where the level is relative to the robust peak
#: (``sigma_scale="peak"``, and a cube of more than three axes): the anchors chosen on that
#: scale (0.07 at 30 dB, above).
SIGMA_END_ADMM_SHORT_PEAK = {28.5: 0.07, 19.5: 0.2}
#: ``max_iter="auto"``: iterations with and without acceleration.  Accelerated (clean data)
#: keeps gaining to 100 (see :data:`SIGMA_END`); plain GAP at 30 dB does not (balloons 27.25 dB
#: at 40, 27.30 at 80; cd 27.08, 26.88) and, from OTD's faster start, 20 do what 40 did
#: (8 tuning scenes at 30 dB: 27.35 dB in 7.1 s against 27.34 dB in 9.5 s; σ_end 0.05: 27.15,
#: 0.08: 26.82; OTD alone 26.88).
#: With the denoiser's symmetries cycling (``cycle=True``) one call per iteration does what two
#: did, and the freed calls go to twice the iterations: accelerated GAP 100 → 200
#: (``benchmarks/results/cv_pnp_gap_calls_clean.md``: 8 tuning scenes, 4 folds, noiseless, TSA,
#: bfloat16; two calls × 100 iterations 32.19 dB, one × 100 32.19, one × 200 32.51, two × 200
#: 32.50; three folds of four chose one × 200).  Plain GAP keeps its number of denoiser calls
#: (20 iterations of two → 40 of one; not re-tuned).
MAX_ITER = {True: 200, False: 40}
#: ``splitting="auto"``: ADMM below :data:`ACCELERATE_ABOVE_DB`; then ``rho="auto"`` is
#: :data:`RHO`, ``max_iter="auto"`` :data:`ADMM_ITER` and ``sigma_end="auto"``
#: :data:`SIGMA_END_ADMM`.  8 tuning scenes, 30 dB, ``σ`` from 0.1, non-negative:
#: 80 iterations, ρ 0.1 / 0.15 / 0.2 / 0.3 → 29.02 / 29.63 / 29.54 / 29.16 dB (σ_end 0.04);
#: ρ 0.2, σ_end 0.03 / 0.04: 29.49 / 29.54; 120 iterations (σ_end 0.03) 29.73 dB at 1.5× the
#: time; 60: −0.3 dB.
SPLITTINGS = ("auto", "gap", "admm")
#: ``rho="auto"``.  With 160 iterations of one call, ρ 0.1 / 0.15 / 0.2 → 31.45 / 31.98 / 31.96
#: dB at 30 dB on 8 tuning scenes as they are and magnified 4×
#: (``benchmarks/results/cv_pnp_gap_rho_30db_zoom4.md``).  :func:`pnp_fast`'s float32 budget (22
#: iterations at 30 dB, over-relaxed by :data:`FAST_RELAX`) keeps it: 0.1 / 0.15 / 0.22 → 32.30 /
#: 32.36 / 32.09 dB (TSA) and 35.85 / 36.19 / 35.84 (random code) on 8 tuning scenes as they are,
#: magnified 4× and lit by CIE FL2, every fold of each code 0.15
#: (``benchmarks/results/cv_pnp_fast_float32_rho_30db.md``).
RHO = 0.15
#: ``relax="auto"``: ADMM's over-relaxation ``α`` (:func:`~tensor_cosdi.solvers.engine.admm`)
#: against the estimated SNR (keys are the estimator's readings, as for :data:`ADMM_ITER`;
#: log-linear between them, rounded to 0.01).  For :func:`pnp_gap` plain ADMM: 8 tuning
#: scenes as they are, magnified 4× and lit by CIE FL2, 4 folds, 30 dB
#: (``benchmarks/results/cv_pnp_gap_relax.md``): 1 / 1.9 → 33.34 / 33.47 dB through the TSA
#: mask (every fold 1.9), 36.47 / 36.39 through a random code (every fold 1); one setting for
#: both codes: 1, three folds of four.
RELAX = {28.5: 1.0, 19.5: 1.0}
#: :func:`pnp_fast`'s ``relax="auto"``, as :data:`RELAX`: over-relaxation moves further along
#: each x-step at no cost per iteration.  8 tuning scenes as they are, magnified 4× and lit by
#: CIE FL2, 4 folds, TSA mask only (``benchmarks/results/cv_pnp_fast_relax.md``):
#: 1 / 1.5 / 1.8 / 1.9 →
#: 32.43 / 32.75 / 32.88 / 32.97 dB at 30 dB (every fold 1.9; 1.9 against 1: the FL2 views
#: +0.92 dB on average, +0.07 to +1.59 a view, the others +0.34, −0.21 to +0.70),
#: 30.33 / 30.07 / 29.94 / 29.93 at 20 dB (every fold 1).  With the float32 budget
#: (:data:`FAST_ITER_FLOAT32`, 22 iterations at 30 dB) through both codes, the same 24 views
#: (``benchmarks/results/cv_pnp_fast_float32_relax_30db.md``): 1 / 1.5 / 1.9 → 31.72 / 32.13 /
#: 32.36 dB (TSA) and 35.40 / 35.96 / 36.22 (random code); every fold of each code chose 1.9.
#: At 20 dB with that budget (18 iterations), both codes, the same views
#: (``benchmarks/results/cv_pnp_fast_float32_relax_20db.md``): 1 / 1.4 / 1.9 → 30.41 / 30.47 /
#: 30.38 dB (TSA) and 33.17 / 32.94 / 32.76 (random code); one setting for both codes: 1, every
#: fold.
FAST_RELAX = {28.5: 1.9, 19.5: 1.0}
#: ADMM 80 → 160 iterations of one call, cross-validated with cycling
#: (``benchmarks/results/cv_pnp_gap_calls_30db.md``: 8 tuning scenes, 4 folds, 30 dB, TSA,
#: bfloat16; one / two calls × 80 iterations 29.94 / 29.94 dB, × 160 30.13 / 30.14 — a tie
#: within 0.05 dB, won by one call at 10.0 s against 14.0 s); with twice the iterations the 30-dB
#: level stays (``benchmarks/results/cv_pnp_gap_iter_30db_zoom4.md``: 8 tuning scenes as they
#: are and magnified 4×, 160 / 240 iterations × σ_end 0.05 / 0.06 / 0.08; 160 at 0.06 31.98 dB,
#: 240 at 0.06 31.97).  At 20 dB, where the level stays at 0.2 throughout, more iterations
#: over-smooth: 80 / 120 / 160 → 27.97 / 27.71 / 27.55 dB, every fold 80
#: (``benchmarks/results/cv_pnp_gap_iter_20db_zoom4.md``).  Keys are the estimator's readings,
#: as for :data:`SIGMA_END_ADMM`; log-linear between them, rounded.
ADMM_ITER = {28.5: 160, 19.5: 80}
#: Keys are the estimator's readings: on the tuning scenes it reads a true 30 dB as 28.0-28.9 dB
#: and a true 20 dB as 19.6-19.8 dB.  At 20 dB (ρ 0.15, 80 iterations): σ 0.1 → 0.06 / 0.09 /
#: 0.13: 23.60 / 24.83 / 25.87 dB; 0.2 throughout 26.70; 0.3 → 0.2 26.71; 0.3 throughout 26.44
#: (OTD alone 21.71) — so the level starts at ``max(sigma, sigma_end)``.
#: At a true 40 dB (read as 34.2-36.9 dB, so ADMM): 30.21 dB against plain GAP's 28.14 and
#: accelerated GAP's 25.50; σ_end 0.025 there would add 0.16 dB (not adopted: untested on
#: the report split).  The 30-dB anchor is 0.06, cross-validated over ρ and σ_end at 30 dB on 8
#: tuning scenes as they are and magnified 4× (4 folds, TSA mask;
#: ``benchmarks/results/pnp_gap_admm_30db_zoom4.md``): 0.04 kept the noise on smooth,
#: magnified scenes (balloons ×4: 33.84 dB, OTD's start 33.82; 0.06: 37.45), tuning means
#: 31.48 → 31.72 dB (as they are 29.96 → 29.88, magnified 33.00 → 33.57).  Checked again
#: with the fine-tuned network (``benchmarks/results/cv_pnp_gap_sigma_30db_ft128.md``, the same
#: 16 views): σ_end 0.05 / 0.06 / 0.07 → 32.00 / 32.18 / 32.22 dB, a tie within 0.05 dB.
#: All of these were relative to the start's robust peak.  Relative to its RMS
#: (:data:`SIGMA_SCALE`), the anchors are 0.05 at 30 dB and 0.2 at 20 dB, cross-validated on
#: the same 16 views (``benchmarks/results/cv_pnp_gap_sigma_scale.md``,
#: ``cv_pnp_gap_sigma_scale_20db.md``, bfloat16).  Checked again with the network fine-tuned
#: on 256×256 patches, float32 (``cv_pnp_gap_sigma_30db_ft256.md``, the same 16 views):
#: 0.04 / 0.05 / 0.065 → 32.54 / 32.61 / 32.34 dB, every fold 0.05.
SIGMA_END_ADMM = {28.5: 0.05, 19.5: 0.2}
#: :data:`SIGMA_END_ADMM` where the level is relative to the robust peak
#: (``sigma_scale="peak"``, and a cube of more than three axes): the anchors chosen on that
#: scale (0.06 at 30 dB, above).
SIGMA_END_ADMM_PEAK = {28.5: 0.06, 19.5: 0.2}
#: ``guard``: accelerated GAP stops when its residual has risen three iterations in a row to
#: above this many times its lowest (see :func:`pnp_gap`).  At 1.3 it stopped a converging run
#: on a scene lit by a fluorescent lamp (balloons~FL2, noiseless, TSA: 35.37 dB after 6.7 s,
#: 42.25 dB at 2.0; ``benchmarks/results/pnp_guard_fl2.md``); on the 24 tuning views of
#: ``benchmarks/results/cv_pnp_gap_guard.md`` (8 scenes as they are and lit by A and LED-B3)
#: 1.3, 2 and 4 never stopped a run and tied (34.66 dB), so the looser 2.0 is the default.
#: It is not free: on the report scenes 1.3 had stopped real_and_fake_apples (noiseless) at a
#: better iterate, and the report rows lost 0.13 dB (TSA) and 0.35 dB (random code) with 2.0
#: (measured with the earlier denoiser network; the CHANGELOG keeps both runs).
GUARD = 2.0
#: ``pan_spectrum``: the OTD start's spectral atoms (see :func:`pnp_gap`).  OTD's own default,
#: ``"auto"``, ties with plain atoms here: 8 tuning scenes as they are and lit by CIE A and
#: LED-B3, 4 folds, noiseless, TSA, bfloat16 (``benchmarks/results/cv_pnp_gap_pan_spectrum.md``):
#: 34.66 dB plain against 34.67 for a second first stage (median 14.0 → 16.9 s a cube); the 200
#: denoiser iterations wash the start's spectral atoms out, so the start stays single.
#: :func:`pnp_fast`'s 46 iterations keep more of it: 33.53 → 33.73 dB, every fold
#: (``benchmarks/results/cv_pnp_fast_pan_spectrum.md``; up to +1.4 dB on scenes lit by
#: LED-B3), but its median time went from 4.8 to 6.2 s a cube, past its 5-s budget, so it
#: stays an option there too (``pnp_fast(..., pan_spectrum="auto")``).  A gate read part-way
#: through one first stage costs nothing (:data:`FAST_PAN_SPECTRUM`); for ``pnp_gap`` it pays on
#: clean measurements only: 8 tuning scenes as they are and lit by A, LED-B3 and FL11, 4 folds,
#: noiseless and 30 dB, TSA (``benchmarks/results/light_gate_pnp_gap.md``): held out 37.19 →
#: 37.80 dB, every fold chose the clean threshold and a shut gate on noisy data (noiseless
#: +1.23 dB, FL11 views up to +8.7; 30 dB: open on FL11 views it lost 1.0 dB on average).
PAN_SPECTRUM = "gated_clean"
#: ``sigma_scale="auto"``: what the denoiser's level is relative to, by splitting (see
#: :class:`~tensor_cosdi.solvers.priors.Denoiser`).  On noisy data (ADMM) the level follows
#: the noise, and a measurement's noise at a given SNR scales with the scene's mean
#: brightness, not with its highlights: relative to the robust peak, a bright, flat scene was
#: under-regularised (balloons magnified 4× at 20 dB: 20.24 dB, 34.29 with the RMS scale) and
#: a dark one with highlights over-smoothed.  8 tuning scenes as they are and magnified 4×,
#: 4 folds, TSA, every fold chose the RMS scale: ``pnp_gap`` (bfloat16) tuning means
#: 32.18 → 32.54 dB at 30 dB (``benchmarks/results/cv_pnp_gap_sigma_scale.md``) and
#: 28.26 → 29.49 dB at 20 dB (``cv_pnp_gap_sigma_scale_20db.md``); ``pnp_fast``
#: 31.97 → 32.08 and 28.94 → 29.67 (``cv_pnp_fast_sigma_scale.md``,
#: ``cv_pnp_fast_sigma_scale_20db.md``).  On clean data (accelerated GAP) the level
#: regularises the code's ill-posedness, not noise, and the best one there does not follow
#: the ratio of peak to RMS (``pnp_gap_sigma_clean_zoom4.md``): it keeps the peak.  Only a
#: cube of three axes (x, y, λ) takes this table; one with more (CASSDI-DFA's depth planes,
#: CS2LI's and Mu-CoSDI's phase steps) keeps the peak: its RMS is diluted by the planes a
#: pixel does not occupy, and the RMS scale was cross-validated on spectral cubes only.
SIGMA_SCALE = {"gap": "peak", "admm": "rms"}
#: ``ensemble="auto"``: denoiser calls per iteration (see :func:`pnp_gap`).
ENSEMBLE = 1
#: ``eps="auto"`` without acceleration: ε against the estimated SNR (with it: 1e-6).
EPS = {30.0: 0.1, 20.0: 0.3}


def gap_settings(system, measurement, accelerate, eps, *, need_snr: bool = False):
    """``(accelerate, eps, snr)`` with ``"auto"`` values resolved from the estimated SNR
    (:func:`~tensor_cosdi.solvers.snr.estimate_snr`).

    ``accelerate="auto"``: only above :data:`ACCELERATE_ABOVE_DB`;
    ``eps="auto"``: 1e-6 with acceleration, else :data:`EPS`.  ``snr`` is
    ``None`` unless something needed it (or ``need_snr``).
    """
    for name, v in (("eps", eps), ("accelerate", accelerate)):
        if isinstance(v, str) and v != "auto":
            raise ValueError(f"{name} must be 'auto' or a value, got {v!r}")
    snr = None
    if need_snr or accelerate == "auto" or eps == "auto":
        from .snr import estimate_snr

        snr = estimate_snr(system, measurement).snr_db
    if accelerate == "auto":
        accelerate = bool(snr >= ACCELERATE_ABOVE_DB)
    elif not isinstance(accelerate, bool):
        raise ValueError(f"accelerate must be True, False or 'auto', got {accelerate!r}")
    if eps == "auto":  # never below the system's own floor (an ill-conditioned A Aᵀ)
        floor = getattr(system, "gap_eps", 1e-6)
        eps = max(floor, 1e-6 if accelerate else snr_schedule(snr, EPS))
    return accelerate, check_positive("eps", eps), snr


def pnp_gap(
    system,
    measurement,
    *,
    denoiser="spectral_net",
    sigma: float = 0.1,
    sigma_end="auto",
    max_iter="auto",
    warm: str = "otd",
    warm_iter="auto",
    pan_iter="auto",
    pan_tv_steps="auto",
    pan_atoms="auto",
    pan_spectrum=PAN_SPECTRUM,
    accelerate="auto",
    eps="auto",
    splitting="auto",
    rho="auto",
    relax="auto",
    nonneg: bool = True,
    tol: float = 1e-5,
    guard=GUARD,
    ensemble="auto",
    cycle: bool = True,
    precision: str = "float32",
    sigma_scale="auto",
    progress: bool = False,
):
    """Plug-and-play GAP / ADMM (see the module).  Registered as ``"pnp_gap"``.

    Parameters
    ----------
    denoiser : str or callable
        A registered denoiser (:func:`~tensor_cosdi.solvers.denoisers.denoisers`)
        or a callable ``(x, sigma) -> x``.
    sigma, sigma_end : float
        Denoiser level of the first and the last iteration, relative to the
        start's robust peak or to its RMS (``sigma_scale``).
        ``sigma_end="auto"`` follows the measurement's estimated SNR
        (:data:`SIGMA_END` for GAP, :data:`SIGMA_END_ADMM` for ADMM;
        :func:`tensor_cosdi.noise.snr_schedule`) and the run's length
        (:data:`SIGMA_END_SHORT`, :data:`SIGMA_END_ADMM_SHORT` up to
        :data:`SHORT_RUN` iterations): the noisier the data, the higher the
        floor (a short accelerated run's too), and the first level is then
        ``max(sigma, sigma_end)``.  At 30 dB the first level 0.1 and the OTD
        start's own ADMM iterations were cross-validated against 0.05 and 0.2
        and a 10-iteration start (8 tuning scenes as they are and magnified
        4×, TSA): every fold kept them, 32.55 dB against 32.43 to 32.52
        (``benchmarks/results/cv_pnp_gap_noisy_start.md``).
    warm : ``"gap_tv"``, ``"otd"``, ``"dcosnet"`` or ``"none"``
        Start from ``warm_iter`` iterations of :func:`~.gap_tv.gap_tv` at its
        defaults (``"auto"``: 80), from OTD with ``warm_iter`` iterations of
        its ADMM stage (``"auto"``: :data:`WARM_ITER_CLEAN` on a clean
        measurement with accelerated GAP, where the system has a first stage,
        else OTD's default; 0: the first stage's cube alone, where the system
        has a first stage; the first stage is OTD's either way), from one pass
        of the shipped thesis
        D-CoSNet (:func:`~.dcosnet.dcosnet` with ``start="zero"``: no first stage of its
        own; SD-CASSI, 28 bands, 2 px per band), or from the least-norm solution.
        The denoiser refines a good start; from the least-norm one it climbs
        slowly (a learned denoiser removes what looks like noise, not the
        coded-aperture pattern's large-scale errors).
    pan_iter : int or "auto"
        With ``warm="otd"``: the iterations of OTD's first stage (its
        ``pan_iter``; ``"auto"``: OTD's default).  Any other start refuses an
        integer here.
    pan_tv_steps : int or "auto"
        With ``warm="otd"``: the warm-started Chambolle steps per iteration of
        that first stage (OTD's ``pan_tv_steps``; ``"auto"``:
        :data:`START_PAN_TV_STEPS`).
    pan_atoms : int or "auto"
        With ``warm="otd"``: the spectral DCT atoms of that first stage (OTD's
        ``pan_atoms``; ``"auto"``: OTD's default,
        :func:`~tensor_cosdi.solvers.subspace.pan_atoms_for`).
    pan_spectrum : str (one of :data:`~tensor_cosdi.solvers.panchromatic.PAN_SPECTRA`)
        With ``warm="otd"``: how that first stage spans the bands (OTD's
        ``pan_spectrum``, :data:`~tensor_cosdi.solvers.panchromatic.PAN_SPECTRA`).
        ``"flat"``: plain DCT atoms, one first stage; ``"auto"`` also tries the atoms
        weighted by the fitted mean spectrum on a clean measurement (OTD's default; a second
        first stage, about 2.9 s at 256×256×28, which gained 0.01 dB here) and is
        ``"gated"`` on a noisy one; ``"gated"``
        weights one stage's atoms part-way through, only under a light with sharp lines
        (:func:`~tensor_cosdi.solvers.panchromatic.gate_above`; :func:`pnp_fast`'s default,
        :data:`FAST_PAN_SPECTRUM`); ``"gated_clean"`` (default, :data:`PAN_SPECTRUM`) the
        same on a clean measurement only.  With another start, which has no first stage, the
        two gated settings do nothing.
    accelerate : bool or "auto"
        Accelerated GAP (``ĝ ← ĝ + (g − A x)``); ``"auto"``: only when the
        estimated SNR is above :data:`ACCELERATE_ABOVE_DB` (acceleration
        fits the noise of a noisy measurement).
    eps : float or "auto"
        ``ε`` of ``(AAᵀ + εI)⁻¹`` relative to the sensing gain; ``"auto"``:
        1e-6 with acceleration, else :data:`EPS` against the estimated SNR
        (a larger ``ε`` keeps small code sums from amplifying noise).
    splitting : ``"auto"``, ``"gap"`` or ``"admm"``
        ``"auto"``: accelerated GAP when the estimated SNR is above
        :data:`ACCELERATE_ABOVE_DB` (or ``accelerate`` is given), else ADMM
        with the system's closed-form x-step (see the module).
    rho : float or "auto"
        ADMM penalty relative to the sensing gain (``"auto"``: :data:`RHO`).
    relax : float in (0, 2) or "auto"
        ADMM's over-relaxation ``α`` (:func:`~tensor_cosdi.solvers.engine.admm`;
        ``"auto"``: :data:`RELAX` against the estimated SNR, 1 on a system whose
        ``admm_relax`` is false, such as C3SLFI); 1 is plain ADMM.  Unused by GAP.
    nonneg : bool
        Project the denoiser's output onto ``x ≥ 0`` (default; turn off for
        signed cubes).
    max_iter, tol
        Iterations (``"auto"``: :data:`MAX_ITER`, 200 for accelerated GAP, 40
        for plain GAP; for ADMM :data:`ADMM_ITER` against the estimated SNR,
        160 at 30 dB, 80 at 20 dB) and the relative-change
        tolerance.
    ensemble : int or "auto"
        Average the denoiser over this many symmetries of the image plane
        (1, 2, 4 or 8; :func:`~tensor_cosdi.solvers.denoisers.self_ensemble`):
        costs that many denoiser calls per iteration.  ``"auto"``:
        :data:`ENSEMBLE`, 1: with ``cycle`` the calls of successive
        iterations already take every symmetry, and a second call per
        iteration adds nothing that twice the iterations do not
        (:data:`MAX_ITER`, :data:`ADMM_ITER`).  Without cycling, 2 calls
        gained on the tuning scenes (clean 30.71 → 31.01 dB; 30 dB, four
        scenes, 29.52 → 29.73, against 29.66 for 120 single-call
        iterations), and at 30 dB 4 with ``max_iter=120`` about 0.2 dB more
        (``benchmarks/results/cv_pnp_gap_ensemble.md``).
    cycle : bool
        Each iteration's denoiser calls take the next symmetries of the image
        plane, cycling through all eight over the run, instead of the same
        ``ensemble`` ones every iteration (``self_ensemble(..., cycle=True)``):
        the network's orientation-dependent errors average out over the
        iterations at no extra cost (``benchmarks/results/cv_pnp_gap_cycle.md``
        and ``cv_pnp_fast_cycle.md``: every fold chooses it).
    precision : {"float32", "bfloat16", "auto"}
        The learned denoiser's arithmetic
        (:class:`~tensor_cosdi.learn.spectral_net.SpectralDenoiser`):
        ``"bfloat16"`` runs the network about twice as fast on a CPU with
        native bfloat16 instructions, ``"auto"`` uses it only there.  The
        float32 default gives the same cube on every machine and in any
        measurement units.  Only for ``denoiser="spectral_net"``.
    sigma_scale : {"auto", "peak", "rms"}
        What ``sigma`` and ``sigma_end`` are relative to
        (:class:`~tensor_cosdi.solvers.priors.Denoiser`'s ``scale``): the start's
        robust peak, or :data:`~tensor_cosdi.solvers.priors.PEAK_PER_RMS` times its
        RMS, a level that follows the scene's mean brightness as a measurement's
        noise does (a least-norm start, ``warm="none"``, carries the noise that its
        small code sums amplify into that RMS).  ``"auto"``: :data:`SIGMA_SCALE`
        for the splitting in use (the RMS on noisy data) on a cube of three axes
        ``(x, y, λ)``, the peak on a cube with more.
    guard : float or None
        Accelerated GAP stops when the residual ``‖A x − g‖`` has risen three
        iterations in a row to above ``guard`` times its lowest value, and
        returns the iterate that had the lowest
        (:func:`~tensor_cosdi.solvers.engine.gap`); ``None`` turns it off
        (default :data:`GUARD`, 2.0: 1.3 stopped converging runs).
        Under an earlier 80-iteration schedule, the tuning scene ``cd`` ended at
        22.0 dB without it and 27.9 dB with it at 1.3 (the learned denoiser
        could not represent its diffraction spectra at low levels, and the
        accelerated feedback diverged); at today's defaults no tuning view
        trips it (``benchmarks/results/cv_pnp_gap_guard.md``).

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "coffee", shape=(32, 32), n_bands=8)
    >>> res = tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=5)
    >>> res.cube.shape
    (32, 32, 8)
    """
    for name, v in (("sigma", sigma), ("tol", tol)):
        check_positive(name, v)
    if isinstance(sigma_end, str) and sigma_end != "auto":
        raise ValueError(f"sigma_end must be 'auto' or a value, got {sigma_end!r}")
    if splitting not in SPLITTINGS:
        raise ValueError(f"splitting must be one of {SPLITTINGS}, got {splitting!r}")
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    chosen = accelerate != "auto"
    auto_admm_iter = splitting == "admm" and isinstance(max_iter, str)
    relax = engine.check_relax(relax, auto=True)
    guard = engine.check_guard(guard)  # checked on every splitting, used by accelerated GAP
    need_snr = sigma_end == "auto" or auto_admm_iter or (splitting == "admm" and relax == "auto")
    accelerate, eps, snr = gap_settings(system, measurement, accelerate, eps, need_snr=need_snr)
    if splitting == "auto":
        splitting = "gap" if accelerate or chosen else "admm"
    admm = splitting == "admm"
    sigma_scale = _level_scale(system, sigma_scale, admm)
    if admm:
        rho = RHO if isinstance(rho, str) and rho == "auto" else rho
        rho = check_positive("rho", rho)
    elif not (isinstance(rho, str) and rho == "auto"):
        check_positive("rho", rho)  # validated, unused by GAP
    if relax == "auto":
        relax = _auto_relax(system, snr, RELAX) if admm else 1.0
    if isinstance(max_iter, str):
        if max_iter != "auto":
            raise ValueError(f"max_iter must be 'auto' or an integer ≥ 1, got {max_iter!r}")
        max_iter = round(snr_schedule(snr, ADMM_ITER)) if admm else MAX_ITER[accelerate]
    max_iter = engine.check_int("max_iter", max_iter, 1)
    if sigma_end == "auto":
        # plain (unaccelerated) GAP's own 20-iteration default was tuned with SIGMA_END
        short = max_iter <= SHORT_RUN and (admm or accelerate)
        if admm and sigma_scale == "peak":
            table = SIGMA_END_ADMM_SHORT_PEAK if short else SIGMA_END_ADMM_PEAK
        elif admm:
            table = SIGMA_END_ADMM_SHORT if short else SIGMA_END_ADMM
        else:
            table = SIGMA_END_SHORT if short else SIGMA_END
        sigma_end = snr_schedule(snr, table)
        sigma = max(sigma, sigma_end)  # the level never starts below its floor
    sigma_end = check_positive("sigma_end", sigma_end)
    warm_iter = _check_warm_iter(warm_iter, warm)
    clean_start = warm == "otd" and accelerate and not admm and not system.panchromatic_exact
    if clean_start and warm_iter == "auto":  # the ADMM stage's work is washed out here
        warm_iter = WARM_ITER_CLEAN
    pan_iter = _check_first_stage(pan_iter, warm, "pan_iter")
    pan_tv_steps = _check_first_stage(pan_tv_steps, warm, "pan_tv_steps")
    pan_atoms = _check_first_stage(pan_atoms, warm, "pan_atoms")
    pan_spectrum = _check_pan_spectrum(pan_spectrum, warm)
    den = resolve(denoiser)
    if den is spectral_net:  # fail before the warm start, naming the extra
        from ..learn import require_torch

        require_torch()
        from ..learn.spectral_net import PRECISIONS

        if precision not in PRECISIONS:
            raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
        if precision != "float32":
            den = functools.partial(spectral_net, precision=precision)
    elif precision != "float32":
        raise ValueError(
            f"precision={precision!r} is an option of the learned denoiser 'spectral_net'; "
            f"the denoiser here is {denoiser!r}"
        )
    if isinstance(ensemble, str):
        if ensemble != "auto":
            raise ValueError(
                f"the ensemble size must be 'auto' or one of 1, 2, 4, 8, got {ensemble!r}"
            )
        ensemble = ENSEMBLE
    den = self_ensemble(den, ensemble, cycle=cycle)  # checks cycle
    prior = Denoiser(
        den, sigma=sigma, sigma_end=sigma_end, n_steps=max_iter, nonneg=nonneg, scale=sigma_scale
    )
    return warm_started_gap(
        system,
        measurement,
        prior,
        warm=warm,
        warm_iter=warm_iter,
        pan_iter=pan_iter,
        pan_tv_steps=pan_tv_steps,
        pan_atoms=pan_atoms,
        pan_spectrum=pan_spectrum,
        accelerate=accelerate,
        eps=eps,
        max_iter=max_iter,
        tol=tol,
        progress=progress,
        desc="PnP-ADMM" if admm else "PnP-GAP",
        guard=guard,
        rho=rho if admm else None,
        relax=relax,
    )


def warm_started_gap(
    system, g, prior, *, warm, warm_iter, accelerate, eps, max_iter, tol, progress, desc,
    guard=None, rho=None, pan_iter="auto", pan_tv_steps="auto", pan_atoms="auto",
    pan_spectrum="flat", relax=1.0,
):  # fmt: skip
    """:func:`~tensor_cosdi.solvers.engine.gap` (or, with ``rho``, :func:`~.engine.admm`) with
    ``prior`` from a ``warm`` start (:data:`WARM_STARTS`: ``warm_iter`` GAP-TV iterations at its
    defaults, OTD with ``warm_iter`` iterations of its ADMM stage, the shipped D-CoSNet, or the
    least-norm solution; ``"auto"``: :data:`GAP_TV_WARM_ITER`, OTD's own; ``pan_iter``: OTD's
    first-stage iterations, ``pan_tv_steps`` its Chambolle steps and ``pan_atoms`` its spectral
    atoms, ``"auto"`` its own (the steps: :data:`START_PAN_TV_STEPS`); ``pan_spectrum`` its
    spectral atoms' weighting, ``"flat"`` by default); one history for both stages; ``relax``:
    the ADMM's over-relaxation (not the start's).  Returns ``(x, history, converged)``."""
    if warm not in WARM_STARTS:
        raise ValueError(f"warm must be one of {WARM_STARTS}, got {warm!r}")
    warm_iter = _check_warm_iter(warm_iter, warm)
    if warm == "otd" and warm_iter == 0 and system.panchromatic_exact:
        raise ValueError(
            f"warm_iter=0 starts from OTD's first stage, and {type(system).__name__} has none "
            "(its panchromatic image is exact); use warm_iter ≥ 1"
        )
    pan_iter = _check_first_stage(pan_iter, warm, "pan_iter")
    pan_tv_steps = _check_first_stage(pan_tv_steps, warm, "pan_tv_steps")
    pan_atoms = _check_first_stage(pan_atoms, warm, "pan_atoms")
    pan_spectrum = _check_pan_spectrum(pan_spectrum, warm)
    start, hist = None, None
    if warm == "gap_tv":
        from .gap_tv import gap_tv

        n = GAP_TV_WARM_ITER if warm_iter == "auto" else warm_iter
        start, hist, _ = gap_tv(system, g, max_iter=n, progress=progress)
    elif warm == "otd":
        from .otd import online_tucker_admm

        steps = START_PAN_TV_STEPS if pan_tv_steps == "auto" else pan_tv_steps
        first = {"pan_iter": pan_iter, "pan_tv_steps": steps, "pan_atoms": pan_atoms}
        pan = {k: v for k, v in first.items() if v != "auto"}
        start, hist, _ = online_tucker_admm(
            system, g, admm_iter=warm_iter, progress=progress, pan_spectrum=pan_spectrum, **pan
        )
    elif warm == "dcosnet":  # one pass of the shipped network (torch; weights for this system)
        from ._base import History
        from .dcosnet import dcosnet

        start, first, _ = dcosnet(system, g, start="zero")
        hist = History()
        hist.extend(first)
    common = {"max_iter": max_iter, "tol": tol, "progress": progress, "desc": desc}
    if rho is not None:  # ADMM; a start handed over in a list is freed after its first use
        handed, start = (None if start is None else [start]), None
        x, h2, conv = engine.admm(
            system.operator, g, prior, rho=rho, start=handed, relax=relax, **common
        )
    else:
        x, h2, conv = engine.gap(
            system.operator, g, prior, eps=eps, start=start, accelerate=accelerate, guard=guard,
            **common,
        )  # fmt: skip
    return x, _joined(hist, h2), conv


def _level_scale(system, sigma_scale, admm: bool) -> str:
    """``sigma_scale`` checked, ``"auto"`` resolved by the splitting (:data:`SIGMA_SCALE`) on a
    cube of three axes, ``"peak"`` on more."""
    if not isinstance(sigma_scale, str) or sigma_scale not in ("auto", *LEVEL_SCALES):
        raise ValueError(
            f"sigma_scale must be 'auto' or one of {LEVEL_SCALES}, got {sigma_scale!r}"
        )
    if sigma_scale != "auto":
        return sigma_scale
    three_way = len(tuple(getattr(system, "cube_shape", ()))) == 3
    return SIGMA_SCALE["admm" if admm else "gap"] if three_way else "peak"


def _auto_relax(system, snr_db: float, table: dict) -> float:
    """``relax="auto"``: ``table`` against the estimated SNR, rounded to 0.01; plain ADMM (1) on
    a system whose ``admm_relax`` is false."""
    if not getattr(system, "admm_relax", True):
        return 1.0
    return round(snr_schedule(snr_db, table), 2)


def _check_warm_iter(warm_iter, warm):
    """``"auto"`` or an integer ≥ 0 (0: OTD's first stage alone; refused with the GAP-TV
    start, which is its iterations)."""
    if isinstance(warm_iter, str):
        if warm_iter != "auto":
            raise ValueError(f"warm_iter must be 'auto' or an integer ≥ 0, got {warm_iter!r}")
        return warm_iter
    warm_iter = engine.check_int("warm_iter", warm_iter, 0)
    if warm_iter == 0 and warm == "gap_tv":
        raise ValueError(
            "warm_iter=0 is for warm='otd' (its first stage alone); warm='gap_tv' needs "
            "warm_iter ≥ 1 (warm='none' starts from the least-norm solution)"
        )
    return warm_iter


def _check_first_stage(value, warm, name):
    """An option of the OTD start's first stage: ``"auto"`` or an integer ≥ 1, refused with any
    other start."""
    if isinstance(value, str):
        if value != "auto":
            raise ValueError(f"{name} must be 'auto' or an integer ≥ 1, got {value!r}")
        return value
    value = engine.check_int(name, value, 1)
    if warm in WARM_STARTS and warm != "otd":  # an unknown start is named by its own check
        raise ValueError(
            f"{name} sets the first stage of the OTD start; warm={warm!r} has none "
            f"(use warm='otd' or leave {name}='auto')"
        )
    return value


def _check_pan_spectrum(value, warm):
    """The OTD start's ``pan_spectrum``: one of ``PAN_SPECTRA``; anything but ``"flat"`` and
    the gated settings (a gate that stays shut where there is no first stage) is refused with
    another start."""
    if not isinstance(value, str) or value not in PAN_SPECTRA:
        raise ValueError(f"pan_spectrum must be one of {PAN_SPECTRA}, got {value!r}")
    if value not in ("flat", "gated", "gated_clean") and warm in WARM_STARTS and warm != "otd":
        raise ValueError(
            f"pan_spectrum sets the first stage of the OTD start; warm={warm!r} has none "
            f"(use warm='otd' or leave pan_spectrum='flat')"
        )
    return value


def _joined(first, second):
    if first is None:
        return second
    first.extend(second)
    return first


def pnp_fast(
    system, measurement, *, max_iter="auto", ensemble: int = 1, precision: str = "auto",
    warm: str = "otd", warm_iter="auto", pan_iter="auto", pan_tv_steps="auto", pan_atoms="auto",
    pan_spectrum=FAST_PAN_SPECTRUM, sigma: float = 0.1, sigma_end="auto", rho="auto",
    relax="auto", nonneg: bool = True, cycle: bool = True, sigma_scale="auto",
    progress: bool = False,
):  # fmt: skip
    """The learned path with fewer and cheaper denoiser calls: :func:`pnp_gap` (accelerated
    GAP on clean data, ADMM on noisy data, as there) with one denoiser call per iteration
    (``ensemble=1``), each in the next of the eight symmetries of the image plane
    (``cycle=True``, as in :func:`pnp_gap`), the network in bfloat16 where the CPU runs it
    natively (``precision="auto"``), a short OTD start whose first stage's TV takes
    :data:`FAST_PAN_TV_STEPS` steps an iteration and whose spectral atoms follow a light with
    sharp lines (:data:`FAST_PAN_SPECTRUM`), and a budget by the data
    (:func:`fast_budget`): on noisy data :data:`FAST_WARM_ITER` ADMM iterations of the start
    and :data:`FAST_ITER` iterations, the level ending where a short run's was
    cross-validated (:data:`SIGMA_END_ADMM_SHORT`); on clean data the first stage's cube
    alone and :data:`FAST_ITER_CLEAN` iterations ending at :data:`FAST_SIGMA_END_CLEAN`.
    Registered as ``"pnp_fast"``.

    ``benchmarks/results/pnp_precision.md`` (report scenes, TSA mask, 2 cores) gives its time
    (of a single call, the SNR fit included) and PSNR beside :func:`pnp_gap`'s and the 30-line
    GAP-TV's.  On noisy data a 20-iteration OTD start ties with the 10-iteration one on the
    tuning scenes and is up to 0.1 dB better on the report scenes
    (``benchmarks/results/cv_pnp_fast_noisy_start.md``) for about 0.4 s more:
    ``pnp_fast(warm_iter=20)``.  On a CPU without native bfloat16 instructions
    (:func:`~tensor_cosdi.learn.spectral_net.bfloat16_is_fast` false, e.g. AVX2 only) the
    network runs in float32, where a call takes about twice as long, and the budget takes
    fewer calls, chosen within the same 5 s (:func:`fast_budget`; time and PSNR on the report
    scenes on such a CPU: ``benchmarks/results/pnp_fast_no_bf16.md``); there a smaller network
    (``denoiser_weights_fast_w40b3.md``), the network quantized to int8 after training
    (``denoiser_int8.md``) and its convolutions in Tucker-2 form
    (``denoiser_weights_fast_k24.md``) each cost PSNR and stayed over 5 s at the full budget.
    The budget follows the network's arithmetic, so the same call runs fewer iterations on
    such a CPU; for the same iterations on every machine pass ``max_iter``, ``warm_iter`` and
    ``sigma_end`` (``fast_budget(system, g, precision="bfloat16")`` gives the full ones).  In
    bfloat16 the result depends on the machine and moves by about 1e-3 when the measurement
    is rescaled; use ``precision="float32"`` (or :func:`pnp_gap`) where that matters.  It
    needs torch (``pip install "tensor_cosdi[torch]"``), like the learned denoiser it calls:
    ``tc.reconstruct(system, g, "pnp_fast")``.

    Parameters
    ----------
    max_iter, warm_iter, sigma_end
        As in :func:`pnp_gap`; ``"auto"`` (default): :func:`fast_budget` (a given value is
        kept, the others still follow the data).
    ensemble, precision, warm, pan_iter, pan_tv_steps, pan_atoms, pan_spectrum
        As in :func:`pnp_gap`, with the defaults above (``pan_tv_steps="auto"``:
        :data:`FAST_PAN_TV_STEPS` with the OTD start; :func:`fast_settings` lists them
        all).
    sigma
        The first level, as in :func:`pnp_gap` (0.1).  Cross-validated against 0.06 and 0.15
        (8 tuning scenes as they are and magnified 4×, TSA; clean also at 46 iterations):
        clean 35.08 dB against 34.98 and 35.01 (46 iterations: 34.22 to 34.31), 30 dB 32.08
        against 32.09 and 31.99 (``benchmarks/results/cv_pnp_fast_first_level_clean.md``,
        ``cv_pnp_fast_first_level_30db.md``).
    relax
        As in :func:`pnp_gap`; ``"auto"`` (default): :data:`FAST_RELAX` against the
        estimated SNR (1.9 at 30 dB, 1 at 20 dB; 1 where the system's ``admm_relax`` is
        false).
    rho, nonneg, cycle, sigma_scale, progress
        As in :func:`pnp_gap`.  Every other option of :func:`pnp_gap` keeps its
        default here (call ``"pnp_gap"`` to change it).

    Returns
    -------
    cube, history, converged
        As :func:`pnp_gap`.
    """
    return pnp_gap(
        system, measurement, **fast_settings(
            system, measurement, max_iter=max_iter, ensemble=ensemble, precision=precision,
            warm=warm, warm_iter=warm_iter, pan_iter=pan_iter, pan_tv_steps=pan_tv_steps,
            pan_atoms=pan_atoms,
            pan_spectrum=pan_spectrum, sigma=sigma, sigma_end=sigma_end, rho=rho, relax=relax,
            nonneg=nonneg, cycle=cycle, sigma_scale=sigma_scale,
        ), progress=progress,
    )  # fmt: skip


def fast_settings(system, measurement, **options) -> dict:
    """The :func:`pnp_gap` options that :func:`pnp_fast` runs with on ``measurement``: its
    defaults, updated by ``options`` (any of its own), with the ``"auto"`` ones resolved as it
    resolves them: its start's TV steps (:data:`FAST_PAN_TV_STEPS` with the OTD start) and its
    budget (:func:`fast_budget`).  ``pnp_gap(system, g, denoiser=d, **fast_settings(system,
    g))`` is :func:`pnp_fast` with the denoiser ``d``.

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``
    **options
        Options of :func:`pnp_fast`; any other name is a ``ValueError``.

    Returns
    -------
    dict
        Keyword arguments of :func:`pnp_gap`.

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)
    >>> s = fast_settings(p.system, p.measurement, precision="bfloat16")
    >>> s["pan_tv_steps"], s["warm_iter"], s["max_iter"], s["sigma_end"]
    (3, 0, 66, 0.04)
    >>> fast_settings(p.system, p.measurement, warm="gap_tv")["pan_tv_steps"]
    'auto'
    """
    import inspect

    params = inspect.signature(pnp_fast).parameters
    unknown = sorted(set(options) - set(params) - {"system", "measurement"})
    if unknown or "system" in options or "measurement" in options:
        raise ValueError(f"fast_settings: {unknown or ['system/measurement']} are not options "
                         f"of pnp_fast")  # fmt: skip
    out = {
        k: p.default for k, p in params.items()
        if p.default is not inspect.Parameter.empty and k != "progress"
    }  # fmt: skip
    out.update(options)
    auto_steps = isinstance(out["pan_tv_steps"], str) and out["pan_tv_steps"] == "auto"
    if out["warm"] == "otd" and auto_steps:
        out["pan_tv_steps"] = FAST_PAN_TV_STEPS
    auto = [k for k in BUDGET if isinstance(out[k], str) and out[k] == "auto"]
    if auto:
        budget = fast_budget(system, measurement, out["warm"], out["precision"], out["sigma_scale"])
        out.update({k: budget[k] for k in auto})
    if engine.check_relax(out["relax"], auto=True) == "auto":
        from .snr import estimate_snr

        snr = estimate_snr(system, measurement).snr_db  # cached: pnp_gap reads it too
        out["relax"] = _auto_relax(system, snr, FAST_RELAX)
    return out


#: The options :func:`fast_budget` resolves.
BUDGET = ("warm_iter", "max_iter", "sigma_end")


def float32_on_cpu(measurement, precision: str = "auto") -> bool:
    """Whether :func:`pnp_fast`'s learned denoiser runs its network in float32 on a CPU for
    ``measurement``, where a call takes about twice as long as in bfloat16
    (``benchmarks/results/denoiser_speed_avx2.md`` against ``denoiser_speed.md``) and
    :func:`fast_budget` spends fewer of them.  Needs torch.

    Parameters
    ----------
    measurement : tensor or ndarray
        The measurement: its device is the network's
        (:func:`~tensor_cosdi.learn.spectral_net.network_device`).
    precision : {"auto", "float32", "bfloat16"}
        :func:`pnp_fast`'s ``precision``
        (:func:`~tensor_cosdi.learn.spectral_net.network_precision`).

    Returns
    -------
    bool

    Examples
    --------
    >>> import torch
    >>> g = torch.zeros(8, 10)  # a CPU tensor: the network runs on the CPU
    >>> float32_on_cpu(g, "float32"), float32_on_cpu(g, "bfloat16")
    (True, False)
    """
    from ..learn.spectral_net import network_device, network_precision

    device = network_device(measurement)
    return device.type == "cpu" and network_precision(precision, device) == "float32"


def fast_budget(
    system, measurement, warm: str = "otd", precision: str = "auto", sigma_scale: str = "auto"
) -> dict:
    """:func:`pnp_fast`'s ``warm_iter``, ``max_iter`` and ``sigma_end`` for ``measurement``.

    On a clean one (accelerated GAP: an estimated SNR of :data:`ACCELERATE_ABOVE_DB` or more)
    started from OTD's first stage (a system without an exact panchromatic image): that
    stage's cube alone (:data:`FAST_WARM_ITER_CLEAN`), :data:`FAST_ITER_CLEAN` iterations,
    the level ending at :data:`FAST_SIGMA_END_CLEAN`.  Otherwise :data:`FAST_WARM_ITER` ADMM
    iterations of the start, :data:`FAST_ITER` iterations and :func:`pnp_gap`'s own
    ``sigma_end="auto"`` (:data:`SIGMA_END_ADMM_SHORT` on noisy data).  Where the network runs
    in float32 on a CPU (:func:`float32_on_cpu`: ``precision="float32"``, or ``"auto"`` on a
    CPU without native bfloat16), where each denoiser call takes about twice as long, fewer:
    :data:`FAST_CLEAN_FLOAT32` on clean data, :data:`FAST_WARM_ITER_FLOAT32` and
    :data:`FAST_ITER_FLOAT32` against the estimated SNR on noisy data, each chosen within the
    5-s budget on such a CPU, the level ending at :data:`FAST_SIGMA_END_FLOAT32`.  The trade is
    time-neutral at 256×256×28 (the cross-validation of :data:`FAST_ITER_CLEAN`); on small
    cubes, where the first stage is cheap beside the denoiser, it mostly costs more time
    (``benchmarks/results/fast_budget_systems.md``: every imager with a first stage at
    64×64×16, 0.98-1.77× the seconds against 10 ADMM iterations, +0.04 to +1.02 dB).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``
    warm : str
        :func:`pnp_fast`'s start (:data:`WARM_STARTS`).
    precision : {"auto", "float32", "bfloat16"}
        :func:`pnp_fast`'s ``precision``: with the measurement's device, the network's
        arithmetic (:func:`float32_on_cpu`).
    sigma_scale : str
        :func:`pnp_fast`'s ``sigma_scale``: the float32 budget's last level on noisy data
        (:data:`FAST_SIGMA_END_FLOAT32`) is on the RMS scale, so it applies there (``"rms"``,
        or ``"auto"`` on a cube of three axes); elsewhere ``sigma_end`` stays ``"auto"``.

    Returns
    -------
    dict
        ``{"warm_iter": int, "max_iter": int, "sigma_end": float or "auto"}``.

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> clean = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)
    >>> fast_budget(clean.system, clean.measurement, precision="bfloat16")
    {'warm_iter': 0, 'max_iter': 66, 'sigma_end': 0.04}
    >>> noisy = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=30)
    >>> fast_budget(noisy.system, noisy.measurement, precision="bfloat16")
    {'warm_iter': 10, 'max_iter': 46, 'sigma_end': 'auto'}
    """
    if warm not in WARM_STARTS:
        raise ValueError(f"warm must be one of {WARM_STARTS}, got {warm!r}")
    sigma_scale = _level_scale(system, sigma_scale, admm=True)  # the noisy budget's splitting
    slow = float32_on_cpu(measurement, precision)  # checks precision
    first_stage = warm == "otd" and not system.panchromatic_exact
    accelerate, _, snr = gap_settings(system, measurement, "auto", "auto", need_snr=slow)
    if first_stage and accelerate:
        if slow:
            return dict(FAST_CLEAN_FLOAT32)
        return {"warm_iter": FAST_WARM_ITER_CLEAN, "max_iter": FAST_ITER_CLEAN,
                "sigma_end": FAST_SIGMA_END_CLEAN}  # fmt: skip
    if slow:
        return {"warm_iter": round(snr_schedule(snr, FAST_WARM_ITER_FLOAT32)),
                "max_iter": round(snr_schedule(snr, FAST_ITER_FLOAT32)),
                "sigma_end": round(snr_schedule(snr, FAST_SIGMA_END_FLOAT32), 4)
                if sigma_scale == "rms" else "auto"}  # fmt: skip
    return {"warm_iter": FAST_WARM_ITER, "max_iter": FAST_ITER, "sigma_end": "auto"}


register_method(
    "pnp_fast",
    pnp_fast,
    summary="the learned plug-and-play path with 46 (noisy data) or 66 (clean) single "
    "denoiser calls in bfloat16 where the CPU runs it natively, fewer in float32 on a CPU "
    "(torch)",
    requires=("torch",),
)

register_method(
    "pnp_gap",
    pnp_gap,
    summary="plug-and-play GAP (clean) / ADMM (noisy) with an annealed denoiser "
    "(default: learned, torch)",
    requires=("torch",),
)
