"""The demo command: runs, prints its table, writes PNGs, never overwrites silently."""

import re

import pytest

from tensor_cosdi.cli import main


def test_demo_prints_table_and_writes_pngs(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--size", "16", "--bands", "8", "--out", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    for structure in ("Diagonal", "PixelBlocks", "RowBanded"):
        assert structure in text
    psnrs = [float(v) for v in re.findall(r"(-?\d+\.\d+)dB", text)]
    assert len(psnrs) == 3 and all(p > 5 for p in psnrs)
    # 4 shots measure more than one: the closed-form estimate must be better
    assert psnrs[1] > psnrs[0]
    errs = [float(v) for v in re.findall(r"\s(\d\.\de[-+]\d\d)\s", text)]
    assert errs and max(errs) < 1e-10
    assert sorted(p.name for p in out.iterdir()) == [f"measurement_{i}.png" for i in (1, 2, 3)]


def test_demo_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "demo"
    args = ["demo", "--size", "8", "--bands", "4", "--out", str(out), "--quiet"]
    assert main(args) == 0
    before = (out / "measurement_1.png").read_bytes()
    assert main(args) == 2
    assert "--force" in capsys.readouterr().err
    assert (out / "measurement_1.png").read_bytes() == before
    assert main(args + ["--force"]) == 0
    # a partial earlier run: nothing is written unless every file may be
    (out / "measurement_1.png").unlink()
    assert main(args) == 2
    assert not (out / "measurement_1.png").exists()


def test_demo_rejects_bad_sizes(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--size", "-3"])
    assert "positive integer" in capsys.readouterr().err
