"""Simulation studies: a seeded (system, scene, measurement) problem for every imager, and comparisons.

:func:`make_problem` builds what the demo, the benchmarks and the quality
tests share: one of the five imagers (or a CASSI baseline) with seeded codes,
a scene of :mod:`tensor_cosdi.scenes` shaped for it, and a noisy measurement.
:func:`compare` runs reconstruction methods on a problem and scores them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import metrics, scenes
from . import systems as S
from .operators import validate_shape

__all__ = ["SYSTEMS", "SCENES", "Problem", "make_problem", "compare", "score", "score_depth", "spectral_view"]

SYSTEMS = ("sd_cassi", "dd_cassi", "dual_camera", "cassi_vsi", "cassdi_dfa", "c3slfi", "cs2li", "mu_cosdi")
"""System names :func:`make_problem` accepts."""

SCENES = ("colorchecker",) + scenes.PHOTOS + ("motorcycle",)
"""Scene names :func:`make_problem` accepts (the spectral reflectance at the heart of every problem)."""


@dataclass(frozen=True)
class Problem:
    """A simulated acquisition.

    Attributes
    ----------
    name : str
        ``"<system>/<scene>"``.
    system : tensor_cosdi.systems.System
    cube : ndarray of ``system.cube_shape``
        The ground truth the measurement was simulated from.
    measurement : ndarray of ``system.measurement_shape``
    wavelengths : ndarray (Nλ,)
    snr_db : float or None
    reflectance : ndarray (Nx, Ny, Nλ)
        The scene's spectral reflectance (for sRGB previews; for C3SLFI the
        centre view, for CASSDI-DFA the all-in-focus cube).
    depth : ndarray (Nx, Ny) or None
        The depth-plane index (CASSDI-DFA), disparity (C3SLFI) or height
        (CS2LI, Mu-CoSDI) the scene was built with.
    extras : dict
        Anything else the scene was built with (CS2LI / Mu-CoSDI: the fringe
        ``"phase"`` and ``"phase_per_height"``).
    """

    name: str
    system: Any
    cube: np.ndarray
    measurement: Any
    wavelengths: np.ndarray
    snr_db: float | None
    reflectance: np.ndarray
    depth: np.ndarray | None = None
    extras: dict = field(default_factory=dict)


def _scene_cube(scene, shape, wl):
    if scene == "colorchecker":
        return scenes.colorchecker(shape, wl)
    if scene == "motorcycle":
        return scenes.motorcycle(shape, wl)[0]
    return scenes.photo(scene, shape, wl)


def make_problem(
    system: str,
    scene: str = "chelsea",
    *,
    shape=(64, 64),
    n_bands: int = 16,
    snr_db: float | None = 30.0,
    rng=0,
    code=None,
    shifts=1,
    n_depths: int = 3,
    views=(4, 4),
    n_snapshots: int = 4,
    n_steps: int = 4,
    max_disparity: float = 1.0,
) -> Problem:
    """A seeded problem: ``system`` imaging ``scene`` at ``shape`` with ``n_bands`` bands.

    Parameters
    ----------
    system : str
        One of :data:`SYSTEMS`.
    scene : str
        One of :data:`SCENES`.
    shape : (Nx, Ny)
        Detector-side spatial size of the cube (for C3SLFI the 3-D lenslet
        image ``(Ñ1, Ñ2)``, divisible by ``views``).
    n_bands : int
        Bands between 450 and 650 nm.
    snr_db : float or None
        Measurement SNR (SPEC §9); ``None`` for noise-free.
    rng : int or Generator
        Seeds codes and noise.
    code : array, optional
        A measured coded aperture (e.g. ``tsa_mask256.mat``) for the CASSI
        systems (``sd_cassi``, ``dual_camera``, ``cassi_vsi``); default a
        seeded random binary code.
    shifts : int or sequence
        Dispersion, pixels per band (or per-band shifts).
    n_depths : int
        Depth planes of CASSDI-DFA (from the motorcycle disparity).
    views : (N4, N5)
        Light-field views of C3SLFI.
    n_snapshots : int
        Complementary colour-coded snapshots of C3SLFI.
    n_steps : int
        Fringe phase steps of CS2LI / Mu-CoSDI (one frequency).
    max_disparity : float
        Largest disparity (px per view step) of the C3SLFI light field.

    Examples
    --------
    >>> p = make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=8)
    >>> p.system.cube_shape, p.measurement.shape
    ((16, 16, 8), (16, 23))
    """
    from ._backend import default_rng

    if system not in SYSTEMS:
        raise ValueError(f"unknown system {system!r}; choose one of {SYSTEMS}")
    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; choose one of {SCENES}")
    nx, ny = validate_shape(shape, "shape")
    wl = scenes.default_wavelengths(n_bands)
    gen = default_rng(rng)
    seed = int(gen.integers(2**31))
    depth = None
    extras = {}
    if code is not None and system not in ("sd_cassi", "dual_camera", "cassi_vsi"):
        raise ValueError(f"code= is for sd_cassi, dual_camera and cassi_vsi, not {system!r}")
    if system == "c3slfi":
        n4, n5 = validate_shape(views, "views")
        if nx % n4 or ny % n5:
            raise ValueError(f"c3slfi: shape {shape} must be divisible by views {views}")
        centre = _scene_cube(scene, (nx // n4, ny // n5), wl)
        _, disp = scenes.motorcycle((nx // n4, ny // n5), [550.0])
        d = (disp - disp.mean()) / max(np.abs(disp - disp.mean()).max(), 1e-12) * max_disparity
        lf = scenes.light_field(centre, d, views=(n4, n5))
        sys_ = S.C3SLFI.example((nx, ny, n_bands), rng=seed, n_snapshots=n_snapshots, views=(n4, n5),
                                wavelengths=wl)
        cube = np.asarray(sys_.to_3d(lf))
        reflectance, depth = centre, d
    else:
        reflectance = _scene_cube(scene, (nx, ny), wl)
        cube = reflectance
        if system in ("sd_cassi", "dual_camera", "cassi_vsi"):
            cls = {"sd_cassi": S.SDCASSI, "dual_camera": S.DualCameraCASSI, "cassi_vsi": S.CASSIVSI}[system]
            if code is None:
                sys_ = cls.example((nx, ny, n_bands), rng=seed, shifts=shifts, wavelengths=wl)
            else:
                sys_ = cls(code, n_bands=n_bands, shifts=shifts, wavelengths=wl)
                if sys_.cube_shape[:2] != (nx, ny):
                    raise ValueError(f"code of shape {np.shape(code)} does not give a {shape} scene")
        elif system == "dd_cassi":
            sys_ = S.DDCASSI.example((nx, ny, n_bands), rng=seed, shifts=shifts, wavelengths=wl)
        elif system == "cassdi_dfa":
            _, disp = scenes.motorcycle((nx, ny), [550.0])
            depth = scenes.depth_planes(disp, n_depths)
            cube = scenes.depth_layers(reflectance, depth, n_depths)
            sys_ = S.CASSDIDFA.example((nx, ny, n_bands, n_depths), rng=seed, shifts=shifts, wavelengths=wl)
        else:  # cs2li, mu_cosdi: one fringe frequency, n_steps phase steps
            sl = scenes.structured_light((nx, ny), wl, rng=seed)
            cube = np.asarray(S.fringe_cube(reflectance, sl.phase, n_steps=n_steps, amplitude=0.5))
            depth = sl.height
            extras = {"phase": sl.phase, "phase_per_height": sl.phase_per_height}
            if system == "cs2li":
                sys_ = S.CS2LI.example((nx, ny, n_bands, n_steps), rng=seed, shifts=shifts, wavelengths=wl)
            else:
                sys_ = S.MuCoSDI.example((nx, ny, n_bands, n_steps), rng=seed, shifts=shifts, wavelengths=wl)
    g = sys_.simulate(cube, snr_db=snr_db, rng=gen)
    return Problem(f"{system}/{scene}", sys_, cube, g, wl, snr_db, reflectance, depth, extras)


def score(problem: Problem, cube) -> dict:
    """PSNR, SSIM (data range = the truth's peak), SAM (degrees) and RMSE of ``cube`` against the truth.

    Cubes with more than three axes fold the extra axes (depth, pattern)
    into the band axis for PSNR/SSIM/RMSE and into pixels for SAM.
    """
    from . import _backend as B

    truth = np.asarray(problem.cube, dtype=np.float64)
    est = np.asarray(B.to_numpy(cube), dtype=np.float64)
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
    """How well a result's depth channel (``Result.depth``) matches the problem's truth; ``{}`` if neither has one.

    * CASSDI-DFA: ``"planes_right"``, the fraction of pixels on the right depth plane;
    * C3SLFI: ``"disparity_mae"``, mean absolute disparity error (px per view step);
    * CS2LI / Mu-CoSDI: ``"phase_mae"``, mean absolute wrapped-phase error (rad) of the first frequency.
    """
    from . import _backend as B
    from .depth import wrap

    if depth is None or problem.depth is None:
        return {}
    d = np.asarray(B.to_numpy(depth), dtype=np.float64)
    if isinstance(problem.system, S.CASSDIDFA):
        return {"planes_right": float(np.mean(np.round(d) == problem.depth))}
    if isinstance(problem.system, S.C3SLFI):
        return {"disparity_mae": float(np.mean(np.abs(d - problem.depth)))}
    if "phase" in problem.extras:
        return {"phase_mae": float(np.mean(np.abs(wrap(d[..., 0] - problem.extras["phase"][..., 0]))))}
    return {}


def compare(problem: Problem, methods=("otd", "gap_tv"), options=None, *, progress: bool = False) -> list[dict]:
    """Run ``methods`` on ``problem``; one row per method with its scores and seconds.

    ``options`` maps a method name to its keyword options.
    """
    from .solvers import reconstruct

    options = options or {}
    rows = []
    for m in methods:
        opts = dict(options.get(m, {}))
        if progress and "progress" in _defaults(m):
            opts.setdefault("progress", True)
        t0 = time.perf_counter()
        res = reconstruct(problem.system, problem.measurement, m, **opts)
        seconds = time.perf_counter() - t0
        rows.append({"problem": problem.name, "method": m, **score(problem, res.cube), "seconds": seconds,
                     "iterations": res.iterations, "result": res})
    return rows


def _defaults(method):
    from .solvers import METHODS

    return METHODS[method].defaults


def spectral_view(problem: Problem, cube) -> np.ndarray:
    """An ``(Nx, Ny, Nλ)`` reflectance-like view of a cube of ``problem.system`` (for sRGB previews).

    C3SLFI: the centre view of the light field; CASSDI-DFA: the sum over
    depth planes (all-in-focus); CS2LI / Mu-CoSDI: the mean over the phase
    steps divided by the fringe offset (the reflectance, Eq. 107); other
    systems: the cube itself.
    """
    from . import _backend as B

    c = np.asarray(B.to_numpy(cube), dtype=np.float64)
    name = problem.name.split("/")[0]
    if name == "c3slfi":
        five = np.asarray(problem.system.to_5d(c))
        return five[:, :, :, five.shape[3] // 2, five.shape[4] // 2]
    if name == "cassdi_dfa":
        return c.sum(axis=3)
    if name in ("cs2li", "mu_cosdi"):
        return c.mean(axis=3)  # offset 1: Σ_k (1 + a cos(φ + 2πk/K)) / K = 1
    return c
