"""OTD's first stage (SPEC §5 steps 1-2): the panchromatic estimate ``Z`` whose singular vectors
start the spatial bases, and the cube on the way to it (:func:`subspace_gap_tv`)."""

from __future__ import annotations

import tensorly as tl

from ..validate import number
from . import engine
from .subspace import (  # noqa: F401  (the subspace fit and its atom counts, re-exported here)
    MANY_BANDS,
    PAN_ATOMS,
    PAN_ATOMS_MANY,
    ROUGH_SPECTRUM,
    fitted_mean_spectrum,
    has_many_bands,
    pan_atoms_for,
    subspace_denoise,
    subspace_gap_tv,
)

__all__ = [
    "panchromatic_estimate", "subspace_gap_tv", "pan_weight_for", "pan_atoms_for",
    "has_many_bands", "PAN_WEIGHTS",
    "PAN_WEIGHTS_MANY",
    "PAN_ATOMS", "PAN_ATOMS_MANY", "MANY_BANDS", "PAN_SPECTRA", "FITTED_SPECTRUM_ABOVE_DB",
    "FITTED_MARGIN", "FIT_TV_STEPS", "keeps_fitted",
    "GATE_FRACTION", "GATE_ABOVE_CLEAN", "GATE_ABOVE_NOISY", "GATE_NOISY_FROM_DB", "gate_above",
]  # fmt: skip

_check_int = engine.check_int

#: ``pan_spectrum``: how the first stage's atoms span the bands (:func:`panchromatic_estimate`).
PAN_SPECTRA = ("flat", "fitted", "fitted_z", "auto", "gated", "gated_clean")
#: ``pan_spectrum="auto"`` weighs the fitted spectrum only from this estimated SNR (dB) on.  On
#: noisy data the misfit rule fails: the fitted spectrum is noisy and the weighted atoms fit
#: the noise (clay, 96×96×28, TSA, 20 dB: OTD at lam 0.1 29.36 → 22.74 dB).  At 30 dB the
#: cross-validation tied (``benchmarks/results/cv_otd_pan_spectrum.md``), so only clean data
#: pay for the second stage; a noise-free TSA measurement estimates at 40-47 dB.  Nor does
#: ``"fitted_z"`` (``Z`` from the weighted atoms, the start from the plain ones) pay on noisy
#: data: 8 tuning scenes as they are and lit by A and LED-B3, 4 folds, TSA
#: (``benchmarks/results/cv_otd_fitted_z.md``): 30 dB 30.28 → 30.34 dB (every fold chose it,
#: report scenes 29.57 → 29.55) for a second first stage (median 5.4 → 8.1 s a cube over
#: the 24 views), 20 dB 28.87 → 28.40.  Below this estimate ``"auto"`` is ``"gated"``: 8 tuning
#: scenes as they are and lit by A, LED-B3 and FL11, 4 folds, TSA, OTD
#: (``benchmarks/results/cv_otd_gated.md``): at 30 dB the gated stage 33.95 dB over the 32
#: views against 31.94 for the plain one, every fold (the lamps' lines the plain atoms cannot
#: hold); noiseless the two stages kept 34.92 against the gate's 34.59.  The rule that takes
#: each where it won (``cv_otd_noisy_gate.md``): noiseless 35.13 (views that read under this
#: estimate get the gate), 30 dB 33.95, every fold; through a random binary code at 30 dB 36.25
#: against the plain stage's 35.54, every fold (``cv_otd_noisy_gate_random.md``).  The unlit
#: report scenes' gates stay shut.
FITTED_SPECTRUM_ABOVE_DB = 38.0
#: ``pan_spectrum="auto"`` on a clean measurement keeps the weighted first stage unless its
#: residual ``‖A x − g‖`` exceeds the plain stage's by more than this share.  Both stages
#: nearly interpolate a noiseless measurement, so their residuals differ by a few per cent and
#: a plain comparison (0) is close to a coin flip where the weighted atoms help.
#: Cross-validated over 0 / 0.01 / 0.02 / 0.05 / 0.1 / 0.2 / always the weighted stage, OTD
#: on 12 tuning scenes as they are and lit by CIE A, LED-B3 and FL11 (48 views, 4 folds), TSA
#: mask and a random code, noiseless (``benchmarks/results/pan_spectrum_pick.md``): one margin
#: for both codes chose 0.1 on one fold and 0.2 on three; over the 48 views 0 → 0.2 moved the
#: TSA mean 35.20 → 35.26 dB and the random code's 38.35 → 38.33; on the report scenes under
#: the same lights TSA +0.38 dB (−0.04 … +3.93 a view), random +0.03 (−0.07 … +0.37).  That
#: run's plain stage took 20 Chambolle steps an iteration; at :data:`FIT_TV_STEPS` its
#: residual is higher and the weighted stage is kept more often (see there).
FITTED_MARGIN = 0.2
#: ``pan_fit_tv_steps``: warm-started Chambolle steps per iteration of the plain first stage
#: where it serves to fit the mean spectrum (``pan_spectrum="fitted"``, and ``"auto"`` on a
#: clean measurement, where it is also the fallback).  The spectrum needs no finer plain
#: stage than that, but the stage's residual is higher at fewer steps, so with 5 steps
#: :data:`FITTED_MARGIN` keeps the weighted stage where the 20-step plain stage had won
#: (cd, TSA: OTD 29.72 → 28.99 dB, both runs in the file below).  Cross-validated end to
#: end against 20 (OTD's
#: ``pan_tv_steps``), OTD on 8 tuning scenes as they are and lit by A, LED-B3 and FL11
#: (32 views, 4 folds, TSA mask and a random code, noiseless, ties within 0.05 dB to the
#: faster; ``benchmarks/results/cv_otd_pan_fit_tv_steps.md``): every fold chose 5; tuning
#: means 35.21 → 35.19 dB (TSA) and 37.84 → 37.84 (random), median 9.22 → 8.39 s and
#: 9.84 → 8.92 s a cube.
FIT_TV_STEPS = 5
#: ``pan_spectrum="gated"``: the share of the first stage's iterations after which the mean
#: spectrum is fitted and the gate read (:func:`~tensor_cosdi.solvers.subspace.subspace_gap_tv`'s
#: ``refit_at``).  Within ``pnp_fast`` on four tuning scenes lit by FL2 and LED-B3 (cloth,
#: balloons, cd, feathers; noiseless, TSA), gate forced open: 0.25 / 0.4 / 0.55 → 34.55 /
#: 34.72 / 34.64 dB under FL2, 33.27 / 33.27 dB under LED-B3 at 0.4 / 0.55 (plain atoms
#: under FL2: 33.78; both stages in full, ``"auto"``: 34.91 at 1.4 s more a cube).
GATE_FRACTION = 0.4
#: ``pan_spectrum="gated"``: the gate's roughness threshold on a clean measurement (estimated
#: SNR from :data:`FITTED_SPECTRUM_ABOVE_DB`), :data:`GATE_ABOVE_NOISY` on a noisy one down to
#: an estimated :data:`GATE_NOISY_FROM_DB`, shut below.  All three and the weights' floor
#: (:data:`~tensor_cosdi.solvers.subspace.GATE_FLOOR`) chosen together by 4-fold
#: cross-validation for ``pnp_fast`` over 8 tuning scenes as they are and lit by A, LED-B3 and
#: FL11, noiseless, 30 and 20 dB, TSA, 150 candidates (``benchmarks/results/light_gate.md``):
#: held out 35.44 → 35.91 dB against the gate shut on noisy data with a floor of 1e-3, every
#: fold; noiseless +0.15, 30 dB +1.49 (FL11 views up to +7.5, no view lower), 20 dB unchanged
#: (the gate open there lost up to 1.9 dB a view).  A white LED's peak (readings 0.07-0.25)
#: opens it on clean data only: at 30 dB its fitted spectrum weighted the atoms into losses of
#: up to 6 dB (clay~LED-B3).
GATE_ABOVE_CLEAN = ROUGH_SPECTRUM
#: See :data:`GATE_ABOVE_CLEAN`.
GATE_ABOVE_NOISY = 0.3
#: See :data:`GATE_ABOVE_CLEAN`.
GATE_NOISY_FROM_DB = 25.0

#: ``pan_weight="auto"``: the subspace GAP-TV weight against the measurement's estimated SNR
#: (:func:`tensor_cosdi.noise.snr_schedule`), for panchromatic axes shorter than
#: :data:`MANY_BANDS` (three atoms), chosen on the tuning scenes (SD-CASSI, TSA mask):
#: noiseless (balloons, flowers, clay) 28.23 dB at 0.3 (27.78 at 0.1, 27.69 at 0.6); 30 dB
#: (balloons, clay) 27.19 dB at 2.0 (26.95 at 1.0, 27.02 at 1.5); 20 dB (balloons, clay, lam 0.3)
#: 26.55 dB at 4.0 (24.82 at 2.0, 26.48 at 8.0).  A noise-free TSA measurement estimates at
#: 40-47 dB.
PAN_WEIGHTS = {40.0: 0.3, 30.0: 2.0, 20.0: 4.0}
#: The same from :data:`MANY_BANDS` on (with :data:`PAN_ATOMS_MANY` atoms), each anchor chosen
#: by 4-fold cross-validation over 16 tuning scenes as they are and magnified 2× (SD-CASSI,
#: 28 bands): noiseless 0.3 from 0.15 / 0.3 / 0.6 (TSA;
#: ``benchmarks/results/pan_weight_clean_zoom2.md``); 30 dB 0.25 from 0.25-2.0, both codes
#: (``pan_weight_30db_both_zoom2.md``; tuning means against :data:`PAN_WEIGHTS`' 2.0: TSA
#: 29.22 → 29.85 dB, random 31.62 → 32.14); 20 dB 1.0 from 0.5-4.0 (TSA;
#: ``pan_weight_20db_zoom2.md``: 27.61 → 27.96 dB against 4.0), all with six atoms.  A
#: many-atom first stage does best with far less smoothing under noise than the schedule
#: chosen with three atoms.
PAN_WEIGHTS_MANY = {40.0: 0.3, 30.0: 0.25, 20.0: 1.0}


def _check_pan_weight(pan_weight):
    if isinstance(pan_weight, str):
        if pan_weight != "auto":
            raise ValueError(f"pan_weight must be a number > 0 or 'auto', got {pan_weight!r}")
        return pan_weight
    from ._base import check_positive

    return check_positive("pan_weight", pan_weight)


def pan_weight_for(system, measurement, pan_weight) -> float:
    """``pan_weight`` as a number: ``"auto"`` follows :data:`PAN_WEIGHTS` (or, when a
    panchromatic axis has :data:`MANY_BANDS` samples or more, :data:`PAN_WEIGHTS_MANY`)
    against the measurement's estimated SNR (:func:`~tensor_cosdi.solvers.snr.estimate_snr`)."""
    if _check_pan_weight(pan_weight) == "auto":
        from ..noise import snr_schedule
        from .snr import estimate_snr

        table = PAN_WEIGHTS_MANY if has_many_bands(system) else PAN_WEIGHTS
        return snr_schedule(estimate_snr(system, measurement).snr_db, table)
    return float(pan_weight)


def panchromatic_estimate(
    system,
    measurement,
    *,
    pan_iter: int = 60,
    pan_atoms="auto",
    pan_weight="auto",
    pan_tv_steps: int | None = 10,
    pan_spectrum: str = "flat",
    pan_fit_tv_steps: int | None = FIT_TV_STEPS,
    progress: bool = False,
):
    """SPEC §5 step 1: ``Z`` and, where one was computed on the way, a starting cube.

    Systems whose :meth:`~tensor_cosdi.systems.System.panchromatic` is exact
    (complementary C3SLFI by Lemma 1, the dual-camera CASSI) use it.  The
    others use :func:`subspace_gap_tv` (``pan_iter`` iterations,
    ``pan_atoms`` spectral atoms (:func:`pan_atoms_for`), ``pan_tv_steps`` warm-started Chambolle
    steps per iteration — :class:`~tensor_cosdi.solvers.denoisers.WarmTV`;
    ``None``: 50 cold ones) and ``Z = D x``; with ``pan_iter = 0`` they
    fall back to the Tikhonov solve of the flat decimated model.

    ``pan_spectrum`` (:data:`PAN_SPECTRA`): ``"flat"`` spans the bands by plain DCT atoms;
    ``"fitted"`` runs the stage twice, the second time with the atoms weighted by the scene's
    mean spectrum fitted from the first (:func:`fitted_mean_spectrum`; a light with sharp
    spectral features); ``"fitted_z"`` runs both and takes ``Z`` from the weighted atoms'
    estimate and the starting cube from the plain one's; ``"auto"``, from
    :data:`MANY_BANDS` bands on and on a clean measurement (estimated SNR from
    :data:`FITTED_SPECTRUM_ABOVE_DB`), runs both stages as ``"fitted"`` does and keeps
    the weighted one unless its ``‖A x − g‖`` exceeds the plain one's by more than
    :data:`FITTED_MARGIN` (:func:`keeps_fitted`), and
    is ``"gated"`` on a noisy measurement (its gate at the noisy threshold, shut below an
    estimated :data:`GATE_NOISY_FROM_DB`; the plain stage where no gate can be read);
    ``"gated"`` runs one stage, fits the mean spectrum after
    :data:`GATE_FRACTION` of its iterations and, only when that spectrum has sharp lines
    (:func:`~tensor_cosdi.solvers.subspace.spectral_roughness` above :func:`gate_above`:
    :data:`GATE_ABOVE_CLEAN` on clean data, the higher :data:`GATE_ABOVE_NOISY` on noisy
    data, shut below an estimated :data:`GATE_NOISY_FROM_DB`), weights the atoms of the
    remaining iterations by it (floored at
    :data:`~tensor_cosdi.solvers.subspace.GATE_FLOOR` of its peak) — the plain stage, at its
    cost, under a smooth light, and wherever no gate can be read (fewer bands, several
    panchromatic axes); ``"gated_clean"`` is ``"gated"`` on a clean measurement and the plain
    stage on a noisy one (a long run after the start does better from plain atoms there).
    Weighted atoms need one panchromatic axis (``"fitted"`` and
    ``"fitted_z"`` refuse more).  Where the plain stage serves to fit the spectrum
    (``"fitted"``, and ``"auto"`` on a clean measurement) it takes ``pan_fit_tv_steps``
    Chambolle steps per iteration (:data:`FIT_TV_STEPS`; ``None``: 50 cold ones) instead of
    ``pan_tv_steps``; ``"fitted_z"``, whose starting cube it is, keeps ``pan_tv_steps``.

    Returns
    -------
    Z : tensor of ``system.panchromatic_shape``
    start : tensor of ``system.cube_shape`` or None
    """
    pan_iter = _check_int("pan_iter", pan_iter, 0)
    if pan_fit_tv_steps is not None:  # checked before any work, as pan_tv_steps is
        pan_fit_tv_steps = _check_int("pan_fit_tv_steps", pan_fit_tv_steps, 1)
    _check_pan_weight(pan_weight)
    pan_atoms_for(MANY_BANDS, pan_atoms)  # checked even where the exact estimate needs none
    if pan_spectrum not in PAN_SPECTRA:
        raise ValueError(f"pan_spectrum must be one of {PAN_SPECTRA}, got {pan_spectrum!r}")
    if system.panchromatic_exact or pan_iter == 0:
        return system.panchromatic(measurement), None
    axes = list(system.panchromatic_axes)
    if pan_spectrum == "auto" and not _clean(system, measurement):
        pan_spectrum = "gated"  # a noisy measurement: one stage and the gate, as "gated"
    gated = pan_spectrum in ("gated", "gated_clean")
    above = None  # the gate's threshold; None: no gate to read, the plain stage
    if pan_spectrum == "gated":
        above = gate_above(system, measurement)
    elif pan_spectrum == "gated_clean" and _clean(system, measurement):
        above = GATE_ABOVE_CLEAN
    if gated and above is None:
        pan_spectrum, gated = "flat", False
    if pan_spectrum != "flat" and len(axes) != 1:
        raise ValueError(
            f"pan_spectrum={pan_spectrum!r} needs one panchromatic axis; {system.name} has {axes}"
        )
    common = dict(
        n_atoms=pan_atoms,
        max_iter=pan_iter,
        tv_weight=pan_weight_for(system, measurement, pan_weight),
        tv_steps=pan_tv_steps,
        progress=progress,
    )
    if gated:  # one stage, its atoms weighted part-way where the light is sharp
        at = max(1, round(pan_iter * GATE_FRACTION))
        x = subspace_gap_tv(system, measurement, refit_at=at, refit_above=above, **common)
        return system.decimation.forward(x), x
    fit_only = pan_spectrum in ("fitted", "auto")  # the plain stage fits the spectrum
    plain = dict(common, tv_steps=pan_fit_tv_steps) if fit_only else common
    x = subspace_gap_tv(system, measurement, **plain)
    if pan_spectrum != "flat":
        w = fitted_mean_spectrum(system, measurement, x, axes[0])
        xw = subspace_gap_tv(system, measurement, spectral_weights={axes[0]: w}, **common)
        if pan_spectrum == "fitted_z":
            return system.decimation.forward(xw), x
        if pan_spectrum == "fitted" or keeps_fitted(
            _misfit(system, xw, measurement), _misfit(system, x, measurement)
        ):
            x = xw
    return system.decimation.forward(x), x


def _clean(system, measurement) -> bool:
    """Whether the fitted spectrum is worth weighing: one panchromatic axis of
    :data:`MANY_BANDS` samples or more, and an estimated SNR from
    :data:`FITTED_SPECTRUM_ABOVE_DB`."""
    return _one_long_axis(system) and _snr_db(system, measurement) >= FITTED_SPECTRUM_ABOVE_DB


def _one_long_axis(system) -> bool:
    return len(system.panchromatic_axes) == 1 and has_many_bands(system)


def _snr_db(system, measurement) -> float:
    from .snr import estimate_snr

    return estimate_snr(system, measurement).snr_db


def gate_above(system, measurement) -> float | None:
    """The roughness above which ``pan_spectrum="gated"`` weights the first stage's atoms for
    this measurement: :data:`GATE_ABOVE_CLEAN` from an estimated SNR of
    :data:`FITTED_SPECTRUM_ABOVE_DB`, :data:`GATE_ABOVE_NOISY` below it down to
    :data:`GATE_NOISY_FROM_DB`, ``inf`` (shut) below that; ``None`` where no gate can be read
    (several panchromatic axes, or fewer than :data:`MANY_BANDS` bands).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``

    Returns
    -------
    float or None
        Compared with :func:`~tensor_cosdi.solvers.subspace.spectral_roughness` of the fitted
        mean spectrum (``inf``: the gate stays shut).
    """
    if not _one_long_axis(system):
        return None
    snr_db = _snr_db(system, measurement)
    if snr_db >= FITTED_SPECTRUM_ABOVE_DB:
        return float(GATE_ABOVE_CLEAN)
    return float(GATE_ABOVE_NOISY if snr_db >= GATE_NOISY_FROM_DB else float("inf"))


def keeps_fitted(misfit_fitted: float, misfit_flat: float, margin: float | None = None) -> bool:
    """``pan_spectrum="auto"``'s pick on a clean measurement: whether the first stage with
    weighted atoms is kept over the plain one, ``misfit_fitted ≤ (1 + margin) · misfit_flat``.

    Parameters
    ----------
    misfit_fitted, misfit_flat : float
        The residuals ``‖A x − g‖`` of the weighted and the plain first stage (finite, ≥ 0).
    margin : float, optional
        How much worse (relative) the weighted stage may fit and still be kept: a finite
        number ≥ 0; default :data:`FITTED_MARGIN`.

    Returns
    -------
    bool

    Examples
    --------
    >>> keeps_fitted(1.02, 1.0, 0.05), keeps_fitted(1.1, 1.0, 0.05)
    (True, False)
    """
    fitted = number("misfit_fitted", misfit_fitted, low=0)
    flat = number("misfit_flat", misfit_flat, low=0)
    margin = number("margin", FITTED_MARGIN if margin is None else margin, low=0)
    return bool(fitted <= (1.0 + margin) * flat)


def _misfit(system, x, g) -> float:
    return float(tl.norm(system.operator.apply(x) - g))
