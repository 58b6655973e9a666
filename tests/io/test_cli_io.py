"""`tensor-cosdi plan`, `acquire` and `reconstruct` end to end on simulated captures."""

import os

import numpy as np
import pytest
import tifffile

import tensor_cosdi as tc
from tensor_cosdi import io
from tensor_cosdi.cli import main


def test_plan_command(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert main(["plan", "patterns", "8", str(out)]) == 0
    assert len(io.AcquisitionPlan.load(out).steps) == 8
    assert main(["plan", "patterns", "8", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert (
        main(
            [
                "plan",
                "focal-sweep",
                "2",
                str(tmp_path / "fs.json"),
                "--zernike",
                "4:-0.5,6:0.9",
                "--zernike",
                "4:0.5,6:0.9",
            ]
        )
        == 0
    )
    assert io.AcquisitionPlan.load(tmp_path / "fs.json").steps[1].commands[1] == "DM 4:0.5 6:0.9"


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminal fake device needs POSIX")
def test_acquire_command_and_resume(tmp_path, capsys):
    frames = tmp_path / "frames"
    frames.mkdir()
    plan = io.AcquisitionPlan.snapshots(3)
    plan.save(tmp_path / "plan.json")

    def camera_software(n):  # the camera writes the frame the trigger fired
        tifffile.imwrite(frames / plan.steps[n].frame, np.full((4, 4), n, np.uint16))

    dev = io.FakeTriggerDevice(on_trigger=camera_software, silent={"DMD 2"})
    try:
        args = [
            "acquire",
            str(tmp_path / "plan.json"),
            "--port",
            dev.port,
            "--frames-dir",
            str(frames),
            "--log",
            str(tmp_path / "log.jsonl"),
            "--timeout",
            "0.2",
            "--retries",
            "0",
            "--quiet",
        ]
        assert main(args) == 3
        assert "step 2" in capsys.readouterr().err
        dev.silent.clear()
        assert main(args) == 0
        assert "1 frame(s) acquired (2 already in" in capsys.readouterr().out
        assert dev.fired == [0, 1, 2]
    finally:
        dev.disconnect()


def test_reconstruct_command(tmp_path, capsys):
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    cal = io.save_bundle(tmp_path / "calibration.npz", system=p.system)
    dark = np.full(p.system.measurement_shape, 50.0)
    raw = (np.asarray(p.measurement) * 1000 + dark).astype(np.float32)
    tifffile.imwrite(tmp_path / "capture.tif", raw)
    tifffile.imwrite(tmp_path / "dark.tif", dark.astype(np.float32))
    out = tmp_path / "result.npz"
    args = [
        "reconstruct",
        str(cal),
        str(tmp_path / "capture.tif"),
        "--dark",
        str(tmp_path / "dark.tif"),
        "--out",
        str(out),
        "--method",
        "otd",
        "--option",
        "max_iter=30",
        "--quiet",
    ]
    assert main(args) == 0
    assert "reconstructed with otd" in capsys.readouterr().out
    b = io.load_bundle(out)
    assert b.cube.shape == (32, 32, 8) and b.info["kind"] == "reconstruction"
    assert b.metadata["options"]["max_iter"] == 30
    assert {os.path.basename(s["path"]) for s in b.provenance} == {
        "capture.tif",
        "calibration.npz",
        "dark.tif",
    }
    # the counts were scaled by 1000: the reconstruction is too
    assert tc.metrics.psnr(p.cube * 1000, b.cube, data_range=1000) > 15
    assert main(args) == 2 and "exists" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0
    assert (
        main(
            [
                "reconstruct",
                str(cal),
                str(tmp_path / "capture.tif"),
                "--out",
                str(tmp_path / "x"),
                "--method",
                "nope",
            ]
        )
        == 2
    )
    assert "unknown method 'nope'" in capsys.readouterr().err
    # a folder holding the frame and its dark frame: the dark is not taken for a frame
    folder = tmp_path / "session"
    folder.mkdir()
    tifffile.imwrite(folder / "capture.tif", raw)
    tifffile.imwrite(folder / "dark.tif", dark.astype(np.float32))
    assert (
        main(
            [
                "reconstruct",
                str(cal),
                str(folder),
                "--dark",
                str(folder / "dark.tif"),
                "--out",
                str(tmp_path / "z.npz"),
                "--quiet",
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "reconstruct",
                str(cal),
                str(tmp_path / "dark.tif"),
                "--dark",
                str(tmp_path / "capture.tif"),
                "--out",
                str(tmp_path / "y.npz"),
            ]
        )
        == 2
    )
    assert "not above the dark frame" in capsys.readouterr().err
    # the bundle is written under the name given, or not at all
    tif_out = tmp_path / "x.tif"
    assert main(args[:6] + [str(tif_out)] + args[7:]) == 2
    err = capsys.readouterr().err
    assert "x.tif" in err and ".npz" in err and len(err.strip().splitlines()) == 1
    assert not tif_out.exists() and not (tmp_path / "x.tif.npz").exists()
