"""Which Zernike aberration encodes depth best in CASSDI-DFA (re-exported by
:mod:`tensor_cosdi.studies`; thesis Section 4.3).

The deformable mirror adds one Zernike mode to the focal sweep; the thesis
picks vertical astigmatism (Noll 6) at ≈ 0.9-1 wave.  A PSF cropped to a few
pixels and renormalised is not that PSF: with the default lens a 9 × 9 crop
holds 9 % of the light of Z6 at 0.9 wave (unit-RMS Zernikes), and the
answer "Z6 beats pure defocus" flipped between a 9 × 9 and a 41 × 41 crop.
So every record carries ``energy``, the share of the PSF's light inside the
crop (against a ``reference_size`` crop), and ``separation``, a property of
the optics alone: how far apart the PSFs of neighbouring depth planes are
(half the ℓ1 distance of the normalised reference PSFs, the least over
plane pairs, mean over bands; 0 = indistinguishable, 1 = disjoint).
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np

from ..validate import precision

__all__ = ["zernike_design", "zernike_run", "default_lens", "DEPTHS_MM"]

#: Object distances (mm) of the depth planes and the lens of the DFA design studies.
DEPTHS_MM = (800.0, 1000.0, 1300.0)


def default_lens():
    from ..optics import Lens

    return Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)


def zernike_run(
    aberration, psf_size, *, scene="cave.face", shape=(48, 48), n_bands=12, depths_mm=DEPTHS_MM,
    lens=None, snr_db=30.0, method="dfa", seed=0, reference_size=81, sweep=False,
    dtype="float64", **options,
) -> dict:  # fmt: skip
    """One cell of :func:`zernike_design`: CASSDI-DFA whose PSFs add ``aberration = (Noll index,
    waves RMS)`` to defocus (amplitude 0: pure defocus, "DFD"), cropped to ``psf_size``;
    ``sweep=True``: the focal-sweep model (every plane seen at every step); the measurement
    reaches the reconstruction in ``dtype``."""
    from .. import codes, optics, scenes
    from ..solvers import reconstruct
    from ..systems import CASSDIDFA, wavelengths_for
    from .problems import Problem, score

    dtype = precision("dtype", dtype)
    mode, amp = int(aberration[0]), float(aberration[1])
    if int(psf_size) > int(reference_size):
        raise ValueError(f"psf_size {psf_size} exceeds reference_size {reference_size}")
    lens = default_lens() if lens is None else lens
    wl = wavelengths_for(None, n_bands)
    nz = len(depths_mm)
    planes = scenes.depth_planes(scenes.motorcycle(tuple(shape), [550.0])[1], nz)
    cube = scenes.depth_layers(scenes.scene_cube(scene, tuple(shape), wl), planes, nz)
    zern = {mode: amp} if amp else None
    kw = dict(lens=lens, zernike=zern, size=int(reference_size), min_share=None)
    if sweep:  # (…, Nλ, Nz, K): the mirror refocuses on each plane in turn
        ref = optics.sweep_psf_stack(wl, depths_mm, depths_mm, **kw)
    else:  # the study measures the crops' light itself
        ref = optics.psf_stack(wl, depths_mm, **kw)
    c, h = int(reference_size) // 2, int(psf_size) // 2
    energy = ref[c - h : c + h + 1, c - h : c + h + 1].sum(axis=(0, 1))  # (Nλ, Nz[, K])
    psfs = ref[c - h : c + h + 1, c - h : c + h + 1] / energy  # the crop, renormalised
    dist = [  # per band (and step): how far apart the PSFs of planes i and j are
        0.5 * np.abs(ref[:, :, :, i] - ref[:, :, :, j]).sum(axis=(0, 1)).reshape(len(wl), -1)
        for i in range(nz)
        for j in range(i + 1, nz)
    ]
    system = CASSDIDFA(
        codes.depth_codes(tuple(shape), nz, rng=seed), n_bands=n_bands, psfs=psfs, wavelengths=wl
    )
    g = np.asarray(system.simulate(cube, snr_db=snr_db, rng=seed), dtype=dtype)
    t0 = time.perf_counter()
    res = reconstruct(system, g, method, **options)
    seconds = time.perf_counter() - t0
    p = Problem(f"cassdi_dfa/{scene}", system, cube, g, wl, snr_db, cube)
    out = {"mode": mode if amp else 0, "amplitude": amp, **score(p, res.cube)}
    if getattr(res, "depth", None) is not None:
        out["depth_accuracy"] = float(np.mean(np.asarray(res.depth) == planes))
    out.update(
        energy=float(energy.min()),
        separation=float(np.min(np.mean(dist, axis=2), axis=0).mean()),
        seconds=seconds,
    )
    return out


def zernike_design(
    modes=(5, 6, 7, 8, 9, 11), amplitudes=(0.25, 0.5, 0.9), psf_sizes=(15, 41), *,
    scene="cave.face", shape=(48, 48), n_bands=12, snr_db=30.0, method="dfa", seeds=(0,),
    reference_size=81, sweep=False, dtype="float64", client=None, progress=True, **options,
) -> list[dict]:  # fmt: skip
    """Depth and spectral quality of CASSDI-DFA against the Zernike mode and amplitude the
    deformable mirror adds to defocus, at several PSF crop sizes (thesis Section 4.3).

    Pure defocus (amplitude 0, the thesis' "CASSDI-DFD") is always included.
    Three depth planes at 800 / 1000 / 1300 mm, a 50 mm f/16.7 lens focused
    at 1 m, 6 µm pixels; the codes are :func:`tensor_cosdi.codes.depth_codes`.

    Parameters
    ----------
    modes : sequence of int
        Noll indices (5, 6: astigmatism; 7, 8: coma; 9, 10: trefoil; 11:
        spherical).
    amplitudes : sequence of float
        Coefficients in waves RMS (unit-RMS Zernikes), > 0.
    psf_sizes : sequence of odd int
        Crops of the PSFs the system is built with; compare a verdict only
        across crops whose ``energy`` is near 1.
    scene, shape, n_bands, snr_db, method, seeds, client, progress
        As for :func:`~tensor_cosdi.studies.colour_code_design` (``method``
        ``"dfa"`` also gives the depth map; ``options`` go to it).
    reference_size : odd int
        The crop that stands for the whole PSF in ``energy`` and ``separation``.
    sweep : bool
        The focal-sweep model (:func:`tensor_cosdi.optics.sweep_psf_stack`:
        every plane seen at every focal step through its own PSF) instead of
        the thesis' per-plane model, where plane ``z`` is seen only at step
        ``z`` and the codes alone tell the planes apart.  ``separation`` then
        averages over the steps.
    dtype : {"float64", "float32"}
        The precision the measurement reaches the reconstruction in (the solver keeps it):
        ``"float32"``, a camera's data, runs the Fourier-domain blurs 1.2-1.7× faster
        (``benchmarks/results/blur_operators.md``; ``benchmarks/thesis_findings.py`` uses
        it).

    Returns
    -------
    list of dict
        One record per (mode, amplitude, crop, seed): ``mode`` (0 for pure
        defocus), ``amplitude``, ``psf_size``, ``seed``, ``psnr``, ``ssim``,
        ``sam``, ``rmse``, ``depth_accuracy`` (share of pixels on the right
        plane), ``energy`` (least share of a PSF's light inside the crop),
        ``separation`` and ``seconds``.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.zernike_design((6,), (0.5,), (9,), scene="colorchecker", shape=(16, 16),
    ...                               n_bands=4, reference_size=31, progress=False, max_iter=2)
    >>> [(r["mode"], r["amplitude"], r["psf_size"]) for r in recs]
    [(0, 0.0, 9), (6, 0.5, 9)]
    """
    from .sweeping import seed_list
    from .sweeping import sweep as run_grid

    modes = [int(m) for m in modes]
    if any(m < 2 for m in modes):
        raise ValueError(f"Noll indices start at 1 (piston) and 2-3 are tilts; got {modes}")
    amps = [float(a) for a in amplitudes]
    if any(not a > 0 for a in amps):
        raise ValueError(f"amplitudes must be > 0 waves (0 is the pure-defocus row), got {amps}")
    sizes = [int(s) for s in psf_sizes]
    if any(s < 1 or s % 2 == 0 or s > reference_size for s in sizes):
        raise ValueError(f"psf_sizes must be odd, 1…reference_size={reference_size}: {sizes}")
    cases = [(0, 0.0)] + [(m, a) for m in modes for a in amps]
    grid = {"aberration": cases, "psf_size": sizes, "seed": seed_list(seeds)}
    run = partial(  # a module-level function: picklable for Dask workers
        zernike_run, scene=scene, shape=tuple(shape), n_bands=n_bands, snr_db=snr_db,
        method=method, reference_size=reference_size, sweep=bool(sweep),
        dtype=str(precision("dtype", dtype)), **options,
    )  # fmt: skip
    recs = run_grid(grid, run, client=client, progress=progress)
    for r in recs:
        r.pop("aberration", None)
    return recs
