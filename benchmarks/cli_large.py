"""The real-capture size through the command line: a 660×714 SD-CASSI measurement, start to file.

Published real CASSI captures are 660×714 with a 660×660 mask (28 bands,
2 px per band).  This builds such a pair of ``.mat`` files from a seeded
scene — a tuning scene of ``hsi_train`` (``--scene``, 256×256) upsampled
to 660×660 by linear interpolation, a seeded random binary mask, 30 dB
Gaussian noise — and times the whole command a user would run::

    tensor-cosdi reconstruct --system sd_cassi --mask mask.mat:mask --shift 2 --bands 28 \\
        --wavelengths 453:648 --measurement meas.mat:meas --out cube.h5 --quiet

in a fresh process (interpreter start, imports, reading, OTD, writing the
HDF5 bundle), ``--repeats`` times, and reports the median seconds, the
output's size and the PSNR of the written cube (data range 1).  Target
(issue "real data"): ≤ 60 s on 2 cores.

    python benchmarks/cli_large.py [--repeats 3] [--method otd] [--scene balloons]

Appends a line to ``benchmarks/results/cli_large.md``.  Never asserts anything.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def make_files(folder: Path, scene: str, size: int = 660):
    import scipy.io
    from scipy.ndimage import zoom

    import tensor_cosdi as tc
    from tensor_cosdi import datasets

    cube, wl = datasets.load_hsi(scene, "kaist", dtype="float32")
    cube = zoom(cube, (size / cube.shape[0], size / cube.shape[1], 1), order=1)
    cube = np.clip(cube, 0, None).astype(np.float32)
    mask = tc.codes.random_binary((size, size), rng=0).astype(np.float32)
    system = tc.systems.SDCASSI(mask, n_bands=28, shifts=2, wavelengths=wl)
    g = np.asarray(system.simulate(cube, snr_db=30, rng=0), dtype=np.float32)
    scipy.io.savemat(folder / "mask.mat", {"mask": mask})
    scipy.io.savemat(folder / "meas.mat", {"meas": g})
    return cube, g.shape


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--method", default="otd")
    ap.add_argument("--scene", default="balloons")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    from tensor_cosdi import metrics
    from tensor_cosdi.io import load_bundle

    exe = shutil.which("tensor-cosdi") or str(Path(sys.executable).with_name("tensor-cosdi"))
    times, sizes, psnrs = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        truth, gshape = make_files(d, args.scene)
        for r in range(args.repeats):
            out = d / f"cube{r}.h5"
            cmd = [
                exe, "reconstruct", "--system", "sd_cassi", "--mask", f"{d / 'mask.mat'}:mask",
                "--shift", "2", "--bands", "28", "--wavelengths", "453:648",
                "--measurement", f"{d / 'meas.mat'}:meas", "--method", args.method,
                "--out", str(out), "--quiet",
            ]  # fmt: skip
            t = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t)
            sizes.append(out.stat().st_size / 1e6)
            psnrs.append(metrics.psnr(truth, load_bundle(out).cube, data_range=1.0))
            print(f"run {r + 1}: {times[-1]:.1f} s, {sizes[-1]:.1f} MB, {psnrs[-1]:.2f} dB")
    line = (
        f"| {time.strftime('%Y-%m-%d')} | {platform.node()[:12]} | {args.method} | "
        f"{args.scene} 660×660×28 → {gshape[0]}×{gshape[1]}, 30 dB | "
        f"{statistics.median(times):.1f} s (of {len(times)}) | {np.median(sizes):.1f} MB | "
        f"{np.median(psnrs):.2f} dB |"
    )
    print(line)
    res = Path(args.out) / "cli_large.md"
    if not res.exists():
        res.parent.mkdir(parents=True, exist_ok=True)
        res.write_text(
            "| date | machine | method | input | median start-to-file | output | PSNR |\n"
            "|---|---|---|---|---|---|---|\n"
        )
    with open(res, "a") as f:
        f.write(line + "\n")


if __name__ == "__main__":
    main()
