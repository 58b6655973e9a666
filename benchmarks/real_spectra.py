"""Reconstruction on real hyperspectral scenes: the standard 256×256×28 SD-CASSI protocol.

Protocol: CAVE scenes of ``../shared/data/hsi_train`` (2×2-averaged to
256×256) resampled onto the 28 KAIST band centres (453–648 nm, linear
interpolation), SD-CASSI with the real TSA 256×256 mask and 2 px per band
(measurement 256×310), noiseless and at 30 dB, float32, PSNR over the cube
with data range 1 (mean of the per-band PSNRs), SSIM per band, SAM in degrees.

Scenes: the held-back :data:`tensor_cosdi.datasets.REPORT_SCENES` by default
(``--split tune`` for the scenes defaults may be tuned on — never report those).
Methods: any registered method, plus ``plain_gap_tv``, a reference written
here in a few lines (accelerated GAP, ``x ← TV(x + Aᵀ((ĝ − A x) / Φsum))``,
scikit-image's Chambolle TV (10 inner iterations) with weight 0.2 in reflectance units, 80
iterations) — the baseline this library must beat.

Every run is appended to ``<out>/<name>.json`` as it finishes and skipped
when the file already holds it (a killed run resumes); the Markdown table
``<out>/<name>.md`` holds means over scenes and median seconds.

    python benchmarks/real_spectra.py [--methods plain_gap_tv,gap_tv,otd] [--snr none,30]
        [--split report|tune] [--scenes a,b] [--name real_spectra] [--out benchmarks/results]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets, metrics

ROOT = Path(__file__).resolve().parents[1]
MASK = ROOT / ".." / "shared" / "data" / "masks" / "tsa_mask256.mat"


def plain_gap_tv(system, g, *, iters=80, weight=0.2, tv_iter=10):
    """The reference: accelerated GAP-TV in a few lines (Φsum = A Aᵀ's diagonal)."""
    from skimage.restoration import denoise_tv_chambolle

    op = system.operator
    phisum = np.asarray(op.gram_dual().d, dtype=g.dtype)
    phisum = np.where(phisum == 0, 1, phisum)
    x = op.adjoint(g / phisum)
    y1 = np.zeros_like(g)
    for _ in range(iters):
        ax = op.forward(x)
        y1 = y1 + (g - ax)
        x = x + op.adjoint((y1 - ax) / phisum)
        x = denoise_tv_chambolle(x, weight=weight, max_num_iter=tv_iter, channel_axis=-1)
    return x


def problem(scene, snr, mask, seed=0):
    cube, wl = datasets.load_hsi(scene, "kaist", dtype="float32")
    system = tc.systems.SDCASSI(mask, n_bands=28, shifts=2, wavelengths=wl)
    g = system.simulate(cube, snr_db=snr, rng=seed)
    return system, cube, np.asarray(g, dtype=np.float32)


def score(truth, est):
    est = np.asarray(est, dtype=np.float64)
    truth = np.asarray(truth, dtype=np.float64)
    return {
        "psnr": metrics.psnr(truth, est, data_range=1.0),
        "ssim": metrics.ssim(truth, est, data_range=1.0),
        "sam": metrics.sam(truth, est),
    }


def run(method, system, g, options):
    t0 = time.perf_counter()
    if method == "plain_gap_tv":
        cube = plain_gap_tv(system, g, **options)
    else:
        cube = tc.reconstruct(system, g, method, **options).cube
    return cube, time.perf_counter() - t0


def summarise(runs, methods, snrs):
    lines = [
        "| SNR | method | PSNR dB | SSIM | SAM ° | median s | scenes |",
        "|---|---|---|---|---|---|---|",
    ]
    for snr in snrs:
        for m in methods:
            rs = [r for r in runs if r["method"] == m and r["snr_db"] == snr]
            if not rs:
                continue
            lines.append(
                f"| {'noiseless' if snr is None else f'{snr:g} dB'} | {m} | "
                f"{np.mean([r['psnr'] for r in rs]):.2f} | "
                f"{np.mean([r['ssim'] for r in rs]):.3f} | "
                f"{np.mean([r['sam'] for r in rs]):.2f} | "
                f"{np.median([r['seconds'] for r in rs]):.2f} | "
                f"{len(rs)} |"
            )
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default="plain_gap_tv,gap_tv,otd")
    ap.add_argument("--snr", default="none,30", help="comma list; 'none' = noiseless")
    ap.add_argument("--split", choices=("report", "tune"), default="report")
    ap.add_argument("--scenes", default=None, help="override the split's scenes")
    ap.add_argument("--options", default="{}", help='JSON {"method": {option: value}}')
    ap.add_argument("--name", default="real_spectra")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    import scipy.io

    mask = scipy.io.loadmat(MASK)["mask"].astype(np.float64)
    methods = args.methods.split(",")
    snrs = [None if s.strip().lower() == "none" else float(s) for s in args.snr.split(",")]
    scenes = (
        args.scenes.split(",")
        if args.scenes
        else list(datasets.REPORT_SCENES if args.split == "report" else datasets.TUNE_SCENES)
    )
    options = json.loads(args.options)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    store = out / f"{args.name}.json"
    runs = json.loads(store.read_text())["runs"] if store.exists() else []
    done = {
        (r["scene"], r["snr_db"], r["method"], json.dumps(r["options"], sort_keys=True))
        for r in runs
    }
    for scene in scenes:
        for snr in snrs:
            system, cube, g = problem(scene, snr, mask)
            for m in methods:
                opts = options.get(m, {})
                key = (scene, snr, m, json.dumps(opts, sort_keys=True))
                if key in done:
                    continue
                est, sec = run(m, system, g, opts)
                row = {
                    "scene": scene,
                    "snr_db": snr,
                    "method": m,
                    "options": opts,
                    "seconds": sec,
                    **score(cube, est),
                }
                runs.append(row)
                done.add(key)
                print(
                    f"{scene:24s} {str(snr):5s} {m:14s} PSNR {row['psnr']:6.2f} SSIM "
                    f"{row['ssim']:.3f} "
                    f"SAM {row['sam']:5.2f} {sec:6.2f} s",
                    flush=True,
                )
                store.write_text(json.dumps({"runs": runs}, indent=1))
    head = (
        f"SD-CASSI 256×256×28 (KAIST bands), TSA mask, 2 px/band, float32; scenes "
        f"{', '.join(scenes)} ({args.split} split); {platform.machine()}, NumPy {np.__version__}, "
        f"tensor_cosdi {tc.__version__}.\n\n"
    )
    table = summarise([r for r in runs if r["scene"] in scenes], methods, snrs)
    (out / f"{args.name}.md").write_text(head + table + "\n")
    print(head + table)


if __name__ == "__main__":
    main()
