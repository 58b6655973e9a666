"""CASSI-VSI studies: its beam-splitting ratio, and the imagers against each other on the same
scene and code (re-exported by :mod:`tensor_cosdi.studies`)."""

from __future__ import annotations

import time
from functools import partial

import numpy as np

from ..validate import precision

__all__ = [
    "VSI_COMPARISON_SYSTEMS", "vsi_comparison", "vsi_comparison_run", "vsi_ratio",
    "vsi_ratio_run", "VSI_RATIOS",
]  # fmt: skip

#: The αT grid of the thesis' splitting-ratio study (Fig. 21-22).
VSI_RATIOS = tuple(round(0.1 * k, 1) for k in range(1, 11))

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
    from .sweeping import seed_list, sweep

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
    grid = {"system": systems, "scene": scenes, "seed": seed_list(seeds)}
    return sweep(grid, run, client=client, progress=progress)


def vsi_ratio_run(
    alpha_t, *, scene="cave.face", shape=(64, 64), n_bands=16, shifts=1, snr_db=30.0,
    method="otd", seed=0, dtype="float64", **options,
) -> dict:  # fmt: skip
    """One cell of :func:`vsi_ratio`: CASSI-VSI with splitting ratio ``alpha_t`` (``None``:
    SD-CASSI with the same code) imaging ``scene``; returns PSNR / SSIM / RMSE / SAM, the
    panchromatic estimate's PSNR and seconds.

    Equal light: the noise is one absolute level, the one that puts SD-CASSI's measurement at
    ``snr_db`` (``None``: no noise), so a ratio that sends light to the grayscale arm pays for
    it in the dispersed one.  The panchromatic estimate is the reconstruction summed over its
    bands, scored against the scene's.  The measurement reaches the reconstruction in ``dtype``
    (``"float64"`` or ``"float32"``).
    """
    from .. import codes, metrics, scenes
    from ..solvers import reconstruct
    from ..systems import CASSIVSI, SDCASSI, wavelengths_for
    from ..validate import integer, number

    shape = tuple(shape)
    dtype = precision("dtype", dtype)
    wl = wavelengths_for(None, integer("n_bands", n_bands, low=1))
    if alpha_t is not None:
        alpha_t = number("alpha_t", alpha_t, low=0, high=1)
    cube = np.asarray(scenes.scene_cube(scene, shape, wl))
    code = codes.random_binary(shape, rng=seed)
    sd = SDCASSI(code, n_bands=len(wl), shifts=shifts, wavelengths=wl)
    clean = np.asarray(sd.forward(cube))
    system = sd
    if alpha_t is not None:
        system = CASSIVSI(code, n_bands=len(wl), alpha_t=alpha_t, shifts=shifts, wavelengths=wl)
    g = clean if system is sd else np.asarray(system.forward(cube))
    if snr_db is not None:
        from ..noise import check_snr_db

        sigma = np.sqrt(np.mean(clean**2) / 10 ** (check_snr_db(snr_db) / 10))
        g = g + np.random.default_rng(seed + 1).standard_normal(g.shape) * sigma
    g = np.asarray(g, dtype=dtype)
    t0 = time.perf_counter()
    est = np.asarray(reconstruct(system, g, method, **options).cube)
    seconds = time.perf_counter() - t0
    pan, pan_est = cube.sum(axis=2), est.sum(axis=2)
    return {
        "psnr": metrics.psnr(cube, est), "ssim": metrics.ssim(cube, est),
        "rmse": metrics.rmse(cube, est), "sam": metrics.sam(cube, est),
        "pan_psnr": metrics.psnr(pan, pan_est, data_range=float(pan.max())),
        "seconds": seconds,
    }  # fmt: skip


def vsi_ratio(
    scenes=("cave.face",), alphas=VSI_RATIOS, *, shape=(64, 64), n_bands=16, shifts=1,
    snr_db=30.0, method="otd", seeds=(0,), dtype="float64", client=None, progress=True,
    **options,
) -> list[dict]:  # fmt: skip
    """CASSI-VSI's beam-splitting ratio αT at equal light (thesis Sec. 3.3.2-3.3.3, Fig. 21-22,
    102): quality over αT, the combined error of Eq. 49 that picks one ratio
    (:func:`tensor_cosdi.metrics.combined_error`; the thesis finds ≈ 0.7 at 15, 20 and 30 dB)
    and the panchromatic estimate, best as αT → 0 (Fig. 22A).  Each cell is
    :func:`vsi_ratio_run`; ``None`` in ``alphas`` adds SD-CASSI with the same code.

    Parameters
    ----------
    scenes : sequence of str
        Names of :data:`tensor_cosdi.scenes.SCENES` (real ``"cave.<name>"`` scenes to judge).
    alphas : sequence of float or None
        Splitting ratios in [0, 1] (default :data:`VSI_RATIOS`).
    shape, n_bands, shifts, snr_db
        The cube's size, pixels of dispersion per band and SD-CASSI's SNR (the one absolute
        noise level of every cell).
    method : str
        The reconstruction (``"otd"``, or the thesis' ``"avsi"`` for CASSI-VSI only).
    seeds, client, progress
        As in :func:`~tensor_cosdi.studies.sweep`.
    dtype : {"float64", "float32"}
        The precision the measurements reach the reconstruction in (the solver keeps it).
    **options
        Passed to the reconstruction.

    Returns
    -------
    list of dict
        One record per scene × αT × seed: PSNR, SSIM, RMSE, SAM, ``pan_psnr`` and seconds.

    Examples
    --------
    >>> rows = vsi_ratio(("chelsea",), (0.3, 0.7), shape=(16, 16), n_bands=4, progress=False,
    ...                  max_iter=5, pan_iter=5)
    >>> [r["alpha_t"] for r in rows]
    [0.3, 0.7]
    """
    from ..validate import number
    from .sweeping import seed_list, sweep

    if isinstance(scenes, str) or isinstance(alphas, str):
        raise ValueError("scenes and alphas must be sequences, not one string")
    scenes = list(scenes)
    alphas = [None if a is None else number("alpha_t", a, low=0, high=1) for a in alphas]
    if not scenes or not alphas:
        raise ValueError("scenes and alphas must each hold at least one value")
    run = partial(
        vsi_ratio_run, shape=tuple(shape), n_bands=n_bands, shifts=shifts, snr_db=snr_db,
        method=method, dtype=str(precision("dtype", dtype)), **options,
    )  # fmt: skip
    grid = {"scene": scenes, "alpha_t": alphas, "seed": seed_list(seeds)}
    return sweep(grid, run, client=client, progress=progress)
