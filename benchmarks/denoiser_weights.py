"""Two spectral-denoiser weight files compared inside ``pnp_gap`` (or ``pnp_fast``) on tuning
scenes.

Whether a retrained denoiser should replace the shipped one is decided here,
on tuning scenes both were trained on (never the report scenes): the
protocol of ``benchmarks/_protocol.py`` (256×256×28 SD-CASSI, 2 px per band,
``--mask`` code, PSNR with data range 1), ``--method`` at its defaults with
each weight file's denoiser (``pnp_fast``: its settings with the denoiser in ``precision="auto"``),
noiseless and at 30 dB.  The verdict line is
computed from the means.

    python benchmarks/denoiser_weights.py CANDIDATE.pt [--reference shipped]
        [--scenes balloons,cd,clay,feathers] [--snr none,30] [--mask tsa] [--threads 1]
        [--method pnp_gap|pnp_fast]
        [--out benchmarks/results/denoiser_weights.md]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402
    RESULTS,
    load_mask,
    pnp_fast_settings,
    problem,
    score,
    snr_label,
    write_results,
)

import tensor_cosdi as tc  # noqa: E402


def _in_pnp_gap(system, g, den):
    return tc.reconstruct(system, g, "pnp_gap", denoiser=den).cube


def _in_pnp_fast(system, g, den):
    """``pnp_fast`` with another denoiser: ``pnp_gap`` with ``pnp_fast``'s own settings."""
    return tc.reconstruct(system, g, "pnp_gap", denoiser=den, **pnp_fast_settings()).cube


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("candidate", help="a train-denoiser weights file")
    ap.add_argument("--reference", default="shipped", help="'shipped' or a weights file")
    ap.add_argument("--scenes", default="balloons,cd,clay,feathers")
    ap.add_argument("--snr", default="none,30")
    ap.add_argument("--mask", default="tsa")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--method", default="pnp_gap", choices=("pnp_gap", "pnp_fast"))
    ap.add_argument("--out", default=str(RESULTS / "denoiser_weights.md"))
    args = ap.parse_args(argv)
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser, default_weights

    torch.set_num_threads(args.threads)
    scenes = args.scenes.split(",")
    bad = [s for s in scenes if s not in tc.datasets.TUNE_SCENES]
    if bad:
        raise SystemExit(f"--scenes must be tuning scenes; not tuning scenes: {bad}")
    snrs = [None if s == "none" else float(s) for s in args.snr.split(",")]
    files = {
        "reference": default_weights() if args.reference == "shipped" else Path(args.reference),
        "candidate": Path(args.candidate),
    }
    mask = load_mask(args.mask)
    run = _in_pnp_fast if args.method == "pnp_fast" else _in_pnp_gap
    rows = {k: {snr: [] for snr in snrs} for k in files}
    secs = {k: [] for k in files}
    for key, path in files.items():
        den = SpectralDenoiser(path, precision="auto" if args.method == "pnp_fast" else "float32")
        for scene in scenes:
            for snr in snrs:
                system, cube, g = problem(scene, snr, mask)
                t0 = time.perf_counter()
                est = run(system, g, den)
                secs[key].append(time.perf_counter() - t0)
                rows[key][snr].append(score(cube, est)["psnr"])
                print(key, scene, snr_label(snr), f"{rows[key][snr][-1]:.2f}", flush=True)
    lines = [
        f"# Denoiser weights in `{args.method}`: {', '.join(scenes)} ({args.mask} code)",
        "",
        f"reference: `{files['reference'].name}`; candidate: `{files['candidate'].name}`",
        "",
        "| weights | " + " | ".join(f"PSNR dB, {snr_label(s)}" for s in snrs) + " | median s |",
        "|---|" + "---|" * (len(snrs) + 1),
    ]
    means = {k: [float(np.mean(rows[k][s])) for s in snrs] for k in files}
    for k in files:
        cells = " | ".join(f"{m:.2f}" for m in means[k])
        lines.append(f"| {k} | {cells} | {np.median(secs[k]):.1f} |")
    better = all(c >= r for c, r in zip(means["candidate"], means["reference"]))
    diffs = ", ".join(
        f"{snr_label(s)} {c - r:+.2f} dB"
        for s, c, r in zip(snrs, means["candidate"], means["reference"])
    )
    verdict = "replaces" if better else "does not replace"
    lines += ["", f"Verdict: the candidate {verdict} the reference ({diffs})."]
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
