"""Simulation studies: a seeded (system, scene, measurement) problem for every imager, and
comparisons.

:func:`make_problem` builds what the demo, the benchmarks and the quality
tests share: one of the five imagers (or a CASSI baseline) with seeded codes,
a scene of :mod:`tensor_cosdi.scenes` shaped for it, and a noisy measurement.
:func:`compare` runs reconstruction methods on a problem and scores them.
"""

from __future__ import annotations

import csv
import itertools
import numbers
import time
from pathlib import Path

import numpy as np

from . import metrics, scenes
from . import systems as S
from .systems import Problem

__all__ = [
    "SYSTEMS",
    "SCENES",
    "Problem",
    "make_problem",
    "compare",
    "score",
    "score_depth",
    "spectral_view",
    "sweep",
    "local_client",
    "conditioning",
    "conditioning_design",
    "vsi_arms",
    "prism_grid",
    "colour_code_design",
    "zernike_design",
    "c3slfi_table",
    "reconstruction_run",
    "write_csv",
]

SYSTEMS = S.REGISTRY
"""The systems :func:`make_problem` accepts: :data:`tensor_cosdi.systems.REGISTRY` (a read-only
mapping)."""

SCENES = scenes.SCENES
"""The scenes :func:`make_problem` accepts: :data:`tensor_cosdi.scenes.SCENES`."""

_RENAMED = {"dual_camera": "dual_camera_cassi"}

from ._dask import local_client  # noqa: E402 - the local cluster of sweep('local')
from ._studies_conditioning import conditioning_design, vsi_arms  # noqa: E402 - design κ
from ._studies_design import c3slfi_table, colour_code_design  # noqa: E402 - design studies
from ._studies_optics import zernike_design  # noqa: E402 - DFA aberration design (Sec. 4.3)
from .optics.design import prism_grid  # noqa: E402 - the prism design study (thesis App. B)


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
        from .noise import check_snr_db

        snr_db = check_snr_db(snr_db)
    return cls.example_problem(
        scene, shape=shape, n_bands=n_bands, snr_db=snr_db, rng=rng, shifts=shifts, **options
    )


def score(problem: Problem, cube) -> dict:
    """PSNR, SSIM (data range = the truth's peak), SAM (degrees) and RMSE of ``cube`` against the
    truth.

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
    """How well a result's depth channel (``Result.depth``) matches the problem's truth; ``{}`` if
    neither has one.

    * depth planes (CASSDI-DFA): ``"planes_right"``, the fraction of pixels on the right plane;
    * disparity (C3SLFI): ``"disparity_mae"``, mean absolute error (px per view step);
    * fringe phase (CS2LI / Mu-CoSDI): ``"phase_mae"``, mean absolute wrapped-phase error (rad)
      of the first frequency.
    """
    return problem.system.score_depth(depth, problem)


def compare(
    problem: Problem, methods=("otd", "gap_tv"), options=None, *, progress: bool = False
) -> list[dict]:
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
    from .solvers import METHODS

    return METHODS[method].defaults


def spectral_view(problem: Problem, cube) -> np.ndarray:
    """An ``(Nx, Ny, Nλ)`` reflectance-like view of a cube of ``problem.system`` (for sRGB
    previews).

    C3SLFI: the centre view of the light field; CASSDI-DFA: the sum over
    depth planes (all-in-focus); CS2LI / Mu-CoSDI: the mean over the phase
    steps divided by the fringe offset (the reflectance, Eq. 107); other
    systems: the cube itself (``problem.system.spectral_view``).
    """
    return problem.system.spectral_view(cube)


def _call(run, params):
    out = run(**params)
    if not isinstance(out, dict):
        raise TypeError(f"run(**{params}) must return a dict of results, got {type(out).__name__}")
    clash = sorted(set(out) & set(params))
    if clash:
        raise ValueError(f"run's results {clash} would overwrite the parameters of the same name")
    return {**params, **out}


def sweep(grid: dict, run, *, client=None, progress: bool = True) -> list[dict]:
    """Run ``run(**params)`` for every combination of ``grid``; one record per combination.

    Parameters
    ----------
    grid : dict of name → sequence
        The parameter grid (e.g. systems × scenes × SNR × methods × design
        parameters); the records come back in ``itertools.product`` order.
    run : callable
        ``run(**params) -> dict`` of results (PSNR, seconds, …); picklable
        (a module-level function) when a Dask cluster runs it.
        :func:`reconstruction_run` is one for the usual study.
    client : None, ``"local"``, a scheduler address or a ``dask.distributed.Client``
        ``None`` runs serially here; ``"local"`` starts a local cluster for the
        sweep (:func:`local_client`, closed after it); an address
        (``"tcp://host:8786"``) connects to a running scheduler; a client is used
        as is.  Needs the ``.[dask]`` extra.
    progress : bool
        A tqdm bar (serial) or Dask's progress bar.

    Returns
    -------
    list of dict — the parameters and the results of each combination, ready
    for :func:`write_csv` (or ``pandas.DataFrame``).
    """
    if not isinstance(grid, dict) or not grid:
        raise ValueError("grid must be a non-empty dict of name → sequence of values")
    for k, v in grid.items():
        if isinstance(v, (str, bytes)) or not hasattr(v, "__iter__"):
            raise ValueError(f"grid[{k!r}] must be a sequence of values, got {v!r}")
    if not callable(run):
        raise ValueError(f"run must be callable, got {run!r}")
    keys = list(grid)
    combos = [dict(zip(keys, vals)) for vals in itertools.product(*(list(grid[k]) for k in keys))]
    if client is None:
        from tqdm import tqdm

        return [_call(run, c) for c in tqdm(combos, desc="sweep", disable=not progress)]
    try:
        from dask.distributed import Client
        from dask.distributed import progress as dask_progress
    except ImportError:
        raise ImportError(
            "a Dask sweep needs the dask extra: pip install 'tensor_cosdi[dask]'"
        ) from None
    def gather(client):
        futures = client.map(_call, [run] * len(combos), combos, pure=False)
        if progress:
            dask_progress(futures)
        return client.gather(futures)

    if client == "local":
        with local_client() as own:
            return gather(own)
    if isinstance(client, str):
        with Client(client) as own:
            return gather(own)
    return gather(client)


def reconstruction_run(
    system, scene="chelsea", method="otd", snr_db=30.0, shape=(64, 64), n_bands=8, seed=0, **options
) -> dict:
    """One study cell for :func:`sweep`: :func:`make_problem` then :func:`tensor_cosdi.reconstruct`
    with ``options``; returns PSNR / SSIM / SAM (and depth error where the system has depth),
    seconds and iterations."""
    from .solvers import reconstruct

    p = make_problem(system, scene, shape=tuple(shape), n_bands=n_bands, snr_db=snr_db, rng=seed)
    t0 = time.perf_counter()
    res = reconstruct(p.system, p.measurement, method, **options)
    seconds = time.perf_counter() - t0
    out = {**score(p, res.cube), "seconds": seconds, "iterations": res.iterations}
    if p.depth is not None and res.depth is not None:
        out.update({f"depth_{k}": v for k, v in score_depth(p, res.depth).items()})
    return out


def write_csv(records, path, *, overwrite: bool = False) -> Path:
    """Write :func:`sweep` records as CSV (columns: the union of keys, in first-seen order),
    atomically; an existing file only with ``overwrite=True``."""
    from .io._atomic import atomic_write

    records = list(records)
    if not records:
        raise ValueError("no records to write")
    cols = list(dict.fromkeys(k for r in records for k in r))

    def write(tmp):
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=cols)
            w.writeheader()
            for r in records:
                w.writerow({k: r.get(k, "") for k in cols})

    return atomic_write(path, write, overwrite=overwrite)


def _gram_eigenvalues(gram):
    """All eigenvalues of ``A Aᵀ`` and Gershgorin (lower, upper) bounds from its structure."""
    kind = gram.kind
    if kind == "diagonal":
        d = np.asarray(gram.d, dtype=np.float64).ravel()
        return d, (float(d.min()), float(d.max()))
    if kind == "pixel_blocks":
        q = np.asarray(gram.Q, dtype=np.float64)
        q = q.reshape(-1, *q.shape[-2:])
        ev = np.linalg.eigvalsh(q).ravel()
        centre = np.diagonal(q, axis1=1, axis2=2)
        radius = np.abs(q).sum(axis=2) - np.abs(centre)
        return ev, (float((centre - radius).min()), float((centre + radius).max()))
    if kind == "row_banded":
        import scipy.linalg

        b = gram.bandwidth
        evs, lo, hi = [], np.inf, -np.inf
        for ab in gram.upper_form():
            diag, radius = ab[b], np.zeros(ab.shape[1])
            for o in range(1, b + 1):  # off-diagonal o: ab[b − o, o:] couples p and p + o
                off = np.abs(ab[b - o, o:])
                radius[:-o] += off
                radius[o:] += off
            evs.append(scipy.linalg.eig_banded(ab, eigvals_only=True))
            lo, hi = min(lo, float((diag - radius).min())), max(hi, float((diag + radius).max()))
        return np.concatenate(evs), (lo, hi)
    raise ValueError(f"unknown structure {kind!r}")  # pragma: no cover


def conditioning(system, *, exact_below: int = 4096, tol: float = 1e-8) -> dict:
    """How well posed the system's Woodbury inner matrix ``A Aᵀ`` is (SPEC §4).

    Returns ``lambda_min``, ``lambda_max`` (extreme eigenvalues of ``A Aᵀ``,
    i.e. squared extreme singular values of ``A``), ``cond`` =
    ``lambda_max / lambda_min`` (``inf`` when singular), ``zero`` (how many
    eigenvalues are below ``tol · lambda_max``: measurement entries no
    voxel reaches), ``lambda_min_nonzero`` and ``cond_nonzero`` (the same on
    the rest; Lanczos gives only the extremes, so there they equal the
    plain ones unless the smallest is zero), Gershgorin bounds ``gershgorin_min`` /
    ``gershgorin_max``, the ``structure`` of ``A Aᵀ`` and the ``method``
    used: ``"structure"`` (exact, from the diagonal / per-pixel blocks /
    banded rows the library derives), ``"dense"`` (exact, for at most
    ``exact_below`` measurements) or ``"lanczos"`` (SciPy ``eigsh`` through
    :meth:`~tensor_cosdi.operators.TensorOperator.aslinearoperator`).
    """
    op = system.operator
    gram = op.gram_dual()
    m = int(np.prod(op.output_shape))
    out = {"structure": None if gram is None else gram.kind, "size": m}
    if gram is not None:
        ev, (glo, ghi) = _gram_eigenvalues(gram)
        method = "structure"
    elif m <= exact_below:
        M = op.to_matrix()
        G = (M @ M.T).toarray()
        ev = np.linalg.eigvalsh(G)
        radius = np.abs(G).sum(axis=1) - np.abs(np.diag(G))
        glo, ghi = float((np.diag(G) - radius).min()), float((np.diag(G) + radius).max())
        method = "dense"
    else:
        from scipy.sparse.linalg import LinearOperator, eigsh

        A = op.aslinearoperator()
        AAt = LinearOperator((m, m), matvec=lambda y: A.matvec(A.rmatvec(y)), dtype=np.float64)
        ncv = min(m, 40)
        # full precision (tol 0): a loose tolerance stops "SA" far above a clustered minimum
        hi = float(eigsh(AAt, k=1, which="LA", return_eigenvectors=False, ncv=ncv)[0])
        lo = float(eigsh(AAt, k=1, which="SA", return_eigenvectors=False, ncv=ncv,
                         maxiter=100 * m)[0])  # fmt: skip
        ev = np.array([lo, hi])
        glo, ghi = float("nan"), float("nan")
        method = "lanczos"
    lmax = float(ev.max())
    zero = int((ev <= tol * lmax).sum())
    lmin = float(ev.min())
    nonzero = ev[ev > tol * lmax]
    lnz = float(nonzero.min()) if nonzero.size else float("nan")
    out.update(
        lambda_min=lmin,
        lambda_max=lmax,
        cond=float("inf") if lmin <= tol * lmax else lmax / lmin,
        lambda_min_nonzero=lnz,
        cond_nonzero=lmax / lnz,
        zero=zero,
        gershgorin_min=glo,
        gershgorin_max=ghi,
        method=method,
    )
    return out
