"""The thesis' claim "D-CoSNet reconstructs ≈ 600× faster than PnP-ADMM" (§7.3), on our code.

Mu-CoSDI (monocular: the cube is ``(Nx, Ny, Nλ)``), 256×256×28, a seeded
binary code sheared by 1 px per band, the held-back real scene ``face``
resampled to the KAIST bands, noiseless.  Times, medians of ``--repeats``
runs in one process, one after the other:

* ``pnp_admm`` (the thesis' PnP-ADMM of Ch. 6, Alg. 6) at its defaults
  (TV denoiser, 40 iterations);
* D-CoSNet inference (one forward pass, weights loaded before timing) with
  the shipped architecture (3 stages, arms 16, U-Net 32).  Speed does not
  depend on the weights' values; for Mu-CoSDI no weights are shipped, so
  this network is untrained (its PSNR is printed but means nothing), and
  SD-CASSI is timed with the shipped weights beside it.

    python benchmarks/dcosnet_speed.py [--repeats 3] [--threads 2]

Prints a Markdown table; never asserts anything.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets, metrics


def median_time(fn, repeats):
    out, times = None, []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    import torch

    from tensor_cosdi.learn.dcosnet import DCoSNet, Sensing, build_dcosnet

    torch.set_num_threads(args.threads)
    cube, _ = datasets.load_hsi("face", "kaist", dtype="float32")
    nb = cube.shape[2]
    code = (np.random.default_rng(0).random((256, 256 + nb - 1)) < 0.5).astype(np.float64)
    mu = tc.systems.MuCoSDI(code, n_bands=nb, shifts=1, modality="monocular")
    g = mu.forward(cube.astype(np.float64)).astype(np.float32)
    rows = []

    def psnr(est):
        return metrics.psnr(cube, np.asarray(est), data_range=1.0)

    res, t_pnp = median_time(lambda: tc.reconstruct(mu, g, "pnp_admm"), args.repeats)
    rows.append(("Mu-CoSDI", "pnp_admm (defaults)", t_pnp, psnr(res.cube)))

    net = build_dcosnet(torch, nb, 3, 16, 32).eval()
    sen = Sensing([mu])
    gt = torch.from_numpy(g)[None]

    def forward():
        with torch.no_grad():
            return net(gt / sen.scale(gt)[:, None, None], sen)[0]

    forward()  # warm-up
    _, t_net = median_time(forward, max(args.repeats, 5))
    rows.append(("Mu-CoSDI", "D-CoSNet forward (untrained)", t_net, float("nan")))

    import scipy.io
    from real_spectra import MASK

    mask = scipy.io.loadmat(MASK)["mask"].astype(np.float64)
    sd = tc.systems.SDCASSI(mask, n_bands=nb, shifts=2)
    g_sd = sd.forward(cube.astype(np.float64)).astype(np.float32)
    rec = DCoSNet(device="cpu")
    rec(sd, g_sd)  # load + warm-up
    est, t_sd = median_time(lambda: rec(sd, g_sd), max(args.repeats, 5))
    rows.append(("SD-CASSI", "dcosnet (shipped weights)", t_sd, psnr(est)))
    res, t_gap = median_time(lambda: tc.reconstruct(sd, g_sd, "pnp_gap"), 1)
    rows.append(("SD-CASSI", "pnp_gap (learned denoiser)", t_gap, psnr(res.cube)))

    print(
        f"256×256×{nb}, scene face, noiseless; {platform.machine()}, {args.threads} torch "
        f"threads, torch {torch.__version__}\n"
    )
    print("| system | method | median s | PSNR dB |\n|---|---|---|---|")
    for system, name, sec, psnr in rows:
        print(f"| {system} | {name} | {sec:.3f} | {psnr:.2f} |")
    print(f"\nPnP-ADMM / D-CoSNet on Mu-CoSDI: {t_pnp / t_net:.0f}×")
    print(f"PnP-GAP / D-CoSNet on SD-CASSI: {t_gap / t_sd:.0f}×")


if __name__ == "__main__":
    main()
