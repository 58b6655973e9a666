"""Every imager and the main methods on a CUDA device through TensorLy's PyTorch backend,
against NumPy: what ``tests/test_torch_end_to_end.py`` checks on CPU tensors, on a GPU.

For each registered imager: a seeded 32×32×8 problem (``coffee``, 30 dB) is
reconstructed with NumPy and again from the same measurement as a CUDA tensor
(backend ``pytorch``); each method's cube must come back as a CUDA tensor, and
the table gives the largest difference relative to the NumPy cube's peak and
the two PSNRs.  Then the learned path at the protocol's size (256×256×28
SD-CASSI, the protocol's seeded random code, 2 px per band, a tuning scene when the
research data is there, else a synthetic one): ``pnp_gap`` and ``dcosnet``
times on the GPU (median of ``--repeats``) beside NumPy on the CPU with
``--threads`` threads.

    python benchmarks/cuda_backend.py [--repeats 3] [--threads 2]
        [--out benchmarks/results/cuda_backend.md]

Needs PyTorch with CUDA; never asserts anything: read the numbers.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import tensorly as tl

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, pnp_fast_settings, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402

METHODS = {
    "lsq": {},
    "gap_tv": {"max_iter": 5},
    "otd": {"max_iter": 5, "pan_iter": 5},
    "pnp_gap": {"max_iter": 3, "warm": "gap_tv", "warm_iter": 3},
}


def small_runs(torch, dev):
    rows = []
    for name in tc.systems.REGISTRY:
        p = tc.studies.make_problem(name, "coffee", shape=(32, 32), n_bands=8, snr_db=30)
        g = np.asarray(p.measurement)
        for method, opts in METHODS.items():
            if method == "pnp_gap" and len(p.system.cube_shape) != 3:
                opts = {**opts, "denoiser": "tv"}
            ref = np.asarray(tc.reconstruct(p.system, g, method, **opts).cube)
            with tl.backend_context("pytorch"):
                gt = torch.from_numpy(g).to(dev)
                cube = tc.reconstruct(p.system, gt, method, **opts).cube
            on_gpu = isinstance(cube, torch.Tensor) and cube.device.type == dev
            got = cube.detach().cpu().numpy() if isinstance(cube, torch.Tensor) else cube
            diff = float(np.max(np.abs(got - ref)) / max(np.max(np.abs(ref)), 1e-30))
            psnr = [tc.studies.score(p, c)["psnr"] for c in (ref, got)]
            rows.append((name, method, on_gpu, diff, *psnr))
            print(rows[-1], flush=True)
    return rows


def protocol_problem():
    rng = np.random.default_rng(2024)
    code = (rng.random((256, 256)) < 0.5).astype(np.float64)
    try:
        cube, wl = tc.datasets.load_hsi("balloons", "kaist", dtype="float32")
        what = "balloons (tuning scene)"
    except FileNotFoundError:
        cube = rng.random((256, 256, 28)).astype(np.float32)
        wl, what = None, "uniform random cube"
    system = tc.systems.SDCASSI(code, n_bands=28, shifts=2, wavelengths=wl)
    g = np.asarray(system.simulate(cube, rng=0), dtype=np.float32)
    return system, cube, g, what


def cpu_options(method, system, g):
    """``(method, options)`` that keep the network on the CPU (its default would be the GPU);
    ``pnp_fast`` runs as ``pnp_gap`` with its settings and a CPU denoiser."""
    if method == "dcosnet":
        return method, {"device": "cpu"}
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    if method == "pnp_fast":
        den = SpectralDenoiser(device="cpu", precision="auto")
        return "pnp_gap", {"denoiser": den, **pnp_fast_settings(system, g)}
    return method, {"denoiser": SpectralDenoiser(device="cpu")}


def timed(torch, system, g, method, device, repeats, dev):
    secs, cube = [], None
    for _ in range(repeats):
        sync = torch.cuda.synchronize if dev == "cuda" else (lambda: None)
        sync()
        t0 = time.perf_counter()
        if device == "torch":
            with tl.backend_context("pytorch"):
                cube = tc.reconstruct(system, torch.from_numpy(g).to(dev), method).cube
            sync()
            cube = cube.cpu().numpy()
        else:  # NumPy arrays, and the network on the CPU (its default would be the GPU)
            name, options = cpu_options(method, system, g)
            cube = tc.reconstruct(system, g, name, **options).cube
        secs.append(time.perf_counter() - t0)
    return float(np.median(secs)), np.asarray(cube)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=str(RESULTS / "cuda_backend.md"))
    ap.add_argument("--device", default="cuda", help="torch device (cpu: a dry run of the script)")
    args = ap.parse_args(argv)
    import torch

    dev = args.device
    if dev == "cuda" and not torch.cuda.is_available():
        raise SystemExit("no CUDA device: this benchmark needs one")
    torch.set_num_threads(args.threads)
    rows = small_runs(torch, dev)
    system, cube, g, what = protocol_problem()
    big = []
    for method in ("dcosnet", "pnp_fast", "pnp_gap"):
        for device in ("torch", "numpy"):
            sec, est = timed(torch, system, g, method, device, args.repeats, dev)
            psnr = tc.metrics.psnr(cube, np.clip(est, 0, 1), data_range=1.0)
            big.append((method, device, sec, psnr))
            print(big[-1], flush=True)
    name = torch.cuda.get_device_name(0) if dev == "cuda" else dev
    lines = [
        f"# Every imager on {name} (torch {torch.__version__})",
        "",
        "Seeded 32×32×8 problems (`coffee`, 30 dB); each method run from the NumPy "
        f"measurement and from the same measurement as a `{dev}` tensor.",
        "",
        f"| imager | method | cube on {dev} | max diff / peak | PSNR NumPy | PSNR {dev} |",
        "|---|---|---|---|---|---|",
    ]
    lines += [f"| {n} | {m} | {'yes' if ok else 'NO'} | {d:.1e} | {a:.2f} | {b:.2f} |"
              for n, m, ok, d, a, b in rows]  # fmt: skip
    n_ok = sum(r[2] for r in rows)
    worst = max(r[3] for r in rows)
    lines += [
        "",
        f"{n_ok} of {len(rows)} runs returned a `{dev}` tensor; largest difference "
        f"{worst:.1e} of the peak.",
        "",
        f"## The learned path at 256×256×28 ({what}, random code, noiseless)",
        "",
        f"| method | device | median s of {args.repeats} | PSNR dB |",
        "|---|---|---|---|",
    ]
    lines += [
        f"| {m} | {dev if d == 'torch' else f'NumPy + network on CPU ({args.threads} threads)'} | "
        f"{s:.2f} | {p:.2f} |"
        for m, d, s, p in big
    ]
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
