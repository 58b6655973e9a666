"""Tiled against untiled OTD on a large SD-CASSI capture: PSNR, seconds and peak memory.

An N×N×28 cube (``--size``, default 1024: a tuning scene upsampled by
linear interpolation), a seeded random binary code, 2 px per band, 30 dB.
``tensor_cosdi.reconstruct`` with OTD against
``tensor_cosdi.reconstruct_tiled`` (``--tile``, ``--overlap``), both in
this process with ``tracemalloc`` tracing the peak (serial tiles, so the
peak is comparable; ``--dask N`` adds a run on a local cluster of N worker
processes, timed only).  Target (issue "real data"): tiled within 0.3 dB of
untiled, with less peak memory.

    python benchmarks/tiled.py [--size 1024] [--tile 256] [--overlap 128] [--dask 2]

Appends to ``benchmarks/results/tiled.md``.  Never asserts anything.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from pathlib import Path

import numpy as np
from _results import append

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--tile", type=int, default=256)
    ap.add_argument("--overlap", type=int, default=128)
    ap.add_argument("--scene", default="balloons")
    ap.add_argument("--dask", type=int, default=0, help="also run on N local worker processes")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    from scipy.ndimage import zoom

    import tensor_cosdi as tc
    from tensor_cosdi import datasets, metrics

    n = args.size
    cube, wl = datasets.load_hsi(args.scene, "kaist", dtype="float32")
    cube = np.clip(zoom(cube, (n / 256, n / 256, 1), order=1), 0, None).astype(np.float32)
    system = tc.systems.SDCASSI(
        tc.codes.random_binary((n, n), rng=0), n_bands=28, shifts=2, wavelengths=wl
    )
    g = np.asarray(system.simulate(cube, snr_db=30, rng=0), dtype=np.float32)
    small = tc.systems.SDCASSI(tc.codes.random_binary((32, 32), rng=0), n_bands=28, shifts=2)
    tc.reconstruct(small, small.simulate(np.ones((32, 32, 28)), snr_db=30, rng=0))  # imports
    cube_mib = cube.nbytes / 2**20
    rows = []
    runs = [
        ("untiled", lambda: tc.reconstruct(system, g, "otd")),
        (
            f"tiled {args.tile}/{args.overlap}",
            lambda: tc.reconstruct_tiled(system, g, "otd", tile=args.tile, overlap=args.overlap),
        ),
    ]
    for name, run in runs:
        tracemalloc.start()
        t = time.perf_counter()
        res = run()
        dt = time.perf_counter() - t
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        p = metrics.psnr(cube, res.cube, data_range=1.0)
        mem = f"{peak:.0f} MiB = {peak / cube_mib:.1f} cubes"
        rows.append(f"| {name} | {p:.2f} | {dt:.1f} | {mem} |")
        print(rows[-1], flush=True)
    if args.dask:
        from distributed import Client

        with Client(n_workers=args.dask, threads_per_worker=1) as client:
            t = time.perf_counter()
            res = tc.reconstruct_tiled(
                system, g, "otd", tile=args.tile, overlap=args.overlap, client=client
            )
            dt = time.perf_counter() - t
        p = metrics.psnr(cube, res.cube, data_range=1.0)
        rows.append(f"| tiled on {args.dask} Dask workers | {p:.2f} | {dt:.1f} | (workers) |")
        print(rows[-1], flush=True)
    text = (
        f"\n{time.strftime('%Y-%m-%d')}: SD-CASSI {n}×{n}×28, {args.scene} upsampled, random "
        "code, 30 dB, 2 cores\n\n| run | PSNR dB | s | peak traced memory |\n|---|---|---|---|\n"
        + "\n".join(rows)
        + "\n"
    )
    append(args.out, "tiled.md", text)


if __name__ == "__main__":
    main()
