"""OTD's sparsity weight on one imager, chosen by cross-validation over the tuning scenes.

``lam="auto"`` follows the measurement's estimated SNR through a schedule
(:data:`tensor_cosdi.solvers.otd.LAM_SCHEDULE`) chosen on SD-CASSI.  A system
may replace some of its anchors (``System.otd_lam_anchors``;
:func:`tensor_cosdi.solvers.otd.lam_schedule`).  This script reconstructs
``--system`` (64×64, 16 bands, the system's seeded codes and example options, or
``--options`` in their place, e.g. ``'{"n_filters": 1}'`` for CS2LI with a binary code)
on tuning scenes (``--scenes-per-fold`` of each fold of
``datasets.tune_folds(4)``) at each ``--snr`` with OTD at ``lam="auto"`` and
at every ``--lams`` value, and for each noise level chooses the weight by
4-fold cross-validation (the best mean PSNR on three folds, scored on the
fourth; ``auto`` wins a tie within ``--tie-db``).  Rows are cached in a JSON
file beside the results, so an interrupted run resumes where it stopped.

    python benchmarks/otd_lam_systems.py --system cs2li [--options '{"n_filters": 1}']
        [--snr none,30] [--lams 0.03,0.06,0.1,0.2,0.3] [--scenes-per-fold 4] [--tie-db 0.05]
        [--out benchmarks/results/otd_lam_cs2li.md (with --options: otd_lam_cs2li_n_filters1.md)]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402
    RESULTS,
    cross_validate,
    positive_numbers,
    snr_label,
    write_results,
)

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi.solvers.otd import lam_schedule  # noqa: E402
from tensor_cosdi.solvers.snr import estimate_snr  # noqa: E402

SIDE, BANDS = 64, 16


def _snrs(text):
    try:
        return [None if s == "none" else float(s) for s in text.split(",")]
    except ValueError:
        raise SystemExit(f"--snr takes 'none' or numbers, comma-separated, got {text!r}") from None


def _options(text):
    try:
        options = json.loads(text)
    except json.JSONDecodeError as exc:
        raise SystemExit(f"--options must be a JSON object, got {text!r}: {exc}") from None
    if not isinstance(options, dict):
        raise SystemExit(f"--options must be a JSON object, got {text!r}")
    return options


def _row(system_name, scene, snr, lam, options):
    p = tc.studies.make_problem(
        system_name,
        f"cave.{scene}",
        shape=(SIDE, SIDE),
        n_bands=BANDS,
        snr_db=snr,
        rng=0,
        **options,
    )
    options = {} if lam == "auto" else {"lam": lam}
    t0 = time.perf_counter()
    rec = tc.reconstruct(p.system, p.measurement, "otd", **options)
    seconds = time.perf_counter() - t0
    est = np.clip(np.asarray(rec.cube, dtype=np.float64), 0.0, 1.0)
    return {
        "psnr": tc.metrics.psnr(np.asarray(p.cube, dtype=np.float64), est, data_range=1.0),
        "seconds": seconds,
        "estimated_snr_db": float(estimate_snr(p.system, p.measurement).snr_db),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--system", required=True, help="a system of tensor_cosdi.studies.SYSTEMS")
    ap.add_argument("--options", default="{}", help="the system's example options, JSON")
    ap.add_argument("--snr", default="none,30")
    ap.add_argument("--lams", default="0.03,0.06,0.1,0.2,0.3")
    ap.add_argument("--scenes-per-fold", type=int, default=4)
    ap.add_argument("--tie-db", type=float, default=0.05)
    ap.add_argument(
        "--out", default=None, help="default benchmarks/results/otd_lam_SYSTEM[_OPTIONS].md"
    )
    args = ap.parse_args(argv)
    if args.system not in tc.studies.SYSTEMS:
        raise SystemExit(f"--system must be one of {list(tc.studies.SYSTEMS)}")
    snrs = _snrs(args.snr)
    options = _options(args.options)
    try:
        example = tc.studies.make_problem(
            args.system, "colorchecker", shape=(SIDE, SIDE), n_bands=BANDS, snr_db=None, **options
        ).system
    except ValueError as exc:
        raise SystemExit(f"--options: {exc}") from None
    lams = positive_numbers(args.lams, "--lams")
    if not 1 <= args.scenes_per_fold <= 7:
        raise SystemExit("--scenes-per-fold must be 1 to 7")
    if not args.tie_db >= 0:
        raise SystemExit("--tie-db must be ≥ 0")
    try:
        tc.datasets.data_dir()
    except FileNotFoundError as exc:
        raise SystemExit(f"otd_lam_systems.py needs the research scenes: {exc}") from None
    suffix = "".join(f"_{k}{v}" for k, v in sorted(options.items()))
    if args.out is None and (len(suffix) > 60 or not re.fullmatch(r"[\w.-]*", suffix)):
        raise SystemExit("--options do not make a file name: give --out")
    out = Path(args.out) if args.out else RESULTS / f"otd_lam_{args.system}{suffix}.md"
    cache_path = out.with_suffix(".json")
    cache_path.parent.mkdir(parents=True, exist_ok=True)
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    folds = [list(f[: args.scenes_per_fold]) for f in tc.datasets.tune_folds(4)]
    cands = ["auto"] + lams

    schedule = lam_schedule(example)

    def key(scene, snr, lam):
        # rows of lam="auto" are kept apart for each schedule it has followed
        label = f"auto {json.dumps(schedule, sort_keys=True)}" if lam == "auto" else lam
        system = args.system + (json.dumps(options, sort_keys=True) if options else "")
        return f"{system}|{scene}|{snr_label(snr)}|{label}"

    for snr in snrs:
        for scene in [s for f in folds for s in f]:
            for lam in cands:
                k = key(scene, snr, lam)
                if k in cache:
                    continue
                cache[k] = _row(args.system, scene, snr, lam, options)
                print(k, f"{cache[k]['psnr']:.2f} dB {cache[k]['seconds']:.1f} s", flush=True)
                cache_path.write_text(json.dumps(cache, indent=1, sort_keys=True))

    lines = [
        f"# OTD's sparsity weight on {args.system}: cross-validated over tuning scenes",
        "",
        f"{SIDE}×{SIDE}, {BANDS} bands, the system's seeded codes and example options"
        + (f" with {json.dumps(options, sort_keys=True)}" if options else "")
        + ", noise "
        f"seed 0; PSNR over the cube (data range 1, the estimate clipped to [0, 1]).  4 folds "
        f"of {args.scenes_per_fold} tuning scenes (`datasets.tune_folds(4)`): "
        + "; ".join(f"fold {k}: {', '.join(f)}" for k, f in enumerate(folds))
        + f'.  `auto` is `lam="auto"` as it stands (anchors {{SNR dB: weight}} '
        f"{json.dumps(schedule, sort_keys=True)}); it wins a tie within {args.tie_db:g} dB.",
        "",
        "| true SNR | estimated SNR dB, median | chosen per fold | held-out PSNR dB, mean ± "
        "spread | `auto` on the same folds | chosen on all | "
        + " | ".join(f"lam {c:g}" if c != "auto" else "auto" for c in cands)
        + " |",
        "|---|---|---|---|---|---|" + "---|" * len(cands),
    ]
    chosen_all = {}
    for snr in snrs:

        def rows_of(c, scenes, snr=snr):
            return [cache[key(s, snr, c)]["psnr"] for s in scenes]

        cv = cross_validate(rows_of, cands, folds, tie_db=args.tie_db, keep="auto")
        auto_held = float(np.mean([np.mean(rows_of("auto", f)) for f in folds]))
        est = np.median([cache[key(s, snr, "auto")]["estimated_snr_db"] for f in folds for s in f])
        chosen_all[snr] = cv["chosen_on_all"]
        means = [
            f"**{m:.2f}**" if c == cv["chosen_on_all"] else f"{m:.2f}"
            for c, m in zip(cands, cv["all_means"])
        ]
        lines.append(
            f"| {snr_label(snr)} | {est:.1f} | "
            + ", ".join(str(f["chosen"]) for f in cv["folds"])
            + f" | {cv['mean']:.2f} ± {cv['spread']:.2f} | {auto_held:.2f} | "
            f"{cv['chosen_on_all']} | " + " | ".join(means) + " |"
        )
    lines += [""]
    for snr in snrs:
        c = chosen_all[snr]
        if c == "auto":
            lines.append(
                f'* {snr_label(snr)}: `lam="auto"` stays (no weight leads it by more '
                f"than {args.tie_db:g} dB on all the scenes)."
            )
        else:
            gain = np.mean(
                [cache[key(s, snr, c)]["psnr"] - cache[key(s, snr, "auto")]["psnr"]
                 for f in folds for s in f]
            )  # fmt: skip
            lines.append(
                f"* {snr_label(snr)}: lam {c:g} leads `auto` by {gain:+.2f} dB on the scenes' mean."
            )
    write_results(out, lines)


if __name__ == "__main__":
    main()
