"""The learned spectral denoiser's arithmetic: float32 against bfloat16, time and quality.

One call of :class:`tensor_cosdi.learn.spectral_net.SpectralDenoiser` on a
256×256×28 cube (the report protocol's size) in each ``precision``, with 1
and with all CPU threads (median of ``--repeats`` calls after a warm-up);
and what bfloat16 costs: PSNR of a real tuning scene (``balloons``, KAIST
bands) denoised at three noise levels, in both precisions.  The ratio is
computed in the same run.  bfloat16 only pays on CPUs with native bfloat16
instructions (``bfloat16_is_fast`` is printed).  Then one call as plug-and-play makes it (a
Fortran-ordered cube, each call in the next of the eight symmetries of the image plane, as
``self_ensemble(..., cycle=True)`` hands them over) against the network alone on the
eigen-images, in the same rounds: the rest is the call's own work (spectral subspace, scaling,
memory layouts).

    python benchmarks/denoiser_speed.py [--repeats 7] [--scene balloons] [--name denoiser_speed]
                                        [--precisions float32,bfloat16]

``--precisions float32`` skips bfloat16 (on a CPU that emulates it, the network in its
contiguous layout takes half a minute a call).

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, write_results  # noqa: E402

from tensor_cosdi import datasets, metrics  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--scene", default="balloons", help="a tuning scene (not a report scene)")
    ap.add_argument("--out", default=str(RESULTS), help="the folder of the results file")
    ap.add_argument("--name", default="denoiser_speed", help="the results file's name, no .md")
    ap.add_argument("--precisions", default="float32,bfloat16")
    args = ap.parse_args(argv)
    if not args.name or Path(args.name).name != args.name or args.name.endswith(".md"):
        raise SystemExit(f"--name: a file name without folder or .md, got {args.name!r}")
    precisions = [p for p in args.precisions.split(",") if p]
    known = ("float32", "bfloat16")
    if not precisions or len(set(precisions)) < len(precisions) or set(precisions) - set(known):
        raise SystemExit(
            f"--precisions: float32 and/or bfloat16, comma-separated, got {args.precisions!r}"
        )
    both = len(precisions) == 2
    if args.scene in datasets.REPORT_SCENES:
        raise SystemExit(f"--scene {args.scene} is a report scene; pick a tuning scene")
    try:
        cube = datasets.load_hsi(args.scene, "kaist", dtype="float32")[0]
    except FileNotFoundError as exc:
        raise SystemExit(f"denoiser_speed.py needs the research scenes: {exc}") from None
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser, bfloat16_is_fast

    nets = {p: SpectralDenoiser(precision=p) for p in precisions}
    rng = np.random.default_rng(0)
    threads = sorted({1, os.cpu_count() or 1})
    lines = [
        f"# The learned denoiser in {' and '.join(precisions)}",
        "",
        f"CPU runs bfloat16 natively (`bfloat16_is_fast`): {bfloat16_is_fast()}.  ",
        f"One call on a 256×256×28 cube, median of {args.repeats} (s):",
        "",
        "| threads | " + " | ".join(precisions) + (" | float32 / bfloat16 |" if both else " |"),
        "|---|" + "---|" * (len(precisions) + both),
    ]
    x = (cube + 0.05 * rng.standard_normal(cube.shape)).astype(np.float32)
    saved = torch.get_num_threads()
    for n in threads:
        torch.set_num_threads(n)
        med = {}
        for p, net in nets.items():
            med[p] = _median_call(lambda net=net: net(x, 0.05), args.repeats)
        ratio = f" {med['float32'] / med['bfloat16']:.2f} |" if both else ""
        lines.append(f"| {n} | " + " | ".join(f"{med[p]:.3f}" for p in precisions) + " |" + ratio)
    lines += _layout_table(torch, nets, args.repeats)
    lines += _overhead_table(torch, nets, x, args.repeats)
    torch.set_num_threads(saved)
    if not both:
        write_results(Path(args.out) / f"{args.name}.md", lines)
        return
    lines += [
        "",
        f"PSNR (dB) of `{args.scene}` with white noise σ, denoised:",
        "",
        "| σ | noisy | float32 | bfloat16 | bfloat16 − float32 |",
        "|---|---|---|---|---|",
    ]
    for sigma in (0.02, 0.05, 0.1):
        noisy = (cube + sigma * rng.standard_normal(cube.shape)).astype(np.float32)
        p = {k: metrics.psnr(cube, net(noisy, sigma), data_range=1.0) for k, net in nets.items()}
        lines.append(
            f"| {sigma} | {metrics.psnr(cube, noisy, data_range=1.0):.2f} | {p['float32']:.2f} | "
            f"{p['bfloat16']:.2f} | {p['bfloat16'] - p['float32']:+.3f} |"
        )
    write_results(Path(args.out) / f"{args.name}.md", lines)


def _median_call(f, repeats: int) -> float:
    f()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _layout_table(torch, nets, repeats: int) -> list:
    """The network alone on 12 eigen-images at 256×256, its weights in the default (contiguous)
    layout against channels-last, which the denoiser uses on a CPU; every thread."""
    import copy

    lines = [
        "",
        f"The network alone (12 eigen-images, 256×256, {torch.get_num_threads()} threads), "
        f"median of {repeats} (ms):",
        "",
        "| precision | contiguous | channels-last | contiguous / channels-last |",
        "|---|---|---|---|",
    ]
    for p, den in nets.items():
        dtype = torch.bfloat16 if p == "bfloat16" else torch.float32
        # the denoiser keeps its own network channels-last on a CPU: both layouts set here
        plain = copy.deepcopy(den.net).to(dtype).to(memory_format=torch.contiguous_format)
        fast = copy.deepcopy(plain).to(memory_format=torch.channels_last)
        y = torch.rand(1, 12, 256, 256, generator=torch.Generator().manual_seed(0)).to(dtype)
        s = torch.tensor([0.05], dtype=dtype)
        with torch.no_grad():
            t = {
                k: _median_call(lambda n=n: n(y, s), repeats)
                for k, n in (("c", plain), ("l", fast))
            }
        lines.append(f"| {p} | {1e3 * t['c']:.1f} | {1e3 * t['l']:.1f} | {t['c'] / t['l']:.2f} |")
    return lines


def _overhead_table(torch, nets, x, repeats: int) -> list:
    """One call as plug-and-play makes it against the network alone, every thread: per round,
    eight calls through the cycling self-ensemble on a Fortran-ordered cube and eight of the
    network on 12 eigen-images of the cube's size; medians over the rounds of the mean call."""
    import copy

    from tensor_cosdi.solvers.denoisers import self_ensemble

    cube = np.asfortranarray(x)
    lines = [
        "",
        f"One call as plug-and-play makes it ({torch.get_num_threads()} threads; a "
        "Fortran-ordered cube, each call the next of the eight symmetries) against the network "
        f"alone on its eigen-images, median over {repeats} rounds of eight (ms):",
        "",
        "| precision | call | network | rest of the call | rest / call |",
        "|---|---|---|---|---|",
    ]
    for p, den in nets.items():
        cycled = self_ensemble(den, 1, cycle=True)
        dtype = torch.bfloat16 if p == "bfloat16" else torch.float32
        # the network as the denoiser runs it on a CPU: channels-last
        net = copy.deepcopy(den.net).to(dtype).to(memory_format=torch.channels_last)
        y = torch.rand(1, den.r_max, *cube.shape[:2], generator=torch.Generator().manual_seed(0))
        y, s = y.to(dtype), torch.tensor([0.05], dtype=dtype)

        def eight_calls():
            for _ in range(8):
                cycled(cube, 0.05)

        def eight_nets():
            with torch.no_grad():
                for _ in range(8):
                    net(y, s)

        eight_calls(), eight_nets()  # warm-up
        calls, nets_alone = [], []
        for _ in range(repeats):
            for f, acc in ((eight_calls, calls), (eight_nets, nets_alone)):
                t0 = time.perf_counter()
                f()
                acc.append((time.perf_counter() - t0) / 8)
        c, n = 1e3 * float(np.median(calls)), 1e3 * float(np.median(nets_alone))
        lines.append(f"| {p} | {c:.1f} | {n:.1f} | {c - n:.1f} | {(c - n) / c:.2f} |")
    return lines


if __name__ == "__main__":
    main()
