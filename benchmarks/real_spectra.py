"""Reconstruction on real hyperspectral scenes: the standard 256×256×28 SD-CASSI protocol,
with defaults chosen by cross-validation over scene folds.

Protocol (``benchmarks/_protocol.py``): CAVE scenes of the research data
(``TENSOR_COSDI_DATA``, else ``../shared/data``) resampled onto the 28 KAIST
band centres, SD-CASSI with 2 px per band and the real TSA mask or a seeded
random binary code, noiseless / 30 dB / 20 dB, PSNR over the cube (data range
1, estimates clipped to [0, 1]), SSIM, SAM.  ``plain_gap_tv`` is a reference
written in a few lines (accelerated GAP with scikit-image's Chambolle TV,
weight 0.2, 80 iterations) — the baseline this library must beat.

Two modes:

* **report** (default): ``--methods`` on the three report scenes
  (:data:`tensor_cosdi.datasets.REPORT_SCENES`, never tuned on) for every
  ``--snr`` × ``--masks`` condition; ``<out>/<name>.md``.
* **cross-validation** (``--cv METHOD --grid JSON``): every candidate of the
  grid on the 28 tuning scenes; per condition, for each of the 4 folds of
  :func:`tensor_cosdi.datasets.tune_folds`, the candidate best on the other
  three folds is scored on it (fold mean ± spread), and the candidate best on
  all 28 is then scored once on the report scenes, beside ``plain_gap_tv``.
  ``<out>/cv_<METHOD>[_<name>].md``.

Every run is appended to a JSON file as it finishes and skipped when the file
already holds it, so a killed run resumes with the same command; ``--fresh
METHODS`` (or ``all``) computes those methods' runs again after a code change.
The Markdown tables carry the date, machine, commit and command, and the
commits the rows were computed at.

    python benchmarks/real_spectra.py [--methods plain_gap_tv,gap_tv,otd]
        [--snr none,30,20] [--masks tsa,random] [--name real_spectra]
    python benchmarks/real_spectra.py --methods plain_gap_tv,pnp_gap,pnp_gap+bf16
        --options '{"pnp_gap+bf16": {"precision": "bfloat16"}}'   (a method twice)
    python benchmarks/real_spectra.py --cv otd --grid '{"lam": [0.05, 0.1, 0.2]}'
        [--snr none,30,20] [--masks tsa,random] [--scenes-per-fold N] [--zoom Z]
        [--light A,LED-B3]

``--zoom Z`` adds every tuning scene magnified ``Z``× (the view ``scene@Z``,
in its scene's fold) to the cross-validation: data from a camera of finer
resolution than the CAVE scenes, where a default chosen on CAVE alone does
less well.  A scene label ``name@Z`` works in report mode too (``--scenes``), as
does ``name~A``: the scene lit by a CIE illuminant (a key of ``colour.SDS_ILLUMINANTS``)
and scaled to a peak of 1, the kind of scene a radiance database holds (``name@Z~A``:
both).  ``--light A,LED-B3`` adds every tuning scene's ``~A`` and ``~LED-B3`` views to the
cross-validation, in its scene's fold.

``--tie-db DB`` makes candidates within ``DB`` of the best mean a tie, won by the
fastest (or by ``--keep JSON``, the default in use, where it ties); ``--no-slower``
lets only candidates no slower than ``--keep`` compete, and ``--budget-s SECONDS``
only those whose median time a cube is at most ``SECONDS`` (a method's stated
budget, such as ``pnp_fast``'s 5 s).  Each timed run starts with no SNR estimate
cached, as a user's single call does.

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402  (the benchmarks folder is not a package)
    MASKS,
    RESULTS,
    Store,
    candidates,
    cross_validate,
    plain_gap_tv,
    problem,
    provenance,
    provenance_lines,
    scene_view,
    score,
    snr_label,
    views,
)

from tensor_cosdi import datasets  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The real TSA mask (``dcosnet_speed.py`` and ``dcosnet_ablation.py`` read it too).
MASK = ROOT / ".." / "shared" / "data" / "masks" / "tsa_mask256.mat"

__all__ = ["MASK", "plain_gap_tv", "problem", "score", "main"]


def _conditions(args):
    snrs = [None if s.strip().lower() == "none" else float(s) for s in args.snr.split(",")]
    masks = [m.strip() for m in args.masks.split(",")]
    for m in masks:
        if m not in MASKS:
            raise SystemExit(f"--masks: {m!r} is not one of {', '.join(MASKS)}")
    return [(s, m) for m in masks for s in snrs]


def _mean(rows, field):
    return float(np.mean([r[field] for r in rows]))


def _method(label: str) -> str:
    """The registered method of a ``--methods`` entry: ``pnp_gap+bf16`` is ``pnp_gap`` run with
    the ``--options`` given under ``"pnp_gap+bf16"`` (one method, two settings, one run)."""
    return label.split("+", 1)[0]


def _versus(text: str, methods) -> list[tuple[str, str]]:
    """``--versus A:B,C:D`` as ``[(B, A), (D, C)]``: ``A`` against ``B``, each a ``--methods``
    entry."""
    out = []
    for pair in (p for p in text.split(",") if p):
        a, sep, b = pair.partition(":")
        if not sep or a not in methods or b not in methods:
            raise SystemExit(
                f"--versus: {pair!r} must be METHOD:OTHER, both among --methods {methods}"
            )
        out.append((b, a))
    return out


def report(args, store, cache):
    methods = args.methods.split(",")
    options = json.loads(args.options)
    scenes = args.scenes.split(",") if args.scenes else list(datasets.REPORT_SCENES)
    conds = _conditions(args)
    versus = _versus(args.versus, methods)  # checked before anything runs
    for scene in scenes:
        for snr, mk in conds:
            for m in methods:
                store.ensure(scene, snr, mk, _method(m), options.get(m, {}), cache=cache)
    base = "plain_gap_tv" if "plain_gap_tv" in methods else None
    lines = [
        "| code | SNR | method | PSNR dB | SSIM | SAM ° | median s | scenes |"
        + (" lead over plain_gap_tv, dB (min…max per scene) |" if base else ""),
        "|---|---|---|---|---|---|---|---|" + ("---|" if base else ""),
    ]
    for snr, mk in conds:
        for m in methods:
            rs = [store.get(s, snr, mk, _method(m), options.get(m, {})) for s in scenes]
            row = (
                f"| {mk} | {snr_label(snr)} | {m} | {_mean(rs, 'psnr'):.2f} | "
                f"{_mean(rs, 'ssim'):.3f} | {_mean(rs, 'sam'):.2f} | "
                f"{np.median([r['seconds'] for r in rs]):.2f} | {len(rs)} |"
            )
            if base:
                ref = [store.get(s, snr, mk, base, options.get(base, {}))["psnr"] for s in scenes]
                d = np.array([r["psnr"] for r in rs]) - np.array(ref)
                spread = f"{d.mean():+.2f} ({d.min():+.2f}…{d.max():+.2f})"
                row += " — |" if m == base else f" {spread} |"
            lines.append(row)
    pairs = [(base, m) for m in methods if base and m != base]
    pairs += versus
    if pairs:  # one computed line per pair: where the method stands against the other
        lines.append("")
    for ref, m in pairs:
        d = np.array([
            store.get(s, snr, mk, _method(m), options.get(m, {}))["psnr"]
            - store.get(s, snr, mk, _method(ref), options.get(ref, {}))["psnr"]
            for snr, mk in conds for s in scenes
        ])  # fmt: skip
        where = (
            "above it in every case" if d.min() > 0
            else "under it in every case" if d.max() < 0
            else f"above it in {int((d > 0).sum())} of {d.size} cases"
        )  # fmt: skip
        lines.append(
            f"* `{m}` against `{ref}`, per scene and condition: {where} "
            f"({d.min():+.2f} to {d.max():+.2f} dB, mean {d.mean():+.2f})."
        )
    head = (
        f"# Real spectra: {', '.join(scenes)}\n\nSD-CASSI 256×256×28 (KAIST bands), 2 px/band, "
        f"float32; options {json.dumps(options)}.\n\n"
    )
    return head + "\n".join(lines)


def cv(args, store, cache):
    method = args.cv
    grid = json.loads(args.grid)
    cands = candidates(grid)
    folds = datasets.tune_folds(4)
    if args.scenes_per_fold:
        folds = tuple(f[: args.scenes_per_fold] for f in folds)
    # a scene and its magnified view stay in one fold: no fold scores a view of a scene it
    # chose on
    folds = tuple(views(f, args.zoom, args.light) for f in folds)
    tune = [s for f in folds for s in f]
    conds = _conditions(args)
    # cheapest first: every candidate on a scene before the next scene
    for snr, mk in conds:
        for scene in tune:
            for c in cands:
                store.ensure(scene, snr, mk, method, c, cache=cache)
            if args.baseline_on_tune:
                store.ensure(scene, snr, mk, "plain_gap_tv", {}, cache=cache)
    results = {}
    for snr, mk in conds:

        def psnrs(c, scenes, snr=snr, mk=mk):
            return [store.get(s, snr, mk, method, c)["psnr"] for s in scenes]

        def seconds(c, scenes, snr=snr, mk=mk):
            return [store.get(s, snr, mk, method, c)["seconds"] for s in scenes]

        res = cross_validate(
            psnrs, cands, folds, seconds_of=seconds, tie_db=args.tie_db, keep=args.keep,
            no_slower=args.no_slower, budget_s=args.budget_s,
        )  # fmt: skip
        chosen = res["chosen_on_all"]
        rep, rep_zoom = {}, {}
        magnified = views(datasets.REPORT_SCENES, args.zoom)[len(datasets.REPORT_SCENES) :]
        for m, opts in ((method, chosen), ("plain_gap_tv", {})):
            rows = [store.ensure(s, snr, mk, m, opts, cache=cache) for s in datasets.REPORT_SCENES]
            rep[m] = {
                "psnr": _mean(rows, "psnr"),
                "ssim": _mean(rows, "ssim"),
                "sam": _mean(rows, "sam"),
                "seconds": float(np.median([r["seconds"] for r in rows])),
                "per_scene": [r["psnr"] for r in rows],
            }
            if magnified:  # the report scenes seen closer, scored once like them
                rows = [store.ensure(s, snr, mk, m, opts, cache=cache) for s in magnified]
                rep_zoom[m] = {"psnr": _mean(rows, "psnr"), "per_scene": [r["psnr"] for r in rows]}
        if rep_zoom:
            res["report_zoom"] = rep_zoom
        if args.baseline_on_tune:
            base = [store.get(s, snr, mk, "plain_gap_tv", {})["psnr"] for s in tune]
            res["gap_tv_tune_mean"] = float(np.mean(base))
        res["report"] = rep
        results[f"{mk}/{snr_label(snr)}"] = res
    results["joint"] = _joint(
        method,
        cands,
        folds,
        conds,
        store,
        cache,
        args.tie_db,
        args.keep,
        args.no_slower,
        args.budget_s,
    )
    return _cv_markdown(method, grid, folds, results, args), results


def _joint(
    method, cands, folds, conds, store, cache, tie_db=0.0, keep=None, no_slower=False,
    budget_s=None,
):  # fmt: skip
    """One setting for every code and noise level, cross-validated the same way: on each fold
    the candidate with the best mean over the conditions on the other three folds; then the
    choice on all folds, its loss against each condition's own best, and its report PSNR."""

    def mean_over_conditions(c, scenes):
        return [
            float(np.mean([store.get(s, snr, mk, method, c)["psnr"] for snr, mk in conds]))
            for s in scenes
        ]

    def seconds(c, scenes):
        return [store.get(s, snr, mk, method, c)["seconds"] for s in scenes for snr, mk in conds]

    res = cross_validate(
        mean_over_conditions, cands, folds, seconds_of=seconds, tie_db=tie_db, keep=keep,
        no_slower=no_slower, budget_s=budget_s,
    )  # fmt: skip
    chosen = res["chosen_on_all"]
    tune = [s for f in folds for s in f]
    res["loss"], res["report"] = {}, {}
    for snr, mk in conds:
        means = [np.mean([store.get(s, snr, mk, method, c)["psnr"] for s in tune]) for c in cands]
        label = f"{mk}/{snr_label(snr)}"
        res["loss"][label] = float(max(means) - means[cands.index(chosen)])
        report = datasets.REPORT_SCENES
        rows = [store.ensure(s, snr, mk, method, chosen, cache=cache) for s in report]
        base = [store.get(s, snr, mk, "plain_gap_tv", {}) for s in report]
        res["report"][label] = {"psnr": _mean(rows, "psnr"), "plain_gap_tv": _mean(base, "psnr")}
    return res


def _cv_markdown(method, grid, folds, results, args):
    fmt = lambda c: ", ".join(f"{k}={v}" for k, v in c.items()) or "defaults"  # noqa: E731
    keep = args.keep is not None
    n = sum(len(f) for f in folds)
    zoomed = args.zoom not in (None, 1)
    per_scene = 1 + zoomed + len(args.light)
    seen = f"{n // per_scene} tuning scenes as they are"
    if zoomed:
        seen += (
            f", magnified {args.zoom:g}× (`@{args.zoom:g}`: the centre crop magnified back to "
            "256×256, the larger-scale structure of a finer camera)"
        )
    if args.light:
        seen += (
            ", lit by CIE illuminant "
            + " and ".join(f"`{x}` (`~{x}`)" for x in args.light)
            + " and scaled to a peak of 1 (a radiance database's kind of scene)"
        )
    n = f"{n} views" if per_scene > 1 else n
    lines = [
        f"# Cross-validated choice for `{method}`",
        "",
        f"Grid {json.dumps(grid)} ({len(candidates(grid))} candidates); 4 folds of "
        f"{seen} (`datasets.tune_folds(4)`): "
        + "; ".join(f"fold {k}: {', '.join(f)}" for k, f in enumerate(folds))
        + ".  Each fold is scored with the candidate best on the other three"
        + (
            f" (candidates within {args.tie_db:g} dB of the best mean are a tie, won by "
            + (f"the default in use, {fmt(args.keep)}, where it ties, else by " if keep else "")
            + "the smallest median time)."
            if args.tie_db > 0
            else "."
        )
        + (
            f"  Only candidates no slower than {fmt(args.keep)} (median seconds a cube on the "
            "scenes chosen on) are chosen: a time budget the default in use meets."
            if args.no_slower
            else ""
        )
        + (
            f"  Only candidates whose median time a cube on the scenes chosen on is at most "
            f"{args.budget_s:g} s are chosen (the fastest where none is): the method's time "
            "budget."
            if args.budget_s is not None
            else ""
        ),
        "",
        f"| code | SNR | chosen per fold | held-out PSNR dB, mean ± spread | chosen on all {n} |"
        " report PSNR dB | plain GAP-TV, report | lead dB |"
        + (f" report ×{args.zoom:g}: PSNR dB, lead |" if zoomed else ""),
        "|---|---|---|---|---|---|---|---|" + ("---|" if zoomed else ""),
    ]
    for cond, res in results.items():
        if cond == "joint":
            continue
        mk, snr = cond.split("/")
        rep = res["report"]
        lead = rep[method]["psnr"] - rep["plain_gap_tv"]["psnr"]
        chosen = "; ".join(fmt(f["chosen"]) for f in res["folds"])
        row = (
            f"| {mk} | {snr} | {chosen} | {res['mean']:.2f} ± {res['spread']:.2f} | "
            f"{fmt(res['chosen_on_all'])} | {rep[method]['psnr']:.2f} | "
            f"{rep['plain_gap_tv']['psnr']:.2f} | {lead:+.2f} |"
        )
        if zoomed:
            rz = res["report_zoom"]
            zp, zb = rz[method]["psnr"], rz["plain_gap_tv"]["psnr"]
            row += f" {zp:.2f}, {zp - zb:+.2f} |"
        lines.append(row)
    lines += ["", "Mean PSNR (dB) of every candidate over the tuning scenes:", ""]
    cands = candidates(grid)
    lines.append("| code | SNR | " + " | ".join(fmt(c) for c in cands) + " |")
    lines.append("|---|---|" + "---|" * len(cands))
    for cond, res in results.items():
        if cond == "joint":
            continue
        mk, snr = cond.split("/")
        best = int(np.argmax(res["all_means"]))
        cells = [
            f"**{v:.2f}**" if i == best else f"{v:.2f}" for i, v in enumerate(res["all_means"])
        ]
        lines.append(f"| {mk} | {snr} | " + " | ".join(cells) + " |")
    if args.tie_db > 0 or args.no_slower or args.budget_s is not None:  # time decides too
        lines += ["", "Median seconds a cube of every candidate over the tuning scenes:", ""]
        lines.append("| code | SNR | " + " | ".join(fmt(c) for c in cands) + " |")
        lines.append("|---|---|" + "---|" * len(cands))
        for cond, res in results.items():
            if cond != "joint":
                mk, snr = cond.split("/")
                lines.append(
                    f"| {mk} | {snr} | " + " | ".join(f"{v:.2f}" for v in res["all_seconds"]) + " |"
                )
    joint = results.get("joint")
    if joint:
        chosen = "; ".join(fmt(f["chosen"]) for f in joint["folds"])
        worst = max(joint["loss"].items(), key=lambda kv: kv[1])
        leads = [r["psnr"] - r["plain_gap_tv"] for r in joint["report"].values()]
        lines += [
            "",
            "One setting for every code and noise level (chosen per fold by the mean over all "
            f"conditions on the other three folds): per fold {chosen}; held-out mean over the "
            f"conditions {joint['mean']:.2f} ± {joint['spread']:.2f} dB; chosen on all "
            f"{n}: **{fmt(joint['chosen_on_all'])}**, at most {worst[1]:.2f} dB under a "
            f"condition's own best ({worst[0]}); on the report scenes "
            f"{min(leads):+.2f} to {max(leads):+.2f} dB over plain GAP-TV per condition.",
        ]
    return "\n".join(lines)


def _load_torch_if_needed(labels) -> bool:
    """Import torch where a method of ``labels`` needs it (and is available), even when every
    run is already stored: the machine line then says whether the CPU runs bfloat16 natively
    (``_protocol.machine``), as it does after a computed run of a learned method.  Whether it
    did."""
    from tensor_cosdi.solvers._base import METHODS

    for label in labels:
        entry = METHODS.get(_method(label))
        if entry is not None and "torch" in entry.requires and entry.available:
            import torch  # noqa: F401

            return True
    return False


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default="plain_gap_tv,gap_tv,otd")
    ap.add_argument("--snr", default="none,30,20", help="comma list; 'none' = noiseless")
    ap.add_argument("--masks", default="tsa,random", help=f"comma list of {', '.join(MASKS)}")
    ap.add_argument("--scenes", default=None, help="report mode: override the report scenes")
    ap.add_argument("--options", default="{}", help='report mode: JSON {"method": {option: v}}')
    ap.add_argument("--cv", metavar="METHOD", help="cross-validate METHOD over --grid")
    ap.add_argument("--grid", default="{}", help='JSON {"option": [values, ...]} for --cv')
    ap.add_argument("--scenes-per-fold", type=int, default=None, help="--cv: a smaller run")
    ap.add_argument(
        "--zoom", type=float, default=None,
        help="--cv: also each tuning scene magnified ZOOM× (its view 'scene@ZOOM', same fold)",
    )  # fmt: skip
    ap.add_argument(
        "--light", default="",
        help="--cv: also each tuning scene lit by these CIE illuminants (views 'scene~ILL')",
    )  # fmt: skip
    ap.add_argument(
        "--baseline-on-tune", action="store_true", help="--cv: also plain GAP-TV on the folds"
    )
    ap.add_argument(
        "--tie-db", type=float, default=0.0, metavar="DB",
        help="--cv: candidates within DB of the best mean are a tie, won by the fastest",
    )  # fmt: skip
    ap.add_argument(
        "--keep", default=None, metavar="JSON",
        help="--cv with --tie-db: the candidate in use as a default; it wins the ties it is in",
    )  # fmt: skip
    ap.add_argument(
        "--no-slower", action="store_true",
        help="--cv with --keep: only candidates no slower (median seconds) than --keep compete",
    )  # fmt: skip
    ap.add_argument(
        "--budget-s", type=float, default=None, metavar="SECONDS",
        help="--cv: only candidates whose median seconds a cube are at most SECONDS compete",
    )  # fmt: skip
    ap.add_argument(
        "--versus", default="", metavar="A:B,…",
        help="report mode: also a computed line for method A against method B",
    )  # fmt: skip
    ap.add_argument("--name", default=None, help="results file stem")
    ap.add_argument(
        "--fresh", default="", metavar="METHODS",
        help="comma list of methods (or 'all') whose stored runs are computed again",
    )  # fmt: skip
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    if args.keep is not None:
        if not args.cv or args.tie_db <= 0:
            raise SystemExit("--keep needs --cv and --tie-db > 0")
        try:
            args.keep = json.loads(args.keep)
        except json.JSONDecodeError as exc:
            raise SystemExit(f"--keep must be a JSON object of options: {exc}") from None
        if args.keep not in candidates(json.loads(args.grid)):
            raise SystemExit(f"--keep {json.dumps(args.keep)} is not a candidate of --grid")
    if args.no_slower and args.keep is None:
        raise SystemExit("--no-slower needs --keep (the default in use whose time is the budget)")
    if args.budget_s is not None and not (args.cv and args.budget_s > 0):
        raise SystemExit(
            f"--budget-s needs --cv and a number of seconds > 0, got {args.budget_s:g}"
        )
    if not args.tie_db >= 0:
        raise SystemExit(f"--tie-db must be a number ≥ 0, got {args.tie_db:g}")
    if args.zoom is not None and not args.zoom >= 1:
        raise SystemExit(f"--zoom must be a number ≥ 1, got {args.zoom:g}")
    args.light = tuple(x for x in args.light.split(",") if x)
    for light in args.light:
        try:
            scene_view(f"scene~{light}")
        except ValueError:
            raise SystemExit(
                f"--light: {light!r} is not a key of colour.SDS_ILLUMINANTS (e.g. A, D65, LED-B3)"
            ) from None
    try:
        datasets.data_dir()
    except FileNotFoundError as exc:
        raise SystemExit(f"real_spectra.py needs the research scenes: {exc}") from None
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.cv:
        name = args.name or f"cv_{args.cv}"
    else:
        name = args.name or "real_spectra"
    store = Store(out / f"{name}.json", fresh=[m for m in args.fresh.split(",") if m])
    cache = {}
    _load_torch_if_needed([args.cv] if args.cv else args.methods.split(","))
    if args.cv:
        text, results = cv(args, store, cache)
        (out / f"{name}.summary.json").write_text(json.dumps(results, indent=1))
    else:
        text = report(args, store, cache)
    text += f"\n\nRows computed at commit {store.commits()}.  \n"
    text += provenance_lines(provenance()) + "\n"
    (out / f"{name}.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
