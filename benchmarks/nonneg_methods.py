"""Non-negativity, method by method: each method with ``nonneg=True`` against ``nonneg=False``.

Every method that takes ``nonneg`` runs on its own imager (CASSI-VSI for
``avsi``, CASSDI-DFA for ``dfa``, CASSDI-DFA with PSFs for ``split_tv``,
Lytro-CASSI for ``lytro``, CS2LI and Mu-CoSDI for ``pnp_admm``, SD-CASSI for
the others; ``dcosnet`` with its shipped weights' 28 bands and 2 px per
band) on real tuning scenes (never the report scenes), centred crops,
noiseless and 30 dB.  Both estimates are clipped at 0 before scoring, so the
table measures what projecting *inside* the iterations adds beyond clipping
the result; ``neg`` is the share of negative voxels the method returns
with ``nonneg=False``.  The verdict per method is computed from the
differences (more than 0.1 dB on average either way decides) and checked
against the method's registered default.

Runs are appended to ``<out>/nonneg_methods.json`` as they finish, each with
the commit it ran at (a killed run resumes; a cached row is not run again —
delete a method's rows to re-run it); ``<out>/nonneg_methods.md`` holds the
table and the commits its rows were computed at.

    python benchmarks/nonneg_methods.py [--methods avsi,dfa] [--scenes balloons,clay]
        [--size 48] [--bands 16]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, provenance, provenance_lines  # noqa: E402

import tensor_cosdi as tc  # noqa: E402

#: ``(method, imager)`` pairs measured; ``"cassdi_dfa_psf"`` is CASSDI-DFA with a lens' PSFs.
CASES = (
    ("lsq", "sd_cassi"),
    ("avsi", "cassi_vsi"),
    ("dfa", "cassdi_dfa"),
    ("split_tv", "cassdi_dfa_psf"),
    ("otd_nl", "sd_cassi"),
    ("lytro", "lytro_cassi"),
    ("pnp_admm", "cs2li"),
    ("pnp_admm", "mu_cosdi"),
    ("dcosnet", "sd_cassi"),
)
#: Default tuning scenes (one per fold of ``datasets.tune_folds(4)`` but the first).
SCENES = ("balloons", "clay", "feathers")


def problem(imager: str, scene: str, size: int, bands: int, snr):
    """``(system, cube, measurement)`` of ``scene`` on ``imager`` (seeded codes and noise)."""
    if imager == "cassdi_dfa_psf":
        from tensor_cosdi import optics
        from tensor_cosdi.systems import CASSDIDFA

        p = tc.studies.make_problem(
            "cassdi_dfa", f"cave.{scene}", shape=(size, size), n_bands=bands, snr_db=None, rng=0
        )
        wl = p.system.wavelengths
        lens = optics.Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
        depths = np.linspace(800.0, 1300.0, p.system.cube_shape[3])
        psfs = optics.psf_stack(wl, depths, lens=lens, zernike={6: 0.25}, size=9, min_share=None)
        system = CASSDIDFA(p.system.codes, n_bands=bands, psfs=psfs, wavelengths=wl)
        return system, p.cube, system.simulate(p.cube, snr_db=snr, rng=0)
    if imager == "sd_cassi" and bands == 28:  # dcosnet's shipped weights: 2 px per band
        p = tc.studies.make_problem(
            "sd_cassi", f"cave.{scene}", shape=(size, size), n_bands=28, snr_db=snr, rng=0,
            shifts=2,
        )  # fmt: skip
    else:
        p = tc.studies.make_problem(
            imager, f"cave.{scene}", shape=(size, size), n_bands=bands, snr_db=snr, rng=0
        )
    return p.system, p.cube, p.measurement


def psnr(truth, est) -> float:
    truth = np.asarray(truth, dtype=np.float64)
    est = np.clip(np.asarray(est, dtype=np.float64), 0, None)
    flat = truth.shape[:2] + (-1,)
    return tc.metrics.psnr(truth.reshape(flat), est.reshape(flat), data_range=float(truth.max()))


def verdict(method: str, diffs) -> str:
    """What the differences say, and whether the method's registered default agrees."""
    mean = float(np.mean(diffs))
    default = tc.solvers.METHODS[method].defaults["nonneg"]
    if mean < -0.1:
        said, fits = f"the projection costs {mean:+.2f} dB on average", not default
    elif mean > 0.1:
        said, fits = f"the projection adds {mean:+.2f} dB on average", default
    else:
        said, fits = f"no difference beyond ±0.1 dB on average ({mean:+.2f})", True
    word = "on" if default else "off"
    return f"{said}; the default ({word}) {'agrees' if fits else 'DISAGREES'}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(dict.fromkeys(m for m, _ in CASES)))
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--size", type=int, default=48)
    ap.add_argument("--bands", type=int, default=16)
    ap.add_argument("--snr", default="none,30", help="comma list; 'none' = noiseless")
    ap.add_argument("--name", default="nonneg_methods")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    try:
        tc.datasets.data_dir()
    except FileNotFoundError as exc:
        raise SystemExit(f"nonneg_methods.py needs the research scenes: {exc}") from None
    methods = args.methods.split(",")
    unknown = sorted(set(methods) - {m for m, _ in CASES})
    if unknown:
        raise SystemExit(f"--methods: {', '.join(unknown)} not among {[m for m, _ in CASES]}")
    has_torch = importlib.util.find_spec("torch") is not None
    snrs = [None if s.strip().lower() == "none" else float(s) for s in args.snr.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    store = out / f"{args.name}.json"
    runs = json.loads(store.read_text())["runs"] if store.exists() else []
    done = {(r["method"], r["imager"], r["scene"], r["snr_db"], r["nonneg"]) for r in runs}
    commit = provenance()["commit"]
    for method, imager in CASES:
        if method not in methods or (method == "dcosnet" and not has_torch):
            continue
        bands = 28 if method == "dcosnet" else args.bands
        for scene in args.scenes.split(","):
            for snr in snrs:
                system = None
                for nonneg in (True, False):
                    if (method, imager, scene, snr, nonneg) in done:
                        continue
                    if system is None:
                        system, cube, g = problem(imager, scene, args.size, bands, snr)
                    t0 = time.perf_counter()
                    est = tc.reconstruct(system, g, method, nonneg=nonneg).cube
                    sec = time.perf_counter() - t0
                    arr = np.asarray(est)
                    row = {
                        "method": method, "imager": imager, "scene": scene, "snr_db": snr,
                        "nonneg": nonneg, "psnr": psnr(cube, est), "seconds": sec,
                        "negative_share": float(np.mean(arr < 0)), "commit": commit,
                    }  # fmt: skip
                    runs.append(row)
                    done.add((method, imager, scene, snr, nonneg))
                    print(
                        f"{method:9s} {imager:15s} {scene:10s} {str(snr):5s} nonneg={nonneg!s:5s} "
                        f"PSNR {row['psnr']:6.2f}  neg {row['negative_share']:.3f}  {sec:6.1f} s",
                        flush=True,
                    )
                    store.write_text(json.dumps({"runs": runs}, indent=1))
    counts = {}
    for r in runs:
        c = r.get("commit", "not recorded")
        counts[c] = counts.get(c, 0) + 1
    rows_at = ", ".join(f"{c} ({n} rows)" for c, n in counts.items())
    text = (
        table(runs)
        + f"\n\nRows computed at commit {rows_at}.  \n"
        + provenance_lines(provenance())
        + "\n"
    )
    (out / f"{args.name}.md").write_text(text)
    print(text)


def table(runs) -> str:
    """The Markdown table: per method and imager, PSNR on and off per scene × SNR, the
    difference and the computed verdict."""
    by = {}
    for r in runs:
        by.setdefault((r["method"], r["imager"]), {})[(r["scene"], r["snr_db"], r["nonneg"])] = r
    lines = [
        "# Non-negativity inside each method",
        "",
        "PSNR (dB, truth's peak; both estimates clipped at 0) with `nonneg=True` / `False`;",
        "`neg`: share of negative voxels returned with `nonneg=False`.",
        "",
        "| method | imager | scene | SNR | on | off | on − off | neg |",
        "|---|---|---|---|---|---|---|---|",
    ]
    verdicts = []
    for (method, imager), rows in by.items():
        diffs = []
        for (scene, snr, nonneg), r in sorted(rows.items(), key=lambda kv: str(kv[0])):
            if not nonneg or (scene, snr, False) not in rows:
                continue
            off = rows[(scene, snr, False)]
            d = r["psnr"] - off["psnr"]
            diffs.append(d)
            snr_txt = "noiseless" if snr is None else f"{snr:g} dB"
            lines.append(
                f"| {method} | {imager} | {scene} | {snr_txt} | {r['psnr']:.2f} | "
                f"{off['psnr']:.2f} | {d:+.2f} | {off['negative_share']:.3f} |"
            )
        if diffs:
            verdicts.append(
                f"* `{method}` on {imager}: {len(diffs)} cases, on − off "
                f"{min(diffs):+.2f} … {max(diffs):+.2f} dB — {verdict(method, diffs)}."
            )
    return "\n".join(lines + ["", "Verdicts (computed):", ""] + verdicts)


if __name__ == "__main__":
    main()
