"""Reconstruction quality and speed: OTD vs WDCT-ADMM vs GAP-TV on every system (issue:
reconstruction core).

For each system at full size — spectral systems 256×256×28 (the real
``tsa_mask256.mat`` with a 2-px shift where a binary CASSI code is used:
SD-CASSI and CASSI-VSI; seeded codes elsewhere), C3SLFI 128×128×28 with 4×4
views — on several scenes and at 20 and 30 dB SNR, runs every method on the
same measurement and reports mean PSNR / SSIM / SAM and the median seconds.
The SD-CASSI speed ratio GAP-TV/OTD is a ratio of medians measured in the
same run.  Memory: peak bytes allocated by NumPy during one OTD
reconstruction of a 256×256×28 float32 SD-CASSI measurement (tracemalloc,
after a small warm-up run so that module imports are not counted; the
system's own operator caches are), in cube sizes, and the process' peak-RSS
growth.

    python benchmarks/reconstruction.py [--systems sd_cassi,cassi_vsi] [--scenes ...]
        [--snr 20,30] [--size 256] [--bands 28] [--mask PATH] [--out benchmarks/results]

Writes ``reconstruction.md`` (the table) and ``reconstruction.json`` (every
run) into ``--out``; never asserts anything — read the numbers.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import time
import tracemalloc
from pathlib import Path

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import studies

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_MASK = ROOT / ".." / "shared" / "data" / "masks" / "tsa_mask256.mat"
METHODS = ("otd", "wdct", "gap_tv")
# Options per SNR, the same for every system (documented in the README): noisier data, a larger ℓ1
# weight.
# GAP-TV keeps its defaults (doubling its TV weight at 20 dB made it collapse to 9.8 dB on the
# ColorChecker).
OPTIONS = {20.0: {"otd": {"lam": 0.3}, "wdct": {"lam": 0.3}}, 30.0: {}}
MASK_SYSTEMS = ("sd_cassi", "cassi_vsi")


def load_mask(path):
    import scipy.io

    return scipy.io.loadmat(path)["mask"].astype(np.float64)


def problem_for(system, scene, snr, args, mask):
    kw = dict(n_bands=args.bands, snr_db=snr, rng=args.seed)
    if system == "c3slfi":
        kw.update(shape=(args.size // 2, args.size // 2), views=(4, 4))
    else:
        kw.update(shape=(args.size, args.size))
    if system in MASK_SYSTEMS and mask is not None:
        kw.update(code=mask, shifts=2)
    elif system in ("sd_cassi", "cassi_vsi", "dd_cassi", "cassdi_dfa", "cs2li", "mu_cosdi"):
        kw.update(shifts=2)
    return studies.make_problem(system, scene, **kw)


def memory_probe(args, mask):
    small = studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30.0)
    tc.reconstruct(small.system, small.measurement, "otd")  # imports (not per-reconstruction)
    p = problem_for("sd_cassi", "chelsea", 30.0, args, mask)
    g = np.asarray(p.measurement, dtype=np.float32)
    cube_bytes = int(np.prod(p.system.cube_shape)) * 4
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    tracemalloc.start()
    tc.reconstruct(p.system, g, "otd")
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "cube_bytes": cube_bytes,
        "peak_traced_bytes": peak,
        "peak_cubes": peak / cube_bytes,
        "rss_growth_kib": rss1 - rss0,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--systems",
        default=",".join(s for s in studies.SYSTEMS if s not in ("dd_cassi", "dual_camera_cassi")),
    )
    ap.add_argument("--scenes", default="colorchecker,chelsea,coffee,astronaut")
    ap.add_argument("--snr", default="20,30")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--bands", type=int, default=28)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--mask", default=str(DEFAULT_MASK))
    ap.add_argument("--no-memory", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    ap.add_argument("--name", default="reconstruction", help="file stem of the outputs")
    args = ap.parse_args(argv)
    mask = load_mask(args.mask) if Path(args.mask).exists() and args.size == 256 else None
    systems = args.systems.split(",")
    scenes = args.scenes.split(",")
    snrs = [float(s) for s in args.snr.split(",")]
    methods = args.methods.split(",")
    runs = []
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    partial = out / f"{args.name}.partial.json"
    mem = None if args.no_memory else memory_probe(args, mask)
    if mem:
        print(
            f"memory: OTD peak {mem['peak_traced_bytes'] / 2**20:.0f} MiB traced = "
            f"{mem['peak_cubes']:.1f} cubes; "
            f"RSS growth {mem['rss_growth_kib'] / 1024:.0f} MiB",
            flush=True,
        )
    for system in systems:
        for snr in snrs:
            for scene in scenes:
                p = problem_for(system, scene, snr, args, mask)
                g = np.asarray(p.measurement, dtype=np.float32)
                for m in methods:
                    opts = OPTIONS.get(snr, {}).get(m, {})
                    t0 = time.perf_counter()
                    res = tc.reconstruct(p.system, g, m, **opts)
                    sec = time.perf_counter() - t0
                    row = {
                        "system": system,
                        "scene": scene,
                        "snr_db": snr,
                        "method": m,
                        "seconds": sec,
                        "iterations": res.iterations,
                        "cube": list(p.system.cube_shape),
                        "options": opts,
                        **studies.score(p, res.cube),
                    }
                    runs.append(row)
                    print(
                        f"{system:10s} {scene:12s} {snr:4.0f} dB {m:7s} PSNR {row['psnr']:6.2f} "
                        f"SSIM {row['ssim']:.3f} "
                        f"SAM {row['sam']:5.2f} {sec:7.2f} s",
                        flush=True,
                    )
                    # Every run is saved as it finishes, so a long benchmark that is interrupted
                    # keeps what it measured.
                    partial.write_text(json.dumps({"memory": mem, "runs": runs}, indent=1))
    table = summarise(runs, systems, snrs, methods)
    header = (
        f"Machine: {platform.processor() or platform.machine()}, {platform.python_version()}, "
        f"NumPy {np.__version__}; tensor_cosdi {tc.__version__}; float32; seed {args.seed}; "
        f"scenes: {', '.join(scenes)}; mask: "
        f"{'tsa_mask256.mat, 2 px/band' if mask is not None else 'seeded'}.\n"
    )
    if mem:
        header += (
            f"\nMemory: one OTD reconstruction (SD-CASSI {args.size}×{args.size}×{args.bands} "
            f"float32) peaks at "
            f"{mem['peak_traced_bytes'] / 2**20:.0f} MiB of NumPy allocations = "
            f"{mem['peak_cubes']:.1f} cube sizes "
            f"(process RSS grew {mem['rss_growth_kib'] / 1024:.0f} MiB).\n"
        )
    (out / f"{args.name}.md").write_text(header + "\n" + table + "\n")
    (out / f"{args.name}.json").write_text(json.dumps({"memory": mem, "runs": runs}, indent=1))
    partial.unlink(missing_ok=True)
    print(header)
    print(table)


def summarise(runs, systems, snrs, methods):
    lines = [
        "| system | cube | SNR | method | PSNR dB | SSIM | SAM ° | median s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for system in systems:
        for snr in snrs:
            for m in methods:
                rs = [
                    r
                    for r in runs
                    if r["system"] == system and r["snr_db"] == snr and r["method"] == m
                ]
                if not rs:
                    continue
                cube = "×".join(map(str, rs[0]["cube"]))
                lines.append(
                    f"| {system} | {cube} | {snr:g} dB | {m} | "
                    f"{np.mean([r['psnr'] for r in rs]):.2f} | "
                    f"{np.mean([r['ssim'] for r in rs]):.3f} | "
                    f"{np.mean([r['sam'] for r in rs]):.2f} | "
                    f"{np.median([r['seconds'] for r in rs]):.2f} |"
                )
    sd = {
        m: [r["seconds"] for r in runs if r["system"] == "sd_cassi" and r["method"] == m]
        for m in methods
    }
    if sd.get("otd") and sd.get("gap_tv"):
        lines.append("")
        lines.append(
            f"SD-CASSI: OTD median {np.median(sd['otd']):.2f} s, GAP-TV median "
            f"{np.median(sd['gap_tv']):.2f} s, "
            f"ratio {np.median(sd['gap_tv']) / np.median(sd['otd']):.1f}× (same run)."
        )
    return "\n".join(lines)


if __name__ == "__main__":
    main()
