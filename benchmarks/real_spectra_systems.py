"""Every imager on real spectra: the ``cave.<name>`` scenes through ``studies.make_problem``.

The SD-CASSI protocol of ``real_spectra.py`` judges the priors on one
system.  This runs every system of ``systems.REGISTRY`` on the held-back
real scenes (:data:`tensor_cosdi.datasets.REPORT_SCENES`, centred crops,
bands between 450 and 650 nm, seeded codes, 30 dB by default) with the
generic methods and each system's own thesis algorithm, scored by
:func:`tensor_cosdi.studies.score` (PSNR / SSIM with the truth's peak as
data range, SAM).  Depth-bearing cubes (DFA planes, fringe patterns) are
scored as whole cubes.

Every run is appended to ``<out>/<name>.json`` as it finishes and skipped
when already there (a killed run resumes); ``<out>/<name>.md`` holds the
means over scenes and median seconds.

    python benchmarks/real_spectra_systems.py [--systems a,b] [--methods otd,gap_tv,pnp_gap]
        [--size 96] [--bands 16] [--snr 30] [--name real_spectra_systems]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets

ROOT = Path(__file__).resolve().parents[1]
#: The thesis' own algorithm per system, run beside the generic methods.
OWN = {"cassi_vsi": "avsi", "cassdi_dfa": "dfa", "cs2li": "pnp_admm", "mu_cosdi": "pnp_admm"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--systems", default=",".join(tc.systems.REGISTRY))
    ap.add_argument("--methods", default="gap_tv,otd,pnp_gap")
    ap.add_argument("--own", action=argparse.BooleanOptionalAction, default=True)
    ap.add_argument("--scenes", default=",".join(datasets.REPORT_SCENES))
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--bands", type=int, default=16)
    ap.add_argument("--snr", default="30", help="dB, or 'none' for noiseless")
    ap.add_argument("--name", default="real_spectra_systems")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    snr = None if args.snr.lower() == "none" else float(args.snr)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    store = out / f"{args.name}.json"
    runs = json.loads(store.read_text())["runs"] if store.exists() else []
    done = {(r["system"], r["scene"], r["method"]) for r in runs}
    systems = args.systems.split(",")
    methods = {
        s: args.methods.split(",") + ([OWN[s]] if args.own and s in OWN else []) for s in systems
    }
    for system in systems:
        for scene in args.scenes.split(","):
            p = tc.studies.make_problem(
                system, f"cave.{scene}", shape=(args.size, args.size), n_bands=args.bands,
                snr_db=snr, rng=0,
            )  # fmt: skip
            for m in methods[system]:
                if (system, scene, m) in done:
                    continue
                t0 = time.perf_counter()
                cube = tc.reconstruct(p.system, p.measurement, m).cube
                sec = time.perf_counter() - t0
                sc = tc.studies.score(p, cube)
                row = {"system": system, "scene": scene, "method": m, "seconds": sec}
                row.update({k: float(sc[k]) for k in ("psnr", "ssim", "sam")})
                runs.append(row)
                done.add((system, scene, m))
                msg = f"{system:18s} {scene:22s} {m:9s} PSNR {row['psnr']:6.2f} "
                print(
                    msg + f"SSIM {row['ssim']:.3f} SAM {row['sam']:5.2f} {sec:6.2f} s", flush=True
                )
                store.write_text(json.dumps({"runs": runs}, indent=1))
    lines = [
        f"Every system on real spectra: cave.<scene> crops {args.size}×{args.size}, "
        f"{args.bands} bands 450-650 nm, "
        f"{'noiseless' if snr is None else f'{snr:g} dB'}, seeded codes (rng 0); scenes "
        f"{args.scenes}; tensor_cosdi {tc.__version__}.  Mean PSNR dB / SSIM / SAM ° "
        "(median s) over the scenes.\n",
        "| system | " + " | ".join(sorted({m for ms in methods.values() for m in ms})) + " |",
    ]
    cols = sorted({m for ms in methods.values() for m in ms})
    lines.append("|---" * (len(cols) + 1) + "|")
    for system in systems:
        cells = []
        for m in cols:
            rs = [r for r in runs if r["system"] == system and r["method"] == m]
            mean = {k: np.mean([r[k] for r in rs]) if rs else 0 for k in ("psnr", "ssim", "sam")}
            sec = np.median([r["seconds"] for r in rs]) if rs else 0
            cells.append(
                f"{mean['psnr']:.2f} / {mean['ssim']:.3f} / {mean['sam']:.1f} ({sec:.1f})"
                if rs
                else "—"
            )
        lines.append(f"| {system} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    (out / f"{args.name}.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
