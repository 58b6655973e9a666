"""Seeded problems for every imager, and how reconstructions of them are scored.

:func:`make_problem` builds what the demo, the benchmarks and the quality
tests share: one of the imagers with seeded codes, a scene of
:mod:`tensor_cosdi.scenes` shaped for it, and a noisy measurement.
:func:`compare` runs reconstruction methods on a problem and scores them.
"""

from __future__ import annotations

import numbers
import time

import numpy as np

from .. import _backend as B
from .. import metrics, scenes
from .. import systems as S
from ..systems import Problem
from ..validate import real_array

__all__ = [
    "SYSTEMS", "SCENES", "Problem", "make_problem", "score", "score_depth", "compare",
    "spectral_view", "reconstruction_run",
]  # fmt: skip

SYSTEMS = S.REGISTRY
"""The systems :func:`make_problem` accepts: :data:`tensor_cosdi.systems.REGISTRY` (a read-only
mapping)."""

SCENES = scenes.SCENES
"""The scenes :func:`make_problem` accepts: :data:`tensor_cosdi.scenes.SCENES`."""

_RENAMED = {"dual_camera": "dual_camera_cassi"}


def make_problem(
    system: str,
    scene: str = "chelsea",
    *,
    shape=(64, 64),
    n_bands: int = 16,
    snr_db: float | None = 30.0,
    rng=0,
    shifts=1,
    **options,
) -> Problem:
    """A seeded problem: ``system`` imaging ``scene`` at ``shape`` with ``n_bands`` bands.

    The registry's class builds it (``REGISTRY[system].example_problem``).

    Parameters
    ----------
    system : str
        A name of :data:`SYSTEMS` (``"sd_cassi"``, ``"cassi_vsi"``, …).
    scene : str
        A name of :data:`SCENES`.
    shape : (Nx, Ny)
        Detector-side spatial size of the cube (for C3SLFI the 3-D lenslet
        image ``(Ñ1, Ñ2)``, divisible by ``views``).
    n_bands : int
        Bands between 450 and 650 nm.
    snr_db : float or None
        Measurement SNR (SPEC §9); ``None`` for noise-free.
    rng : int or Generator
        Seeds codes and noise.
    shifts : int or sequence
        Dispersion, pixels per band (or per-band shifts).
    **options
        The system's own options (``REGISTRY[system].example_options``):
        ``code`` (a measured coded aperture, e.g. ``tsa_mask256.mat``, for
        ``sd_cassi``, ``dual_camera_cassi``, ``cassi_vsi``), ``n_depths``
        (CASSDI-DFA planes), ``views`` / ``n_snapshots`` / ``max_disparity``
        (C3SLFI), ``n_steps`` (CS2LI / Mu-CoSDI phase steps).  An option the
        system does not have is an error listing the ones it has.

    Examples
    --------
    >>> p = make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=8)
    >>> p.system.cube_shape, p.measurement.shape
    ((16, 16, 8), (16, 23))
    """
    if system in _RENAMED:
        raise ValueError(
            f"the system {system!r} is now called {_RENAMED[system]!r} (systems.REGISTRY)"
        )
    cls = SYSTEMS[system]
    if (
        isinstance(shape, (str, bytes))
        or np.ndim(shape) != 1
        or len(shape) != 2
        or not all(
            isinstance(n, numbers.Integral) and not isinstance(n, bool) and n > 0 for n in shape
        )
    ):
        raise ValueError(f"shape must be (rows, columns), two positive integers, got {shape!r}")
    if snr_db is not None:
        from ..noise import check_snr_db

        snr_db = check_snr_db(snr_db)
    return cls.example_problem(
        scene, shape=shape, n_bands=n_bands, snr_db=snr_db, rng=rng, shifts=shifts, **options
    )


def _problem(who: str, problem) -> Problem:
    if not isinstance(problem, Problem):
        raise ValueError(
            f"{who} needs a Problem (studies.make_problem), got {type(problem).__name__}"
        )
    return problem


def score(problem: Problem, cube) -> dict:
    """PSNR, SSIM (data range = the truth's peak), SAM (degrees) and RMSE of ``cube`` against the
    truth.

    Cubes with more than three axes fold the extra axes (depth, pattern)
    into the band axis for PSNR/SSIM/RMSE and into pixels for SAM.
    """
    truth = np.asarray(_problem("score", problem).cube, dtype=np.float64)
    est = real_array("cube", B.to_numpy(cube), finite=False)
    if est.shape != truth.shape:
        raise ValueError(f"cube of shape {est.shape} does not match the truth's {truth.shape}")
    peak = float(truth.max())
    t3 = truth.reshape(truth.shape[:2] + (-1,))
    e3 = est.reshape(t3.shape)
    return {
        "psnr": metrics.psnr(t3, e3, data_range=peak),
        "ssim": metrics.ssim(t3, e3, data_range=peak),
        "sam": metrics.sam(truth, est),  # spectra along axis 2; all-zero truth spectra are skipped
        "rmse": metrics.rmse(t3, e3),
    }


def score_depth(problem: Problem, depth) -> dict:
    """How well a result's depth channel (``Result.depth``) matches the problem's truth; ``{}`` if
    neither has one.

    * depth planes (CASSDI-DFA): ``"planes_right"``, the fraction of pixels on the right plane;
    * disparity (C3SLFI): ``"disparity_mae"``, mean absolute error (px per view step);
    * fringe phase (CS2LI / Mu-CoSDI): ``"phase_mae"``, mean absolute wrapped-phase error (rad)
      of the first frequency.
    """
    return _problem("score_depth", problem).system.score_depth(depth, problem)


def compare(
    problem: Problem, methods=("otd", "gap_tv"), options=None, *, progress: bool = False
) -> list[dict]:
    """Run ``methods`` (a method name or a sequence of them) on ``problem``; one row per method
    with its scores and seconds.

    ``options`` maps a method name to its keyword options; options for a method that is not
    among ``methods`` are an error (they would be dropped).
    """
    from ..solvers import reconstruct

    if not isinstance(problem, Problem):
        raise ValueError(
            f"compare needs a Problem (studies.make_problem), got {type(problem).__name__}"
        )
    if isinstance(methods, str):
        methods = (methods,)
    methods = tuple(methods)
    if not methods:
        raise ValueError("compare needs at least one method")
    options = {} if options is None else options
    if not isinstance(options, dict):
        raise ValueError(f"options must map method names to option dicts, got {options!r}")
    unused = sorted(set(options) - set(methods))
    if unused:  # options for a method that does not run would be dropped without a word
        raise ValueError(
            f"options given for {unused}, which are not among the methods {list(methods)}"
        )
    rows = []
    for m in methods:
        opts = dict(options.get(m, {}))
        if progress and "progress" in _defaults(m):
            opts.setdefault("progress", True)
        t0 = time.perf_counter()
        res = reconstruct(problem.system, problem.measurement, m, **opts)
        seconds = time.perf_counter() - t0
        rows.append(
            {
                "problem": problem.name,
                "method": m,
                **score(problem, res.cube),
                "seconds": seconds,
                "iterations": res.iterations,
                "result": res,
            }
        )
    return rows


def _defaults(method):
    from ..solvers import METHODS

    return METHODS[method].defaults


def spectral_view(problem: Problem, cube) -> np.ndarray:
    """An ``(Nx, Ny, Nλ)`` reflectance-like view of a cube of ``problem.system`` (for sRGB
    previews).

    C3SLFI: the centre view of the light field; CASSDI-DFA: the sum over
    depth planes (all-in-focus); CS2LI / Mu-CoSDI: the mean over the phase
    steps divided by the fringe offset (the reflectance, Eq. 107); other
    systems: the cube itself (``problem.system.spectral_view``).
    """
    system = _problem("spectral_view", problem).system
    shape = tuple(np.shape(B.to_numpy(cube)))
    if shape != tuple(system.cube_shape):
        raise ValueError(
            f"spectral_view: cube of shape {shape} is not one of this system's "
            f"{tuple(system.cube_shape)}"
        )
    return system.spectral_view(cube)


def reconstruction_run(
    system, scene="chelsea", method="otd", snr_db=30.0, shape=(64, 64), n_bands=8, seed=0, **options
) -> dict:
    """One study cell for :func:`sweep`: :func:`make_problem` then :func:`tensor_cosdi.reconstruct`
    with ``options``; returns PSNR / SSIM / SAM (and depth error where the system has depth),
    seconds and iterations."""
    from ..solvers import reconstruct

    p = make_problem(system, scene, shape=tuple(shape), n_bands=n_bands, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    res = reconstruct(p.system, p.measurement, method, **options)
    seconds = time.perf_counter() - t0
    out = {**score(p, res.cube), "seconds": seconds, "iterations": res.iterations}
    if p.depth is not None and res.depth is not None:
        out.update({f"depth_{k}": v for k, v in score_depth(p, res.depth).items()})
    return out
