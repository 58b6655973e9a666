"""Spectral-denoiser weight files compared inside ``pnp_gap`` (or ``pnp_fast``) on tuning
scenes.

Whether a retrained denoiser should replace the shipped one is decided here, on tuning scenes
both were trained on (never the report scenes): the protocol of ``benchmarks/_protocol.py``
(256×256×28 SD-CASSI, 2 px per band, ``--mask`` code, PSNR with data range 1), ``--method`` at
its defaults with each weight file's denoiser (``pnp_fast``: its settings with the denoiser in
``precision="auto"``), noiseless and at 30 dB. ``--zoom Z`` scores magnified views of the
scenes instead (the centre crop of ``1/Z`` of the side, magnified back to 256×256: the
smoother, larger-scale structure of another camera, a proxy for scenes from another database).
``--illuminant A`` scores the scenes lit by a CIE illuminant and scaled to a peak of 1
(:func:`tensor_cosdi.colour.radiance`): a radiance database's scenes carry their light's
spectrum, which the reflectance scenes trained on do not. Each candidate's verdict line is
computed from the means.

Each run is timed as a user's single call, the SNR fit included (no SNR estimate cached by the
reference's run on the same measurement).  ``--within-db DB --budget-s S`` asks another
question of a candidate meant to be faster: is it within ``DB`` of the reference at every
noise level, and is its median time a cube at most ``S`` seconds?

    python benchmarks/denoiser_weights.py CANDIDATE.pt [CANDIDATE2.pt …] [--reference shipped]
        [--scenes balloons,cd,clay,feathers] [--snr none,30] [--mask tsa] [--threads 1]
        [--method pnp_gap|pnp_fast] [--zoom 1] [--illuminant A] [--within-db DB --budget-s S]
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
    clear_snr_cache,
    load_mask,
    pnp_fast_with,
    problem,
    scene_view,
    score,
    snr_label,
    write_results,
)

import tensor_cosdi as tc  # noqa: E402


def _in_pnp_gap(system, g, den):
    return tc.reconstruct(system, g, "pnp_gap", denoiser=den).cube


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("candidate", nargs="+", help="train-denoiser weights files")
    ap.add_argument("--reference", default="shipped", help="'shipped' or a weights file")
    ap.add_argument("--scenes", default="balloons,cd,clay,feathers")
    ap.add_argument("--snr", default="none,30")
    ap.add_argument("--mask", default="tsa")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--method", default="pnp_gap", choices=("pnp_gap", "pnp_fast"))
    ap.add_argument("--zoom", type=float, default=1.0, help="score magnified views (≥ 1)")
    ap.add_argument(
        "--illuminant", default=None, help="light the scenes (a key of colour.SDS_ILLUMINANTS)"
    )
    ap.add_argument("--within-db", type=float, default=None, help="with --budget-s: see above")
    ap.add_argument("--budget-s", type=float, default=None, help="with --within-db: see above")
    ap.add_argument("--out", default=str(RESULTS / "denoiser_weights.md"))
    args = ap.parse_args(argv)
    if (args.within_db is None) != (args.budget_s is None):
        raise SystemExit("--within-db and --budget-s go together")
    for flag, v in (("--within-db", args.within_db), ("--budget-s", args.budget_s)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise SystemExit(f"{flag} must be a positive number, got {v}")
    if not args.zoom >= 1:
        raise SystemExit(f"--zoom must be ≥ 1, got {args.zoom}")
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser, default_weights

    torch.set_num_threads(args.threads)
    scenes = args.scenes.split(",")
    bad = [s for s in scenes if s not in tc.datasets.TUNE_SCENES]
    if bad:
        raise SystemExit(f"--scenes must be tuning scenes; not tuning scenes: {bad}")
    snrs = [None if s == "none" else float(s) for s in args.snr.split(",")]
    if args.reference == "shipped":
        ref = default_weights()
    else:
        ref = Path(args.reference)
        if not ref.is_file():
            raise SystemExit(f"reference weights not found: {ref}")
    files = {"reference": ref}
    names = [Path(c) for c in args.candidate]
    for i, path in enumerate(names):
        if not path.is_file():
            raise SystemExit(f"candidate weights not found: {path}")
        files["candidate" if len(names) == 1 else f"candidate {i + 1}"] = path
    if args.illuminant is not None:
        try:
            scene_view(f"scene~{args.illuminant}")  # the protocol's check of a light's name
        except ValueError:
            raise SystemExit(
                f"--illuminant: unknown {args.illuminant!r}; e.g. A, D65, LED-B3"
            ) from None
    mask = load_mask(args.mask)
    run = pnp_fast_with if args.method == "pnp_fast" else _in_pnp_gap
    rows = {k: {snr: [] for snr in snrs} for k in files}
    secs = {k: [] for k in files}
    for key, path in files.items():
        den = SpectralDenoiser(path, precision="auto" if args.method == "pnp_fast" else "float32")
        for scene in scenes:
            for snr in snrs:
                system, cube, g = problem(
                    scene, snr, mask, zoom=args.zoom, illuminant=args.illuminant
                )
                clear_snr_cache()
                t0 = time.perf_counter()
                est = run(system, g, den)
                secs[key].append(time.perf_counter() - t0)
                rows[key][snr].append(score(cube, est)["psnr"])
                print(key, scene, snr_label(snr), f"{rows[key][snr][-1]:.2f}", flush=True)
    view = "" if args.zoom == 1 else f", magnified {args.zoom:g}×"
    if args.illuminant is not None:
        view += f", lit by CIE {args.illuminant}"
    lines = [
        f"# Denoiser weights in `{args.method}`: {', '.join(scenes)} ({args.mask} code{view})",
        "",
        "; ".join(f"{k}: `{p.name}`" for k, p in files.items()),
        "",
        "| weights | " + " | ".join(f"PSNR dB, {snr_label(s)}" for s in snrs) + " | median s |",
        "|---|" + "---|" * (len(snrs) + 1),
    ]
    means = {k: [float(np.mean(rows[k][s])) for s in snrs] for k in files}
    for k in files:
        cells = " | ".join(f"{m:.2f}" for m in means[k])
        lines.append(f"| {k} | {cells} | {np.median(secs[k]):.1f} |")
    lines.append("")
    for k in list(files)[1:]:
        lines.append(
            verdict(k, means[k], means["reference"], snrs, secs[k], args.within_db, args.budget_s)
        )
    write_results(args.out, lines)


def verdict(name, means, ref_means, snrs, seconds, within_db=None, budget_s=None) -> str:
    """The verdict line of candidate ``name`` from its mean PSNR per noise level (``means``,
    in the order of ``snrs``) against the reference's: without ``within_db``, whether it
    replaces the reference (at least as good at every level); with ``within_db`` and
    ``budget_s``, whether it stays within ``within_db`` at every level and whether the median
    of its ``seconds`` fits the budget."""
    diffs = ", ".join(f"{snr_label(s)} {c - r:+.2f} dB" for s, c, r in zip(snrs, means, ref_means))
    if within_db is None:
        better = all(c >= r for c, r in zip(means, ref_means))
        return (
            f"Verdict: the {name} {'replaces' if better else 'does not replace'} the reference "
            f"({diffs}).  "
        )
    close = all(c >= r - within_db for c, r in zip(means, ref_means))
    median = float(np.median(seconds))
    return (
        f"Verdict: the {name} is {'within' if close else 'not within'} {within_db:g} dB of the "
        f"reference at every noise level ({diffs}) and its median time ({median:.1f} s) "
        f"{'fits' if median <= budget_s else 'exceeds'} the {budget_s:g}-s budget.  "
    )


if __name__ == "__main__":
    main()
