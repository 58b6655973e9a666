"""D-CoSNet's measurement scale with and without the floor on ``diag(AAᵀ)``.

The network runs on ``g / s`` (``learn.dcosnet.Sensing.scale``: the 99.9th
percentile of ``g / d``, ``d = diag(AAᵀ)``, read only where ``d`` is at least
``SCALE_MIN_D`` of its mean).  ``SCALE_MIN_D = 0`` is the earlier rule, which
read every pixel with ``d > 0``.  For each scene, code and SNR this prints
``s`` of the noisy measurement under both rules as a multiple of ``s`` of the
same scene's noiseless measurement under the current rule (1 = the network
sees the cube at its own level).  SD-CASSI 256×256×28 (KAIST bands), 2 px per
band, the real TSA mask and the seeded random code of ``real_spectra.py``,
noise seed 0.

    python benchmarks/dcosnet_scale.py [--scenes balloons,cd,clay,feathers]

Writes ``benchmarks/results/dcosnet_scale.md``; never asserts anything.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, load_mask, problem, write_results  # noqa: E402


def _scale(module, system, g, min_d: float) -> float:
    torch = importlib.import_module("torch")
    kept = module.SCALE_MIN_D
    module.SCALE_MIN_D = min_d
    try:
        return float(module.Sensing([system]).scale(torch.from_numpy(g)[None])[0])
    finally:
        module.SCALE_MIN_D = kept


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="balloons,cd,clay,feathers")
    ap.add_argument("--snr", default="30,20", help="noisy SNRs in dB")
    args = ap.parse_args(argv)
    module = importlib.import_module("tensor_cosdi.learn.dcosnet")
    floor = module.SCALE_MIN_D
    snrs = [float(s) for s in args.snr.split(",")]
    lines = [
        "# D-CoSNet's measurement scale with and without the floor on diag(AAᵀ)",
        "",
        f"`s` of the noisy measurement over `s` of the noiseless one (current rule, floor "
        f"{floor:g} × mean d); `floor 0` is the earlier rule.  SD-CASSI 256×256×28, 2 px/band, "
        "noise seed 0.",
        "",
        f"| scene | code | SNR dB | s / s_clean, floor 0 | s / s_clean, floor {floor:g} |",
        "|---|---|---|---:|---:|",
    ]
    worst = {}
    for mask_name in ("tsa", "random"):
        mask = load_mask(mask_name)
        for scene in args.scenes.split(","):
            system, _, clean = problem(scene, None, mask)
            ref = _scale(module, system, clean, floor)
            for snr in snrs:
                _, _, g = problem(scene, snr, mask)
                before = _scale(module, system, g, 0.0) / ref
                now = _scale(module, system, g, floor) / ref
                lines.append(f"| {scene} | {mask_name} | {snr:g} | {before:.2f} | {now:.2f} |")
                for rule, value in (("floor 0", before), (f"floor {floor:g}", now)):
                    key = (mask_name, rule)
                    worst[key] = max(worst.get(key, 0.0), abs(np.log10(value)))
    lines.append("")
    for (mask_name, rule), value in sorted(worst.items()):
        lines.append(
            f"* {mask_name}, {rule}: the noisy scale is within {10**value:.2f}× of the "
            "noiseless one on every scene and SNR."
        )
    write_results(Path(RESULTS) / "dcosnet_scale.md", lines)


if __name__ == "__main__":
    main()
