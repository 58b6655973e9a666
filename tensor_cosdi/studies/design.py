"""Design studies of coded apertures and snapshot counts (re-exported by
:mod:`tensor_cosdi.studies`)."""

from __future__ import annotations

import time
from functools import lru_cache, partial

import numpy as np

from ..validate import precision, real_array

__all__ = [
    "colour_code_design", "colour_code_run", "cs2li_code_design", "cs2li_code_run",
    "cs2li_comparison", "cs2li_comparison_run", "CS2LI_IMAGERS", "c3slfi_sparsity",
    "c3slfi_table", "c3slfi_table_run", "c3slfi_dictionary",
]  # fmt: skip


def colour_code_run(
    n_filters, transmittance, *, scene="cave.face", shape=(64, 64), n_bands=16, shifts=1,
    snr_db=30.0, method="otd", seed=0, **options,
) -> dict:  # fmt: skip
    """One cell of :func:`colour_code_design`: SD-CASSI with a colour-coded aperture of
    ``n_filters`` filters and transmittance ``transmittance`` (``#f = 1``: a binary code),
    imaging ``scene``; returns PSNR / SSIM / SAM, the conditioning of ``A Aᵀ`` and seconds."""
    from .. import codes, scenes
    from ..solvers import reconstruct
    from ..systems import SDCASSI, wavelengths_for
    from .condition import conditioning
    from .problems import Problem, score

    wl = wavelengths_for(None, n_bands)
    cube = scenes.scene_cube(scene, tuple(shape), wl)
    code = codes.colour_coded_aperture(
        tuple(shape), n_bands, n_filters=n_filters, transmittance=transmittance, rng=seed
    )
    system = SDCASSI(code, n_bands=n_bands, shifts=shifts, wavelengths=wl, colour=True)
    g = system.simulate(cube, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    res = reconstruct(system, g, method, **options)
    seconds = time.perf_counter() - t0
    p = Problem(f"sd_cassi/{scene}", system, cube, g, wl, snr_db, cube)
    cond = conditioning(system)
    return {
        **score(p, res.cube),
        "cond": cond["cond_nonzero"],
        "unreached": cond["zero"],
        "seconds": seconds,
    }


def colour_code_design(
    filters=(1, 2, 4, 6, 8, 16), transmittances=(0.25, 0.5, 0.75), *, scene="cave.face",
    shape=(64, 64), n_bands=16, snr_db=30.0, method="otd", seeds=(0,), client=None,
    progress=True, **options,
) -> list[dict]:  # fmt: skip
    """Reconstruction quality and conditioning of colour-coded SD-CASSI against the number of
    filters ``#f`` and the transmittance ``κ`` (thesis Section 6.3.2;
    :func:`tensor_cosdi.codes.colour_coded_aperture`).

    Judge it on a real scene (``"cave.<name>"``, the default): photo-derived
    spectra live in a 3-D subspace and favour any code.

    Parameters
    ----------
    filters : sequence of int
        Numbers of filters ``#f`` (``1 ≤ #f ≤ n_bands``; 1 is a binary code).
    transmittances : sequence of float
        Open fractions ``κ`` in (0, 1].
    scene : str
        A name of :data:`tensor_cosdi.scenes.SCENES`.
    shape, n_bands, snr_db
        Spatial size, bands (450-650 nm) and measurement SNR of each cell.
    method : str
        The reconstruction method (``options`` go to it; ``shifts=`` to the
        system).
    seeds : sequence of int
        Seeds of code and noise; one record per seed.
    client, progress
        As for :func:`~tensor_cosdi.studies.sweep` (``client`` for Dask).

    Returns
    -------
    list of dict
        One record per ``(#f, κ, seed)``: ``n_filters``, ``transmittance``,
        ``seed``, ``psnr``, ``ssim``, ``sam``, ``rmse``, ``cond`` (condition
        number of ``A Aᵀ`` on its range), ``unreached`` (detector pixels no
        voxel reaches) and ``seconds``; :func:`~tensor_cosdi.studies.write_csv`
        writes them.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.colour_code_design((1, 4), (0.5,), scene="colorchecker",
    ...                                   shape=(16, 16), n_bands=8, progress=False)
    >>> [(r["n_filters"], r["transmittance"]) for r in recs]
    [(1, 0.5), (4, 0.5)]
    """
    from ..validate import integer
    from .sweeping import seed_list, sweep

    filters = [integer("#f", f) for f in filters]  # 2.5 is an error, not 2
    if any(f < 1 or f > n_bands for f in filters):
        raise ValueError(f"every #f must lie in 1…n_bands = {n_bands}, got {filters}")
    if any(not 0 < k <= 1 for k in transmittances):
        raise ValueError(f"every κ must lie in (0, 1], got {list(transmittances)}")
    grid = {"n_filters": filters, "transmittance": list(transmittances), "seed": seed_list(seeds)}
    run = partial(  # a module-level function: picklable for Dask workers
        colour_code_run, scene=scene, shape=tuple(shape), n_bands=n_bands, snr_db=snr_db,
        method=method, **options,
    )  # fmt: skip
    return sweep(grid, run, client=client, progress=progress)


def _check_code_grid(filters, transmittances, n_bands):
    from ..validate import integer, number

    n_bands = integer("n_bands", n_bands, low=1)
    if isinstance(filters, (str, bytes)) or isinstance(transmittances, (str, bytes)):
        raise ValueError("filters and transmittances must be sequences of numbers")
    filters = [integer("#f", f, low=1, high=n_bands) for f in filters]
    kappas = [number("κ (transmittance)", k, low=0, low_open=True, high=1) for k in transmittances]
    if not filters or not kappas:
        raise ValueError("filters and transmittances must each hold at least one value")
    return filters, kappas, n_bands


def _fringe_problem(scene, shape, n_bands, n_patterns, fringe_axis, seed):
    """``(wavelengths, structured-light scene, cube)``: the seeded height map and fringes of
    :func:`tensor_cosdi.scenes.structured_light` (one frequency, ``n_patterns`` phase steps, the
    phase running along ``fringe_axis``) with ``scene``'s reflectance."""
    from dataclasses import replace

    from .. import scenes
    from ..systems import fringe_cube, wavelengths_for
    from ..validate import integer

    wl = wavelengths_for(None, integer("n_bands", n_bands, low=1))
    integer("n_patterns (phase steps)", n_patterns, low=3)
    sl = scenes.structured_light(shape, wl, frequencies=(4.0,), fringe_axis=fringe_axis, rng=seed)
    sl = replace(sl, reflectance=np.asarray(scenes.scene_cube(scene, shape, wl)))
    cube = np.asarray(fringe_cube(sl.reflectance, sl.phase, n_steps=n_patterns, amplitude=0.5))
    return wl, sl, cube


def _fringe_scores(sl, cube, est, seconds) -> dict:
    """The reflectance's PSNR / SSIM / SAM / RMSE (the mean over the phase steps, Eq. 107), the
    height map's PSNR / SSIM / RMSE from the wrapped phase of the estimate summed over its bands
    (unwrapped with the true phase: only the reconstruction is judged), the wrapped phase's mean
    absolute error and the whole cube's PSNR."""
    from .. import depth, metrics

    refl = est.mean(axis=3)
    phi = depth.wrapped_phase(est.sum(axis=2))
    err = depth.wrap(phi - sl.phase[..., 0])
    height = sl.height + err / sl.phase_per_height
    top = float(sl.height.max())
    flat = cube.reshape(*cube.shape[:2], -1)
    return {
        "psnr": metrics.psnr(sl.reflectance, refl),
        "ssim": metrics.ssim(sl.reflectance, refl),
        "sam": metrics.sam(sl.reflectance, refl),
        "rmse": metrics.rmse(sl.reflectance, refl),
        "depth_psnr": metrics.psnr(sl.height, height, data_range=top),
        "depth_ssim": metrics.ssim(sl.height, height, data_range=top),
        "depth_rmse": metrics.rmse(sl.height, height),
        "phase_mae": float(np.abs(err).mean()),
        "cube_psnr": metrics.psnr(flat, est.reshape(flat.shape)),
        "seconds": seconds,
    }


def cs2li_code_run(
    n_filters, transmittance, *, scene="cave.face", shape=(48, 48), n_bands=8, n_patterns=4,
    shifts=1, snr_db=30.0, fringe_axis=0, method="otd", seed=0, **options,
) -> dict:  # fmt: skip
    """One cell of :func:`cs2li_code_design`: CS2LI with a colour-coded aperture of
    ``n_filters`` filters and transmittance ``transmittance`` imaging :func:`_fringe_problem`'s
    scene; returns the scores of :func:`_fringe_scores`."""
    from ..solvers import reconstruct
    from ..systems import CS2LI

    (n_filters,), (transmittance,), n_bands = _check_code_grid(
        [n_filters], [transmittance], n_bands
    )  # fmt: skip
    shape = tuple(shape)
    wl, sl, cube = _fringe_problem(scene, shape, n_bands, n_patterns, fringe_axis, seed)
    system = CS2LI.example(  # the colour-coded aperture of #f filters, κ open, seeded
        (*shape, n_bands, n_patterns), rng=seed, n_filters=n_filters,
        transmittance=transmittance, shifts=shifts, wavelengths=wl,
    )  # fmt: skip
    g = system.simulate(cube, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    est = np.asarray(reconstruct(system, g, method, **options).cube)
    return _fringe_scores(sl, cube, est, time.perf_counter() - t0)


#: :func:`cs2li_comparison`'s imagers: CS2LI with a binary code, CS2LI with the thesis'
#: trade-off colour code (#f 6, κ 50 %), and structured light captured pattern by pattern with
#: an SD-CASSI of the same binary code (the same light and frame count).
CS2LI_IMAGERS = ("cs2li", "cs2li_colour", "sl_sd_cassi")


def cs2li_comparison_run(
    imager, *, scene="cave.face", shape=(48, 48), n_bands=8, n_patterns=4, snr_db=30.0,
    fringe_axis=0, method="otd", seed=0, **options,
) -> dict:  # fmt: skip
    """One cell of :func:`cs2li_comparison` (one dispersion pixel per band); returns the scores
    of :func:`_fringe_scores`."""
    from .. import codes
    from ..solvers import reconstruct
    from ..systems import CS2LI, SDCASSI

    if not isinstance(imager, str) or imager not in CS2LI_IMAGERS:
        raise ValueError(f"imager must be one of {', '.join(CS2LI_IMAGERS)}, got {imager!r}")
    shape = tuple(shape)
    wl, sl, cube = _fringe_problem(scene, shape, n_bands, n_patterns, fringe_axis, seed)
    nl, (nx, ny) = len(wl), shape
    code = codes.random_binary((nx, ny + nl - 1), rng=seed)
    if imager == "cs2li_colour":
        code = codes.colour_coded_aperture(
            (nx, ny + nl - 1), nl, n_filters=min(6, nl), transmittance=0.5, rng=seed
        )
    t0 = time.perf_counter()
    if imager == "sl_sd_cassi":
        sd = SDCASSI(code[:, :ny], n_bands=nl, shifts=1, wavelengths=wl)
        est = np.empty_like(cube)
        for t in range(cube.shape[3]):
            g = sd.simulate(cube[..., t], snr_db=snr_db, rng=seed + t)
            est[..., t] = np.asarray(reconstruct(sd, g, method, **options).cube)
    else:
        cs = CS2LI(code, n_bands=nl, n_patterns=cube.shape[3], shifts=1, wavelengths=wl)
        g = cs.simulate(cube, snr_db=snr_db, rng=seed)
        est = np.asarray(reconstruct(cs, g, method, **options).cube)
    return _fringe_scores(sl, cube, est, time.perf_counter() - t0)


def cs2li_comparison(
    scenes=("cave.face",), imagers=CS2LI_IMAGERS, *, snrs=(20.0, 30.0, 50.0), shape=(48, 48),
    n_bands=8, n_patterns=4, fringe_axis=0, method="otd", seeds=(0,), client=None,
    progress=True, **options,
) -> list[dict]:  # fmt: skip
    """CS2LI against structured light captured with an SD-CASSI, with a binary and with a colour
    code, over the noise (thesis Sec. 6.3.1, Fig. 56; Sec. 6.3 for the depth gain).

    The thesis reports CS2LI's depth up to 4 dB above the SD-CASSI capture (called SCCI there)
    with comparable SAM and RMSE and up to 0.10 more SSIM, and the colour code up to 1 dB and
    0.5° SAM better than the binary one.  Each cell is :func:`cs2li_comparison_run`.

    Parameters
    ----------
    scenes : sequence of str
        Reflectances (names of :data:`tensor_cosdi.scenes.SCENES`).
    imagers : sequence of str
        A subset of :data:`CS2LI_IMAGERS`.
    snrs : sequence of float
        Measurement SNRs in dB.
    shape, n_bands, n_patterns, fringe_axis
        Spatial size, bands, phase steps and the fringes' axis (0: across the dispersion).
    method : str
        The reconstruction of every imager (``options`` go to it).
    seeds, client, progress
        As in :func:`~tensor_cosdi.studies.sweep`.

    Returns
    -------
    list of dict
        One record per scene × imager × SNR × seed with the scores of
        :func:`cs2li_comparison_run`.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.cs2li_comparison(("colorchecker",), snrs=(30,), shape=(16, 16), n_bands=4,
    ...                                 progress=False, max_iter=3, pan_iter=3)
    >>> [r["imager"] for r in recs]
    ['cs2li', 'cs2li_colour', 'sl_sd_cassi']
    """
    from ..noise import check_snr_db
    from .sweeping import seed_list, sweep

    if any(isinstance(v, (str, bytes)) for v in (scenes, imagers, snrs)):
        raise ValueError("scenes, imagers and snrs must be sequences, not one string")
    bad = [i for i in imagers if not isinstance(i, str) or i not in CS2LI_IMAGERS]
    if bad:
        raise ValueError(f"imagers must be among {', '.join(CS2LI_IMAGERS)}, got {bad!r}")
    scenes, imagers, snrs = list(scenes), list(imagers), [check_snr_db(v) for v in snrs]
    if not scenes or not imagers or not snrs:
        raise ValueError("scenes, imagers and snrs must each hold at least one value")
    grid = {"scene": scenes, "imager": imagers, "snr_db": snrs, "seed": seed_list(seeds)}
    run = partial(
        cs2li_comparison_run, shape=tuple(shape), n_bands=n_bands, n_patterns=n_patterns,
        fringe_axis=fringe_axis, method=method, **options,
    )  # fmt: skip
    return sweep(grid, run, client=client, progress=progress)


def cs2li_code_design(
    filters=None, transmittances=(0.25, 0.5, 0.75), *, scene="cave.face",
    shape=(48, 48), n_bands=8, n_patterns=4, snr_db=30.0, fringe_axis=0, method="otd",
    seeds=(0,), client=None, progress=True, **options,
) -> list[dict]:  # fmt: skip
    """CS2LI's colour-coded aperture against its number of filters ``#f`` and transmittance
    ``κ``, judged on the spectra *and* the depth (thesis Sec. 6.3.2, Fig. 58).

    The thesis finds the least SAM and RMSE at ``#f = Nλ, κ = 25 %``, the best depth at
    ``#f = 1, κ = 75 %`` (depth nearly invariant to ``#f``) and picks ``#f = 6, κ = 50 %``
    as the trade-off.  Each cell is :func:`cs2li_code_run`.

    Parameters
    ----------
    filters : sequence of int, optional
        ``#f`` values (``1 ≤ #f ≤ n_bands``; 1 is a binary code); default the thesis'
        ``1, 2, 6, Nλ`` (those up to ``n_bands``).
    transmittances : sequence of float
        ``κ`` values in (0, 1].
    scene : str
        The reflectance (a name of :data:`tensor_cosdi.scenes.SCENES`; judge it on a real
        ``"cave.<name>"`` scene).
    shape, n_bands, n_patterns, snr_db, fringe_axis
        Spatial size, bands, phase steps, measurement SNR and the fringes' axis (0: across
        the dispersion, 1: along it).
    method : str
        The reconstruction (``options`` go to it).
    seeds, client, progress
        As in :func:`colour_code_design`.

    Returns
    -------
    list of dict
        One record per ``(#f, κ, seed)`` with the scores of :func:`cs2li_code_run`.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.cs2li_code_design((1, 4), (0.5,), scene="colorchecker", shape=(16, 16),
    ...                                  n_bands=4, progress=False, max_iter=3, pan_iter=3)
    >>> [(r["n_filters"], r["transmittance"]) for r in recs]
    [(1, 0.5), (4, 0.5)]
    """
    from .sweeping import seed_list, sweep

    if filters is None:
        n = n_bands if isinstance(n_bands, int) and n_bands >= 1 else 1  # checked just below
        filters = sorted({f for f in (1, 2, 6, n) if f <= n})
    filters, kappas, n_bands = _check_code_grid(filters, transmittances, n_bands)
    grid = {"n_filters": filters, "transmittance": kappas, "seed": seed_list(seeds)}
    run = partial(
        cs2li_code_run, scene=scene, shape=tuple(shape), n_bands=n_bands,
        n_patterns=n_patterns, snr_db=snr_db, fringe_axis=fringe_axis, method=method, **options,
    )  # fmt: skip
    return sweep(grid, run, client=client, progress=progress)


def _energy_shares(coefficients, fractions, points):
    """The share of the largest coefficients that holds each energy fraction, and the energy
    captured at ``points`` (shares of the coefficients, sorted by magnitude)."""
    e = np.sort(np.abs(real_array("coefficients", coefficients, finite=False)).ravel() ** 2)[::-1]
    cum = np.cumsum(e) / e.sum()
    n = e.size
    # min(…, n − 1): a fraction of 1 can sit above the last cumulative sum by rounding
    shares = {f: float((min(int(np.searchsorted(cum, f)), n - 1) + 1) / n) for f in fractions}
    curve = [float(cum[max(0, min(n - 1, int(np.ceil(q * n)) - 1))]) for q in points]
    return shares, curve


#: :func:`c3slfi_sparsity`'s curve: the shares of the sorted coefficients it reports the energy at.
SPARSITY_POINTS = tuple(float(v) for v in np.round(np.geomspace(1e-4, 1.0, 25), 6))


def c3slfi_sparsity(
    scene="cave.face", *, shape=(64, 64), views=(4, 4), n_bands=16, n_snapshots=2, snr_db=30.0,
    seed=0, fractions=(0.99, 0.999, 0.9999), **options,
) -> list[dict]:  # fmt: skip
    """How sparsely each basis represents a spectral light field in its 3-D (lenslet) and 5-D
    forms (thesis Sec. 5.3.1, Fig. 45).

    Bases as the thesis fixes them: WDCT ``Ψ_W ⊗ Ψ_W ⊗ Ψ_DCT`` (3-D) and
    ``Ψ_W ⊗ Ψ_W ⊗ Ψ_DCT ⊗ I ⊗ I`` (5-D; Symlet-8, as deep as the size allows), and OTD's:
    the complete HOSVD bases (:func:`tensor_cosdi.bases.tucker_bases`) of OTD's own
    reconstruction from a seeded C3SLFI measurement in that form — what OTD learns, not the
    truth's bases.  The true light field is projected on each, its coefficients sorted by
    magnitude.  The thesis finds OTD's basis sparser than WDCT in both forms and the 3-D
    form sparser than the 5-D one.

    Parameters
    ----------
    scene : str
        A name of :data:`tensor_cosdi.scenes.SCENES` (a real ``"cave.<name>"`` scene to judge).
    shape, views, n_bands, n_snapshots, snr_db, seed
        The C3SLFI problem (:func:`~tensor_cosdi.studies.make_problem`) OTD reconstructs.
    fractions : sequence of float
        Energy fractions in (0, 1] to report the needed share of coefficients for.
    **options
        Passed to OTD.

    Returns
    -------
    list of dict
        One record per form (``"3d"``, ``"5d"``) and basis (``"wdct"``, ``"otd"``): the share
        of coefficients holding each fraction (``share_0.999``…), the energy captured at the
        shares :data:`SPARSITY_POINTS` (``curve``) and the OTD reconstruction's PSNR.

    Examples
    --------
    >>> recs = c3slfi_sparsity("chelsea", shape=(16, 16), views=(2, 2), n_bands=4,
    ...                        max_iter=5, pan_iter=5)
    >>> [(r["form"], r["basis"]) for r in recs]
    [('3d', 'wdct'), ('3d', 'otd'), ('5d', 'wdct'), ('5d', 'otd')]
    """
    from ..bases import KroneckerBasis, dct, identity, tucker_bases, wavelet
    from ..solvers import reconstruct
    from ..validate import number
    from .problems import make_problem, score

    if isinstance(fractions, (str, bytes)) or not len(fractions):
        raise ValueError(f"fractions must be a sequence of numbers in (0, 1], got {fractions!r}")
    fractions = [number("energy fraction", f, low=0, low_open=True, high=1) for f in fractions]
    p = make_problem("c3slfi", scene, shape=tuple(shape), n_bands=n_bands, snr_db=snr_db,
                     rng=seed, n_snapshots=n_snapshots, views=tuple(views))  # fmt: skip
    truth3 = np.asarray(p.cube)
    forms = {
        "3d": (p.system, p.measurement, truth3),
        "5d": (p.system.as_5d(), p.system.measurement_to_5d(p.measurement),
               np.asarray(p.system.to_5d(truth3))),
    }  # fmt: skip
    out = []
    for form, (system, g, truth) in forms.items():
        est = np.asarray(reconstruct(system, g, "otd", **options).cube)
        psnr = score(p, est if form == "3d" else np.asarray(p.system.to_3d(est)))["psnr"]
        fixed = {0: wavelet(truth.shape[0]), 1: wavelet(truth.shape[1]), 2: dct(truth.shape[2])}
        fixed.update({m: identity(truth.shape[m]) for m in range(3, truth.ndim)})
        for name, mats in (("wdct", fixed), ("otd", tucker_bases(est))):
            coef = KroneckerBasis(truth.shape, mats).analysis(truth)
            shares, curve = _energy_shares(coef, fractions, SPARSITY_POINTS)
            out.append({
                "form": form, "basis": name, "otd_psnr": psnr,
                **{f"share_{f:g}": v for f, v in shares.items()}, "curve": curve,
            })  # fmt: skip
    return out


def c3slfi_dictionary(
    shape=(64, 64), views=(4, 4), n_bands=31, *, exclude=(), seed=0, aligned=False
):
    """The DL baselines' K-SVD dictionary for :func:`c3slfi_table` (cached per argument set).

    Trained (8 × 8 × ``n_bands`` patches, 2× over-complete, 3000 patches,
    4 iterations, :func:`~tensor_cosdi.solvers.dictionary.train_dictionary`)
    on the lenslet (3-D) light fields of the tuning scenes
    (:data:`tensor_cosdi.datasets.TUNE_SCENES`), or without the research data
    on the photo scenes not in ``exclude`` — never on a scene it is scored on.
    ``aligned=False``: DL-3D, patches anywhere on the lenslet image;
    ``True``: DL-5D, patches of whole lenslets (``align=views``), each one
    the 5-D patch of ``8 / views`` scene points per axis × every view ×
    every band, coded on the same aligned grid.
    """
    from .. import datasets
    from ..scenes import SCENES

    try:
        datasets.data_dir()
        names = [f"cave.{s}" for s in datasets.TUNE_SCENES]
    except FileNotFoundError:
        names = [s for s in SCENES if not s.startswith("cave.")]
    names = tuple(s for s in names if s not in set(exclude))
    if not names:
        raise ValueError(f"no training scene left once {list(exclude)} are excluded")
    if aligned and any(8 % v for v in views):
        raise ValueError(f"DL-5D needs views dividing the 8-pixel patch, got {tuple(views)}")
    return _trained_dictionary(names, tuple(shape), tuple(views), int(n_bands), seed, bool(aligned))


@lru_cache(maxsize=8)
def _trained_dictionary(names, shape, views, n_bands, seed, aligned=False):
    from ..solvers.dictionary import train_dictionary
    from .problems import make_problem

    cubes = [
        make_problem("c3slfi", s, shape=tuple(shape), n_bands=n_bands, rng=seed, n_snapshots=2,
                     views=tuple(views)).cube
        for s in names
    ]  # fmt: skip
    return train_dictionary(cubes, patch=8, n_patches=3000, n_iter=4, rng=seed,
                            align=tuple(views) if aligned else 1)  # fmt: skip


def c3slfi_table_run(
    scene, n_snapshots, snr_db, method, form, *, shape=(128, 128), views=(4, 4), n_bands=31,
    seed=0, dtype="float64", **options,
) -> dict:  # fmt: skip
    """One cell of :func:`c3slfi_table`: C3SLFI with ``n_snapshots`` complementary colour-coded
    snapshots imaging ``scene``, reconstructed by ``method`` on the 3-D lenslet form
    (``form="3d"``) or the 5-D light field (``"5d"``) from a measurement in ``dtype``; scored
    on the 3-D cube."""
    from ..solvers import reconstruct
    from .problems import make_problem, score

    if form not in ("3d", "5d"):
        raise ValueError(f"form must be '3d' or '5d', got {form!r}")
    if method == "lytro" and form != "3d":
        raise ValueError("the Lytro-CASSI baseline images the 3-D lenslet cube: use form='3d'")
    dtype = precision("dtype", dtype)
    p = make_problem(
        "lytro_cassi" if method == "lytro" else "c3slfi", scene, shape=tuple(shape),
        n_bands=n_bands, snr_db=snr_db, rng=seed, n_snapshots=n_snapshots, views=tuple(views),
    )  # fmt: skip
    system, g = p.system, np.asarray(p.measurement, dtype=dtype)
    if method in ("dl", "dl5"):  # DL-3D / DL-5D: K-SVD dictionaries from other scenes
        if form != "3d":
            raise ValueError("the DL baselines code lenslet patches: use form='3d'")
        options.setdefault(
            "dictionary",
            c3slfi_dictionary(
                tuple(shape), tuple(views), n_bands, exclude=(scene,), aligned=method == "dl5"
            ),
        )
        method = "dl"
    if form == "5d":
        system, g = p.system.as_5d(), p.system.measurement_to_5d(g)
    t0 = time.perf_counter()
    res = reconstruct(system, g, method, **options)
    seconds = time.perf_counter() - t0
    cube = p.system.to_3d(res.cube) if form == "5d" else res.cube
    return {**score(p, cube), "ratio": n_snapshots / n_bands, "seconds": seconds}


def c3slfi_table(
    scenes=("cave.face",), snapshots=(2, 3), snrs=(15.0, 20.0, 50.0), methods=("otd", "wdct"),
    forms=("3d", "5d"), *, shape=(128, 128), views=(4, 4), n_bands=31, seeds=(0,),
    dtype="float64", client=None, progress=True, **options,
) -> list[dict]:  # fmt: skip
    """The thesis' Table 1 (Section 5.3.2): C3SLFI reconstruction quality over the compression
    ratio ``C = K / N3`` (snapshots per band), the SNR, the method and the 3-D or 5-D
    parameterisation.

    The thesis uses 100-band spectral light fields at ``C`` = 5 % and 9 %
    (K = 5, 9); here ``n_bands`` (default 31) with K = 2, 3 gives
    6.5 % and 9.7 %.  ``options`` go to every method.  ``"dl"`` (DL-3D, the
    3-D form only) trains its K-SVD dictionary on other scenes with
    :func:`c3slfi_dictionary` unless ``dictionary=`` is given; ``"dl5"``
    (DL-5D) the same with whole-lenslet patches (``aligned=True``: scene
    points × every view × every band).  ``"lytro"``
    is the thesis' Lytro-CASSI baseline: the same lenslet cube seen by
    :class:`~tensor_cosdi.systems.LytroCASSI` (an RGB arm plus ``K`` CASSI
    snapshots, so three more frames than C3SLFI's ``K``), reconstructed with
    a dictionary learned from its own RGB arm (3-D form only).

    Parameters
    ----------
    scenes : sequence of str
        Names of :data:`tensor_cosdi.scenes.SCENES` (the centre view; the
        other views are shifted by a disparity map).  Judge on real spectra
        (``"cave.<name>"``): photo-derived spectra favour learned spectral
        bases.
    snapshots, snrs, methods, forms
        The grid: K, SNR in dB, reconstruction methods, ``"3d"`` / ``"5d"``.
    shape, views, n_bands, seeds, client, progress
        Lenslet image size, views per lenslet, bands; seeds of codes and
        noise; as for :func:`~tensor_cosdi.studies.sweep`.
    dtype : {"float64", "float32"}
        The precision the measurements reach the reconstructions in (the solvers keep it).

    Returns
    -------
    list of dict
        One record per grid cell: ``scene``, ``n_snapshots``, ``snr_db``,
        ``method``, ``form``, ``seed``, ``ratio`` (``K / N3``), ``psnr``,
        ``ssim``, ``sam``, ``rmse``, ``seconds``.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.c3slfi_table(("colorchecker",), (2,), (30.0,), ("wdct",), ("3d", "5d"),
    ...                             shape=(16, 16), views=(2, 2), n_bands=6, progress=False,
    ...                             max_iter=3)
    >>> [(r["form"], round(r["ratio"], 3)) for r in recs]
    [('3d', 0.333), ('5d', 0.333)]
    """
    from .sweeping import seed_list, sweep

    bad = [f for f in forms if f not in ("3d", "5d")]
    if bad:
        raise ValueError(f"forms must be '3d' or '5d', got {bad}")
    if any(int(k) < 1 or int(k) > n_bands for k in snapshots):
        raise ValueError(f"snapshots must lie in 1…n_bands = {n_bands}, got {list(snapshots)}")
    grid = {
        "scene": list(scenes), "n_snapshots": [int(k) for k in snapshots],
        "snr_db": [float(s) for s in snrs], "method": list(methods), "form": list(forms),
        "seed": seed_list(seeds),
    }  # fmt: skip
    run = partial(
        c3slfi_table_run, shape=tuple(shape), views=tuple(views), n_bands=n_bands,
        dtype=str(precision("dtype", dtype)), **options,
    )  # fmt: skip
    return sweep(grid, run, client=client, progress=progress)
