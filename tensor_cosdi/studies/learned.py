"""Learned reconstructors as design studies (re-exported by :mod:`tensor_cosdi.studies`):
D-CoSNet with a learned coded aperture against the same network on a fixed random code
(thesis §7.3), and one unrolled network trained for SD-CASSI against the same for CASSI-VSI
(§3.3.5)."""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path

import numpy as np

__all__ = [
    "CODE_STUDY_WEIGHTS", "IMAGER_STUDY_WEIGHTS", "learned_code", "learned_code_run",
    "learned_imagers", "REPORT_CAVE_SCENES",
]  # fmt: skip

_WEIGHTS = Path(__file__).resolve().parent.parent / "learn" / "weights"
#: The shipped pair of the study: the same D-CoSNet (3 stages, SD-CASSI, 28 bands, 2 px per
#: band) trained once on one fixed seeded 64×64 code and once learning that code
#: (``tensor_cosdi/learn/weights/README.md`` gives both commands).
CODE_STUDY_WEIGHTS = {
    "seeded": _WEIGHTS / "dcosnet_seeded_s2.pt",
    "learned": _WEIGHTS / "dcosnet_learned_s2.pt",
}
#: The shipped pair of the imager study: the same D-CoSNet (3 stages, 28 bands, 2 px per band,
#: one fixed seeded 64×64 code, 64×64 crops) trained for SD-CASSI and for CASSI-VSI (αT 0.7).
IMAGER_STUDY_WEIGHTS = {
    "sd_cassi": _WEIGHTS / "dcosnet_imager_sd_cassi.pt",
    "cassi_vsi": _WEIGHTS / "dcosnet_imager_cassi_vsi.pt",
}
#: The report scenes as :mod:`tensor_cosdi.scenes` names.
REPORT_CAVE_SCENES = ("cave.beads", "cave.face", "cave.real_and_fake_apples")


def learned_code_run(
    weights,
    *,
    scene="cave.face",
    shape=(256, 256),
    snr_db=None,
    seed=0,
    device="cpu",
    reference=None,
) -> dict:
    """One cell of :func:`learned_code` and :func:`learned_imagers`: the D-CoSNet ``weights``
    reconstruct ``scene`` imaged by their system (SD-CASSI or CASSI-VSI) through the code
    they were trained with, tiled over ``shape``.

    Returns PSNR / SSIM / SAM / RMSE, seconds, the system's name, and the
    code's kind (``"seeded"`` or ``"learned"``), open fraction (``density``)
    and the dispersion step (``shift``, px per band); with ``reference`` (a
    method name, e.g. ``"otd"``) also ``reference_psnr``, that method on the
    same measurement.
    """
    from .. import scenes
    from ..datasets import KAIST_WAVELENGTHS
    from ..learn.dcosnet import DCoSNet, read_config, tile_code, training_code
    from ..systems import CASSIVSI, SDCASSI
    from .problems import Problem, score

    cfg = read_config(weights)
    code = training_code(weights)
    if (code is None or cfg.get("system") not in ("sd_cassi", "cassi_vsi")
            or int(cfg["channels"]) != 28):  # fmt: skip
        raise ValueError(
            f"{weights}: not D-CoSNet weights for SD-CASSI or CASSI-VSI with 28 bands trained "
            "on one seeded or learned code (tensor-cosdi train-dcosnet --mask seeded …)"
        )
    shape = tuple(int(n) for n in shape)
    wl = np.asarray(KAIST_WAVELENGTHS)
    cube = scenes.scene_cube(scene, shape, wl)
    options = {"n_bands": len(wl), "shifts": int(cfg["shift"]), "wavelengths": wl}
    if cfg["system"] == "cassi_vsi":
        system = CASSIVSI(tile_code(code, shape), alpha_t=float(cfg["alpha_t"]), **options)
    else:
        system = SDCASSI(tile_code(code, shape), **options)
    g = system.simulate(cube, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    est = DCoSNet(weights, device=device)(system, g)
    seconds = time.perf_counter() - t0
    p = Problem(f"{cfg['system']}/{scene}", system, cube, g, wl, snr_db, cube)
    out = {
        **score(p, est), "seconds": seconds, "system": cfg["system"], "code": cfg["code"],
        "density": float(code.mean()), "shift": int(cfg["shift"]),
    }  # fmt: skip
    if reference is not None:
        from ..solvers import reconstruct

        out["reference_psnr"] = score(p, reconstruct(system, g, reference).cube)["psnr"]
    return out


def learned_code(
    weights=None, scenes=REPORT_CAVE_SCENES, *, shape=(256, 256), snrs=(None, 30.0), seeds=(0,),
    device="cpu", reference=None, client=None, progress=True,
) -> list[dict]:  # fmt: skip
    """D-CoSNet trained with a learned coded aperture against a fixed one (thesis §7.3).

    The thesis trains "the coded aperture and the shearing weights" together
    with the network.  Here each entry of ``weights`` is a D-CoSNet trained
    by ``tensor-cosdi train-dcosnet --mask seeded`` (one fixed Bernoulli(½)
    64×64 code drawn from the seed) or with ``--learn-code`` as well (that
    code learned with a straight-through binary estimator during the first
    half of the steps, then held while the network adapts); everything else
    is equal.  Each network reconstructs every scene imaged through its own
    code tiled over ``shape``.  The shear is an integer (px per band), so it
    is compared by training one pair per step rather than by gradient.

    Parameters
    ----------
    weights : mapping of label → path, optional
        Default :data:`CODE_STUDY_WEIGHTS` (the shipped pair at 2 px).
    scenes : sequence of str
        Names of :data:`tensor_cosdi.scenes.SCENES` (default the report scenes).
    shape, snrs, seeds
        Spatial size (the code is tiled over it), measurement SNRs (``None``:
        noiseless) and noise seeds.
    device, client, progress
        Torch device; as in :func:`~tensor_cosdi.studies.sweep`.
    reference : str, optional
        A method run on the same measurements too (``reference_psnr``).

    Returns
    -------
    list of dict
        One record per weights × scene × SNR × seed: the parameters, PSNR,
        SSIM, SAM, RMSE, seconds, ``system``, ``code``, ``density`` and
        ``shift`` (and ``reference_psnr``).

    Examples
    --------
    >>> rows = learned_code(scenes=("chelsea",), shape=(64, 64), snrs=(None,),
    ...                     progress=False)
    >>> sorted(r["code"] for r in rows)
    ['learned', 'seeded']
    """
    from .sweeping import seed_list, sweep

    weights = dict(CODE_STUDY_WEIGHTS if weights is None else weights)
    if not weights:
        raise ValueError("weights must name at least one D-CoSNet weights file")
    missing = [str(p) for p in weights.values() if not Path(p).is_file()]
    if missing:
        raise FileNotFoundError(f"D-CoSNet weights not found: {', '.join(missing)}")
    if isinstance(scenes, str) or not scenes or any(not isinstance(s, str) for s in scenes):
        raise ValueError(f"scenes must be a non-empty sequence of scene names, got {scenes!r}")
    snrs = [None if s is None else float(s) for s in snrs]

    paths = {str(k): str(v) for k, v in weights.items()}
    grid = {"weights": list(paths), "scene": list(scenes), "snr_db": snrs,
            "seed": seed_list(seeds)}  # fmt: skip
    return sweep(grid, partial(_cell, paths=paths, shape=tuple(shape), device=device,
                               reference=reference), client=client, progress=progress)  # fmt: skip


def learned_imagers(
    weights=None, scenes=REPORT_CAVE_SCENES, *, shape=(256, 256), snrs=(20.0, 30.0),
    seeds=(0,), device="cpu", reference="otd", client=None, progress=True,
) -> list[dict]:  # fmt: skip
    """One learned reconstructor trained for SD-CASSI and for CASSI-VSI (thesis §3.3.5).

    The thesis trains λ-net on each forward model (one fixed code, αT 0.7)
    and finds CASSI-VSI up to 3.49 dB better, and better at 20 and 30 dB on
    most test images (Fig. 25-27).  Here the unrolled network is D-CoSNet,
    whose x-step is each system's exact ``(μI + A Aᵀ)⁻¹`` — a division for
    SD-CASSI, a Cholesky solve of each detector row's banded block for
    CASSI-VSI — trained identically for both on one fixed seeded code
    (``tensor-cosdi train-dcosnet --mask seeded --system …``).  Same scenes,
    code (tiled), noise levels and seeds for both.  ``reference`` (default
    OTD) runs on the same measurements: what the forward models give a
    training-free method, beside what the networks learned.

    Parameters
    ----------
    weights : mapping of label → path, optional
        Default :data:`IMAGER_STUDY_WEIGHTS` (the shipped pair).
    scenes, shape, snrs, seeds, device, reference, client, progress
        As for :func:`learned_code` (default 20 and 30 dB, the thesis'
        Fig. 26-27; ``reference=None`` skips it).

    Returns
    -------
    list of dict
        As :func:`learned_code`, with each network's ``system``.

    Examples
    --------
    >>> rows = learned_imagers(scenes=("chelsea",), shape=(32, 32), snrs=(30.0,),
    ...                        progress=False)
    >>> sorted(r["system"] for r in rows)
    ['cassi_vsi', 'sd_cassi']
    """
    return learned_code(
        IMAGER_STUDY_WEIGHTS if weights is None else weights, scenes, shape=shape, snrs=snrs,
        seeds=seeds, device=device, reference=reference, client=client, progress=progress,
    )  # fmt: skip


def _cell(*, paths, weights, **params):
    """A picklable cell for Dask: the label's weights file, then :func:`learned_code_run`."""
    return learned_code_run(paths[weights], **params)
