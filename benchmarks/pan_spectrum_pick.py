"""How OTD's ``pan_spectrum="auto"`` should choose between its two first stages on a clean
measurement: cross-validated over scene folds.

On a clean measurement with many bands, ``pan_spectrum="auto"`` runs the first stage twice,
with plain DCT spectral atoms and with atoms weighted by the scene's fitted mean spectrum
(:func:`tensor_cosdi.solvers.subspace.fitted_mean_spectrum`), and keeps the weighted stage
unless its residual ``‖A x − g‖`` exceeds the plain one's by more than a relative margin
(:data:`tensor_cosdi.solvers.panchromatic.FITTED_MARGIN`).  Both
stages nearly interpolate a noiseless measurement, so their residuals are close and the
plain comparison (margin 0) is close to a coin flip.

For every view (tuning scenes of :func:`tensor_cosdi.datasets.tune_folds`, as they are and lit
by CIE illuminants, both codes, noiseless) this runs OTD with ``pan_spectrum="flat"`` and
``"fitted"`` (rows as ``real_spectra.py`` stores them, in ``results/<name>.json``) and the
two first stages alone (their residuals and the fitted spectrum's roughness:
``results/<name>_stages.json``); every margin of ``--margins`` is then a rule that picks one
of the two stored OTD results per view.  Per code, for each of the 4 folds, the margin best
on the other three is scored on it (``_protocol.cross_validate``); one margin for both codes
is chosen the same way, then scored once on the report scenes under the same lights.  Runs
are appended as they finish; a killed run resumes with the same command.

    python benchmarks/pan_spectrum_pick.py [--scenes-per-fold 3] [--light A,LED-B3,FL11]
        [--masks tsa,random] [--margins 0,0.01,0.02,0.05,0.1,0.2,inf] [--name pan_spectrum_pick]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402  (the benchmarks folder is not a package)
    MASKS,
    RESULTS,
    Store,
    cross_validate,
    load_mask,
    problem,
    provenance,
    scene_view,
    views,
    write_results,
)

from tensor_cosdi import datasets  # noqa: E402
from tensor_cosdi.solvers import otd as otd_module  # noqa: E402
from tensor_cosdi.solvers.panchromatic import (  # noqa: E402
    FITTED_MARGIN,
    keeps_fitted,
    panchromatic_estimate,
)
from tensor_cosdi.solvers.subspace import fitted_mean_spectrum, spectral_roughness  # noqa: E402

SNR = None  # the pick only runs on a clean measurement
VARIANTS = ("flat", "fitted")


def _otd_first_stage_options() -> dict:
    """The first-stage options OTD passes with its defaults (read from its signature)."""
    sig = inspect.signature(otd_module.online_tucker_admm).parameters
    return {k: sig[k].default for k in ("pan_iter", "pan_atoms", "pan_weight", "pan_tv_steps")}


def stages(system, g) -> dict:
    """Both first stages' residuals ``‖A x − g‖`` and the fitted spectrum's roughness."""
    import tensorly as tl

    opts = _otd_first_stage_options()
    out = {}
    for variant in VARIANTS:
        _, x = panchromatic_estimate(system, g, pan_spectrum=variant, **opts)
        out[f"misfit_{variant}"] = float(tl.norm(system.operator.apply(x) - g))
        if variant == "flat":
            axis = system.panchromatic_axes[0]
            out["roughness"] = float(spectral_roughness(fitted_mean_spectrum(system, g, x, axis)))
    return out


class StageStore:
    """The first stages' numbers per view, appended to a JSON file as they finish."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.rows = json.loads(self.path.read_text()) if self.path.exists() else {}

    def ensure(self, scene: str, mask_kind: str) -> dict:
        k = f"{scene}|{mask_kind}"
        if k not in self.rows:
            name, zoom, light = scene_view(scene)
            system, _, g = problem(name, SNR, load_mask(mask_kind), zoom=zoom, illuminant=light)
            self.rows[k] = stages(system, g)
            tmp = self.path.with_name(self.path.name + ".tmp")
            tmp.write_text(json.dumps(self.rows, indent=1))
            os.replace(tmp, self.path)
            r = self.rows[k]
            print(
                f"{scene:26s} {mask_kind:6s} stages: misfit flat {r['misfit_flat']:.4f} "
                f"fitted {r['misfit_fitted']:.4f} roughness {r['roughness']:.3f}",
                flush=True,
            )
        return self.rows[k]


def kept(row: dict, margin: float) -> bool:
    """Whether ``pan_spectrum="auto"`` keeps the weighted stage of a view at ``margin``
    (:func:`tensor_cosdi.solvers.panchromatic.keeps_fitted`; ``inf``: always)."""
    return math.isinf(margin) or keeps_fitted(row["misfit_fitted"], row["misfit_flat"], margin)


def _label(m: float) -> str:
    return "always fitted" if math.isinf(m) else f"margin {m:g}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes-per-fold", type=int, default=3)
    ap.add_argument("--light", default="A,LED-B3,FL11")
    ap.add_argument("--masks", default="tsa,random")
    ap.add_argument("--margins", default="0,0.01,0.02,0.05,0.1,0.2,inf")
    ap.add_argument(
        "--against", type=float, default=0.0, metavar="MARGIN",
        help="the margin the chosen one is compared with (default 0: the plain comparison)",
    )  # fmt: skip
    ap.add_argument("--name", default="pan_spectrum_pick")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    masks = [m for m in args.masks.split(",") if m]
    if not masks or any(m not in MASKS for m in masks):
        raise SystemExit(f"--masks takes a comma list of {', '.join(MASKS)}, got {args.masks!r}")
    try:
        margins = [float(v) for v in args.margins.split(",")]
    except ValueError:
        margins = []
    if not margins or not all(m >= 0 for m in margins) or not args.against >= 0:
        raise SystemExit(f"--margins and --against take numbers ≥ 0 (inf: always the weighted "
                         f"stage), got {args.margins!r} and {args.against!r}")  # fmt: skip
    if args.scenes_per_fold < 1:
        raise SystemExit(f"--scenes-per-fold must be ≥ 1, got {args.scenes_per_fold}")
    lights = tuple(v for v in args.light.split(",") if v)
    for light in lights:  # refused before any run
        try:
            scene_view(f"scene~{light}")
        except ValueError as exc:
            raise SystemExit(f"--light: {exc}") from None
    out = Path(args.out)
    store = Store(out / f"{args.name}.json")
    stage_store = StageStore(out / f"{args.name}_stages.json")
    folds = tuple(views(f[: args.scenes_per_fold], None, lights) for f in datasets.tune_folds(4))
    tune = [s for f in folds for s in f]
    report = list(views(datasets.REPORT_SCENES, None, lights))
    cache: dict = {}
    for scenes in (tune, report):
        for mk in masks:
            for scene in scenes:
                stage_store.ensure(scene, mk)
                for v in VARIANTS:
                    store.ensure(scene, SNR, mk, "otd", {"pan_spectrum": v}, cache=cache)

    def psnr(scene, mk, margin):
        row = stage_store.rows[f"{scene}|{mk}"]
        v = "fitted" if kept(row, margin) else "flat"
        return store.get(scene, SNR, mk, "otd", {"pan_spectrum": v})["psnr"]

    cands = [{"margin": m} for m in margins]
    lines = [
        '# OTD\'s first-stage pick on clean data (`pan_spectrum="auto"`)',
        "",
        f"Noiseless SD-CASSI 256×256×28; {len(tune)} tuning views in 4 folds "
        f"({args.scenes_per_fold} scenes a fold as they are"
        + (f" and lit by CIE {', '.join(lights)}" if lights else "")
        + "); each margin keeps the weighted first stage unless its residual exceeds the "
        "plain one's by more than the margin (relative).  Each fold is scored with the margin "
        f"best on the other three.  In use: margin {FITTED_MARGIN:g}.",
        "",
        "| code | chosen per fold | held-out PSNR dB, mean ± spread | "
        + " | ".join(_label(m) for m in margins)
        + " |",
        "|---|---|---|" + "---|" * len(margins),
    ]
    per_code = {}
    for mk in masks:

        def rows_of(c, scenes, mk=mk):
            return [psnr(s, mk, c["margin"]) for s in scenes]

        res = cross_validate(rows_of, cands, folds)
        per_code[mk] = res
        best = max(res["all_means"])
        means = " | ".join(
            (f"**{v:.2f}**" if v == best else f"{v:.2f}") for v in res["all_means"]
        )  # fmt: skip
        chosen = "; ".join(f"{f['chosen']['margin']:g}" for f in res["folds"])
        lines.append(f"| {mk} | {chosen} | {res['mean']:.2f} ± {res['spread']:.2f} | {means} |")

    def joint_rows(c, scenes):
        return [float(np.mean([psnr(s, mk, c["margin"]) for mk in masks])) for s in scenes]

    joint = cross_validate(joint_rows, cands, folds)
    chosen = joint["chosen_on_all"]["margin"]
    per_fold = "; ".join(f"{f['chosen']['margin']:g}" for f in joint["folds"])
    against = float(np.mean([np.mean(joint_rows({"margin": args.against}, f)) for f in folds]))
    lines += [
        "",
        "Mean PSNR over the tuning views for each margin (columns); bold: the best.",
        "",
        f"One margin for both codes (chosen per fold by the mean over the codes on the other "
        f"three): per fold {per_fold}; "
        f"held-out mean {joint['mean']:.2f} ± {joint['spread']:.2f} dB ({_label(args.against)} "
        f"on the same folds: {against:.2f} dB); chosen on all "
        f"{len(tune)} views: **{_label(chosen)}**.",
        "",
        "How often each stage is kept over the tuning views, and how much the better of the "
        "two would give (an oracle no rule can read):",
        "",
        f"| code | views | weighted stage kept at the chosen margin | at {_label(args.against)} | "
        "oracle PSNR dB |",
        "|---|---|---|---|---|",
    ]  # fmt: skip
    for mk in masks:
        rows = [stage_store.rows[f"{s}|{mk}"] for s in tune]
        oracle = np.mean([
            max(store.get(s, SNR, mk, "otd", {"pan_spectrum": v})["psnr"] for v in VARIANTS)
            for s in tune
        ])  # fmt: skip
        lines.append(
            f"| {mk} | {len(tune)} | {sum(kept(r, chosen) for r in rows)} | "
            f"{sum(kept(r, args.against) for r in rows)} | {oracle:.2f} |"
        )
    lines += [
        "",
        f"Report scenes under the same lights ({len(report)} views, never tuned on), "
        f"{_label(args.against)} against the chosen margin:",
        "",
        f"| code | {_label(args.against)} | {_label(chosen)} | change dB (min…max per view) |",
        "|---|---|---|---|",
    ]
    for mk in masks:
        old = [psnr(s, mk, args.against) for s in report]
        new = [psnr(s, mk, chosen) for s in report]
        d = np.subtract(new, old)
        lines.append(
            f"| {mk} | {np.mean(old):.2f} | {np.mean(new):.2f} | {d.mean():+.2f} "
            f"({d.min():+.2f}…{d.max():+.2f}) |"
        )
    lines += ["", f"Rows computed at {store.commits()}."]
    write_results(out / f"{args.name}.md", lines)
    summary = {"margins": margins, "per_code": per_code, "joint": joint, "chosen": chosen,
               "provenance": provenance()}  # fmt: skip
    (out / f"{args.name}.summary.json").write_text(json.dumps(summary, indent=1, default=str))


if __name__ == "__main__":
    main()
