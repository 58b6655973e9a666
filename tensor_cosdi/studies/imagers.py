"""Imagers against each other on the same scene and code (re-exported by
:mod:`tensor_cosdi.studies`)."""

from __future__ import annotations

import time
from functools import partial

__all__ = ["VSI_COMPARISON_SYSTEMS", "vsi_comparison", "vsi_comparison_run"]

#: The imagers of thesis Sec. 3.3.4 (Fig. 23): SD-CASSI, CASSI-VSI and the dual-arm CASSI (an
#: SD-CASSI frame plus a panchromatic camera).
VSI_COMPARISON_SYSTEMS = ("sd_cassi", "cassi_vsi", "dual_camera_cassi")


def _check_system(system) -> str:
    if not isinstance(system, str) or system not in VSI_COMPARISON_SYSTEMS:
        raise ValueError(
            f"system must be one of {', '.join(VSI_COMPARISON_SYSTEMS)}, got {system!r}"
        )
    return system


def _imager(system, code, n_bands, shifts, wl, alpha_t):
    from ..systems import CASSIVSI, SDCASSI, DualCameraCASSI

    if system == "sd_cassi":
        return SDCASSI(code, n_bands=n_bands, shifts=shifts, wavelengths=wl)
    if system == "cassi_vsi":
        return CASSIVSI(code, n_bands=n_bands, alpha_t=alpha_t, shifts=shifts, wavelengths=wl)
    return DualCameraCASSI(code, n_bands=n_bands, shifts=shifts, wavelengths=wl)


def vsi_comparison_run(
    system, *, scene="cave.face", shape=(64, 64), n_bands=16, shifts=1, snr_db=30.0,
    alpha_t=0.7, method="otd", seed=0, **options,
) -> dict:  # fmt: skip
    """One cell of :func:`vsi_comparison`: ``system`` (one of :data:`VSI_COMPARISON_SYSTEMS`)
    imaging ``scene`` through the code seeded by ``seed``; returns PSNR / SSIM / SAM / RMSE
    and seconds.

    Every measurement carries noise at ``snr_db`` of its own signal; the dual-arm
    CASSI's panchromatic frame is noise-free and registered, as the thesis simulates it.
    """
    from .. import codes, scenes
    from ..solvers import reconstruct
    from ..systems import wavelengths_for
    from ..validate import integer
    from .problems import Problem, score

    _check_system(system)
    shape = tuple(shape)
    wl = wavelengths_for(None, integer("n_bands", n_bands, low=1))
    cube = scenes.scene_cube(scene, shape, wl)
    imager = _imager(system, codes.random_binary(shape, rng=seed), len(wl), shifts, wl, alpha_t)
    g = imager.simulate(cube, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    res = reconstruct(imager, g, method, **options)
    seconds = time.perf_counter() - t0
    p = Problem(f"{system}/{scene}", imager, cube, g, wl, snr_db, cube)
    return {**score(p, res.cube), "seconds": seconds}


def vsi_comparison(
    scenes=("cave.face",), *, shape=(64, 64), n_bands=16, shifts=1, snr_db=30.0, alpha_t=0.7,
    method="otd", seeds=(0,), systems=VSI_COMPARISON_SYSTEMS, client=None, progress=True,
    **options,
) -> list[dict]:  # fmt: skip
    """CASSI-VSI against SD-CASSI and the dual-arm CASSI (thesis Sec. 3.3.4, Fig. 23).

    Each imager sees the same scene through the same seeded binary code, at
    ``snr_db`` on its own measurement; the dual-arm CASSI adds a noise-free,
    registered panchromatic image (the thesis' simulation), CASSI-VSI splits
    the light ``alpha_t`` : ``1 − alpha_t`` between its dispersed and grayscale
    arms on one sensor.  The thesis reports CASSI-VSI comparable to the
    dual-arm CASSI and better than CASSI in PSNR, RMSE and SSIM, and the
    dual-arm CASSI best in SAM.  Judge it on real scenes (``"cave.<name>"``).

    Parameters
    ----------
    scenes : sequence of str
        Names of :data:`tensor_cosdi.scenes.SCENES`.
    shape, n_bands, shifts, snr_db, alpha_t
        The cube's spatial size and band count, pixels of dispersion per band,
        the noise and CASSI-VSI's splitting ratio.
    method : str
        The reconstruction of every imager (``"otd"`` serves all three).
    seeds : sequence of int
        Codes and noise.
    systems : sequence of str
        A subset of :data:`VSI_COMPARISON_SYSTEMS`.
    client, progress
        As in :func:`~tensor_cosdi.studies.sweep`.
    **options
        Passed to the reconstruction.

    Returns
    -------
    list of dict
        One record per system × scene × seed: the parameters, PSNR, SSIM,
        SAM, RMSE and seconds.

    Examples
    --------
    >>> rows = vsi_comparison(("chelsea",), shape=(16, 16), n_bands=4, progress=False,
    ...                       max_iter=5, pan_iter=5)
    >>> sorted(r["system"] for r in rows)
    ['cassi_vsi', 'dual_camera_cassi', 'sd_cassi']
    """
    from .sweeping import sweep

    if isinstance(systems, str) or isinstance(scenes, str):
        raise ValueError("systems and scenes must be sequences of names, not one string")
    systems, scenes = [_check_system(s) for s in systems], list(scenes)
    if not systems:
        raise ValueError(f"systems must name at least one of {VSI_COMPARISON_SYSTEMS}")
    if not scenes or any(not isinstance(s, str) for s in scenes):
        raise ValueError(f"scenes must be a non-empty sequence of scene names, got {scenes!r}")
    run = partial(
        vsi_comparison_run, shape=tuple(shape), n_bands=n_bands, shifts=shifts, snr_db=snr_db,
        alpha_t=alpha_t, method=method, **options,
    )  # fmt: skip
    grid = {"system": systems, "scene": scenes, "seed": list(seeds)}
    return sweep(grid, run, client=client, progress=progress)
