"""The thesis' loss ablation for D-CoSNet (Table 2: ℓ1 25.64, SSIM 26.16, ℓ1 + SSIM 26.79 dB).

Trains one network per loss (``l1``, ``ssim``, ``l1+ssim``; the ``ℓ1(G, G̃)``
term is in all three, as Eq. 152) with the same seed, data and schedule on
the tuning scenes, then evaluates each on the held-back report scenes with
the real-spectra protocol (SD-CASSI 256×256×28, TSA mask, 2 px/band,
noiseless and 30 dB).  Training checkpoints and resumes: rerun the same
command after an interruption; finished weights are reused.

    python benchmarks/dcosnet_ablation.py [--steps 600] [--stages 1] [--out benchmarks/results]

Prints a Markdown table (mean PSNR / SSIM / SAM over the scenes); never asserts anything.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import scipy.io
from real_spectra import MASK, problem, score

from tensor_cosdi import datasets
from tensor_cosdi.learn.dcosnet import DCoSNet
from tensor_cosdi.learn.dcosnet_train import LOSSES, DCoSNetConfig, train_dcosnet

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--stages", type=int, default=1, help="the thesis' network has one")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    import torch

    torch.set_num_threads(2)
    folder = Path(args.out) / "dcosnet_ablation"
    folder.mkdir(parents=True, exist_ok=True)
    weights = {}
    for loss in LOSSES:
        cfg = DCoSNetConfig(steps=args.steps, stages=args.stages, loss=loss, seed=args.seed)
        path = folder / f"{loss.replace('+', '_')}_{args.steps}_{args.stages}.pt"
        if not path.exists():
            ckpt = path.with_name(path.name + ".ckpt")
            train_dcosnet(path, cfg, resume=ckpt.exists(), device="cpu")
        weights[loss] = path
    mask = scipy.io.loadmat(MASK)["mask"].astype(np.float64)
    rows = {(loss, snr): [] for loss in LOSSES for snr in (None, 30.0)}
    for scene in datasets.REPORT_SCENES:
        for snr in (None, 30.0):
            system, cube, g = problem(scene, snr, mask)
            for loss in LOSSES:
                est = DCoSNet(weights[loss], device="cpu")(system, g)
                rows[(loss, snr)].append(score(cube, est))
    print(
        f"D-CoSNet loss ablation: {args.stages} stage(s), {args.steps} steps, seed {args.seed}; "
        f"report scenes {', '.join(datasets.REPORT_SCENES)}\n"
    )
    print("| SNR | loss | PSNR dB | SSIM | SAM ° |\n|---|---|---|---|---|")
    for (loss, snr), rs in rows.items():
        print(
            f"| {'noiseless' if snr is None else f'{snr:g} dB'} | {loss} | "
            f"{np.mean([r['psnr'] for r in rs]):.2f} | {np.mean([r['ssim'] for r in rs]):.3f} | "
            f"{np.mean([r['sam'] for r in rs]):.2f} |"
        )


if __name__ == "__main__":
    main()
