"""The learned denoiser's network in 8-bit integers inside ``pnp_fast``: time and PSNR.

On a CPU without native bfloat16 (AVX2 only) ``pnp_fast`` runs its network in float32 and
misses its 5-s budget (``benchmarks/results/pnp_fast_no_bf16.md``).  This measures the other
low-precision route such CPUs have: post-training static int8 quantization of the network's
convolutions (``torch.ao.quantization``, the ``x86`` engine: per-channel int8 weights, 8-bit
activations calibrated with histogram observers), on the protocol of
``benchmarks/_protocol.py`` (256×256×28 SD-CASSI, 2 px per band, ``--mask`` code).

The activations are calibrated on the network's inputs inside ``pnp_fast`` runs on
``--calib`` tuning scenes (every 4th call, noiseless and at each ``--snr``), then every
variant runs ``pnp_fast``'s own settings on the other ``--scenes`` (tuning scenes, never the
report scenes):

* ``float32``: the network as shipped;
* ``int8 body``: the residual blocks in int8, the input and output convolutions and the
  linear path in float32;
* ``int8``: every convolution but the linear path in int8.

Each run is timed as a user's single call, the SNR fit included.  The verdict line per
variant is computed from the means.  ``torch.ao.quantization`` is deprecated in recent torch
releases (its successor is the separate ``torchao`` package); this script is a measurement,
the library does not use it.

    python benchmarks/denoiser_int8.py [--calib cloth,cd]
        [--scenes balloons,feathers,flowers,chart_and_stuffed_toy] [--snr none,30]
        [--mask tsa] [--threads 2] [--out benchmarks/results/denoiser_int8.md]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import copy
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402
    RESULTS,
    clear_snr_cache,
    load_mask,
    pnp_fast_with,
    problem,
    score,
    snr_label,
    write_results,
)

import tensor_cosdi as tc  # noqa: E402

VARIANTS = ("float32", "int8 body", "int8")
#: Every CALIB_EVERY-th network call of a calibration run is kept.
CALIB_EVERY = 4


def _quantized(torch, net, inputs, whole: bool):
    """``net`` with its residual blocks (``whole``: also head and tail) in int8, calibrated on
    ``inputs`` (the head's inputs); returns a module ``(y, sigma) -> noise``."""
    import torch.ao.quantization as tq

    nn = torch.nn

    class Body(nn.Module):
        def __init__(self):
            super().__init__()
            self.quant, self.dequant = tq.QuantStub(), tq.DeQuantStub()
            self.head, self.tail = copy.deepcopy(net.head), copy.deepcopy(net.tail)
            self.blocks = nn.ModuleList()
            for b in net.body:
                m = nn.Module()
                m.a, m.relu, m.b = copy.deepcopy(b.a), nn.ReLU(), copy.deepcopy(b.b)
                m.add = nn.quantized.FloatFunctional()
                self.blocks.append(m)

        def forward(self, d):
            x = self.head(self.quant(d)) if whole else self.quant(self.head(d))
            for m in self.blocks:
                x = m.add.add(x, m.b(m.relu(m.a(x))))
            return self.dequant(self.tail(x)) if whole else self.tail(self.dequant(x))

    class Quantized(nn.Module):
        def __init__(self, body):
            super().__init__()
            self.body = body

        def forward(self, y, sigma):
            d = net.down(y)
            smap = sigma.reshape(-1, 1, 1, 1).to(d.dtype).expand(-1, 1, *d.shape[-2:])
            d = torch.cat([d, smap], dim=1)
            return net.up(net.linear(d) + self.body(d))

    torch.backends.quantized.engine = "x86"
    body = Body().eval()
    for m in body.blocks:
        tq.fuse_modules(m, [["a", "relu"]], inplace=True)
    body.qconfig = tq.get_default_qconfig("x86")
    if not whole:
        body.head.qconfig = body.tail.qconfig = None
    prepared = tq.prepare(body)
    with torch.no_grad():
        for d in inputs:
            prepared(d)
    return Quantized(tq.convert(prepared)).eval()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calib", default="cloth,cd", help="tuning scenes the int8 ranges come from")
    ap.add_argument("--scenes", default="balloons,feathers,flowers,chart_and_stuffed_toy")
    ap.add_argument("--snr", default="none,30")
    ap.add_argument("--mask", default="tsa")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=str(RESULTS / "denoiser_int8.md"))
    args = ap.parse_args(argv)
    calib, scenes = args.calib.split(","), args.scenes.split(",")
    for flag, names in (("--calib", calib), ("--scenes", scenes)):
        bad = [s for s in names if s not in tc.datasets.TUNE_SCENES]
        if bad:
            raise SystemExit(f"{flag} must be tuning scenes; not tuning scenes: {bad}")
    if set(calib) & set(scenes):
        raise SystemExit(f"--calib and --scenes overlap: {sorted(set(calib) & set(scenes))}")
    if args.threads < 1:
        raise SystemExit(f"--threads must be ≥ 1, got {args.threads}")
    snrs = [None if s == "none" else float(s) for s in args.snr.split(",")]
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    warnings.filterwarnings("ignore", module="torch.ao")  # its deprecation notices
    warnings.filterwarnings("ignore", message=".*quantiz.*")
    torch.set_num_threads(args.threads)
    mask = load_mask(args.mask)

    ref = SpectralDenoiser(precision="float32")
    inputs, calls = [], [0]

    def keep(_module, given):
        if calls[0] % CALIB_EVERY == 0:
            inputs.append(given[0].detach().clone())
        calls[0] += 1

    hook = ref.net.head.register_forward_pre_hook(keep)
    for scene in calib:
        for snr in sorted({None, *snrs}, key=lambda s: -1 if s is None else s):
            system, _, g = problem(scene, snr, mask)
            pnp_fast_with(system, g, ref)
    hook.remove()
    print(f"calibration: {len(inputs)} network inputs", flush=True)

    class Swapped(SpectralDenoiser):
        """The shipped denoiser with another network module (float32 in, float32 out)."""

        def __init__(self, module):
            super().__init__(precision="float32")
            self.module = module

        def _network(self, dev):
            return self.module, torch.float32

    dens = {
        "float32": ref,
        "int8 body": Swapped(_quantized(torch, ref.net, inputs, whole=False)),
        "int8": Swapped(_quantized(torch, ref.net, inputs, whole=True)),
    }
    psnr = {v: {s: [] for s in snrs} for v in VARIANTS}
    secs = {v: [] for v in VARIANTS}
    for scene in scenes:
        for snr in snrs:
            system, cube, g = problem(scene, snr, mask)
            for v in VARIANTS:
                clear_snr_cache()
                t0 = time.perf_counter()
                est = pnp_fast_with(system, g, dens[v])
                secs[v].append(time.perf_counter() - t0)
                psnr[v][snr].append(score(cube, est)["psnr"])
                print(v, scene, snr_label(snr), f"{psnr[v][snr][-1]:.2f}", flush=True)
    means = {v: [float(np.mean(psnr[v][s])) for s in snrs] for v in VARIANTS}
    lines = [
        f"# The denoiser's network in int8 inside `pnp_fast`: {', '.join(scenes)} "
        f"({args.mask} code)",
        "",
        f"Calibrated on {', '.join(calib)} ({len(inputs)} network inputs); torch "
        f"{torch.__version__}, engine x86, {args.threads} threads.",
        "",
        "| network | " + " | ".join(f"PSNR dB, {snr_label(s)}" for s in snrs)
        + " | median s | time / float32 |",
        "|---|" + "---|" * (len(snrs) + 2),
    ]  # fmt: skip
    base = float(np.median(secs["float32"]))
    for v in VARIANTS:
        cells = " | ".join(f"{m:.2f}" for m in means[v])
        median = float(np.median(secs[v]))
        lines.append(f"| {v} | {cells} | {median:.2f} | {median / base:.2f} |")
    lines.append("")
    for v in VARIANTS[1:]:
        worst = min(
            float(np.min(np.subtract(psnr[v][s], psnr["float32"][s]))) for s in snrs
        )  # fmt: skip
        diffs = ", ".join(
            f"{snr_label(s)} {m - r:+.2f} dB" for s, m, r in zip(snrs, means[v], means["float32"])
        )  # fmt: skip
        median = float(np.median(secs[v]))
        lines.append(
            f"* {v}: mean {diffs} (worst run {worst:+.2f} dB), median time "
            f"{median:.2f} s against {base:.2f} s ({'within' if median <= 5 else 'over'} "
            f"`pnp_fast`'s 5-s budget)."
        )
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
