"""The library's quality targets against the committed report tables: where each is met.

Reads the per-scene rows of the report runs of ``benchmarks/real_spectra.py`` (the JSON files
beside their tables; nothing is run here) and, for each set of views, code and noise level,
computes every method's lead over the 30-line ``plain_gap_tv`` of the same file (the mean of
the per-scene leads over the three report scenes) and its median seconds a cube, then checks
the targets:

* the training-free default (``otd``): a lead of at least ``+3 dB`` in at most 10 s a cube;
* the best learned method (``pnp_gap``): at least ``+6 dB``, noiseless and at 30 dB;
* the fast learned path (``pnp_fast``): at least ``+5 dB`` in at most 5 s a cube, and within
  1 dB of ``pnp_gap`` (noiseless and at 30 dB, where it was run).

Every verdict is computed from the numbers printed beside it (rounded as printed), never
typed.  Seconds are those of the run that wrote each file on its machine (its
``plain_gap_tv`` seconds give that run's scale); ``pnp_fast`` on the plain report scenes
comes from its own file (the float32 network of a CPU without native bfloat16), and a block
of its own gives ``pnp_fast`` where bfloat16 is native (``pnp_precision.json``, whose rows
are older: the sources line names each file's commits).

    python benchmarks/quality_targets.py [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, snr_label, write_results  # noqa: E402

#: ``(label, [(JSON file, methods read from it)])``: the views of each block of rows.
SOURCES = (
    ("report scenes", [
        ("real_spectra.json", ("plain_gap_tv", "otd", "pnp_gap")),
        ("pnp_fast_no_bf16.json", ("plain_gap_tv", "pnp_fast")),
    ]),
    ("report scenes, CPU with native bfloat16", [
        ("pnp_precision.json", ("plain_gap_tv", "pnp_gap", "pnp_fast")),
    ]),
    ("report scenes magnified 4×", [
        ("real_spectra_zoom4.json", ("plain_gap_tv", "otd", "pnp_gap", "pnp_fast")),
    ]),
    ("lit by CIE A", [("real_spectra_lit_a.json", ("plain_gap_tv", "otd", "pnp_gap", "pnp_fast"))]),
    ("lit by LED-B3", [
        ("real_spectra_lit_led.json", ("plain_gap_tv", "otd", "pnp_gap", "pnp_fast")),
    ]),
    ("lit by CIE FL2", [
        ("real_spectra_lit_fl2.json", ("plain_gap_tv", "otd", "pnp_gap", "pnp_fast")),
    ]),
)  # fmt: skip

#: Blocks whose rows speak to the fast path only (the learned method's own verdicts come from the
#: current report table above them; here ``pnp_gap`` is the reference ``pnp_fast`` is held to).
FAST_ONLY = ("report scenes, CPU with native bfloat16",)

TRAINING_FREE = {"method": "otd", "lead_db": 3.0, "seconds": 10.0}
LEARNED = {"method": "pnp_gap", "lead_db": 6.0, "snrs": (None, 30.0)}
FAST = {"method": "pnp_fast", "lead_db": 5.0, "seconds": 5.0, "within_db": 1.0}
SCENES = 3  # the report scenes: a condition counts only with all of them


def _rows(path: Path, methods) -> dict:
    """``{(method, mask, snr): {scene: (psnr, seconds)}}`` of ``path``'s runs at default options
    (the last row of a scene wins, as in the report)."""
    runs = json.loads(path.read_text())["runs"]
    out: dict = {}
    for r in runs:
        if r["method"] in methods and not r["options"]:
            cond = (r["method"], r["mask"], r["snr_db"])
            out.setdefault(cond, {})[r["scene"]] = (float(r["psnr"]), float(r["seconds"]))
    return out


def condition(per_method: dict, gap_tv: dict) -> dict:
    """``{method: (lead dB, median s)}`` for one condition: the mean over the scenes both have
    of the method's PSNR less ``plain_gap_tv``'s (``gap_tv``: ``{scene: (psnr, s)}`` of the same
    file), rounded to 0.01 dB, and its median seconds, rounded to 0.01 s; a method without all
    :data:`SCENES` scenes is left out."""
    out = {}
    for method, (scenes, ref) in per_method.items():
        shared = sorted(set(scenes) & set(ref))
        if len(shared) < SCENES:
            continue
        lead = statistics.fmean(scenes[s][0] - ref[s][0] for s in shared)
        seconds = statistics.median(scenes[s][1] for s in shared)
        out[method] = (round(lead, 2), round(seconds, 2))
    if gap_tv:
        out["plain_gap_tv"] = (
            round(statistics.fmean(p for p, _ in gap_tv.values()), 2),
            round(statistics.median(s for _, s in gap_tv.values()), 2),
        )
    return out


def verdicts(values: dict, snr) -> dict:
    """The targets' verdicts (``"yes"``, ``"no"`` or ``"—"`` where a method or the condition is
    not covered) from the rounded ``(lead, seconds)`` of :func:`condition`."""
    out = {}
    tf = values.get(TRAINING_FREE["method"])
    out["training-free"] = (
        "—"
        if tf is None
        else _yes(tf[0] >= TRAINING_FREE["lead_db"] and tf[1] <= TRAINING_FREE["seconds"])
    )
    learned = values.get(LEARNED["method"])
    out["learned"] = (
        "—" if learned is None or snr not in LEARNED["snrs"]
        else _yes(learned[0] >= LEARNED["lead_db"])
    )  # fmt: skip
    fast = values.get(FAST["method"])
    out["fast"] = (
        "—" if fast is None else _yes(fast[0] >= FAST["lead_db"] and fast[1] <= FAST["seconds"])
    )
    out["fast within"] = (
        "—" if fast is None or learned is None
        else _yes(round(learned[0] - fast[0], 2) <= FAST["within_db"])
    )  # fmt: skip
    return out


def _yes(ok: bool) -> str:
    return "yes" if ok else "no"


def _cell(values: dict, method: str) -> str:
    """A method's lead and median seconds as the table prints them (``—``: not run)."""
    if method not in values:
        return "—"
    lead, s = values[method]
    return f"{lead:+.2f} ({s:.2f} s)"


def table(results: Path) -> tuple[list[str], dict]:
    """The Markdown lines and ``{target: [verdicts]}`` over every condition covered."""
    head = (
        "| views | code | SNR | plain GAP-TV dB (s) | otd lead (s) | pnp_gap lead (s) | "
        "pnp_fast lead (s) | pnp_fast under pnp_gap, dB | otd ≥ +3 dB, ≤ 10 s | "
        "pnp_gap ≥ +6 dB | pnp_fast ≥ +5 dB, ≤ 5 s | pnp_fast within 1 dB |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    tally: dict = {"training-free": [], "learned": [], "fast": [], "fast within": []}
    sources_used = []
    for label, files in SOURCES:
        per_cond: dict = {}
        for name, methods in files:
            path = results / name
            if not path.is_file():
                continue
            sources_used.append(name)
            rows = _rows(path, methods)
            for (method, mask, snr), scenes in rows.items():
                if method == "plain_gap_tv":
                    continue
                ref = rows.get(("plain_gap_tv", mask, snr), {})
                slot = per_cond.setdefault((mask, snr), {"methods": {}, "gap_tv": None})
                slot["methods"][method] = (scenes, ref)
                if slot["gap_tv"] is None and len(ref) >= SCENES:
                    slot["gap_tv"] = ref
        order = {"tsa": 0, "random": 1}
        for mask, snr in sorted(per_cond, key=lambda c: (order.get(c[0], 2), -(c[1] or 1e9))):
            slot = per_cond[(mask, snr)]
            values = condition(slot["methods"], slot["gap_tv"] or {})
            v = verdicts(values, snr)
            if label in FAST_ONLY:
                v["training-free"] = v["learned"] = "—"
            for k, verdict in v.items():
                if verdict != "—":
                    tally[k].append(verdict)
            gap = "—"
            if "pnp_fast" in values and "pnp_gap" in values:
                gap = f"{values['pnp_gap'][0] - values['pnp_fast'][0]:.2f}"
            base = values.get("plain_gap_tv")
            lines.append(
                f"| {label} | {mask} | {snr_label(snr)} | "
                f"{'—' if base is None else f'{base[0]:.2f} ({base[1]:.2f} s)'} | "
                f"{_cell(values, 'otd')} | {_cell(values, 'pnp_gap')} | "
                f"{_cell(values, 'pnp_fast')} | {gap} | {v['training-free']} | {v['learned']} | "
                f"{v['fast']} | {v['fast within']} |"
            )
    return lines, {"tally": tally, "sources": sources_used}


def _runs_of(results: Path, names) -> list[str]:
    """Each source table's own lines on when and where its rows were computed, read from its
    Markdown file."""
    out = []
    for name in names:
        md = results / name.replace(".json", ".md")
        text = md.read_text() if md.is_file() else ""
        run = re.search(r"^Run (.*?) on ([^(]*)", text, re.M)
        rows = re.search(r"^Rows computed at (.*?)\.\s*$", text, re.M)
        if run is None:
            out.append(f"`{md.name}`: no table")
            continue
        at = f", rows computed at {rows.group(1)}" if rows else ""
        out.append(f"`{md.name}`: run {run.group(1)} on {run.group(2).strip()}{at}")
    return out


def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(RESULTS), help="results folder (read and written)")
    args = ap.parse_args(argv)
    results = Path(args.out)
    lines, info = table(results)
    names = {
        "training-free": "otd ≥ +3 dB in ≤ 10 s",
        "learned": "pnp_gap ≥ +6 dB (noiseless, 30 dB)",
        "fast": "pnp_fast ≥ +5 dB in ≤ 5 s",
        "fast within": "pnp_fast within 1 dB of pnp_gap",
    }
    summary = []
    for key, verdicts_ in info["tally"].items():
        met = sum(v == "yes" for v in verdicts_)
        summary.append(f"* {names[key]}: met in {met} of {len(verdicts_)} conditions.")
    text = [
        "# Quality targets on the report scenes",
        "",
        "Leads in dB over the 30-line `plain_gap_tv` of the same run (mean over beads, face and "
        "real_and_fake_apples), median seconds a cube in brackets; SD-CASSI 256×256×28, 2 px "
        "per band.",
        "",
        *lines,
        "",
        *summary,
        "",
        "Source tables: " + "; ".join(_runs_of(results, info["sources"])) + ".",
    ]
    return write_results(results / "quality_targets.md", text)


if __name__ == "__main__":
    main()
