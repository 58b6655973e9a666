"""Depth-aware priors (issue: reconstruction quality, item 6): what they change, measured.

1. CASSDI-DFA: ``plane_support`` (one depth plane per pixel) on and off in
   GAP-TV and OTD — PSNR / SSIM of the cube and the depth-plane accuracy.
2. CS2LI and Mu-CoSDI (structured light): the joint OTD prior over the 4-D
   cube ``(x, y, λ, t)`` against priors per fringe pattern — four
   independent 3-D OTD problems, and one ADMM whose pattern mode has the
   identity basis (patterns independent, spatial and spectral bases shared)
   or a fixed DCT (not re-learned).

Seeded scenes of :func:`tensor_cosdi.studies.make_problem` (64×64, 8 bands,
30 dB).  ``python benchmarks/depth_priors.py``; prints Markdown tables; never
asserts anything.
"""

from __future__ import annotations

import time

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import studies
from tensor_cosdi.solvers.otd import initial_bases, tucker_admm

SCENES = ("chelsea", "coffee")


def dfa_table():
    print("| scene | method | plane_support | PSNR dB | SSIM | plane accuracy | s |")
    print("|---|---|---|---|---|---|---|")
    for scene in SCENES:
        p = studies.make_problem("cassdi_dfa", scene, shape=(64, 64), n_bands=8, snr_db=30, rng=0)
        for method in ("gap_tv", "otd"):
            for support in ("auto", False):
                r = tc.reconstruct(p.system, p.measurement, method, plane_support=support)
                x = np.asarray(r.cube)
                acc = float(((x**2).sum(axis=2).argmax(axis=2) == p.depth).mean())
                s = studies.score(p, x)
                print(
                    f"| {scene} | {method} | {support} | {s['psnr']:.2f} | {s['ssim']:.3f} | "
                    f"{acc:.3f} | {r.seconds:.1f} |"
                )


def fringe_table():
    print("\n| system | scene | joint OTD | per pattern (4 OTDs) | t: identity | t: fixed DCT |")
    print("|---|---|---|---|---|---|")
    for name in ("cs2li", "mu_cosdi"):
        for scene in SCENES:
            p = studies.make_problem(name, scene, shape=(64, 64), n_bands=8, snr_db=30, rng=0)
            s, g = p.system, np.asarray(p.measurement)
            psnr = {}
            t0 = time.perf_counter()
            psnr["joint"] = studies.score(p, tc.reconstruct(s, g, "otd").cube)["psnr"]
            joint_s = time.perf_counter() - t0
            one = type(s)(s.code, n_bands=s.cube_shape[2], shifts=s.shifts, n_patterns=1)
            t0 = time.perf_counter()
            cube = np.concatenate(
                [np.asarray(tc.reconstruct(one, g[..., t : t + 1], "otd").cube) for t in
                 range(g.shape[2])],
                axis=3,
            )  # fmt: skip
            per_s = time.perf_counter() - t0
            psnr["per"] = studies.score(p, cube)["psnr"]
            peak = float(np.abs(g).max())
            bases, start = initial_bases(s, g / peak, spatial="panchromatic")
            eye = {**bases, 3: np.eye(s.cube_shape[3])}
            for key, b in (("identity", eye), ("dct", bases)):
                x, _, _ = tucker_admm(s, g / peak, b, start=start, update_modes=(0, 1, 2))
                psnr[key] = studies.score(p, np.asarray(x) * peak)["psnr"]
            print(
                f"| {name} | {scene} | {psnr['joint']:.2f} ({joint_s:.1f} s) | "
                f"{psnr['per']:.2f} ({per_s:.1f} s) | {psnr['identity']:.2f} | {psnr['dct']:.2f} |"
            )


if __name__ == "__main__":
    dfa_table()
    fringe_table()
