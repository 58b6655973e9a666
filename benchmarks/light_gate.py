"""The light gate's threshold and floor, cross-validated over scene folds.

``pan_spectrum="gated"`` (:func:`tensor_cosdi.solvers.panchromatic.panchromatic_estimate`,
``pnp_fast``'s default) fits the scene's mean spectrum part-way through the first stage and,
where it reads rougher than a threshold (:func:`~tensor_cosdi.solvers.subspace.spectral_roughness`;
:data:`~tensor_cosdi.solvers.panchromatic.GATE_ABOVE_CLEAN` on a measurement whose estimated SNR
reads clean, :data:`~tensor_cosdi.solvers.panchromatic.GATE_ABOVE_NOISY` below it down to
:data:`~tensor_cosdi.solvers.panchromatic.GATE_NOISY_FROM_DB`, shut below that), weights the
remaining iterations' atoms by it, raised to at least
:data:`~tensor_cosdi.solvers.subspace.GATE_FLOOR` of its peak.

Every tuning view is run twice or more: once with the gate shut (both thresholds ``inf``; the
reading is recorded on the way, the first stage's iterates up to the gate do not depend on it)
and, where the reading exceeds the smallest finite ``--above``, once with the gate open per
``--floors`` value.  A candidate (floor, clean threshold, noisy threshold, the estimated SNR
from which the noisy threshold applies) then scores a view with the open run where its reading
exceeds the threshold of the view's estimated SNR, else with the shut run — exactly what the
method would return.  The candidates are chosen by 4-fold cross-validation over the scenes
(:func:`_protocol.cross_validate`; the mean over every view and SNR, candidates within
``--tie-db`` of the best are a tie won by the default in use).  The report scenes are not read.
Runs are cached in ``--cache`` (a resumed run skips what it has; delete the file after a change
to the method).

    python benchmarks/light_gate.py [--method pnp_fast] [--snr none,30,20]
                                    [--lights A,LED-B3,FL11] [--floors 0.001,0.1,0.3]
                                    [--above 0.1,0.2,0.3,0.5,inf] [--scenes-per-fold 2]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import (  # noqa: E402
    RESULTS,
    cross_validate,
    load_mask,
    problem,
    run,
    scene_view,
    score,
    snr_label,
    views,
    write_results,
)

from tensor_cosdi import datasets  # noqa: E402
from tensor_cosdi.solvers import panchromatic, subspace  # noqa: E402
from tensor_cosdi.solvers.snr import estimate_snr  # noqa: E402

INF = float("inf")


@contextlib.contextmanager
def gate(above: float, floor: float, readings: list):
    """The method's gate set to ``above`` (clean and noisy alike) and ``floor`` for the
    duration, every reading appended to ``readings``."""
    saved = (
        panchromatic.GATE_ABOVE_CLEAN, panchromatic.GATE_ABOVE_NOISY, subspace.GATE_FLOOR,
        subspace.gate_spectrum,
    )  # fmt: skip
    read = subspace.gate_spectrum

    def recorded(*args, **kwargs):
        w, rough = read(*args, **kwargs)
        readings.append(rough)
        return w, rough

    panchromatic.GATE_ABOVE_CLEAN = panchromatic.GATE_ABOVE_NOISY = above
    subspace.GATE_FLOOR, subspace.gate_spectrum = floor, recorded
    try:
        yield
    finally:
        (
            panchromatic.GATE_ABOVE_CLEAN, panchromatic.GATE_ABOVE_NOISY, subspace.GATE_FLOOR,
            subspace.gate_spectrum,
        ) = saved  # fmt: skip


def measure(view, snr, mask, method, options, floors, lowest) -> dict:
    name, zoom, light = scene_view(view)
    system, cube, g = problem(name, snr, mask, zoom=zoom, illuminant=light)
    readings: list = []
    with gate(INF, subspace.GATE_FLOOR, readings):
        est, sec = run(method, system, g, options)
    # the last reading is the first stage's: the SNR estimate's fit (and a first call's untimed
    # warm-up) read theirs before it
    if not readings:
        raise SystemExit(f"{view}: the gate was not read; {method} does not use it here")
    row = {
        "reading": readings[-1],
        "snr_db": float(estimate_snr(system, g).snr_db),
        "shut": score(cube, est)["psnr"],
        "seconds": sec,
        "open": {},
    }
    if row["reading"] > lowest:
        for f in floors:
            with gate(0.0, f, []):
                est, _ = run(method, system, g, options)
            row["open"][repr(f)] = score(cube, est)["psnr"]
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--method", default="pnp_fast")
    ap.add_argument("--snr", default="none,30,20")
    ap.add_argument("--lights", default="A,LED-B3,FL11")
    ap.add_argument("--floors", default="0.001,0.1,0.3")
    ap.add_argument("--above", default="0.1,0.2,0.3,0.5,inf")
    ap.add_argument(
        "--noisy-from", default="0,25", help="estimated SNRs (dB) the noisy threshold starts at"
    )
    ap.add_argument(
        "--keep",
        default="0.001,0.1,inf,0",
        help="the default in use, which wins ties: floor,clean,noisy,from_db or 'shut'",
    )
    ap.add_argument("--scenes-per-fold", type=int, default=2)
    ap.add_argument("--mask", default="tsa", choices=("tsa", "random"))
    ap.add_argument("--tie-db", type=float, default=0.02)
    ap.add_argument("--cache", default=str(RESULTS / "light_gate.json"))
    ap.add_argument("--out", default=str(RESULTS / "light_gate.md"))
    args = ap.parse_args(argv)
    snrs = [None if s == "none" else float(s) for s in args.snr.split(",")]
    floors = [float(f) for f in args.floors.split(",")]
    aboves = [float(a) for a in args.above.split(",")]
    noisy_from = [float(a) for a in args.noisy_from.split(",")]
    if not floors or not all(0 < f <= 1 for f in floors):
        raise SystemExit(f"--floors: numbers in (0, 1] expected, got {args.floors!r}")
    if not aboves or not all(a >= 0 for a in aboves) or not np.isfinite(aboves).any():
        raise SystemExit(f"--above: numbers >= 0 (inf: shut), one finite, got {args.above!r}")
    lights = [s for s in args.lights.split(",") if s]
    cands = [(f, c, n, d) for f in floors for c in aboves for n in aboves for d in noisy_from]
    shut = (floors[0], INF, INF, noisy_from[0])
    try:
        default = shut if args.keep == "shut" else tuple(float(v) for v in args.keep.split(","))
    except ValueError:
        default = None
    if default not in cands:
        raise SystemExit(f"--keep {args.keep!r} must be 'shut' or one of the candidates")
    options = {} if args.method == "pnp_fast" else {"pan_spectrum": "gated"}
    folds = tuple(views(f[: args.scenes_per_fold], None, lights) for f in datasets.tune_folds(4))
    mask = load_mask(args.mask)
    cache_path = Path(args.cache)
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    lowest = min(a for a in aboves if np.isfinite(a))
    rows = {}
    for fold in folds:
        for view in fold:
            for snr in snrs:
                k = json.dumps([args.method, args.mask, view, snr_label(snr), floors, lowest])
                if k not in cache:
                    cache[k] = measure(view, snr, mask, args.method, options, floors, lowest)
                    cache_path.write_text(json.dumps(cache, indent=1))
                rows[view, snr] = cache[k]
                r = cache[k]
                print(view, snr_label(snr), f"{r['reading']:.3f}", f"{r['shut']:.2f}",
                      r["open"], flush=True)  # fmt: skip

    clean_db = panchromatic.FITTED_SPECTRUM_ABOVE_DB

    def psnr(cand, view, snr):
        f, a_clean, a_noisy, from_db = cand
        r = rows[view, snr]
        est = r["snr_db"]
        above = a_clean if est >= clean_db else (a_noisy if est >= from_db else INF)
        return r["open"][repr(f)] if r["reading"] > above else r["shut"]

    def rows_of(cand, vs):
        return [psnr(cand, v, s) for v in vs for s in snrs]

    cv = cross_validate(rows_of, cands, folds, tie_db=args.tie_db, keep=default)
    every = [v for f in folds for v in f]
    chosen = cv["chosen_on_all"]

    def name(c):
        return f"floor {c[0]:g}, clean above {c[1]:g}, noisy above {c[2]:g}" + (
            f" from {c[3]:g} dB" if np.isfinite(c[2]) else ""
        )

    def mean(c, vs, snr_list=snrs):
        return float(np.mean([psnr(c, v, s) for v in vs for s in snr_list]))

    lines = [
        f"# The light gate of `{args.method}`: threshold and floor, cross-validated",
        "",
        f"{len(every)} tuning views ({', '.join(every)}), SD-CASSI 256×256×28, {args.mask} "
        f"code, SNR {', '.join(snr_label(s) for s in snrs)}; 4 folds by scene.  Candidates: "
        f"floor × clean threshold (estimated SNR from {clean_db:g} dB) × noisy threshold × "
        f"the estimated SNR from which it applies (shut below) over {floors} × {aboves} × "
        f"{aboves} × {noisy_from} "
        f"({len(cands)}); the default in use before: "
        f"{'the gate shut' if default == shut else name(default)}.  Ties within "
        f"{args.tie_db:g} dB go to it.",
        "",
        "| fold | chosen on the other three | held-out PSNR dB | default | gate shut |",
        "|---|---|---|---|---|",
    ]
    for k, f in enumerate(cv["folds"]):
        c = tuple(f["chosen"])
        lines.append(
            f"| {k} | {name(c)} | {f['held_out_psnr']:.2f} | {mean(default, folds[k]):.2f} | "
            f"{mean(shut, folds[k]):.2f} |"
        )
    held_default = np.mean([mean(default, f) for f in folds])
    lines += [
        f"| mean | | **{cv['mean']:.2f}** (spread {cv['spread']:.2f}) | {held_default:.2f} | "
        f"{np.mean([mean(shut, f) for f in folds]):.2f} |",
        "",
        f"Chosen on all folds: **{name(tuple(chosen))}**.",
        "",
        "| SNR | views | gate shut | default | chosen | chosen − default, dB (min…max) |",
        "|---|---|---|---|---|---|",
    ]
    for s in snrs:
        d = np.array([psnr(tuple(chosen), v, s) - psnr(default, v, s) for v in every])
        lines.append(
            f"| {snr_label(s)} | {len(every)} | {mean(shut, every, [s]):.2f} | "
            f"{mean(default, every, [s]):.2f} | {mean(tuple(chosen), every, [s]):.2f} | "
            f"{d.mean():+.2f} ({d.min():+.2f}…{d.max():+.2f}) |"
        )
    lines += [
        "",
        "Mean PSNR by light (dB): the gate shut and forced open at each floor, over the views "
        "whose reading opens the smallest threshold (their count).",
        "",
        "| light | SNR | views | shut | " + " | ".join(f"open, floor {f:g}" for f in floors) + " |",
        "|---|---|---|---|" + "---|" * len(floors),
    ]
    for light in [None, *lights]:
        for s in snrs:
            opened = [
                rows[v, s] for v in every
                if scene_view(v)[2] == light and rows[v, s]["open"]
            ]  # fmt: skip
            if opened:
                lines.append(
                    f"| {light or 'none'} | {snr_label(s)} | {len(opened)} | "
                    f"{np.mean([r['shut'] for r in opened]):.2f} | "
                    + " | ".join(
                        f"{np.mean([r['open'][repr(f)] for r in opened]):.2f}" for f in floors
                    )
                    + " |"
                )
    lines += [
        "",
        "Per view: the gate's reading, the estimated SNR, PSNR with the "
        "gate shut and open at each floor (dB; open runs only above the smallest threshold).",
        "",
        "| view | SNR | reading | estimated SNR dB | shut | "
        + " | ".join(f"open, floor {f:g}" for f in floors)
        + " |",
        "|---|---|---|---|---|" + "---|" * len(floors),
    ]
    for v in every:
        for s in snrs:
            r = rows[v, s]
            opened = [r["open"].get(repr(f)) for f in floors]
            lines.append(
                f"| {v} | {snr_label(s)} | {r['reading']:.3f} | {r['snr_db']:.1f} "
                f"| {r['shut']:.2f} | "
                + " | ".join("—" if o is None else f"{o:.2f}" for o in opened)
                + " |"
            )
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
