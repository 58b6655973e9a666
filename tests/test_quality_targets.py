"""``benchmarks/quality_targets.py``: every verdict follows from the leads and seconds it prints."""

import json

import pytest

SCENES = ("beads", "face", "real_and_fake_apples")


@pytest.fixture(scope="module")
def targets(benchmark_script):
    return benchmark_script("quality_targets")


def _runs(method, snr, psnrs, seconds, mask="tsa", options=None):
    return [
        {"scene": s, "snr_db": snr, "mask": mask, "method": method, "options": options or {},
         "seconds": seconds, "psnr": p, "commit": "abc1234"}
        for s, p in zip(SCENES, psnrs)
    ]  # fmt: skip


def test_leads_are_means_of_per_scene_leads_and_verdicts_flip_at_each_target(targets):
    ref = {s: (p, 10.0) for s, p in zip(SCENES, (20.0, 25.0, 30.0))}
    otd = {s: (p + lead, 9.0) for (s, (p, _)), lead in zip(ref.items(), (2.0, 3.0, 4.0))}
    values = targets.condition({"otd": (otd, ref)}, ref)
    assert values["otd"] == (3.0, 9.0) and values["plain_gap_tv"] == (25.0, 10.0)
    assert targets.verdicts(values, None)["training-free"] == "yes"  # +3.00 in 9 s
    assert targets.verdicts({"otd": (2.99, 9.0)}, None)["training-free"] == "no"
    assert targets.verdicts({"otd": (3.5, 10.01)}, None)["training-free"] == "no"  # too slow
    learned = {"pnp_gap": (6.0, 30.0), "pnp_fast": (5.0, 5.0)}
    v = targets.verdicts(learned, 30.0)
    assert (v["learned"], v["fast"], v["fast within"]) == ("yes", "yes", "yes")
    assert targets.verdicts(learned, 20.0)["learned"] == "—"  # no target at 20 dB
    v = targets.verdicts({"pnp_gap": (6.5, 30.0), "pnp_fast": (5.49, 4.0)}, None)
    assert (v["fast"], v["fast within"]) == ("yes", "no")  # 1.01 dB under pnp_gap
    assert targets.verdicts({"pnp_fast": (6.0, 5.2)}, None)["fast"] == "no"  # over 5 s
    assert targets.verdicts({}, None) == dict.fromkeys(
        ("training-free", "learned", "fast", "fast within"), "—"
    )
    # a method without all three scenes is left out, not scored on fewer
    assert "otd" not in targets.condition({"otd": (dict(list(otd.items())[:2]), ref)}, ref)


def test_the_table_reads_each_file_and_counts_the_verdicts_it_prints(targets, tmp_path):
    base = [*_runs("plain_gap_tv", None, (20, 25, 30), 12.0)]
    main = (
        base
        + _runs("otd", None, (23.5, 28.5, 33.5), 7.0)
        + _runs("pnp_gap", None, (26, 31, 36), 30.0)
        + _runs("otd", None, (40, 40, 40), 7.0, options={"lam": 0.3})
    )  # not the default: ignored
    fast = base + _runs("pnp_fast", None, (24.5, 29.5, 34.5), 4.0)
    (tmp_path / "real_spectra.json").write_text(json.dumps({"runs": main}))
    (tmp_path / "pnp_fast_no_bf16.json").write_text(json.dumps({"runs": fast}))
    (tmp_path / "real_spectra.md").write_text(
        "# t\n\nRows computed at commit abc1234 (9 rows).  \nRun 2026-01-01 00:00 UTC on a "
        "test machine (Python 3).  \nCommand: `x`\n"
    )
    text = targets.main(["--out", str(tmp_path)])
    row = next(line for line in text.splitlines() if line.startswith("| report scenes"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[3:8] == ["25.00 (12.00 s)", "+3.50 (7.00 s)", "+6.00 (30.00 s)",
                          "+4.50 (4.00 s)", "1.50"]  # fmt: skip
    assert cells[8:] == ["yes", "yes", "no", "no"]
    assert "* otd ≥ +3 dB in ≤ 10 s: met in 1 of 1 conditions." in text
    assert "* pnp_fast within 1 dB of pnp_gap: met in 0 of 1 conditions." in text
    assert "rows computed at commit abc1234 (9 rows)" in text
    assert "`pnp_fast_no_bf16.md`: no table" in text
    assert (tmp_path / "quality_targets.md").read_text().startswith("# Quality targets")
    # the bfloat16 block speaks to the fast path only: no second verdict on pnp_gap's own target
    bf16 = base + _runs("pnp_gap", None, (26, 31, 36), 20.0)
    bf16 += _runs("pnp_fast", None, (25.5, 30.5, 35.5), 4.5)
    (tmp_path / "pnp_precision.json").write_text(json.dumps({"runs": bf16}))
    text = targets.main(["--out", str(tmp_path)])
    row = next(line for line in text.splitlines() if "native bfloat16 |" in line)
    assert [c.strip() for c in row.strip("|").split("|")][7:] == ["0.50", "—", "—", "yes", "yes"]
    assert "* pnp_gap ≥ +6 dB (noiseless, 30 dB): met in 1 of 1 conditions." in text
    assert "* pnp_fast within 1 dB of pnp_gap: met in 1 of 2 conditions." in text
