"""D-CoSNet weight files compared on a fold of tuning scenes they were not trained on.

Candidates are trained with ``tensor-cosdi train-dcosnet … --hold-out K`` (fold
``K`` of :func:`tensor_cosdi.datasets.tune_folds` left out); this script
scores each, and a reference (the shipped weights or a file), on that fold with the protocol of
``benchmarks/_protocol.py`` (256×256×28 SD-CASSI, 2 px per band, the TSA mask
and the seeded random code, noiseless and at 30 dB, PSNR with data range 1).
The report scenes are never read.  The verdict is computed: the best
candidate by the mean over every condition, and whether it is at least as good
as the shipped weights in each condition.

    python benchmarks/dcosnet_weights.py NAME=FILE.pt [NAME=FILE.pt ...] [--fold 3]
        [--reference shipped]
        [--snr none,30] [--masks tsa,random] [--out benchmarks/results/dcosnet_weights.md]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, load_mask, problem, score, snr_label, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("candidates", nargs="+", help="NAME=FILE.pt weight files of train-dcosnet")
    ap.add_argument("--fold", type=int, default=3, help="the fold the candidates left out")
    ap.add_argument("--reference", default="shipped", help="'shipped' or a weights file")
    ap.add_argument("--snr", default="none,30")
    ap.add_argument("--masks", default="tsa,random")
    ap.add_argument("--out", default=str(RESULTS / "dcosnet_weights.md"))
    args = ap.parse_args(argv)
    ref = None if args.reference == "shipped" else Path(args.reference)
    if ref is not None and not ref.is_file():
        raise SystemExit(f"--reference: no file {ref}")
    files = {"reference": ref}
    for item in args.candidates:
        name, sep, path = item.partition("=")
        if not sep or not Path(path).is_file():
            raise SystemExit(f"expected NAME=FILE.pt with an existing file, got {item!r}")
        files[name] = Path(path)
    scenes = tc.datasets.tune_folds(4)[args.fold]
    snrs = [None if s == "none" else float(s) for s in args.snr.split(",")]
    masks = args.masks.split(",")
    conds = [(m, s) for m in masks for s in snrs]
    psnr = {k: {c: [] for c in conds} for k in files}
    secs = {k: [] for k in files}
    for mask_name, snr in conds:
        mask = load_mask(mask_name)
        for scene in scenes:
            system, cube, g = problem(scene, snr, mask)
            for key, path in files.items():
                t0 = time.perf_counter()
                est = tc.reconstruct(system, g, "dcosnet", weights=path).cube
                secs[key].append(time.perf_counter() - t0)
                psnr[key][(mask_name, snr)].append(score(cube, est)["psnr"])
            print(mask_name, snr_label(snr), scene, flush=True)
    means = {k: {c: float(np.mean(v)) for c, v in psnr[k].items()} for k in files}
    lines = [
        f"# D-CoSNet weights on tuning fold {args.fold} ({', '.join(scenes)})",
        "",
        f"Candidates trained without this fold; reference: "
        f"`{'the shipped weights' if ref is None else ref.name}`.",
        "",
        "| weights | "
        + " | ".join(f"{m}, {snr_label(s)}" for m, s in conds)
        + " | mean | median s |",
        "|---|" + "---|" * (len(conds) + 2),
    ]
    for k in files:
        cells = " | ".join(f"{means[k][c]:.2f}" for c in conds)
        total = np.mean(list(means[k].values()))
        lines.append(f"| {k} | {cells} | {total:.2f} | {np.median(secs[k]):.2f} |")
    cands = [k for k in files if k != "reference"]
    best = max(cands, key=lambda k: np.mean(list(means[k].values())))
    diffs = {c: means[best][c] - means["reference"][c] for c in conds}
    ok = all(d >= 0 for d in diffs.values())
    verdict = "is at least as good as" if ok else "is not at least as good as"
    detail = ", ".join(f"{m} {snr_label(s)} {d:+.2f} dB" for (m, s), d in diffs.items())
    lines += ["", f"Verdict: the best candidate, {best}, {verdict} the reference ({detail})."]
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
