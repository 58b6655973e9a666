"""ADMM's over-relaxation inside the plug-and-play methods on every imager, noisy data.

``pnp_fast`` and ``pnp_gap`` take ADMM on a noisy measurement; their ``relax`` was
cross-validated on SD-CASSI spectral cubes only (``benchmarks/results/cv_pnp_fast_relax.md``).
This script runs each method with every ``--relax`` value on each registered imager's seeded
problem (``studies.make_problem``, ColorChecker or ``--scenes``, 64×64, 16 bands, ``--snr``
dB, one noise draw), one run each: a check that the default does no harm on the other imagers (their
cubes of more axes, their own closed-form x-steps), not a choice.

    python benchmarks/relax_systems.py [--methods pnp_fast,pnp_gap] [--relax 1.0,1.9]
        [--snr 30] [--systems sd_cassi,...] [--scenes colorchecker,...] [--name relax_systems]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import IMAGERS, RESULTS, positive_numbers, write_results  # noqa: E402

import tensor_cosdi as tc  # noqa: E402

METHODS = ("pnp_fast", "pnp_gap")
#: A difference below −LOSS_DB is named as a loss in the file's last line.
LOSS_DB = 0.3


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--relax", default="1.0,1.9")
    ap.add_argument("--snr", type=float, default=30.0)
    ap.add_argument("--systems", default=",".join(IMAGERS))
    ap.add_argument("--scenes", default="colorchecker")
    ap.add_argument("--name", default="relax_systems")
    args = ap.parse_args(argv)
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", args.name) or args.name.startswith("."):
        raise SystemExit(
            f"--name: expected a file name of letters, digits, _ . -, got {args.name!r}"
        )
    systems = [m for m in args.systems.split(",") if m]
    unknown = sorted(set(systems) - set(IMAGERS))
    if unknown or not systems:
        raise SystemExit(f"--systems: expected some of {','.join(IMAGERS)}, got {args.systems!r}")
    scenes = [m for m in args.scenes.split(",") if m]
    if not scenes:
        raise SystemExit(f"--scenes: expected scene names, comma-separated, got {args.scenes!r}")
    methods = [m for m in args.methods.split(",") if m]
    bad = sorted(set(methods) - set(METHODS))
    if bad or not methods:
        raise SystemExit(f"--methods: expected some of {','.join(METHODS)}, got {args.methods!r}")
    relaxes = positive_numbers(args.relax, "--relax")
    if any(not 0 < a < 2 for a in relaxes) or len(relaxes) < 2:
        raise SystemExit(f"--relax: expected two or more numbers in (0, 2), got {args.relax!r}")
    if not args.snr > 0:
        raise SystemExit(f"--snr: expected a positive number of dB, got {args.snr}")
    base = relaxes[0]
    head = [f"{m}, relax {a:g}" for m in methods for a in relaxes]
    lines = [
        "# ADMM's over-relaxation on every imager",
        "",
        f"{', '.join(scenes)}; 64×64, 16 bands, {args.snr:g} dB (`studies.make_problem`, seed 0); "
        "PSNR dB with the cube's peak as data range, one run each; the difference is "
        f"against relax {base:g}.",
        "",
        "| system | scene | cube axes | "
        + " | ".join(head)
        + " | "
        + " | ".join(f"{m}: relax {a:g} − {base:g} dB" for m in methods for a in relaxes[1:])
        + " |",
        "|---|---|---|" + "---|" * len(head) + "---|" * (len(methods) * (len(relaxes) - 1)),
    ]
    worst = {}  # system -> lowest difference of any method, scene and relax
    for name, scene in ((n, sc) for n in systems for sc in scenes):
        p = tc.studies.make_problem(name, scene, snr_db=args.snr, rng=0)
        peak = float(np.max(p.cube))
        psnr = {}
        for m in methods:
            for a in relaxes:
                r = tc.reconstruct(p.system, p.measurement, m, relax=a)
                psnr[m, a] = tc.metrics.psnr(p.cube, np.asarray(r.cube), data_range=peak)
        diffs = [psnr[m, a] - psnr[m, base] for m in methods for a in relaxes[1:]]
        worst[name] = min(worst.get(name, np.inf), *diffs)
        lines.append(
            f"| {name} | {scene} | {len(p.system.cube_shape)} | "
            + " | ".join(f"{psnr[m, a]:.2f}" for m in methods for a in relaxes)
            + " | "
            + " | ".join(f"{d:+.2f}" for d in diffs)
            + " |"
        )
        print(lines[-1], flush=True)
    lost = [f"{n} ({d:+.2f} dB)" for n, d in worst.items() if d < -LOSS_DB]
    kept = [f"{n} {d:+.2f}" for n, d in worst.items() if d >= -LOSS_DB]
    lines += [
        "",
        f"Systems where a relaxation cost more than {LOSS_DB:g} dB against {base:g} on some "
        f"scene and method: {', '.join(lost) if lost else 'none'}"
        + (f"; elsewhere the worst case: {', '.join(kept)} dB." if kept else "."),
    ]
    write_results(RESULTS / f"{args.name}.md", lines)


if __name__ == "__main__":
    main()
