"""Tiled reconstruction of large CASSI captures: tiles cut with the dispersion's overlap,
reconstructed independently (serially or on a Dask cluster) and blended.

A tile's sub-problem is the same imager on a window of the code: for
SD-CASSI the cube window ``[x0, x1) × [y0, y1)`` lands on measurement
columns ``[y0, y1 + S)`` (``S`` the total shear), whose first and last ``S``
columns also hold light from outside the window — those cube columns are
kept out of the blend; for DD-CASSI the window is exact.  Every tile is
grown by ``overlap`` pixels (plus ``S`` across the shear) on its inner
sides, and the estimates are blended with weights that ramp from 0 to 1
across the overlap.
"""

from __future__ import annotations

import time

import numpy as np

from .. import _backend as B
from ..bases import block_sizes
from ..validate import flag
from ._base import Result, check_call, reconstruct

__all__ = ["reconstruct_tiled", "TILED_SYSTEMS"]

#: Imagers :func:`reconstruct_tiled` can cut into tiles: those whose class has ``window``.
TILED_SYSTEMS = ("sd_cassi", "dd_cassi")


def _solve_tile(system, g, method, options):
    res = reconstruct(system, g, method, **options)
    return np.asarray(B.to_numpy(res.cube), dtype=g.dtype)


def _ramp(n, lo_margin, hi_margin, lo_dead=0, hi_dead=0):
    """Blend weights along one axis of an extended tile: 0 on ``dead`` pixels at an inner edge,
    a linear rise across the rest of the margin, 1 in the core."""
    w = np.ones(n)
    for margin, dead, side in ((lo_margin, lo_dead, 1), (hi_margin, hi_dead, -1)):
        if margin == 0:
            continue
        rise = np.zeros(margin)
        k = margin - dead
        rise[dead:] = (np.arange(k) + 1) / (k + 1)
        if side == 1:
            w[:margin] = rise
        else:
            w[n - margin :] = rise[::-1]
    return w


def reconstruct_tiled(
    system,
    measurement,
    method: str = "otd",
    *,
    tile: int = 256,
    overlap: int = 128,
    client=None,
    progress: bool = False,
    **options,
) -> Result:
    """Reconstruct a large SD-CASSI or DD-CASSI capture tile by tile.

    Parameters
    ----------
    system : SDCASSI or DDCASSI (:data:`TILED_SYSTEMS`)
    measurement : tensor of ``system.measurement_shape``, or a dask array
        A dask array stays lazy: each tile's window of it is computed when
        that tile is solved (serially, one window in memory at a time; with
        ``client``, as the tiles are sent), so a capture larger than memory
        can be read from a chunked store (``dask.array.from_zarr``).  The
        cube comes back as a NumPy array.
    method : str
        Any registered method (:func:`tensor_cosdi.reconstruct`), run on each tile with
        ``options``.
    tile : int
        Largest core of a tile in pixels along each spatial axis (the axes
        are cut into near-equal runs of at most ``tile``).
    overlap : int
        Pixels each tile is grown by on its inner sides (SD-CASSI: plus the
        shear ``S`` across columns), blended with ramped weights.  On a
        256×256×28 SD-CASSI tuning scene (balloons, random code, 30 dB,
        OTD 29.59 dB untiled) tiles of 128 gave 28.90 dB with 16, 28.59
        with 32 and 29.75 with 64: the light of the shear's edge columns
        comes from outside the tile, and OTD's bases carry that error
        inward.  At 1024×1024×28 (upsampled, 30 dB; untiled OTD 34.87 dB)
        tiles of 256 gave 33.77 dB with 64 and 34.72 dB with 128 — the
        default.
    client : dask.distributed.Client, optional
        Reconstruct the tiles on this cluster (``client.map``); ``None``: one
        after the other in this process.  On one machine,
        :func:`tensor_cosdi.studies.local_client` starts a suitable cluster.
    progress : bool
        A progress bar over tiles (serial runs).

    Returns
    -------
    Result
        ``cube`` on the measurement's backend; ``history`` holds per tile
        ``"tiles"`` (``(x0, x1, y0, y1)`` of each core); ``options`` the
        method's and the tiling's.

    Examples
    --------
    >>> import tensor_cosdi as tc
    >>> p = tc.studies.make_problem("sd_cassi", "coffee", shape=(48, 48), n_bands=8)
    >>> res = tc.reconstruct_tiled(p.system, p.measurement, "gap_tv", tile=24, overlap=8)
    >>> res.cube.shape, len(res.history["tiles"])
    ((48, 48, 8), 4)
    """
    from .engine import check_int

    if not callable(getattr(system, "window", None)):
        raise ValueError(
            f"reconstruct_tiled supports {TILED_SYSTEMS}, got {getattr(system, 'name', system)!r}"
        )
    tile, overlap = check_int("tile", tile, 8), check_int("overlap", overlap, 0)
    progress = flag("progress", progress)
    # the method and its options are checked here, once, not by every tile (on a cluster, after
    # every sub-problem was built and sent)
    check_call(system, method, options)
    if client is not None and not all(
        callable(getattr(client, a, None)) for a in ("scatter", "map", "submit")
    ):
        raise ValueError(
            f"client must be a dask.distributed.Client (tensor_cosdi.studies.local_client() "
            f"starts one on this machine) or None, got {client!r}"
        )
    t0 = time.perf_counter()
    lazy = hasattr(measurement, "__dask_graph__")
    # a dask array stays lazy: each tile's window is computed when its tile is solved
    g = measurement if lazy else np.asarray(B.to_numpy(measurement))
    if np.dtype(g.dtype).kind not in "iuf":  # complex, text, objects, booleans: not a capture
        raise ValueError(f"measurement must hold real numbers, got dtype {g.dtype}")
    if np.dtype(g.dtype) not in (np.float32, np.float64):  # raw counts: blend in float64
        g = g.astype(np.float64)
    if tuple(g.shape) != tuple(system.measurement_shape):
        raise ValueError(
            f"measurement has shape {g.shape}; {system.name} expects {system.measurement_shape}"
        )
    if not lazy and not B.all_finite(g):  # (a lazy window is checked by its tile's reconstruct)
        bad = g.size - int(np.count_nonzero(np.isfinite(g)))
        raise ValueError(
            f"reconstruct_tiled: the measurement holds {bad} NaN or infinite values; "
            "expected finite numbers"
        )
    nx, ny, nl = system.cube_shape
    s = system.window_spill
    places = []  # (extended window, core) of each tile, in tile order
    xs, ys = np.cumsum([0] + block_sizes(nx, tile)), np.cumsum([0] + block_sizes(ny, tile))
    for a0, a1 in zip(xs[:-1], xs[1:]):
        for b0, b1 in zip(ys[:-1], ys[1:]):
            x0, x1 = max(0, a0 - overlap), min(nx, a1 + overlap)
            y0, y1 = max(0, b0 - overlap - s), min(ny, b1 + overlap + s)
            places.append(((x0, x1, y0, y1), (a0, a1, b0, b1)))

    def job(i):  # built when needed: sixteen sub-systems at once cost a cube of memory
        x0, x1, y0, y1 = places[i][0]
        sub, (m0, m1) = system.window(x0, x1, y0, y1)
        return sub, np.asarray(g[x0:x1, m0:m1])  # (a dask window: computed here, alone)

    if client is None:
        from tqdm import tqdm

        results = (
            (i, _solve_tile(*job(i), method, options))
            for i in tqdm(range(len(places)), desc="tiles", disable=not progress)
        )
    else:  # blended as they arrive: never every tile in memory at once
        from distributed import as_completed

        subs = [job(i) for i in range(len(places))]
        # scattered first: sub-systems and sub-measurements travel as data, not inside the graph
        systems, parts = client.scatter([j[0] for j in subs]), client.scatter([j[1] for j in subs])
        del subs
        futures = client.map(
            _solve_tile, systems, parts, method=method, options=options, pure=False
        )
        index = {f.key: i for i, f in enumerate(futures)}
        results = ((index[f.key], c) for f, c in as_completed(futures, with_results=True))
    # one cube-sized array in the measurement's dtype: the weighted sum, divided in place
    dtype = np.dtype(g.dtype)
    out, wsum = np.zeros((nx, ny, nl), dtype), np.zeros((nx, ny), dtype)
    for i, cube in results:
        (x0, x1, y0, y1), (a0, a1, b0, b1) = places[i]
        wx = _ramp(x1 - x0, a0 - x0, x1 - a1)
        wy = _ramp(y1 - y0, b0 - y0, y1 - b1, min(s, b0 - y0), min(s, y1 - b1))
        w = np.outer(wx, wy).astype(dtype)
        if cube.flags.writeable:  # (arrays from worker processes may arrive read-only)
            cube *= w[:, :, None]
        else:
            cube = cube * w[:, :, None]
        out[x0:x1, y0:y1] += cube
        wsum[x0:x1, y0:y1] += w
        del cube
    out /= wsum[:, :, None]
    if not isinstance(measurement, np.ndarray) and not lazy:
        out = B.tensor_like(out, measurement)
    return Result(
        cube=out,
        history={"tiles": [p[1] for p in places]},
        seconds=time.perf_counter() - t0,
        options={**options, "tile": tile, "overlap": overlap},
        method=f"{method} (tiled)",
        system=system,
    )
