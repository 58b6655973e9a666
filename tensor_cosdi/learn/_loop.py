"""The training loop every network of :mod:`tensor_cosdi.learn` shares.

Adam with a linear warm-up and a cosine-decayed step, gradients clipped to
norm 1, a progress bar, atomic checkpoints (model, optimiser, scheduler,
step, losses, NumPy and torch random states, configuration) to ``OUT.ckpt``
every ``checkpoint_every`` steps, exact resume, and the final weights to
``OUT`` — never written over without ``force``.  Callers give a frozen
dataclass configuration (with ``steps``, ``lr``, ``lr_end``, ``warmup``,
``seed``, ``checkpoint_every`` and a ``check()`` method), a model builder and
a function computing one batch's loss from the NumPy random stream.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..datasets import training_scenes
from ..validate import integer, output_folder
from . import _exception_text, require_torch, torch_device


def atomic_save(torch, obj, path: Path):
    """``torch.save`` to a temporary file in the same folder, then rename over ``path``."""
    tmp = path.with_name(path.name + ".tmp")
    torch.save(obj, tmp)
    os.replace(tmp, path)


def check_out(out, force: bool) -> tuple[Path, Path]:
    """``(out, checkpoint path)``; refuses an existing ``out`` without ``force``."""
    out = Path(out)
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists; pass force=True (--force) to write over it")
    output_folder(out)
    return out, out.with_name(out.name + ".ckpt")


def check_config(cfg, positive_ints) -> None:
    """The checks every training configuration shares: ``positive_ints`` are integers ≥ 1,
    ``warmup`` an integer ≥ 0, ``seed`` an integer ≥ 0, ``lr`` finite,
    ``0 < lr_end ≤ lr``."""
    for name in positive_ints:
        v = getattr(cfg, name)
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    if isinstance(cfg.warmup, bool) or not isinstance(cfg.warmup, int) or cfg.warmup < 0:
        raise ValueError(f"warmup must be an integer ≥ 0, got {cfg.warmup!r}")
    integer("seed", getattr(cfg, "seed", 0), low=0)
    lr = cfg.lr
    if isinstance(lr, bool) or not isinstance(lr, (int, float)) or not 0 < lr < math.inf:
        raise ValueError(f"lr must be a finite positive number, got {lr!r}")
    if not 0 < cfg.lr_end <= cfg.lr:
        raise ValueError(f"need 0 < lr_end ≤ lr, got {cfg.lr_end}, {cfg.lr}")


def check_stop_after(stop_after):
    if stop_after is not None and (
        isinstance(stop_after, bool) or not isinstance(stop_after, int) or stop_after < 1
    ):
        raise ValueError(f"stop_after must be a positive integer, got {stop_after!r}")


#: What a checkpoint written by :func:`run` holds.
CHECKPOINT_KEYS = (
    "model", "optimizer", "scheduler", "step", "losses", "elapsed", "rng", "torch_rng", "config",
)  # fmt: skip


def _resume_state(torch, path: Path, config_cls):
    """``(state, config)`` of the checkpoint at ``path``, or a one-line ``ValueError`` saying
    that it is damaged or not one of this training's (and how to start over)."""

    def damaged(why):
        return ValueError(
            f"--resume: {path} is not a readable checkpoint of this training ({why}); delete it "
            "or pass --force to start over"
        )

    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # EOFError, a zip reader's RuntimeError, UnpicklingError, …
        raise damaged(_exception_text(exc)) from None
    missing = [k for k in CHECKPOINT_KEYS if not isinstance(state, dict) or k not in state]
    if missing:
        raise damaged(f"no {', '.join(missing)}")
    try:
        fields = json.loads(state["config"])
        if not isinstance(fields, dict):
            raise TypeError(f"the config is a {type(fields).__name__}, not a mapping")
        config = config_cls(**fields)
    except (TypeError, ValueError, RecursionError) as exc:  # unknown fields, bad JSON, too deep
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)[:100]
        raise damaged(f"its config: {why}") from None
    return state, config


def run(
    *,
    desc: str,
    out,
    config,
    config_cls,
    prepare,
    build,
    batch_loss,
    weights_config,
    resume: bool,
    force: bool,
    device,
    progress: bool,
    command,
    stop_after,
    extra_summary=None,
):
    """Train; returns a summary dict (``finished`` False when ``stop_after`` ended the run).

    ``prepare(cfg)`` loads the data (before the seeds are set); ``build(torch,
    cfg, data)`` returns the model; ``batch_loss(torch, net, rng, dev, cfg,
    data, step)`` returns one batch's scalar loss (``step``: the optimiser
    steps done).  ``weights_config(cfg)`` is the dict stored beside the
    weights to rebuild the model.
    """
    torch = require_torch()
    from tqdm import tqdm

    out, ckpt_path = check_out(out, force)
    check_stop_after(stop_after)
    dev = torch_device(torch, device)
    state = None
    if resume:
        if not ckpt_path.is_file():
            raise FileNotFoundError(f"--resume: no checkpoint {ckpt_path}")
        state, saved = _resume_state(torch, ckpt_path, config_cls)
        if config is not None and config != saved:
            raise ValueError(
                f"--resume: the checkpoint was made with {saved}, not {config}; "
                "resume without changing options"
            )
        config = saved
    elif ckpt_path.exists() and not force:
        raise FileExistsError(
            f"{ckpt_path} (an earlier run's checkpoint) exists; pass resume=True (--resume) "
            "to continue it or force=True (--force) to start over"
        )
    cfg = (config or config_cls()).check()
    data = prepare(cfg)
    torch.manual_seed(cfg.seed)
    rng = np.random.default_rng(cfg.seed)
    net = build(torch, cfg, data).to(dev)
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    warm = min(cfg.warmup, cfg.steps - 1) if cfg.steps > 1 else 0

    def lr_at(i):  # linear warm-up, then cosine decay to lr_end (a factor of lr)
        if i < warm:
            return (i + 1) / warm
        t = (i - warm) / max(cfg.steps - warm, 1)
        end = cfg.lr_end / cfg.lr
        # a Python float: NumPy scalars in the scheduler state would not load with weights_only
        return float(end + (1 - end) * 0.5 * (1 + math.cos(math.pi * t)))

    sched = torch.optim.lr_scheduler.LambdaLR(opt, lr_at)
    step, losses, elapsed = 0, [], 0.0
    if state is not None:
        try:
            net.load_state_dict(state["model"])
            opt.load_state_dict(state["optimizer"])
            sched.load_state_dict(state["scheduler"])
            step, losses = int(state["step"]), [float(v) for v in state["losses"]]
            elapsed = float(state["elapsed"])
            rng.bit_generator.state = json.loads(state["rng"])
            torch.set_rng_state(state["torch_rng"])
        except Exception as exc:  # tensors of other shapes, a damaged optimiser or RNG state
            raise ValueError(
                f"--resume: {ckpt_path} does not fit this training ({_exception_text(exc)}); "
                "delete it or pass --force to start over"
            ) from None
        if not 0 <= step <= cfg.steps:
            raise ValueError(
                f"--resume: {ckpt_path} is at step {step}, outside 0…{cfg.steps}; delete it or "
                "pass --force to start over"
            )

    def checkpoint():
        atomic_save(
            torch,
            {
                "model": net.state_dict(),
                "optimizer": opt.state_dict(),
                "scheduler": sched.state_dict(),
                "step": step,
                "losses": losses,
                "elapsed": elapsed + time.perf_counter() - t0,
                "rng": json.dumps(rng.bit_generator.state),
                "torch_rng": torch.get_rng_state(),
                "config": json.dumps(asdict(cfg)),
            },
            ckpt_path,
        )

    last = cfg.steps if stop_after is None else min(cfg.steps, step + stop_after)
    t0 = time.perf_counter()
    bar = tqdm(total=cfg.steps, initial=step, desc=desc, disable=not progress)
    net.train()
    while step < last:
        loss = batch_loss(torch, net, rng, dev, cfg, data, step)
        value = loss.item()
        if not math.isfinite(value):  # diverged: the last checkpoint is kept as it was
            bar.close()
            kept = f"; the last checkpoint ({ckpt_path}) is kept" if ckpt_path.is_file() else ""
            raise ValueError(
                f"training diverged at step {step + 1} (loss {value}); lower the learning "
                f"rate (lr={cfg.lr:g}){kept}"
            )
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
        opt.step()
        sched.step()
        step += 1
        losses.append(value)
        bar.update(1)
        if step % 20 == 0:
            bar.set_postfix(loss=f"{np.mean(losses[-20:]):.2e}")
        if step % cfg.checkpoint_every == 0 or step == last:
            checkpoint()
    bar.close()
    if step < cfg.steps:
        return {"steps": step, "finished": False, "checkpoint": str(ckpt_path)}
    total = elapsed + time.perf_counter() - t0
    summary = {
        "steps": step,
        "finished": True,
        "final_loss": float(np.mean(losses[-100:])),
        "seconds": total,
        "device": str(dev),
        "threads": torch.get_num_threads(),
        "torch": torch.__version__,
        "command": command,
        "scenes": list(training_scenes(getattr(cfg, "hold_out", -1))),
        **(extra_summary or {}),
    }
    net_cpu = {k: v.detach().cpu() for k, v in net.state_dict().items()}
    atomic_save(
        torch,
        {
            "model": net_cpu,
            "config": weights_config(cfg),
            "train_config": json.dumps(asdict(cfg)),
            "summary": json.dumps(summary),
        },
        out,
    )
    return summary
