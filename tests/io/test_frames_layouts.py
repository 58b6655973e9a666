"""Capture files → measurement tensors: readers, corrections, bad files, per-system layouts (issue:
lab adapter)."""

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
import scipy.io
import tifffile

import tensor_cosdi as tc
from tensor_cosdi import io

DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data"
MASK = DATA / "masks" / "tsa_mask256.mat"


@pytest.fixture
def frame():
    return (np.random.default_rng(0).random((12, 16)) * 1000 + 200).astype(np.uint16)


@pytest.mark.parametrize("suffix", [".tif", ".png", ".npy", ".npz", ".mat"])
def test_readers_round_trip_exactly(tmp_path, frame, suffix):
    p = tmp_path / f"f{suffix}"
    if suffix == ".tif":
        tifffile.imwrite(p, frame)
    elif suffix == ".png":
        iio.imwrite(p, frame)
    elif suffix == ".npy":
        np.save(p, frame)
    elif suffix == ".npz":
        np.savez(p, frame=frame)
    else:
        scipy.io.savemat(p, {"frame": frame})
    out = io.read_frame(p)
    assert out.shape == frame.shape and np.array_equal(out, frame)


def test_bad_files_name_the_file(tmp_path, frame):
    p = tmp_path / "cut.tif"
    tifffile.imwrite(p, frame)
    p.write_bytes(p.read_bytes()[:200])  # truncated TIFF
    with pytest.raises(ValueError, match="cut.tif"):
        io.read_frame(p)
    q = tmp_path / "cube.npy"
    np.save(q, np.zeros((3, 4, 5)))
    with pytest.raises(ValueError, match="cube.npy: expected a 2-D frame, got an array of shape"):
        io.read_frame(q)
    r = tmp_path / "text.npy"
    np.save(r, np.array([["a", "b"]]))
    with pytest.raises(ValueError, match="text.npy: expected integer or float pixels"):
        io.read_frame(r)
    s = tmp_path / "rgb.png"
    iio.imwrite(s, np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(ValueError, match="rgb.png: colour image"):
        io.read_frame(s)
    assert io.read_frame(s, channel=1).shape == (4, 4)
    with pytest.raises(ValueError, match="unknown frame format '.xyz'"):
        (tmp_path / "a.xyz").write_text("x")
        io.read_frame(tmp_path / "a.xyz")
    with pytest.raises(FileNotFoundError, match="nope.tif"):
        io.read_frame(tmp_path / "nope.tif")
    m = tmp_path / "two.npz"
    np.savez(m, a=frame, b=frame)
    with pytest.raises(ValueError, match="two.npz: holds 2 arrays"):
        io.read_frame(m)
    assert np.array_equal(io.read_frame(m, key="b"), frame)


def _write_sequence(folder, frames, skip=()):
    folder.mkdir()
    for i in range(frames.shape[2]):
        if i not in skip:
            tifffile.imwrite(folder / f"frame_{i:03d}.tif", frames[..., i])


def test_load_frames_corrections(tmp_path):
    rng = np.random.default_rng(1)
    truth = rng.random((8, 12, 3)) * 500 + 100
    gain = 0.5 + rng.random((8, 12))
    dark = np.full((8, 12), 20.0)
    raw = truth * gain[..., None] + dark[..., None]
    flat = 300 * gain + dark
    _write_sequence(tmp_path / "seq", raw.astype(np.float32))
    out = io.load_frames(tmp_path / "seq", dark=dark, flat=flat)
    expect = truth * gain.mean()  # flat normalised to mean gain 1
    np.testing.assert_allclose(out, expect, rtol=1e-5)
    roi = io.load_frames(tmp_path / "seq", dark=dark, flat=flat, roi=(2, 8, 0, 12), binning=2)
    np.testing.assert_allclose(roi, expect[2:8].reshape(3, 2, 6, 2, 3).sum(axis=(1, 3)), rtol=1e-5)


def test_load_frames_errors(tmp_path):
    frames = np.full((6, 6, 4), 100, np.uint16)
    _write_sequence(tmp_path / "gap", frames, skip={2})
    with pytest.raises(ValueError, match="missing \\['frame_002'\\]"):
        io.load_frames(tmp_path / "gap")
    _write_sequence(tmp_path / "ok", frames)
    with pytest.raises(ValueError, match="expected 5 frames, found 4"):
        io.load_frames(tmp_path / "ok", expected=5)
    with pytest.raises(
        ValueError, match="frame_000.tif: its mean 100 is not above the dark frame's 200"
    ):
        io.load_frames(tmp_path / "ok", dark=np.full((6, 6), 200.0))
    with pytest.raises(ValueError, match="cannot be binned 4×4"):
        io.load_frames(tmp_path / "ok", binning=4)
    with pytest.raises(ValueError, match="roi .* does not lie inside the 6×6 frame"):
        io.load_frames(tmp_path / "ok", roi=(0, 8, 0, 6))
    tifffile.imwrite(tmp_path / "ok" / "frame_004.tif", np.zeros((5, 6), np.uint16))
    with pytest.raises(ValueError, match="frame_004.tif: frame shape \\(5, 6\\) differs"):
        io.load_frames(tmp_path / "ok")
    with pytest.raises(ValueError, match="flat frame .* pixel\\(s\\) ≤ the dark level"):
        io.load_frames([tmp_path / "ok" / "frame_000.tif"], flat=np.zeros((6, 6)))


SYSTEMS = [
    tc.systems.SDCASSI.example((8, 8, 4)),
    tc.systems.SDCASSI(tc.codes.random_binary((8, 8, 3), rng=0), n_bands=4),
    tc.systems.DDCASSI.example((8, 8, 4)),
    tc.systems.DualCameraCASSI.example((8, 8, 4)),
    tc.systems.CASSIVSI.example((8, 8, 4)),
    tc.systems.CASSDIDFA.example((8, 8, 4, 3)),
    tc.systems.C3SLFI.example((8, 8, 4), views=(2, 2), n_snapshots=3),
    tc.systems.C3SLFI.example((8, 8, 4), views=(2, 2), n_snapshots=3).as_5d(),
    tc.systems.C3SLFI.example((8, 8, 4), views=(2, 2), n_snapshots=2, raw_layout="tiled"),
    tc.systems.CS2LI.example((8, 8, 4, 6)),
    tc.systems.MuCoSDI.example((8, 8, 4, 4)),
    tc.systems.MuCoSDI.example((8, 8, 4), modality="lf"),
]


@pytest.mark.parametrize("system", SYSTEMS, ids=lambda s: f"{type(s).__name__}{s.cube_shape}")
def test_measurement_frames_round_trip(system):
    g = system.forward(np.random.default_rng(0).random(system.cube_shape))
    frames = io.measurement_to_frames(system, g)
    assert frames.ndim == 3 and frames.shape[2] == io.frame_count(system)
    back = io.frames_to_measurement(system, frames)
    assert back.shape == tuple(system.measurement_shape) and np.array_equal(back, np.asarray(g))
    # and frames → measurement → frames
    assert np.array_equal(io.measurement_to_frames(system, back), frames)


def test_c3slfi_5d_frames_are_the_raw_lenslet_images():
    s3 = tc.systems.C3SLFI.example((8, 8, 4), views=(2, 2), n_snapshots=3)
    s5 = s3.as_5d()
    cube5 = np.random.default_rng(1).random(s5.cube_shape)
    frames5 = io.measurement_to_frames(s5, s5.forward(cube5))
    frames3 = io.measurement_to_frames(s3, s3.forward(s3.to_3d(cube5)))
    assert np.allclose(frames5, frames3)  # the same sensor frames whichever parameterisation


@pytest.mark.parametrize("suffix", [".tif", ".npy", ".png"])
def test_write_then_load_frames_is_exact(tmp_path, suffix):
    sys_ = tc.systems.CS2LI.example((8, 8, 4, 6))
    frames = io.measurement_to_frames(
        sys_, sys_.forward(np.random.default_rng(0).random(sys_.cube_shape))
    )
    if suffix == ".png":
        frames = (frames * 1000).astype(np.uint16)
    paths = io.write_frames(frames, tmp_path / "cap", suffix=suffix)
    assert [p.name for p in paths][:2] == [f"frame_000{suffix}", f"frame_001{suffix}"]
    back = io.load_frames(tmp_path / "cap")
    assert np.array_equal(back, frames.astype(np.float64))
    assert np.array_equal(io.frames_to_measurement(sys_, back), frames.astype(np.float64))
    with pytest.raises(FileExistsError, match="overwrite=True"):
        io.write_frames(frames, tmp_path / "cap", suffix=suffix)


def test_a_list_of_frames_is_written_frame_by_frame(tmp_path):
    rng = np.random.default_rng(1)
    frames = [rng.random((5, 7)).astype(np.float32) for _ in range(3)]
    paths = io.write_frames(frames, tmp_path / "list", suffix=".npy")
    assert len(paths) == 3  # three frames, not one file per column
    back = io.load_frames(tmp_path / "list")
    assert back.shape == (5, 7, 3) and np.array_equal(back, np.stack(frames, -1))
    for bad, match in (([], "no frames"), ([frames[0], frames[0][:2]], "one shape"),
                       ([np.zeros((2, 2, 2))], "2-D frames")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            io.write_frames(bad, tmp_path / "bad", suffix=".npy")


def test_layout_errors():
    sd = tc.systems.SDCASSI.example((8, 8, 4))
    with pytest.raises(ValueError, match="SDCASSI: expected 1 frame\\(s\\) of \\(8, 11\\)"):
        io.frames_to_measurement(sd, np.zeros((8, 10)))
    cs = tc.systems.CS2LI.example((8, 8, 4, 6))
    with pytest.raises(ValueError, match="takes 6 frame\\(s\\) per measurement, got 5"):
        io.frames_to_measurement(cs, np.zeros((8, 8, 5)))
    dual = tc.systems.DualCameraCASSI.example((8, 8, 4))
    frames = io.dual_camera_frames(np.ones((8, 11)), np.ones((8, 8)))
    assert io.frames_to_measurement(dual, frames).shape == (8, 11, 2)
    bad = np.ones((8, 11))
    bad[2, 3] = np.nan
    for system in (sd, dual):  # every layout stacks through the same check
        with pytest.raises(ValueError, match="frame 0 holds 1 NaN or infinite pixel"):
            io.frames_to_measurement(system, [bad, np.ones((8, 11))][: system.frame_count])
    with pytest.raises(ValueError, match="must hold real numbers, got dtype complex128"):
        io.frames_to_measurement(sd, np.ones((8, 11), complex))
    assert io.frames_to_measurement(sd, np.ones((8, 11), np.uint16)).dtype == np.float64


@pytest.mark.skipif(not MASK.exists(), reason="../shared/data not present")
def test_real_mask_gives_the_documented_geometry():
    mask = io.read_frame(MASK, key="mask")
    assert mask.shape == (256, 256) and mask.dtype == np.float32
    sd = tc.systems.SDCASSI(mask, n_bands=28, shifts=2)
    assert sd.measurement_shape == (256, 310)
    g = sd.forward(np.ones((256, 256, 28)))
    frames = io.measurement_to_frames(sd, g)
    assert frames.shape == (256, 310, 1)


@pytest.mark.parametrize(
    "shifts", [[0, 1, 3, 4, 6], [0, 1.5, 3, 4.5, 6]], ids=["integer", "fractional"]
)
def test_monochromator_calibration_recovers_code_and_shifts(shifts):
    code = tc.codes.random_binary((24, 24), rng=3)
    sd = tc.systems.SDCASSI(code, n_bands=5, shifts=shifts)
    # frame l: the system under monochromatic light of band l (a flat white scene in that band only)
    frames = np.stack(
        [np.asarray(sd.forward(np.ones((24, 24, 1)) * np.eye(5)[l])) for l in range(5)], -1
    )
    dark = np.full(frames.shape[:2], 3.0)
    s = io.shifts_from_line_frames(frames + dark[..., None], dark=dark)
    np.testing.assert_allclose(s, shifts, atol=0.06)
    mean_code, per_band = io.code_from_monochromator(
        frames + dark[..., None], shifts=s, dark=dark, ny=24
    )
    assert per_band.shape == (24, 24, 5)
    # integer shifts: the code itself; half-pixel shifts: the model's own linear interpolation blurs
    # it
    assert np.mean(np.abs(mean_code - code)) < (0.01 if shifts[1] == 1 else 0.15)
    # the calibrated code rebuilds the system: same measurement of a scene
    scene = np.random.default_rng(0).random((24, 24, 5))
    rebuilt = tc.systems.SDCASSI(mean_code, n_bands=5, shifts=s)
    err = np.linalg.norm(rebuilt.forward(scene) - sd.forward(scene)) / np.linalg.norm(
        sd.forward(scene)
    )
    assert err < (0.01 if shifts[1] == 1 else 0.15)
    with pytest.raises(ValueError, match="not non-decreasing"):
        io.shifts_from_line_frames(frames[..., ::-1])


def test_a_frame_folder_is_one_strict_sequence(tmp_path):
    from tensor_cosdi.io import frame_paths, load_frames

    for i in range(3):
        np.save(tmp_path / f"frame_{i:03d}.npy", np.full((4, 4), 10.0 + i))
    np.save(tmp_path / "dark.npy", np.zeros((4, 4)))
    with pytest.raises(
        ValueError, match=r"outside the frame_<number> frame sequence: \['dark.npy'\]"
    ):
        frame_paths(tmp_path)
    # the dark frame beside the frames is excluded, not a frame
    stack = load_frames(tmp_path, dark=tmp_path / "dark.npy")
    assert stack.shape == (4, 4, 3) and stack[0, 0, 2] == 12.0
    np.save(tmp_path / "frame_1.npy", np.zeros((4, 4)))
    with pytest.raises(ValueError, match="share a frame number.*frame_001.npy.*frame_1.npy"):
        frame_paths(tmp_path, exclude=[tmp_path / "dark.npy"])


def test_write_frames_is_atomic_as_a_set(tmp_path, monkeypatch):
    from tensor_cosdi.io import write_frames

    old = np.ones((4, 4, 3))
    paths = write_frames(old, tmp_path, suffix=".npy")
    before = [p.read_bytes() for p in paths]
    real_save, calls = np.save, []

    def failing_save(file, arr, *a, **k):
        calls.append(file)
        if len(calls) == 3:
            raise OSError(28, "No space left on device")
        return real_save(file, arr, *a, **k)

    monkeypatch.setattr(np, "save", failing_save)
    with pytest.raises(OSError, match="No space"):
        write_frames(np.zeros((4, 4, 3)), tmp_path, suffix=".npy", overwrite=True)
    monkeypatch.undo()
    assert [p.read_bytes() for p in paths] == before  # the previous capture is intact
    assert sorted(p.name for p in tmp_path.iterdir()) == [p.name for p in paths]  # no temporaries
    write_frames(np.zeros((4, 4, 3)), tmp_path, suffix=".npy", overwrite=True)
    assert np.load(paths[2]).sum() == 0


def test_read_frame_checks_declared_sizes_before_reading(tmp_path):
    from tensor_cosdi.io import read_frame

    np.save(tmp_path / "f.npy", np.zeros((64, 64)))
    with pytest.raises(ValueError, match="= 32.00 KiB, above the 1000 B limit"):
        read_frame(tmp_path / "f.npy", max_bytes=1000)
    # a forged .npy header declaring a 74 GiB array in a tiny file
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000), }"
    header += " " * (118 - len(header)) + "\n"
    (tmp_path / "forged.npy").write_bytes(
        b"\x93NUMPY\x01\x00" + bytes([len(header), 0]) + header.encode()
    )
    with pytest.raises(ValueError, match="declares shape \\(100000, 100000\\)"):
        read_frame(tmp_path / "forged.npy")
    np.testing.assert_array_equal(read_frame(tmp_path / "f.npy"), np.zeros((64, 64)))
