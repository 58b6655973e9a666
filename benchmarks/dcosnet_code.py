"""D-CoSNet with a learned coded aperture against a fixed one (thesis §7.3), per shear.

Each argument is ``LABEL=WEIGHTS``: a D-CoSNet trained by ``tensor-cosdi
train-dcosnet --mask seeded`` (label ``seeded_sK``) or with ``--learn-code``
as well (``learned_sK``), ``K`` its shear in px per band.  Every network
reconstructs the report scenes (256×256, 28 KAIST bands) through its own
code tiled over the scene, noiseless and at 30 dB
(:func:`tensor_cosdi.studies.learned_code`); the verdict per shear is
computed from the per-case differences (scene × noise level)::

    python benchmarks/dcosnet_code.py seeded_s2=a.pt learned_s2=b.pt … [--out FILE]

``--pack SRC DST`` writes a copy of a weights file with its network tensors
in float16 (the code's logits kept in float32) — how the study's shipped
pair was made from the trained files.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402


def pack(src, dst):
    import torch

    dst = Path(dst)
    if dst.exists():
        raise SystemExit(f"{dst} exists; remove it first")
    ckpt = torch.load(src, map_location="cpu", weights_only=True)
    model = {
        k: v if k == "code_logits" or not v.is_floating_point() else v.half()
        for k, v in ckpt["model"].items()
    }
    torch.save({**ckpt, "model": model, "stored": "float16"}, dst)
    print(f"wrote {dst}")


def _verdict(gains) -> str:
    k, n = int((np.asarray(gains) > 0).sum()), len(gains)
    if k == n:
        return "the learned code better in every case"
    if k == 0:
        return "the fixed code better in every case"
    return f"inconclusive (the learned code better in {k} of {n} cases)"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "weights", nargs="*",
        help="LABEL=PATH, LABEL seeded_sK, learned_sK or learned-VARIANT_sK (not paired)",
    )  # fmt: skip
    ap.add_argument("--pack", nargs=2, metavar=("SRC", "DST"))
    ap.add_argument("--snr", type=float, default=30.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=str(RESULTS / "dcosnet_code.md"))
    args = ap.parse_args(argv)
    if args.pack:
        return pack(*args.pack)
    import torch

    torch.set_num_threads(args.threads)
    files = {}
    for item in args.weights:
        label, _, path = item.partition("=")
        if not re.fullmatch(r"(seeded|learned(-[a-z0-9]+)?)_s\d+", label) or not path:
            ap.error(f"expected LABEL=PATH with LABEL seeded_sK or learned_sK, got {item!r}")
        files[label] = path
    if not files:
        ap.error("name at least one LABEL=PATH")
    scenes = [f"cave.{s}" for s in tc.datasets.REPORT_SCENES]
    rows = tc.studies.learned_code(files, scenes, snrs=(None, args.snr), progress=False)
    for r in rows:
        print(r["weights"], r["scene"], r["snr_db"], f"{r['psnr']:.2f}", flush=True)
    snrs = (None, args.snr)

    def mean(label, key, **match):
        return float(np.mean([r[key] for r in rows if r["weights"] == label
                              and all(r[k] == v for k, v in match.items())]))  # fmt: skip

    lines = [
        f"# D-CoSNet with a learned code against a fixed one: {', '.join(scenes)} (256×256, "
        "28 bands)",
        "",
        "Each network through its own 64×64 code tiled over the scene; PSNR with the "
        "truth's peak as data range (means over the scenes).",
        "",
        "Training (from each file): steps, and the share of them during which the code "
        "changed (0: the fixed seeded code). One network per row: two trainings of one recipe "
        "were not compared, so differences of a few tenths of a dB may be training noise.",
        "",
        f"| network | shear px | steps | code learned | code open fraction | PSNR dB, noiseless | "
        f"PSNR dB, {args.snr:g} dB | SAM ° | median s |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for label in files:
        rs = [r for r in rows if r["weights"] == label]
        tcfg = json.loads(torch.load(files[label], weights_only=True)["train_config"])
        # files older than the option learned the code throughout (--code-until 1 today)
        share = tcfg.get("code_until", 1.0) if tcfg.get("learn_code") else 0
        lines.append(
            f"| {label} | {rs[0]['shift']} | {tcfg['steps']} | {share:g} | "
            f"{rs[0]['density']:.3f} | "
            f"{mean(label, 'psnr', snr_db=None):.2f} | {mean(label, 'psnr', snr_db=args.snr):.2f}"
            f" | {mean(label, 'sam'):.1f} | {np.median([r['seconds'] for r in rs]):.1f} |"
        )
    lines.append("")
    shears = sorted({int(k.rsplit("_s", 1)[1]) for k in files})
    for k in shears:
        a, b = f"learned_s{k}", f"seeded_s{k}"
        if a not in files or b not in files:
            continue
        gains = [mean(a, "psnr", scene=s, snr_db=q) - mean(b, "psnr", scene=s, snr_db=q)
                 for s in scenes for q in snrs]  # fmt: skip
        lines.append(
            f"Shear {k} px: learned − fixed {np.mean(gains):+.2f} dB (cases "
            f"{min(gains):+.2f} … {max(gains):+.2f}): {_verdict(gains)}."
        )
    fixed = {k: mean(f"seeded_s{k}", "psnr") for k in shears if f"seeded_s{k}" in files}
    if len(fixed) > 1:
        best = max(fixed, key=fixed.get)
        lines.append(
            f"Best shear with the fixed code: {best} px ("
            + ", ".join(f"{k} px {v:.2f} dB" for k, v in fixed.items())
            + ", means over scenes and noise levels)."
        )
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
