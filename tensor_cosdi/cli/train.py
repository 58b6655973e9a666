"""``tensor-cosdi train-denoiser`` and ``train-dcosnet``: options and runners (see
:mod:`tensor_cosdi.cli`)."""

from __future__ import annotations

import sys

from .util import _positive_int


def _training_options(p, *, steps: int, batch: int):
    p.add_argument("--out", required=True, help="weights file to write (.pt)")
    p.add_argument("--steps", type=_positive_int, default=steps, help="optimiser steps")
    p.add_argument("--batch", type=_positive_int, default=batch, help="samples per step")
    p.add_argument("--seed", type=int, default=0, help="seed of samples and noise (default 0)")
    p.add_argument(
        "--lr", type=float, default=1e-3,
        help="peak learning rate (default 1e-3; lower to fine-tune a trained network)",
    )  # fmt: skip
    p.add_argument("--data", help="folder of the NAME.npz scenes (default: datasets.data_dir())")
    p.add_argument("--device", help="cpu, cuda, … (default: cuda when available)")
    p.add_argument("--threads", type=_positive_int, help="CPU threads for torch")
    p.add_argument("--resume", action="store_true", help="continue from OUT.ckpt")
    p.add_argument(
        "--stop-after", type=_positive_int, help="stop this run after N steps (resume later)"
    )
    p.add_argument("--force", action="store_true", help="overwrite OUT and start over")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--hold-out", type=int, default=-1, metavar="K",
        help="leave fold K (0-3) of datasets.tune_folds(4) out of training, for validation "
        "(default -1: train on every tuning scene)",
    )  # fmt: skip


def _run_training(args, train, cfg) -> int:
    from ..learn import require_torch

    torch = require_torch()
    if args.threads:
        torch.set_num_threads(args.threads)
    summary = train(
        args.out,
        cfg,
        resume=args.resume,
        force=args.force,
        device=args.device,
        folder=args.data,
        progress=not args.quiet,
        command="tensor-cosdi " + " ".join(sys.argv[1:]) if sys.argv else None,
        stop_after=args.stop_after,
    )
    if not summary["finished"]:
        print(f"stopped at step {summary['steps']}; continue with the same command and --resume")
        return 0
    print(
        f"wrote {args.out}: {summary['steps']} steps, loss {summary['final_loss']:.3e}, "
        f"{summary['seconds']:.0f} s on {summary['device']}"
    )
    return 0


def run_train_denoiser(args) -> int:
    from ..learn.train import TrainConfig, train_denoiser

    cfg = TrainConfig(
        steps=args.steps,
        batch=args.batch,
        patch=args.patch,
        width=args.width,
        blocks=args.blocks,
        conv_rank=args.conv_rank,
        zoom=args.zoom,
        zoom_max=args.zoom_max,
        illumination=args.illumination,
        max_shift=args.max_shift,
        density_spread=args.density_spread,
        seed=args.seed,
        hold_out=args.hold_out,
        init=args.init,
        lr=args.lr,
        lr_end=min(1e-5, args.lr),
        warmup=args.warmup,
    )
    return _run_training(args, train_denoiser, cfg.check())


def run_train_dcosnet(args) -> int:
    from ..learn.dcosnet_train import DCoSNetConfig, train_dcosnet

    cfg = DCoSNetConfig(
        system=args.system,
        n_bands=args.bands,
        shift=args.shift,
        stages=args.stages,
        width=args.width,
        unet_width=args.unet_width,
        prior=args.prior,
        prior_weights=args.prior_weights,
        loss=args.loss,
        mask=args.mask,
        steps=args.steps,
        batch=args.batch,
        patch=args.patch,
        lr=args.lr,
        lr_end=min(1e-5, args.lr),
        seed=args.seed,
        hold_out=args.hold_out,
        learn_code=args.learn_code,
        alpha_t=args.alpha_t,
        code_until=args.code_until,
        start=args.start,
        noise_input=args.noise_input,
        init=args.init or "",
    )
    return _run_training(args, train_dcosnet, cfg.check())
