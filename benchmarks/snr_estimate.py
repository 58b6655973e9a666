"""The measurement SNR estimate on every system: measurement-only against fit residual.

For every registered system, a real CAVE tuning scene (``--scene``, 64×64,
16 bands, the system's seeded random code) noiseless, at 30 dB and at 20 dB
(noise seed 0): the measurement-only reading
(:func:`tensor_cosdi.noise.estimate_snr_db`), the frames' smallest singular
value where the system's frames are low-rank (``snr_frames_low_rank``), the
fit-residual reading, the fit behind it and the estimate
(:func:`tensor_cosdi.solvers.snr.estimate_snr`), and the residual reading the
other fit would give.
The verdict column is computed: ``ok`` when the estimate is within 3 dB of a
noisy truth and above 32 dB when noiseless.

A second table reads the same estimate at the real-spectra protocol
(SD-CASSI, 256×256×28, 2 px per band, ``_protocol.problem``) on every tuning
scene, for the TSA mask and the seeded random code, with the fit the system
calls for (the subspace fit) and, beside it, with the plain GAP-TV fit: the
spread of each over the scenes and how many get the verdict ``ok``.

``--effect`` writes ``snr_frames_effect.md`` instead: what the frames' reading
changes in a reconstruction — ``--methods`` (``"auto"`` settings) on CS2LI and
Mu-CoSDI (64×64, 16 bands, four phase steps) on ``--scenes`` noiseless, at 30
and at 20 dB, with the reading and without it (the system's
``snr_frames_low_rank`` patched to false, a fresh system per arm so that no
cached estimate is shared).

``--fit-tv SYSTEM`` writes ``snr_fit_tv_SYSTEM.md`` instead: the estimate on a system that
uses the GAP-TV fit, for every ``--weights`` value of that fit's TV weight (the system's
``snr_fit_tv``), on every tuning scene (64×64 with 16 bands, 128×128 with 28; noiseless, 30
and 20 dB): how many estimates are ``ok``, and the weight chosen by 4-fold cross-validation
over the scenes (the most ``ok`` on three folds, ties to the smaller mean distance from the
truth, scored on the fourth) — the table behind the system's ``snr_fit_tv``.

``--refit 5,8,none`` writes ``snr_fit_refit.md`` instead: the estimate on every tuning scene
as it is and lit by each ``--lights`` illuminant (default A, LED-B3, FL11; TSA mask,
noiseless, 30 and 20 dB) with the subspace fit's light gate after that many iterations, or
without it — the table behind :data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_REFIT`.

``--recheck 30,31,31.5,32,33 --recheck-clean 40,41,42,43,44`` writes ``snr_fit_recheck.md``
instead: on every tuning scene (as it is and lit by each ``--lights`` illuminant; both codes;
noiseless, 40, 30 and 20 dB) the estimate without the subspace fit's second look, the second
fit's reading, and for each pair of thresholds (the band of first estimates that get the
second look, from / clean) the views that end on the clean path — the table behind
:data:`~tensor_cosdi.solvers.snr.RECHECK_FROM_DB` and
:data:`~tensor_cosdi.solvers.snr.RECHECK_CLEAN_DB`, chosen per fold by a computed rule (no 40,
30 or 20 dB view clean and no second fit run on a 30 or 20 dB one, then the most noiseless
views clean) and scored on the held-out fold.  The per-view readings are kept in
``snr_fit_recheck.json`` (a killed run resumes).

``--recheck-effect`` writes ``snr_recheck_effect.md`` instead: every ``--methods`` method
(its ``"auto"`` settings) with and without the second look (its threshold patched to
infinity: the earlier estimate) on the views of ``snr_fit_recheck.json`` whose path the
second look changes (at most ``--max-views`` per code and SNR, in the file's order); rows kept
in ``snr_recheck_effect.json`` (a killed run resumes).

``--sweep`` writes ``snr_fit_sweep.md`` instead: the subspace fit's residual
reading at the protocol for every ``--iters`` × ``--weights`` pair, the
table behind :data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_ITER` and
:data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_TV`.

    python benchmarks/snr_estimate.py [--scene balloons] [--no-protocol]
                                      [--out benchmarks/results/snr_estimate.md]
    python benchmarks/snr_estimate.py --sweep [--iters 40,60] [--weights 0.1,0.2,0.3]
    python benchmarks/snr_estimate.py --fit-tv c3slfi [--weights 0.1,0.05,0.03,0.02]
    python benchmarks/snr_estimate.py --refit 5,8,none [--lights A,LED-B3,FL11]
    python benchmarks/snr_estimate.py --recheck 30,31,31.5,32,33
                                      [--recheck-clean 40,41,42,43,44] [--lights FL11]
    python benchmarks/snr_estimate.py --recheck-effect [--methods otd,pnp_fast,pnp_gap]
                                      [--max-views 4]
    python benchmarks/snr_estimate.py --effect [--methods otd,pnp_gap]
                                      [--scenes balloons,clay,feathers]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402
    MASKS,
    RESULTS,
    load_mask,
    positive_numbers,
    problem,
    problems,
    scene_view,
    snr_label,
    write_results,
)

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi import _backend as B  # noqa: E402
from tensor_cosdi.solvers import snr as snr_module  # noqa: E402
from tensor_cosdi.solvers.pnp_gap import ACCELERATE_ABOVE_DB as CLEAN  # noqa: E402
from tensor_cosdi.solvers.snr import estimate_snr, residual_reading_db  # noqa: E402
from tensor_cosdi.solvers.subspace import subspace_gap_tv  # noqa: E402


def verdict(true_snr, est) -> str:
    if true_snr is None:
        return "ok" if est > 32 else "reads noise"
    return "ok" if abs(est - true_snr) < 3 else f"off by {est - true_snr:+.1f} dB"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="balloons", help="a tuning scene of the research data")
    ap.add_argument("--out", default=str(RESULTS / "snr_estimate.md"))
    ap.add_argument(
        "--no-protocol", action="store_true", help="skip the 256×256×28 table on the tuning scenes"
    )
    ap.add_argument("--sweep", action="store_true", help="the subspace fit's iterations × weights")
    ap.add_argument(
        "--effect", action="store_true", help="reconstructions with and without the frames' reading"
    )
    ap.add_argument(
        "--methods", default=None,
        help="--effect (otd,pnp_gap), --recheck-effect (otd,pnp_fast,pnp_gap): methods",
    )  # fmt: skip
    ap.add_argument(
        "--recheck-effect", action="store_true",
        help="reconstructions with and without the SNR estimate's second look",
    )  # fmt: skip
    ap.add_argument(
        "--max-views", type=int, default=4, help="--recheck-effect: views per code and SNR"
    )
    ap.add_argument(
        "--scenes", default="balloons,clay,feathers", help="--effect: tuning scenes, comma-sep."
    )
    ap.add_argument("--iters", default="40,60", help="--sweep: iteration counts, comma-separated")
    ap.add_argument("--weights", default="0.1,0.2,0.3", help="--sweep: TV weights, comma-separated")
    ap.add_argument(
        "--fit-tv", default=None, metavar="SYSTEM", help="the GAP-TV fit's TV weight on SYSTEM"
    )
    ap.add_argument(
        "--refit", default=None, metavar="LIST",
        help="the subspace fit's light gate: iterations before it (or 'none'), comma-separated",
    )  # fmt: skip
    ap.add_argument(
        "--lights", default=None, help="--refit (default A,LED-B3,FL11), --recheck (FL11): CIE "
        "illuminants, comma-separated",
    )  # fmt: skip
    ap.add_argument(
        "--recheck", default=None, metavar="LIST",
        help="the subspace fit's second look: lower ends of its band in dB, comma-separated",
    )  # fmt: skip
    ap.add_argument(
        "--recheck-clean", default="40,41,42,43,44", metavar="LIST",
        help="--recheck: the second reading's clean thresholds (the band's tops), dB",
    )  # fmt: skip
    ap.add_argument(
        "--recheck-fit", default=None, metavar="ITER,TV",
        help="--recheck: the second fit's iterations and TV weight (default the library's)",
    )  # fmt: skip
    args = ap.parse_args(argv)
    if args.scene not in tc.datasets.TUNE_SCENES:
        raise SystemExit(f"--scene must be a tuning scene, one of {tc.datasets.TUNE_SCENES}")
    try:
        tc.datasets.data_dir()
    except FileNotFoundError as exc:
        raise SystemExit(f"snr_estimate.py needs the research scenes: {exc}") from None
    if args.effect:
        scenes = args.scenes.split(",")
        if not set(scenes) <= set(tc.datasets.TUNE_SCENES):
            raise SystemExit(f"--scenes must be tuning scenes, of {tc.datasets.TUNE_SCENES}")
        methods = _methods(args.methods, "otd,pnp_gap")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / "snr_frames_effect.md" if default_out else args.out
        write_results(out, effect_table(methods, scenes))
        return
    if args.recheck_effect:
        methods = _methods(args.methods, "otd,pnp_fast,pnp_gap")
        if args.max_views < 1:
            raise SystemExit(f"--max-views must be ≥ 1, got {args.max_views}")
        store = RESULTS / "snr_fit_recheck.json"
        if not store.is_file():
            raise SystemExit(f"--recheck-effect reads {store}: run --recheck first")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = Path(RESULTS / "snr_recheck_effect.md" if default_out else args.out)
        rows = json.loads(store.read_text())
        write_results(
            out, recheck_effect_table(methods, rows, args.max_views, out.with_suffix(".json"))
        )
        return
    if args.fit_tv is not None:
        if args.fit_tv not in tc.studies.SYSTEMS:
            raise SystemExit(f"--fit-tv must be a system of {list(tc.studies.SYSTEMS)}")
        weights = positive_numbers(args.weights, "--weights")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / f"snr_fit_tv_{args.fit_tv}.md" if default_out else args.out
        write_results(out, fit_tv_table(args.fit_tv, weights))
        return
    if args.refit is not None:
        try:
            refits = [None if v == "none" else int(v) for v in args.refit.split(",")]
        except ValueError:
            raise SystemExit("--refit takes integers ≥ 1 or 'none', comma-separated") from None
        if any(r is not None and r < 1 for r in refits):
            raise SystemExit("--refit takes integers ≥ 1 or 'none', comma-separated")
        lights = _lights(args.lights, "A,LED-B3,FL11")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / "snr_fit_refit.md" if default_out else args.out
        write_results(out, refit_table(refits, lights))
        return
    if args.recheck is not None:
        froms = positive_numbers(args.recheck, "--recheck")
        tops = positive_numbers(args.recheck_clean, "--recheck-clean")
        lights = _lights(args.lights, "FL11")
        fit = (snr_module.RECHECK_ITER, snr_module.RECHECK_TV)
        if args.recheck_fit is not None:
            values = positive_numbers(args.recheck_fit, "--recheck-fit")
            if len(values) != 2 or values[0] != int(values[0]):
                raise SystemExit("--recheck-fit takes ITER,TV: an integer ≥ 1 and a weight > 0")
            fit = (int(values[0]), values[1])
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = Path(RESULTS / "snr_fit_recheck.md" if default_out else args.out)
        with mock.patch.multiple(snr_module, RECHECK_ITER=fit[0], RECHECK_TV=fit[1]):
            lines = recheck_table(froms, tops, lights, out.with_suffix(".json"))
        write_results(out, lines)
        return
    if args.sweep:
        try:
            iters = [int(v) for v in args.iters.split(",")]
            weights = [float(v) for v in args.weights.split(",")]
        except ValueError:
            raise SystemExit(
                "--iters takes integers and --weights numbers, comma-separated"
            ) from None
        if min(iters) < 1 or not min(weights) > 0:
            raise SystemExit("--iters must be ≥ 1 and --weights > 0")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / "snr_fit_sweep.md" if default_out else args.out
        write_results(out, sweep_table(iters, weights))
        return
    lines = [
        f"# Measurement SNR estimates, `cave.{args.scene}`, 64×64, 16 bands, random codes",
        "",
        "| system | true SNR | measurement only dB | frames' rank dB | fit residual dB | fit "
        "| estimate dB | verdict | the other fit's residual dB |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in tc.studies.SYSTEMS:
        for snr in (None, 30, 20):
            p = tc.studies.make_problem(
                name, f"cave.{args.scene}", shape=(64, 64), n_bands=16, snr_db=snr, rng=0
            )
            e = estimate_snr(p.system, p.measurement)
            other = "gap_tv" if e.fit == "subspace" else "subspace"
            o = estimate_snr(p.system, p.measurement, fit=other)
            frames = "—" if np.isnan(e.from_frames_db) else f"{e.from_frames_db:.1f}"
            lines.append(
                f"| {name} | {'noiseless' if snr is None else f'{snr} dB'} | "
                f"{e.from_measurement_db:.1f} | {frames} | {e.from_residual_db:.1f} | {e.fit} | "
                f"{e.snr_db:.1f} | "
                f"{verdict(snr, e.snr_db)} | {o.from_residual_db:.1f} ({other}) |"
            )
            print(lines[-1], flush=True)
    if not args.no_protocol:
        lines += protocol_table()
    write_results(args.out, lines)


def protocol_table() -> list[str]:
    """The estimate on every tuning scene at the real-spectra protocol, both codes, with the
    fit the system calls for and with the plain GAP-TV fit."""
    scenes = tc.datasets.TUNE_SCENES
    lines = [
        "",
        f"## SD-CASSI 256×256×28, 2 px per band, the {len(scenes)} tuning scenes",
        "",
        "The estimate with the subspace fit (the one SD-CASSI calls for) and, beside it, with "
        'the plain GAP-TV fit (`estimate_snr(..., fit="gap_tv")`).',
        "",
        f"| code | true SNR | fit | estimate dB: min | median | max | verdict ok "
        f"| read ≥ {CLEAN:g} dB (`pnp_gap`'s accelerated path) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    seconds = {"subspace": [], "gap_tv": []}
    for mask in MASKS:
        code = load_mask(mask)
        for snr in (None, 30, 20):
            est = {"subspace": [], "gap_tv": []}
            for scene in scenes:
                system, _, g = problem(scene, snr, code)
                for fit, values in est.items():
                    t0 = time.perf_counter()
                    values.append(estimate_snr(system, g, fit=fit).snr_db)
                    seconds[fit].append(time.perf_counter() - t0)
            for fit, values in est.items():
                ok = sum(verdict(snr, e) == "ok" for e in values)
                lines.append(
                    f"| {mask} | {'noiseless' if snr is None else f'{snr} dB'} | {fit} | "
                    f"{np.min(values):.1f} | {np.median(values):.1f} | {np.max(values):.1f} | "
                    f"{ok} of {len(values)} | {sum(e >= CLEAN for e in values)} of {len(values)} |"
                )
                print(lines[-1], flush=True)
    lines += [
        "",
        "Median seconds of one estimate (one fit) over these runs: "
        + ", ".join(f"{fit} {np.median(v):.2f} s" for fit, v in seconds.items())
        + ".",
    ]
    return lines


def with_without_header(first: list[str], methods) -> list[str]:
    """A markdown table's header and rule: the ``first`` columns, then each method without,
    with and its gain."""
    cols = first + [f"{m} {c}" for m in methods for c in ("without", "with", "gain dB")]
    return ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]


def effect_table(methods, scenes) -> list[str]:
    """Mean PSNR of each method with and without the frames' reading of the SNR, per system and
    noise level, with the mean estimate of each arm."""
    reg = tc.systems.REGISTRY
    systems = [n for n in tc.studies.SYSTEMS if reg[n].example().snr_frames_low_rank]
    lines = [
        "# What the frames' SNR reading changes in a reconstruction",
        "",
        f"Systems whose frames are low-rank ({', '.join(systems)}), 64×64, 16 bands, four phase "
        f"steps, seeded codes (rng 0), tuning scenes {', '.join(scenes)}; every method with its "
        '`"auto"` settings.  *without*: the system\'s `snr_frames_low_rank` patched to false '
        "(the estimate of the earlier releases).  Mean PSNR dB over the scenes (the study's "
        "score) and the mean estimate.",
        "",
        *with_without_header(["system", "true SNR", "estimate dB without / with"], methods),
    ]
    for name in systems:
        cls = reg[name]
        for snr in (None, 30, 20):
            est = {False: [], True: []}
            psnr = {(m, arm): [] for m in methods for arm in (False, True)}
            for scene in scenes:
                for arm in (False, True):
                    with mock.patch.object(cls, "snr_frames_low_rank", arm):
                        p = tc.studies.make_problem(
                            name, f"cave.{scene}", shape=(64, 64), n_bands=16, snr_db=snr, rng=0
                        )
                        est[arm].append(estimate_snr(p.system, p.measurement).snr_db)
                        for m in methods:
                            cube = tc.reconstruct(p.system, p.measurement, m).cube
                            psnr[(m, arm)].append(float(tc.studies.score(p, cube)["psnr"]))
            cells = []
            for m in methods:
                off, on = np.mean(psnr[(m, False)]), np.mean(psnr[(m, True)])
                cells.append(f"{off:.2f} | {on:.2f} | {on - off:+.2f}")
            lines.append(
                f"| {name} | {'noiseless' if snr is None else f'{snr} dB'} | "
                f"{np.mean(est[False]):.1f} / {np.mean(est[True]):.1f} | "
                + " | ".join(cells)
                + " |"
            )
            print(lines[-1], flush=True)
    return lines


#: ``--fit-tv``'s settings: (side, bands) of the seeded problems.
FIT_TV_SIZES = ((64, 16), (128, 28))
TRUTHS = (None, 30.0, 20.0)


def _fit_tv_choice(est, weights, scenes):
    """The weight with the most ``ok`` estimates over ``scenes`` (ties: the smaller mean
    distance of the noisy estimates from the truth), and its ok count and distance."""

    def key(w):
        cells = [(t, est[w, s, size, t]) for s in scenes for size in FIT_TV_SIZES for t in TRUTHS]
        ok = sum(verdict(t, e) == "ok" for t, e in cells)
        dist = float(np.mean([abs(e - t) for t, e in cells if t is not None]))
        return -ok, dist

    best = min(weights, key=key)
    return best, -key(best)[0], key(best)[1]


def fit_tv_table(name, weights) -> list[str]:
    """The estimate on ``name`` for every GAP-TV fit weight, on every tuning scene; the weight
    chosen by 4-fold cross-validation over the scenes."""
    scenes = tc.datasets.TUNE_SCENES
    est = {}
    t0 = time.perf_counter()
    for side, bands in FIT_TV_SIZES:
        for scene in scenes:
            for snr in TRUTHS:
                p = tc.studies.make_problem(
                    name, f"cave.{scene}", shape=(side, side), n_bands=bands, snr_db=snr, rng=0
                )
                current = type(p.system).snr_fit_tv
                if estimate_snr(p.system, p.measurement).fit != "gap_tv":
                    raise SystemExit(f"{name} does not use the GAP-TV fit; --fit-tv is for those")
                for w in weights:  # systems are immutable: the class attribute is patched
                    with mock.patch.object(type(p.system), "snr_fit_tv", w):
                        e = estimate_snr(p.system, p.measurement)
                    est[w, scene, (side, bands), snr] = e.snr_db
            print(f"{side}×{side}×{bands} {scene} done", flush=True)
    lines = [
        f"# The SNR estimate's GAP-TV fit weight on {name}: the {len(scenes)} tuning scenes",
        "",
        f"The system's seeded codes and its example options, noise seed 0.  Each cell: the "
        "estimate in dB, min / median / max over the scenes, and how many are `ok` (noiseless: "
        "above 32 dB; noisy: within 3 dB of the truth).  Fit: "
        f"{tc.solvers.snr.FIT_ITER} plain GAP-TV iterations.",
        "",
        "| size | true SNR | " + " | ".join(f"TV {w:g}" for w in weights) + " |",
        "|---|---|" + "---|" * len(weights),
    ]
    for size in FIT_TV_SIZES:
        for snr in TRUTHS:
            cells = []
            for w in weights:
                v = np.asarray([est[w, s, size, snr] for s in scenes])
                ok = sum(verdict(snr, e) == "ok" for e in v)
                cells.append(
                    f"{v.min():.1f} / {np.median(v):.1f} / {v.max():.1f} ({ok} of {len(v)})"
                )
            lines.append(
                f"| {size[0]}×{size[0]}×{size[1]} | "
                f"{'noiseless' if snr is None else f'{snr:g} dB'} | " + " | ".join(cells) + " |"
            )
    folds = tc.datasets.tune_folds(4)
    lines += [
        "",
        "Cross-validation (4 folds of `datasets.tune_folds(4)`; the weight chosen on three "
        "folds, scored on the fourth):",
        "",
        "| held-out fold | chosen weight | ok on the fold | cases | mean distance dB, noisy |",
        "|---|---|---|---|---|",
    ]
    held_ok = 0
    held_n = 0
    chosen = []
    for k, fold in enumerate(folds):
        rest = [s for j, f in enumerate(folds) if j != k for s in f]
        w, _, _ = _fit_tv_choice(est, weights, rest)
        _, ok, dist = _fit_tv_choice(est, [w], fold)
        n = len(fold) * len(FIT_TV_SIZES) * len(TRUTHS)
        held_ok += ok
        held_n += n
        chosen.append(w)
        lines.append(f"| {k} | {w:g} | {ok} | {n} | {dist:.2f} |")
    w_all, ok_all, dist_all = _fit_tv_choice(est, weights, scenes)
    n_all = len(scenes) * len(FIT_TV_SIZES) * len(TRUTHS)
    lines += [
        "",
        f"Held out: {held_ok} of {held_n} estimates ok with the weight each fold chose "
        f"({', '.join(f'{w:g}' for w in chosen)}).  Chosen on all {len(scenes)} scenes: "
        f"**TV {w_all:g}**, {ok_all} of {n_all} ok (mean distance of the noisy estimates "
        f"{dist_all:.2f} dB); the system's `snr_fit_tv` is {current:g}.",
        "",
        f"{time.perf_counter() - t0:.0f} s in all.",
    ]
    return lines


def summary_cell(readings, true_snr) -> str:
    """``"min / median / max (k of n)"`` of SNR readings in dB, ``k`` those ``ok``: a noiseless
    truth read at ≥ the clean threshold, a noisy one within 3 dB."""
    v = np.asarray(readings)
    ok = int((v >= CLEAN).sum()) if true_snr is None else int((abs(v - true_snr) < 3).sum())
    return f"{v.min():.1f} / {np.median(v):.1f} / {v.max():.1f} ({ok} of {len(v)})"


def sweep_table(iters, weights) -> list[str]:
    """The subspace fit's residual reading for every iterations × weight pair, at the protocol
    on every tuning scene, both codes: min / median / max over the scenes, and how many read a
    noiseless scene at ≥ the clean threshold or a noisy one within 3 dB."""
    scenes = tc.datasets.TUNE_SCENES
    pairs = [(it, w) for it in iters for w in weights]
    lines = [
        f"# The SNR estimate's subspace fit: iterations × TV weight, SD-CASSI 256×256×28, "
        f"the {len(scenes)} tuning scenes",
        "",
        "Each cell: the residual reading in dB, min / median / max over the scenes, and how "
        f"many are `ok` (noiseless: ≥ {CLEAN:g} dB, the clean path; noisy: within 3 dB).  The "
        "estimate is the larger of this reading and the measurement-only one.",
        "",
        "| code | true SNR | " + " | ".join(f"{it} it, TV {w:g}" for it, w in pairs) + " |",
        "|---|---|" + "---|" * len(pairs),
    ]
    for mask in MASKS:
        code = load_mask(mask)
        for snr in (None, 30, 20):
            read = {p: [] for p in pairs}
            for scene in scenes:
                system, _, g = problem(scene, snr, code)
                g64 = np.asarray(g, dtype=np.float64)
                gu = g64 / np.abs(g64).max()
                for it, w in pairs:
                    x = subspace_gap_tv(
                        system, B.as_tensor(gu, "float32"), max_iter=it, tv_weight=w, tv_steps=5
                    )
                    read[(it, w)].append(residual_reading_db(system, gu, x))
            cells = [summary_cell(read[p], snr) for p in pairs]
            lines.append(
                f"| {mask} | {'noiseless' if snr is None else f'{snr} dB'} | "
                + " | ".join(cells)
                + " |"
            )
            print(lines[-1], flush=True)
    return lines


def refit_table(refits, lights) -> list[str]:
    """The estimate (TSA mask, every tuning scene as it is and lit by each of ``lights``) with
    the subspace fit's light gate after each of ``refits`` iterations (``None``: no gate;
    :data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_REFIT`): min / median / max over the
    scenes, and how many are ``ok`` (noiseless: ≥ the clean threshold; noisy: within 3 dB)."""
    scenes = tc.datasets.TUNE_SCENES
    code = load_mask("tsa")
    label = {r: "no gate" if r is None else f"gate after {r}" for r in refits}
    lines = [
        f"# The SNR estimate under lights with sharp lines: the subspace fit's light gate, "
        f"SD-CASSI 256×256×28, TSA mask, the {len(scenes)} tuning scenes",
        "",
        f"The fit runs {snr_module.SUBSPACE_FIT_ITER} iterations; with the gate its atoms are "
        "weighted by the fitted mean spectrum for the rest where that spectrum reads rough "
        "(`subspace_gap_tv(refit_at=...)`).  Each cell: the estimate in dB without the second "
        "look (`snr_fit_recheck.md`), min / median / max over the scenes, and how many are "
        f"`ok` (noiseless: ≥ {CLEAN:g} dB, the clean path; noisy: within 3 dB).",
        "",
        "| light | true SNR | " + " | ".join(label[r] for r in refits) + " |",
        "|---|---|" + "---|" * len(refits),
    ]
    saved = snr_module.SUBSPACE_FIT_REFIT
    try:
        for light in [None, *lights]:
            for snr in (None, 30, 20):
                read = {r: [] for r in refits}
                for scene in scenes:
                    for r in refits:  # a fresh system each: no estimate cached across gates
                        system, _, g = problem(scene, snr, code, illuminant=light)
                        snr_module.SUBSPACE_FIT_REFIT = r
                        with mock.patch.object(snr_module, "RECHECK_FROM_DB", np.inf):
                            read[r].append(estimate_snr(system, g).snr_db)  # the first fit
                cells = [summary_cell(read[r], snr) for r in refits]
                lines.append(
                    f"| {light or 'none'} | {'noiseless' if snr is None else f'{snr} dB'} | "
                    + " | ".join(cells) + " |"
                )  # fmt: skip
                print(lines[-1], flush=True)
    finally:
        snr_module.SUBSPACE_FIT_REFIT = saved
    return lines


def _methods(text, default) -> list[str]:
    methods = [m for m in (default if text is None else text).split(",") if m]
    if not methods or not set(methods) <= set(tc.solvers.METHODS):
        raise SystemExit(f"--methods must be methods of {sorted(tc.solvers.METHODS)}")
    return methods


def _lights(text, default) -> list[str]:
    lights = [v for v in (default if text is None else text).split(",") if v]
    for light in lights:
        scene_view(f"x~{light}")  # a one-line error for an unknown illuminant
    return lights


RECHECK_SNRS = (None, 40, 30, 20)


def recheck_readings(lights, store: Path) -> list[dict]:
    """Per view (tuning scene as it is or lit, code, true SNR): the estimate without the second
    look (``first``), the second fit's reading (``second``) and its seconds; kept in ``store``
    as they come (a killed run resumes)."""
    rows = json.loads(store.read_text()) if store.is_file() else []
    done = {(r["scene"], r["mask"], r["snr_db"]) for r in rows}
    fold_of = {s: k for k, fold in enumerate(tc.datasets.tune_folds(4)) for s in fold}
    views = [*tc.datasets.TUNE_SCENES]
    views += [f"{s}~{light}" for light in lights for s in tc.datasets.TUNE_SCENES]
    for mask in MASKS:
        code = load_mask(mask)
        for view in views:
            name, _, light = scene_view(view)
            snrs = [snr for snr in RECHECK_SNRS if (view, mask, snr) not in done]
            if not snrs:
                continue
            system, _, gs = problems(name, snrs, code, illuminant=light)
            for snr, g in zip(snrs, gs):
                t0 = time.perf_counter()
                with mock.patch.object(snr_module, "RECHECK_FROM_DB", float("inf")):
                    first = estimate_snr(system, g).snr_db
                t1 = time.perf_counter()
                snr_module.clear_cache()  # the same measurement again, with the second look
                band = {"RECHECK_FROM_DB": -np.inf, "RECHECK_CLEAN_DB": np.inf}
                with mock.patch.multiple(snr_module, **band):
                    second = estimate_snr(system, g).rechecked_db
                seconds = time.perf_counter() - t1 - (t1 - t0)  # the second fit's share
                rows.append({
                    "scene": view, "fold": fold_of[name], "mask": mask, "snr_db": snr,
                    "first": first, "second": second, "seconds": seconds,
                })  # fmt: skip
                store.write_text(json.dumps(rows, indent=0))
                print(f"{view:30s} {mask:6s} {str(snr):5s} {first:6.2f} {second:6.2f}", flush=True)
    return rows


def recheck_final(r, lo, top) -> float:
    """The estimate of row ``r`` with a second look for a first estimate in ``[lo, top)`` dB
    (:func:`tensor_cosdi.solvers.snr.estimate_snr`: the second reading less ``top − CLEAN``)."""
    if lo <= r["first"] < top:
        return r["second"] - (top - CLEAN)
    return r["first"]


def recheck_outcome(rows, lo, top) -> dict:
    """What a second look for first estimates in ``[lo, top)`` dB does on ``rows``: the views
    that end clean per true SNR (``clean[None]`` noiseless ones, ``clean[40]`` ...) and the
    second fits run on 30 / 20 dB views (``fires``) and on the others (``fires_other``)."""
    out = {"clean": {snr: 0 for snr in RECHECK_SNRS}, "fires": 0, "fires_other": 0}
    for r in rows:
        out["clean"][r["snr_db"]] += recheck_final(r, lo, top) >= CLEAN
        if lo <= r["first"] < top:
            out["fires" if r["snr_db"] in (30, 20) else "fires_other"] += 1
    return out


def recheck_choice(rows, pairs):
    """The rule over ``(from, clean)`` pairs: no 40, 30 or 20 dB view clean (the clean path's
    accelerated GAP lets even 40 dB of noise through), no second fit run on a 30 or 20 dB view
    (a noisy measurement would pay its time for nothing, and ``pnp_fast`` spends about 5 s in
    all), then the most noiseless views clean, then the fewest second fits, then the higher
    ``from``."""

    def key(pair):
        o = recheck_outcome(rows, *pair)
        wrong = o["clean"][40] + o["clean"][30] + o["clean"][20]
        return (wrong == 0, o["fires"] == 0, o["clean"][None], -o["fires_other"], pair[0])

    return max(pairs, key=key)


def recheck_table(froms, tops, lights, store: Path) -> list[str]:
    """:func:`recheck_readings` summed up per threshold pair, and the pair chosen per fold."""
    rows = recheck_readings(lights, store)
    n = {snr: sum(r["snr_db"] == snr for r in rows) for snr in RECHECK_SNRS}
    lit = ", ".join(f"`~{light}`" for light in lights)
    pairs = [(lo, top) for lo in froms for top in tops if lo < top]
    lines = [
        "# The SNR estimate's second look: SD-CASSI 256×256×28, the tuning scenes",
        "",
        f"Views: the {len(tc.datasets.TUNE_SCENES)} tuning scenes as they are"
        + (f" and lit by {lit}" if lights else "")
        + f", through the TSA mask and the seeded random code, noiseless, 40, 30 and 20 dB.  "
        f"First: the estimate of the {snr_module.SUBSPACE_FIT_ITER}-iteration fit at TV "
        f"{snr_module.SUBSPACE_FIT_TV:g}; second: the residual reading of the "
        f"{snr_module.RECHECK_ITER}-iteration fit at TV {snr_module.RECHECK_TV:g}.  Clean: an "
        f"estimate of {CLEAN:g} dB or more (the solvers' clean path).",
        "",
        "| true SNR | views | first: min / median / max dB | second: min / median / max dB "
        "| second − first: min / median / max dB | clean by the first |",
        "|---|---|---|---|---|---|",
    ]
    for snr in RECHECK_SNRS:
        f = np.array([r["first"] for r in rows if r["snr_db"] == snr])
        s = np.array([r["second"] for r in rows if r["snr_db"] == snr])
        lines.append(
            f"| {snr_label(snr)} | {n[snr]} | "
            f"{f.min():.1f} / {np.median(f):.1f} / {f.max():.1f} | "
            f"{s.min():.1f} / {np.median(s):.1f} / {s.max():.1f} | "
            f"{(s - f).min():.1f} / {np.median(s - f):.1f} / {(s - f).max():.1f} | "
            f"{int((f >= CLEAN).sum())} |"
        )
    lines += [
        "",
        "A second look for a first estimate in [from, clean) dB makes the estimate the second "
        f"reading less clean − {CLEAN:g} (clean where the second reads `clean` or more).  Views "
        "that end clean with each pair, and the second fits run (time):",
        "",
        "| from dB | clean dB | noiseless | 40 dB | 30 dB | 20 dB | second fits on noiseless / "
        "40 dB | on 30 / 20 dB |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for lo, top in [(float("inf"), float("inf")), *pairs]:
        o = recheck_outcome(rows, lo, top)
        c = o["clean"]
        label = "none | —" if lo == float("inf") else f"{lo:g} | {top:g}"
        lines.append(
            f"| {label} | {c[None]} of {n[None]} | {c[40]} of {n[40]} | {c[30]} of {n[30]} | "
            f"{c[20]} of {n[20]} | {o['fires_other']} | {o['fires']} |"
        )
    per_fold = []
    for k in sorted({r["fold"] for r in rows}):
        lo, top = recheck_choice([r for r in rows if r["fold"] != k], pairs)
        held = [r for r in rows if r["fold"] == k]
        o = recheck_outcome(held, lo, top)
        before = recheck_outcome(held, float("inf"), float("inf"))["clean"]
        per_fold.append(
            f"fold {k}: [{lo:g}, {top:g}) → noiseless clean {o['clean'][None]} of "
            f"{sum(r['snr_db'] is None for r in held)} ({before[None]} without), 40 / 30 / 20 "
            f"dB clean {o['clean'][40]} / {o['clean'][30]} / {o['clean'][20]} ({before[40]} / "
            f"{before[30]} / {before[20]} without), {o['fires']} second fits on 30 / 20 dB"
        )
    lo, top = recheck_choice(rows, pairs)
    secs = [r["seconds"] for r in rows]
    lines += [
        "",
        "Chosen on three folds (`datasets.tune_folds(4)`), scored on the fourth (rule: no 40, "
        "30 or 20 dB view clean — the clean path's accelerated GAP lets even 40 dB of noise "
        "through — and no second fit run on a 30 or 20 dB view — it would pay its time for "
        "nothing, and `pnp_fast` spends about 5 s in all — then the most noiseless views "
        "clean, the fewest second fits, the higher `from`): " + "; ".join(per_fold) + ".",
        "",
        f"Chosen on all views: **[{lo:g}, {top:g}) dB**; the library's `RECHECK_FROM_DB` and "
        f"`RECHECK_CLEAN_DB` are {snr_module.RECHECK_FROM_DB:g} and "
        f"{snr_module.RECHECK_CLEAN_DB:g}.  The second fit took a median of "
        f"{np.median(secs):.2f} s ({min(secs):.2f}-{max(secs):.2f}).",
    ]
    return lines


def changed_views(rows, max_views: int) -> list[dict]:
    """The views of ``rows`` whose path the library's second look changes (clean by the first
    estimate and not by the second, or the other way), at most ``max_views`` per code and true
    SNR, in ``rows``' order."""
    lo, top = snr_module.RECHECK_FROM_DB, snr_module.RECHECK_CLEAN_DB
    out, count = [], {}
    for r in rows:
        if (recheck_final(r, lo, top) >= CLEAN) == (r["first"] >= CLEAN):
            continue
        k = (r["mask"], r["snr_db"])
        if count.get(k, 0) < max_views:
            count[k] = count.get(k, 0) + 1
            out.append(r)
    return out


def recheck_effect_table(methods, rows, max_views, store: Path) -> list[str]:
    """PSNR of each method with and without the second look on :func:`changed_views`."""
    from _protocol import run, score

    views = changed_views(rows, max_views)
    done = json.loads(store.read_text()) if store.is_file() else []
    index = {(d["scene"], d["mask"], d["snr_db"], d["method"], d["arm"]): d for d in done}
    for v in views:
        name, _, light = scene_view(v["scene"])
        system, cube, (g,) = problems(name, [v["snr_db"]], load_mask(v["mask"]), illuminant=light)
        for m in methods:
            for arm in ("without", "with"):
                k = (v["scene"], v["mask"], v["snr_db"], m, arm)
                if k in index:
                    continue
                limit = float("inf") if arm == "without" else snr_module.RECHECK_FROM_DB
                with mock.patch.object(snr_module, "RECHECK_FROM_DB", limit):
                    est, secs = run(m, system, g, {})
                    snr_est = estimate_snr(system, g).snr_db
                index[k] = {
                    "scene": v["scene"], "mask": v["mask"], "snr_db": v["snr_db"], "method": m,
                    "arm": arm, "psnr": score(cube, est)["psnr"], "seconds": secs,
                    "estimate_db": snr_est,
                }  # fmt: skip
                store.write_text(json.dumps(list(index.values()), indent=0))
                print(f"{v['scene']:28s} {v['mask']:6s} {str(v['snr_db']):5s} {m:9s} {arm:7s} "
                      f"{index[k]['psnr']:.2f} dB {secs:.1f} s", flush=True)  # fmt: skip
    lines = [
        "# What the SNR estimate's second look changes in a reconstruction",
        "",
        f"The views of `snr_fit_recheck.json` whose path it changes (a first estimate in "
        f"[{snr_module.RECHECK_FROM_DB:g}, {snr_module.RECHECK_CLEAN_DB:g}) dB gets the second "
        f"look; clean: an estimate of {CLEAN:g} dB or more), at most {max_views} per code and "
        'SNR; each method at its `"auto"` settings *without* the second look (its band '
        "patched away: the earlier estimate) and *with* it; PSNR dB (the second fit's time is "
        "in `snr_fit_recheck.md`).",
        "",
        *with_without_header(["view", "code", "true SNR", "estimate dB without → with"], methods),
    ]
    gains = {m: [] for m in methods}
    for v in views:
        key = (v["scene"], v["mask"], v["snr_db"])
        get = {(m, a): index[(*key, m, a)] for m in methods for a in ("without", "with")}
        first = get[(methods[0], "without")]["estimate_db"]
        second = get[(methods[0], "with")]["estimate_db"]
        cells = []
        for m in methods:
            a, b = get[(m, "without")], get[(m, "with")]
            gains[m].append(b["psnr"] - a["psnr"])
            cells.append(f"{a['psnr']:.2f} | {b['psnr']:.2f} | {b['psnr'] - a['psnr']:+.2f}")
        lines.append(
            f"| {v['scene']} | {v['mask']} | {snr_label(v['snr_db'])} | {first:.1f} → "
            f"{second:.1f} | " + " | ".join(cells) + " |"
        )
    lines += ["", "Gain per method over these views (with − without):", ""]
    for m in methods:
        g = np.array(gains[m])
        lines.append(
            f"* `{m}`: mean {g.mean():+.2f} dB, {g.min():+.2f} to {g.max():+.2f}; "
            f"higher on {int((g > 0).sum())} of {g.size} views."
        )
    return lines


if __name__ == "__main__":
    main()
