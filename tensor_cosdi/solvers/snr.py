"""How noisy is a measurement?  An SNR estimate that does not read a code's texture as noise.

The measurement-only estimate (:func:`tensor_cosdi.noise.estimate_snr_db`,
the median absolute deviation of the finest diagonal wavelet detail) sees
every fine-scale structure of ``g`` as noise.  A coded aperture puts its
pattern on the measurement at the finest scale, so a noiseless measurement
through a random binary code reads as a noisy one.

:func:`estimate_snr` therefore also fits the measurement through the system
and measures the same wavelet MAD on the residual ``g − A x̂``: ``A x̂``
carries the code's pattern, so the residual holds the noise plus what the
fit missed.  Both readings mostly over-state the noise (each adds structure
it cannot model), so the estimate is the larger SNR of the two.

A system whose noiseless frames span fewer dimensions than there are frames
(``snr_frames_low_rank``: CS2LI, Mu-CoSDI with its projector — phase-shifted
fringes are three images per pixel over four or more steps) adds a third
reading, from the frames' smallest singular value
(:func:`tensor_cosdi.noise.frame_rank_sigma`), which no texture reaches; the
estimate is then the largest of the three.  The GAP-TV fit read CS2LI's
fringes through its colour code as noise: a noiseless 64×64×16 measurement
at 21.0 dB, a true 30 dB at 20.5.

The fit is the system's ``snr_fit``:

* ``"subspace"`` (SD-CASSI, CASSDI-DFA, where every measurement pixel sums
  voxels along a sheared diagonal): :data:`SUBSPACE_FIT_ITER` accelerated
  iterations of :func:`~tensor_cosdi.solvers.subspace.subspace_gap_tv` (the
  bands spanned by a few DCT atoms, TV weight :data:`SUBSPACE_FIT_TV`).  The
  plain GAP-TV fit below cannot follow a scene's fine detail through a
  random binary code at 256×256×28 in its few iterations: it read the 28
  noiseless tuning scenes at 21.1-46.7 dB, 15 of them under 38 dB; the
  subspace fit reads them at 32.3-45.7 dB, 6 under 38, and a true 30 or
  20 dB within 3 dB on every scene through either code.  Noise spread along
  a sheared diagonal is what the subspace cannot hold, so the fit leaves it
  in the residual.  Under a light with sharp lines (a fluorescent lamp) the fit's atoms
  follow the fitted mean spectrum after :data:`SUBSPACE_FIT_REFIT`
  iterations, else it would read the lines it cannot hold as noise.  Where the
  first estimate is ambiguous (:data:`RECHECK_FROM_DB` to :data:`RECHECK_CLEAN_DB`)
  a longer, lighter fit takes a second look and decides between the clean and
  the noisy path: a textured noiseless scene reads clean, a true 40 dB reads
  noisy (the clean path lets that much noise through).
* ``"gap_tv"`` (every other system): :data:`FIT_ITER` plain GAP-TV
  iterations.  Where a pixel's voxels share one position — DD-CASSI,
  Mu-CoSDI, CASSI-VSI's direct arm — the accelerated subspace fit takes up
  the noise itself (64×64×16: DD-CASSI and Mu-CoSDI read a true 20 dB at
  about 40 dB, CASSI-VSI at 23.8 against the GAP-TV fit's 22.2); it reads
  Lytro-CASSI as noisier than it is.

Each reading is the noisiest frame of a stacked measurement
(:func:`tensor_cosdi.noise.frame_sigmas`, over the pixels the frame's light
reaches): the fit can absorb one frame's noise (dual-camera CASSI's
panchromatic frame read ≈ 50 dB at a true 30 dB), and averaging it with the
others read the whole measurement as cleaner than it is.  Where a system's
frames come from cameras whose noise is set against their own signal
(``snr_frame_groups``: dual-camera CASSI's two cameras, Lytro-CASSI's two
arms), each camera is read against its own power and the noisiest one is
reported (:func:`grouped_reading_db`): against the whole measurement's power
the bright, noise-free panchromatic frame made a true 30 / 20 dB read 35.9 /
26.5 dB, and Lytro-CASSI's read 27.4 / 18.2.
``benchmarks/results/snr_estimate.md`` shows every reading and the fit on
every system, and the estimate at 256×256×28 on every tuning scene through
the TSA mask and a random binary code.  The estimate is cached for the last few (system,
measurement) pairs, so the ``"auto"`` options of one reconstruction share
one fit.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from typing import NamedTuple

import numpy as np

from .. import _backend as B
from ..noise import frame_powers, frame_rank_sigma, frame_sigmas, snr_db_from_sigma
from ..validate import imager, number, real_array
from .subspace import has_many_bands, subspace_gap_tv

__all__ = [
    "SNREstimate", "estimate_snr", "clear_cache", "residual_reading_db", "grouped_reading_db",
    "FITS", "FIT_ITER",
    "FIT_TV",
    "SUBSPACE_FIT_ITER", "SUBSPACE_FIT_TV", "SUBSPACE_FIT_REFIT", "SUBSPACE_FIT_FLOOR",
    "CLEAN_ABOVE_DB", "RECHECK_FROM_DB", "RECHECK_CLEAN_DB", "RECHECK_ITER", "RECHECK_TV",
]  # fmt: skip

#: Plain GAP-TV iterations of the fit (5 Chambolle steps each).
FIT_ITER = 10
#: The GAP-TV fit's TV weight where the system sets none (its ``snr_fit_tv``).
FIT_TV = 0.1
#: Accelerated iterations and TV weight of the subspace fit (5 warm-started Chambolle steps
#: each, the atoms of :func:`~tensor_cosdi.solvers.subspace.pan_atoms_for`), from 20 / 40
#: iterations × TV 0.1 / 0.3 on the 28 tuning scenes at 256×256×28, TSA mask and a random
#: binary code (``benchmarks/results/snr_fit_sweep.md``): the lighter the weight and the longer
#: the fit, the more noise it takes up and the cleaner a noisy measurement reads (40 at 0.1: a
#: true 20 dB at 23.3-27.5 dB); the shorter and the heavier, the more detail it misses.  20 at
#: 0.3 is the one that reads every noisy scene within 3 dB through both codes, as the plain
#: GAP-TV fit does through the TSA mask (a true 20 dB at 21.0-22.2 dB), and reads noiseless
#: random-code scenes at 32.3-45.7 dB (GAP-TV fit: 21.1-46.7), in less time than the GAP-TV fit
#: (``snr_estimate.md`` times both).
SUBSPACE_FIT_ITER = 20
SUBSPACE_FIT_TV = 0.3
#: The subspace fit's light gate (``subspace_gap_tv(refit_at=...)``; one panchromatic axis of
#: :data:`~tensor_cosdi.solvers.subspace.MANY_BANDS` samples or more, where it was measured):
#: after this many iterations its atoms follow the fitted mean spectrum where that spectrum
#: reads rough.  Smooth atoms cannot hold a fluorescent lamp's lines, and the fit read them as
#: noise: a noiseless tuning scene lit by CIE FL11 at 27.4-46.2 dB, 13 of 28 under the clean
#: threshold.  28 tuning scenes as they are and lit by A, LED-B3 and FL11, TSA mask
#: (``benchmarks/results/snr_fit_refit.md``): gate after 5 / 8 / none → 76 / 77 / 69 of the 84
#: FL11 readings ok (noiseless 25 / 25 / 15 of 28 clean, 30 dB 28 / 28 / 26 within 3 dB,
#: 20 dB 23 / 24 / 28); unlit, A and LED-B3 views read as without it.
SUBSPACE_FIT_REFIT = 8
#: The floor of the gate's weights in the subspace fit (relative to the fitted spectrum's peak),
#: as measured there; the first stage's own floor is
#: :data:`~tensor_cosdi.solvers.subspace.GATE_FLOOR`.
SUBSPACE_FIT_FLOOR = 1e-3
#: The estimated SNR (dB) from which a measurement counts as clean: the solvers' clean path
#: (accelerated GAP, OTD's first stage as the start;
#: :data:`~tensor_cosdi.solvers.otd.ACCELERATE_ABOVE_DB`).
CLEAN_ABOVE_DB = 38.0
#: The second look of the subspace fit.  The short, heavy fit leaves a textured scene's detail
#: in its residual, read as noise, so a noiseless scene through a random code could read under
#: :data:`CLEAN_ABOVE_DB` (6 of the 28 tuning scenes, down to 32.3 dB) and take the noisy path;
#: and a true 40 dB read up to 40.0 dB and took the clean path, whose accelerated GAP lets even
#: that much noise through (``pnp_gap`` on balloons, TSA mask: 26.66 dB against 32.49 on the
#: noisy path, ``benchmarks/results/snr_recheck_effect.md``).  Where the first estimate lies in
#: ``[RECHECK_FROM_DB, RECHECK_CLEAN_DB)`` a longer, lighter fit (:data:`RECHECK_ITER`
#: iterations at TV :data:`RECHECK_TV`) reads the residual again; it follows the detail and
#: reads a noiseless scene far cleaner, a noisy one only a little (it takes up some noise too),
#: and the estimate becomes its reading less ``RECHECK_CLEAN_DB - CLEAN_ABOVE_DB``: clean where
#: it reads :data:`RECHECK_CLEAN_DB` or more.  On the 28 tuning scenes as they are and lit by
#: CIE FL11, both codes (``benchmarks/results/snr_fit_recheck.md``, where the two thresholds are
#: chosen by 4-fold cross-validation): noiseless views clean 74 → 80 of 112, 40 dB views clean
#: 17 → 0, no 30 or 20 dB view's estimate changed; the second fit costs about 1.3 s where it
#: runs.  Like the light gate, only with one panchromatic axis of
#: :data:`~tensor_cosdi.solvers.subspace.MANY_BANDS` samples or more, where it was measured.
RECHECK_FROM_DB = 33.0
RECHECK_CLEAN_DB = 42.0
RECHECK_ITER = 40
RECHECK_TV = 0.1
_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 4


class SNREstimate(NamedTuple):
    """An SNR estimate in dB, its two readings (``inf`` for a noiseless-looking reading) and the
    fit of the residual reading."""

    snr_db: float
    from_measurement_db: float
    from_residual_db: float
    #: The fit behind ``from_residual_db``: ``"subspace"``, ``"gap_tv"`` or ``"none"``.
    fit: str = "none"
    #: The reading from the frames' smallest singular value (``nan`` where the system's
    #: ``snr_frames_low_rank`` is false).
    from_frames_db: float = float("nan")
    #: The subspace fit's second look (:data:`RECHECK_FROM_DB`; ``nan`` where it did not run).
    rechecked_db: float = float("nan")


def clear_cache() -> None:
    """Forget the cached estimates: the next :func:`estimate_snr` of any measurement runs its fit.

    A timing of a reconstruction that reads the SNR (``"auto"`` options) should start from an
    empty cache, or a method timed after another on the same measurement would leave out the
    fit a user's single call pays (0.4 s at 256×256×28).

    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    >>> first = estimate_snr(p.system, p.measurement)
    >>> clear_cache()
    >>> again = estimate_snr(p.system, p.measurement)  # fitted again: a new, equal estimate
    >>> again is first, again.snr_db == first.snr_db
    (False, True)
    """
    _CACHE.clear()


def _fingerprint(g: np.ndarray) -> str:
    return hashlib.blake2b(np.ascontiguousarray(g).tobytes(), digest_size=16).hexdigest()


FITS = ("auto", "subspace", "gap_tv")


def residual_reading_db(system, g_unit, fit) -> float:
    """The SNR in dB read from the residual ``g_unit − A fit`` (the noisiest frame's wavelet MAD
    against the measurement's power, or camera by camera: :func:`grouped_reading_db`; ``-inf``
    for a non-finite residual).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    g_unit : ndarray of ``system.measurement_shape``
        The measurement scaled to a peak of 1, float64.
    fit : tensor of ``system.cube_shape``
        A cube fitted to it.

    Examples
    --------
    >>> import numpy as np
    >>> import tensor_cosdi as tc
    >>> system = tc.systems.SDCASSI.example((16, 16, 4))
    >>> cube = np.random.default_rng(0).random(system.cube_shape)
    >>> g = np.asarray(system.forward(cube)); g = g / g.max()
    >>> bool(residual_reading_db(system, g, cube / np.asarray(system.forward(cube)).max()) > 100)
    True
    """
    r = g_unit - np.asarray(B.to_numpy(system.operator.forward(fit)), dtype=np.float64)
    if not np.isfinite(r).all():
        return -np.inf
    return grouped_reading_db(system, g_unit, frame_sigmas(r, g_unit))


def grouped_reading_db(system, g_unit, sigmas) -> float:
    """The SNR in dB of frame noise levels ``sigmas`` (one per frame of ``g_unit``): against
    the whole measurement's power, or, where the system's ``snr_frame_groups`` names cameras
    whose noise is set against their own signal, each group's noisiest frame against the
    group's power (:func:`tensor_cosdi.noise.frame_powers`), the noisiest group.

    Examples
    --------
    >>> import numpy as np
    >>> import tensor_cosdi as tc
    >>> system = tc.systems.DualCameraCASSI.example((16, 16, 4))
    >>> g = np.zeros(system.measurement_shape); g[..., 0] = 0.5; g[:, :16, 1] = 1.0
    >>> round(grouped_reading_db(system, g, np.array([0.005, 0.0])), 1)  # the CASSI camera
    40.0
    """
    sigmas = real_array("sigmas", sigmas, finite=False)
    groups = getattr(system, "snr_frame_groups", None)
    if not groups:
        return snr_db_from_sigma(float(np.mean(g_unit * g_unit)), float(sigmas.max()))
    powers = frame_powers(g_unit)
    if sorted(k for group in groups for k in group) != list(range(powers.size)):
        raise ValueError(
            f"{type(system).__name__}.snr_frame_groups must name every one of the "
            f"measurement's {powers.size} frames once, got {groups!r}"
        )
    return min(
        snr_db_from_sigma(float(np.mean(powers[list(group)])), float(sigmas[list(group)].max()))
        for group in groups
    )


def estimate_snr(system, measurement, *, fit=True) -> SNREstimate:
    """The measurement's SNR in dB, from the measurement and the fit residual (see the module).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
        The system that took ``measurement``.
    measurement : tensor of ``system.measurement_shape``
    fit : bool or str
        ``True`` or ``"auto"``: the fit the system calls for (its ``snr_fit``;
        see the module);
        ``"subspace"`` or ``"gap_tv"``: that fit; ``False``: none, the
        measurement-only reading.

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(64, 64), n_bands=16, snr_db=20)
    >>> est = estimate_snr(p.system, p.measurement)
    >>> 17 < est.snr_db < 23
    True
    """
    imager(system)
    if fit is True:
        fit = "auto"
    if fit is not False and not (isinstance(fit, str) and fit in FITS):
        raise ValueError(f"fit must be True, False or one of {FITS}, got {fit!r}")
    g = real_array("measurement", B.to_numpy(measurement), finite=False)
    if not np.isfinite(g).all():
        raise ValueError("the measurement holds NaN or inf: no SNR can be estimated from it")
    peak = float(np.max(np.abs(g))) if g.size else 0.0
    if peak == 0.0:
        raise ValueError("the measurement is all zero: there is no signal to reconstruct")
    g_unit = g / peak  # every reading below is of the measurement scaled to a peak of 1
    power = float(np.mean(g_unit * g_unit))
    meas_db = grouped_reading_db(system, g_unit, frame_sigmas(g_unit))
    frames_db = float("nan")
    unfitted_db = meas_db  # the larger SNR of the readings without a fit
    n_frames = int(np.prod(g.shape[2:]))  # one frame (a 2-D measurement): no frames' reading
    n_pixels = int(np.prod(g.shape[:2]))
    if getattr(system, "snr_frames_low_rank", False) and 2 <= n_frames < n_pixels / 4:
        frames_db = snr_db_from_sigma(power, frame_rank_sigma(g_unit))
        unfitted_db = max(meas_db, frames_db)
    if not fit:
        return SNREstimate(unfitted_db, meas_db, float("nan"), "none", frames_db)
    if fit == "auto":
        fit = getattr(system, "snr_fit", "gap_tv")
        if fit not in FITS[1:]:
            raise ValueError(
                f"{type(system).__name__}.snr_fit must be one of {FITS[1:]}, got {fit!r}"
            )
    fit_tv = number(
        f"{type(system).__name__}.snr_fit_tv", getattr(system, "snr_fit_tv", FIT_TV),
        low=0, low_open=True,
    )  # fmt: skip
    # float32 and float64 copies both fit
    key = (id(system), g.shape, _fingerprint(g), fit, fit_tv)
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key][1]
    # Either fit runs in float32 (the measurement at a peak of 1): the GAP-TV fit 2.5× faster than
    # in float64 at 256×256×28 with the same reading to 1e-4 dB (a CAVE scene, TSA mask,
    # noiseless / 30 / 20 dB); the residual is taken in float64.
    g32 = B.as_tensor(g_unit, "float32")
    if fit == "subspace":
        x = _subspace_fit(system, g32, SUBSPACE_FIT_ITER, SUBSPACE_FIT_TV)
    else:
        from .gap_tv import gap_tv

        x, _, _ = gap_tv(
            system, g32, max_iter=FIT_ITER, accelerate=False,
            tv_weight=fit_tv, tv_iter=5, plane_support=False, nonneg=False,
        )  # fmt: skip
    res_db = residual_reading_db(system, g_unit, x)
    snr_db, rechecked = max(unfitted_db, res_db), float("nan")
    if fit == "subspace" and _gated(system) and RECHECK_FROM_DB <= snr_db < RECHECK_CLEAN_DB:
        del x
        rechecked = residual_reading_db(
            system, g_unit, _subspace_fit(system, g32, RECHECK_ITER, RECHECK_TV)
        )
        snr_db = max(unfitted_db, rechecked - (RECHECK_CLEAN_DB - CLEAN_ABOVE_DB))
    est = SNREstimate(snr_db, meas_db, res_db, fit, frames_db, rechecked)
    _CACHE[key] = (system, est)  # the system is held so that its id is not reused
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return est


def _subspace_fit(system, g32, n_iter: int, tv_weight: float):
    """The subspace fit of :func:`estimate_snr` (``n_iter`` iterations at ``tv_weight``, 5
    Chambolle steps each, the light gate where one panchromatic axis has many bands)."""
    gated = _gated(system)
    return subspace_gap_tv(
        system, g32, max_iter=n_iter, tv_weight=tv_weight, tv_steps=5,
        refit_at=SUBSPACE_FIT_REFIT if gated else None,
        refit_floor=SUBSPACE_FIT_FLOOR if gated else None,
    )  # fmt: skip


def _gated(system) -> bool:
    """One panchromatic axis of :data:`~tensor_cosdi.solvers.subspace.MANY_BANDS` samples or
    more: where the subspace fit's light gate and second look were measured."""
    return len(system.panchromatic_axes) == 1 and has_many_bands(system)
