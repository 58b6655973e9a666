"""Every sub-command given user mistakes: exit code 2, no traceback, and one line naming what was
wrong (argparse's own usage errors: its usage lines, then one ``error:`` line)."""

import importlib.util

import numpy as np
import pytest
import scipy.io

from tensor_cosdi import cli


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scipy.io.savemat(tmp_path / "mask.mat", {"mask": np.ones((8, 8))})
    scipy.io.savemat(tmp_path / "meas.mat", {"meas": np.random.default_rng(0).random((8, 11))})
    np.save(tmp_path / "cube.npy", np.ones((8, 8, 4)))
    (tmp_path / "junk.h5").write_bytes(b"not an HDF5 file")
    (tmp_path / "plan.json").write_text("{not json")
    return tmp_path


RECON = ["reconstruct", "--system", "sd_cassi", "--mask", "mask.mat:mask", "--bands", "4",
         "--measurement", "meas.mat:meas", "--shift", "1"]  # fmt: skip
#: ``acquire``'s arguments after the plan: a port that does not exist, frames here, a log.
ACQUIRE = ["--port", "/dev/nonexistent", "--frames-dir", ".", "--log", "l.jsonl"]

MISTAKES = {
    "demo: negative size": (["demo", "--size", "-3"], "size"),
    "plan: unknown kind": (["plan", "bursts", "4", "p.json"], "invalid choice"),
    "plan: count not a number": (["plan", "snapshots", "four", "p.json"], "count"),
    "plan: count too large": (["plan", "snapshots", str(10**8), "p.json"], "frames"),
    "acquire: broken plan file": (["acquire", "plan.json", *ACQUIRE], "plan"),
    "acquire: missing plan file": (["acquire", "nowhere.json", *ACQUIRE], "nowhere.json"),
    "reconstruct: no inputs": (["reconstruct", "--out", "c.h5"], "--system"),
    "reconstruct: unknown system": (
        ["reconstruct", "--system", "cassi9", *RECON[3:], "--out", "c.h5"],
        "cassi9",
    ),
    "reconstruct: unknown method": ([*RECON, "--out", "c.h5", "--method", "magic"], "magic"),
    "reconstruct: missing variable": (
        [*RECON[:-4], "--measurement", "meas.mat:nope", "--shift", "1", "--out", "c.h5"],
        "nope",
    ),
    "reconstruct: wrong measurement width": (
        [*RECON[:-1], "2", "--out", "c.h5"],
        "measurement shape",
    ),
    "reconstruct: micrometre wavelengths": (
        [*RECON, "--wavelengths", "0.45:0.65", "--out", "c.h5"],
        "micrometres",
    ),
    "reconstruct: unsupported output": ([*RECON, "--out", "c.tif"], ".h5"),
    "reconstruct: option of the wrong kind": (
        [*RECON, "--out", "c.h5", "--option", "max_iter=yes"],
        "max_iter",
    ),
    "reconstruct: an option given twice": (
        [*RECON, "--out", "c.h5", "--option", "max_iter=5", "--option", "max_iter=9"],
        "given twice",
    ),
    "reconstruct: a system option given twice": (
        [*RECON, "--out", "c.h5", "--system-option", "a=1", "--system-option", "a=2"],
        "given twice",
    ),
    "reconstruct: an option without a name": ([*RECON, "--out", "c.h5", "--option", "=5"], "name"),
    "reconstruct: an option nested too deeply": (
        [*RECON, "--out", "c.h5", "--option", "x=" + "[" * 100000],
        "nested",
    ),
    "reconstruct: bad system option": (
        [*RECON, "--out", "c.h5", "--system-option", "shear_direction=2"],
        "shear_direction",
    ),
    "reconstruct: --calibrate on the bundle path": (
        ["reconstruct", "cal.npz", "f0.tif", "--out", "o.npz", "--calibrate"],
        "direct path",
    ),
    "reconstruct: preview point not a pair": (
        [*RECON, "--out", "c.h5", "--preview", "--points", "3"],
        "ROW,COL",
    ),
    "reconstruct: a dark frame on the direct path": (
        [*RECON, "--out", "c.h5", "--dark", "nothing.npy"],
        "--dark applies to frames",
    ),
    "reconstruct: binning and a roi on the direct path": (
        [*RECON, "--out", "c.h5", "--binning", "2", "--roi", "0", "4", "0", "4"],
        "--roi, --binning apply to frames",
    ),
    "reconstruct: preview points without --preview": (
        [*RECON, "--out", "c.h5", "--points", "1,1"],
        "add --preview",
    ),
    "reconstruct: a step that shifts past the limit": (
        [*RECON[:-1], "1e308", "--out", "c.h5"],
        "at most 65536 px",
    ),
    "train-denoiser: a patch larger than the scenes": (
        ["train-denoiser", "--out", "w.pt", "--patch", "100000"],
        "8…512",
    ),
    "preview: missing file": (["preview", "nothing.h5"], "nothing.h5"),
    "preview: no wavelengths": (["preview", "cube.npy"], "wavelengths"),
    "preview: garbage HDF5": (["preview", "junk.h5"], "junk.h5"),
    "info: missing file": (["info", "nothing.mat"], "nothing.mat"),
    "info: unknown extension": (["info", "plan.json"], ".json"),
    "train-denoiser: no output": (["train-denoiser"], "--out"),
    "train-dcosnet: negative steps": (
        ["train-dcosnet", "--out", "w.pt", "--steps", "-1"],
        "steps",
    ),
}


@pytest.mark.parametrize("argv, word", list(MISTAKES.values()), ids=list(MISTAKES))
def test_a_mistake_ends_in_one_line_and_exit_code_2(folder, capsys, argv, word):
    try:
        code = cli.main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    message = [line for line in lines if not line.startswith(("usage:", " "))]
    assert len(message) == 1, err  # one line that says what was wrong
    assert word.lower() in message[0].lower(), err


@pytest.mark.skipif(importlib.util.find_spec("torch") is None, reason="PyTorch is not installed")
def test_a_device_this_torch_lacks_is_one_line_before_any_training(folder, capsys):
    assert cli.main(["train-denoiser", "--out", "w.pt", "--device", "tpu", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "device must be" in err and "Traceback" not in err
    assert not (folder / "w.pt").exists() and not (folder / "w.pt.ckpt").exists()
