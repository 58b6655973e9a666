"""The light gate of OTD's first stage: how rough the fitted mean spectrum reads, by light.

``pan_spectrum="gated"`` (:func:`tensor_cosdi.solvers.panchromatic.panchromatic_estimate`)
fits the scene's mean spectrum part-way through the first stage
(:data:`~tensor_cosdi.solvers.panchromatic.GATE_FRACTION` of its iterations) and weights
the remaining iterations' spectral atoms by it only when the spectrum reads rough
(:func:`~tensor_cosdi.solvers.subspace.spectral_roughness` above a threshold: on a clean
measurement :data:`~tensor_cosdi.solvers.subspace.ROUGH_SPECTRUM`, on a noisy one the higher
:data:`~tensor_cosdi.solvers.panchromatic.GATE_ABOVE_NOISY`, see
:func:`~tensor_cosdi.solvers.panchromatic.gate_above` and ``light_gate.py``): a light with
sharp lines.  This
script reads that roughness exactly as the gate does (the first stage's iterates up to the
gate do not depend on it) on every tuning scene, as it is and lit by each ``--lights``
illuminant, noiseless, at 30 and at 20 dB (the real-spectra protocol: SD-CASSI,
256×256×28, 2 px per band, ``--mask``), and counts the views above the clean threshold.
The report scenes are not read.

    python benchmarks/spectral_roughness.py [--lights A,D65,LED-B3,FL11,FL2] [--mask tsa]
                                            [--tv-steps 5]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, load_mask, problem, snr_label, write_results  # noqa: E402

from tensor_cosdi import datasets  # noqa: E402
from tensor_cosdi.solvers import panchromatic, subspace  # noqa: E402


def reading(scene, light, snr, mask, tv_steps, pan_iter) -> float:
    system, _, g = problem(scene, snr, mask, illuminant=light)
    at = max(1, round(pan_iter * panchromatic.GATE_FRACTION))
    x = subspace.subspace_gap_tv(
        system, g, max_iter=at, tv_steps=tv_steps,
        tv_weight=panchromatic.pan_weight_for(system, g, "auto"),
    )  # fmt: skip
    return subspace.gate_spectrum(system, g, x, "λ")[1]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lights", default="A,D65,LED-B3,FL11,FL2")
    ap.add_argument("--mask", default="tsa", choices=("tsa", "random"))
    ap.add_argument("--tv-steps", type=int, default=5, help="the first stage's TV steps")
    ap.add_argument("--pan-iter", type=int, default=90, help="the first stage's iterations")
    ap.add_argument("--scenes", default=None, help="comma list (default: every tuning scene)")
    ap.add_argument("--out", default=str(RESULTS / "spectral_roughness.md"))
    args = ap.parse_args(argv)
    lights = [None] + [s for s in args.lights.split(",") if s]
    scenes = args.scenes.split(",") if args.scenes else list(datasets.TUNE_SCENES)
    bad = [s for s in scenes if s in datasets.REPORT_SCENES]
    if bad:
        raise SystemExit(f"--scenes: {bad} are report scenes; the gate is read on tuning scenes")
    mask = load_mask(args.mask)
    snrs = (None, 30.0, 20.0)
    rows = {}
    for light in lights:
        for snr in snrs:
            vals = [reading(s, light, snr, mask, args.tv_steps, args.pan_iter) for s in scenes]
            rows[light, snr] = np.array(vals)
            print(light, snr_label(snr), np.round(vals, 3), flush=True)
    thr = subspace.ROUGH_SPECTRUM
    lines = [
        "# The light gate: roughness of the fitted mean spectrum",
        "",
        f"{len(scenes)} tuning scenes, SD-CASSI 256×256×28, {args.mask} code; read after "
        f"{max(1, round(args.pan_iter * panchromatic.GATE_FRACTION))} of {args.pan_iter} "
        f"first-stage iterations ({args.tv_steps} TV steps each).  The gate weights the atoms "
        f"above {thr:g} (`ROUGH_SPECTRUM`).",
        "",
        "| light | SNR | min | median | max | views above the gate |",
        "|---|---|---|---|---|---|",
    ]
    for (light, snr), v in rows.items():
        lines.append(
            f"| {light or 'none (reflectance)'} | {snr_label(snr)} | {v.min():.3f} | "
            f"{np.median(v):.3f} | {v.max():.3f} | {(v > thr).sum()} of {v.size} |"
        )
    unlit = np.concatenate([rows[None, s] for s in snrs])
    lines += [
        "",
        f"Unlit views above the gate: {(unlit > thr).sum()} of {unlit.size} "
        f"(highest reading {unlit.max():.3f}).",
    ]
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
