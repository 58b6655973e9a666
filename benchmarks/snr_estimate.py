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

``--sweep`` writes ``snr_fit_sweep.md`` instead: the subspace fit's residual
reading at the protocol for every ``--iters`` × ``--weights`` pair, the
table behind :data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_ITER` and
:data:`~tensor_cosdi.solvers.snr.SUBSPACE_FIT_TV`.

    python benchmarks/snr_estimate.py [--scene balloons] [--no-protocol]
                                      [--out benchmarks/results/snr_estimate.md]
    python benchmarks/snr_estimate.py --sweep [--iters 40,60] [--weights 0.1,0.2,0.3]
    python benchmarks/snr_estimate.py --fit-tv c3slfi [--weights 0.1,0.05,0.03,0.02]
    python benchmarks/snr_estimate.py --refit 5,8,none [--lights A,LED-B3,FL11]
    python benchmarks/snr_estimate.py --effect [--methods otd,pnp_gap]
                                      [--scenes balloons,clay,feathers]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
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
    scene_view,
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
    ap.add_argument("--methods", default="otd,pnp_gap", help="--effect: methods, comma-separated")
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
    ap.add_argument("--lights", default="A,LED-B3,FL11", help="--refit: CIE illuminants")
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
        methods = args.methods.split(",")
        if not set(methods) <= set(tc.solvers.METHODS):
            raise SystemExit(f"--methods must be methods of {sorted(tc.solvers.METHODS)}")
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / "snr_frames_effect.md" if default_out else args.out
        write_results(out, effect_table(methods, scenes))
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
        lights = [v for v in args.lights.split(",") if v]
        for light in lights:
            scene_view(f"x~{light}")  # a one-line error for an unknown illuminant
        default_out = args.out == str(RESULTS / "snr_estimate.md")
        out = RESULTS / "snr_fit_refit.md" if default_out else args.out
        write_results(out, refit_table(refits, lights))
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
        "| system | true SNR | estimate dB without / with | "
        + " | ".join(f"{m} without | {m} with | {m} gain dB" for m in methods)
        + " |",
        "|---|---|---|" + "---|---|---|" * len(methods),
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
        "(`subspace_gap_tv(refit_at=...)`).  Each cell: the estimate in dB, min / median / max "
        f"over the scenes, and how many are `ok` (noiseless: ≥ {CLEAN:g} dB, the clean path; "
        "noisy: within 3 dB).",
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
                        read[r].append(estimate_snr(system, g).snr_db)
                cells = [summary_cell(read[r], snr) for r in refits]
                lines.append(
                    f"| {light or 'none'} | {'noiseless' if snr is None else f'{snr} dB'} | "
                    + " | ".join(cells) + " |"
                )  # fmt: skip
                print(lines[-1], flush=True)
    finally:
        snr_module.SUBSPACE_FIT_REFIT = saved
    return lines


if __name__ == "__main__":
    main()
