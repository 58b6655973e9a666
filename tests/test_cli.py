"""The demo command: runs all imagers, prints its table, writes PNGs, never overwrites silently."""

import re

import pytest

from tensor_cosdi.cli import DEMO_CASES, main

ARGS = ["demo", "--size", "16", "--bands", "6", "--quiet"]


def _rows(text):
    return re.findall(
        r"^(\w+)\s+(\w+)\s+([\d×]+)\s+(\d+\.\d+)\s+(otd|gap_tv)\s+(-?\d+\.\d+)\s+(\d\.\d+)\s+(\d+\.\d+)\s+"
        r"(\d+\.\d+)\s+(\d+% planes|\d+\.\d+ px|\d+\.\d+ rad|-)$",
        text,
        flags=re.M,
    )


def test_demo_prints_table_writes_pngs_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "demo"
    args = ARGS + ["--out", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    rows = _rows(text)
    assert [(r[0], r[4]) for r in rows] == [
        (c[0], m) for c in DEMO_CASES for m in ("otd", "gap_tv")
    ]
    assert {r[0] for r in rows} >= {"cassi_vsi", "cassdi_dfa", "c3slfi", "cs2li", "mu_cosdi"}
    assert all(float(r[5]) > 10 and 0 < float(r[6]) <= 1 for r in rows), rows
    # every depth-capable imager reports its depth error, the spectral ones none
    assert {r[0] for r in rows if r[9] != "-"} == {"cassdi_dfa", "c3slfi", "cs2li", "mu_cosdi"}
    # samples per voxel: one SD-CASSI snapshot of 16×16×6 through 1 px per band is 16×21
    ratio = {r[0]: float(r[3]) for r in rows}
    assert ratio["sd_cassi"] == pytest.approx(16 * 21 / (16 * 16 * 6), abs=5e-4), ratio
    # CASSDI-DFA: the same snapshot for a cube of 3 depth planes
    assert ratio["cassdi_dfa"] == pytest.approx(ratio["sd_cassi"] / 3, abs=5e-4), ratio
    names = sorted(p.name for p in out.iterdir())
    # 5 PNGs per system, 4 depth panels, and (matplotlib present) a labelled comparison per
    # system and the summary
    assert len(names) == 5 * len(DEMO_CASES) + 4 + len(DEMO_CASES) + 1
    assert "summary.png" in names and "cs2li_compare.png" in names
    assert (
        "c3slfi_truth.png" in names
        and "cs2li_error_otd.png" in names
        and "cassdi_dfa_depth.png" in names
    )
    assert str(out.resolve()) in text
    # a second run into the same folder (one file gone, as after a partial earlier run)
    # touches nothing without --force
    before = (out / "sd_cassi_otd.png").read_bytes()
    (out / "sd_cassi_truth.png").unlink()
    assert main(args) == 2
    assert "--force" in capsys.readouterr().err
    assert (out / "sd_cassi_otd.png").read_bytes() == before
    assert not (out / "sd_cassi_truth.png").exists()
    assert main(args + ["--force"]) == 0
    assert (out / "sd_cassi_truth.png").exists()


def test_demo_rejects_bad_sizes(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--size", "-3"])
    assert "positive integer" in capsys.readouterr().err
    assert main(["demo", "--size", "18", "--quiet"]) == 2
    assert "multiple of 4" in capsys.readouterr().err


def test_version_flag(capsys):
    import tensor_cosdi

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"tensor-cosdi {tensor_cosdi.__version__}"
