"""`tensor-cosdi reconstruct` from a measurement and a mask file (no Python), and `info`."""

import os
import stat

import numpy as np
import pytest
import scipy.io

import tensor_cosdi as tc
from tensor_cosdi import cli, metrics
from tensor_cosdi.io import load_bundle


@pytest.fixture
def files(tmp_path):
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, rng=0)
    scipy.io.savemat(tmp_path / "mask.mat", {"mask": p.system.code})
    scipy.io.savemat(tmp_path / "meas.mat", {"meas": np.asarray(p.measurement), "t": np.ones(2)})
    return tmp_path, p


def _args(d, out="cube.h5", *extra):
    return [
        "reconstruct", "--system", "sd_cassi", "--mask", str(d / "mask.mat"), "--shift", "1",
        "--bands", "8", "--wavelengths", "450:650", "--measurement", str(d / "meas.mat") + ":meas",
        "--out", str(d / out), "--method", "gap_tv", "--quiet", *extra,
    ]  # fmt: skip


def test_direct_path_writes_an_hdf5_bundle_with_provenance(files, capsys):
    d, p = files
    assert cli.main(_args(d)) == 0
    assert "written to" in capsys.readouterr().out
    b = load_bundle(d / "cube.h5")
    assert b.cube.dtype == np.float32 and b.cube.shape == (32, 32, 8)
    lsq = tc.studies.score(p, tc.reconstruct(p.system, p.measurement, "lsq").cube)["psnr"]
    psnr = metrics.psnr(p.cube, b.cube, data_range=float(np.max(p.cube)))
    assert psnr > lsq + 1.0, (psnr, lsq)
    np.testing.assert_allclose(b.system.wavelengths, np.linspace(450, 650, 8))
    assert [s["path"].endswith(n) for s, n in zip(b.provenance, ("mask.mat", "meas.mat"))] == [
        True,
        True,
    ]
    assert b.metadata["method"] == "gap_tv"
    mode = stat.S_IMODE(os.stat(d / "cube.h5").st_mode)
    umask = os.umask(0)
    os.umask(umask)
    assert mode == 0o666 & ~umask  # not mkstemp's 0600
    # never overwritten without --force; with it, replaced
    before = (d / "cube.h5").read_bytes()
    assert cli.main(_args(d)) == 2
    assert "--force" in capsys.readouterr().err and (d / "cube.h5").read_bytes() == before
    assert cli.main(_args(d, "cube.h5", "--force")) == 0


@pytest.mark.parametrize(
    "flag, value, message",
    [
        ("--measurement", "meas.mat", "several candidates.*meas \\(32, 39\\)"),
        ("--shift", "2", "does not match the system's"),
        ("--system", "c3slfi", "c3slfi takes no"),
        ("--system", "nope", "nope"),
        ("--wavelengths", "450-650", "START:STOP"),
        ("--mask", None, "needs --mask"),
    ],
)
def test_direct_path_errors_name_what_is_wrong(files, capsys, flag, value, message):
    import re

    d, _ = files
    args = _args(d)
    i = args.index(flag)
    if value is None:
        del args[i : i + 2]
    else:
        args[i + 1] = str(d / value) if value.endswith(".mat") else value
    assert cli.main(args) == 2
    assert re.search(message, capsys.readouterr().err), message
    assert not (d / "cube.h5").exists()


def test_info_lists_arrays_and_bundle_provenance(files, capsys):
    d, _ = files
    assert cli.main(["info", str(d / "meas.mat")]) == 0
    out = capsys.readouterr().out
    assert "meas: (32, 39) float64" in out and "t: (1, 2)" in out
    assert cli.main(_args(d)) == 0
    capsys.readouterr()
    assert cli.main(["info", str(d / "cube.h5")]) == 0
    out = capsys.readouterr().out
    assert "cube: (32, 32, 8) float32" in out and "system: SDCASSI" in out
    assert "sha256" in out and "wavelengths: 8 bands, 450–650 nm" in out
    assert "shifts: 0, 1, 2, 3, 4, 5, 6, 7 px" in out
    assert f'metadata.mask: "{d / "mask.mat"}"' in out  # a long path whole, never cut


def test_info_names_what_it_does_not_read(tmp_path, capsys):
    scipy.io.savemat(tmp_path / "m.mat", {"mask": np.ones((4, 4)), "note": "hi"})
    assert cli.main(["info", str(tmp_path / "m.mat")]) == 0
    out = capsys.readouterr().out
    assert "mask: (4, 4) float64" in out and "note: not read (MATLAB text (char))" in out


def test_a_256x256x28_reconstruction_file_is_at_most_12_mb(tmp_path):
    # a full-size SD-CASSI result: float32 cube, measurement, mask, provenance (issue target
    # ≤ 12 MB; float64 uncompressed it was 105 MB at 660×714)
    rng = np.random.default_rng(0)
    mask = tc.codes.random_binary((256, 256), rng=0)
    system = tc.systems.SDCASSI(mask, n_bands=28, shifts=2)
    g = system.simulate(rng.random((256, 256, 28)), snr_db=30, rng=1)  # noise: incompressible
    np.save(tmp_path / "mask.npy", mask)
    np.save(tmp_path / "meas.npy", np.asarray(g))
    args = [
        "reconstruct", "--system", "sd_cassi", "--mask", str(tmp_path / "mask.npy"),
        "--shift", "2", "--bands", "28", "--measurement", str(tmp_path / "meas.npy"),
        "--out", str(tmp_path / "cube.h5"), "--method", "lsq", "--quiet",
    ]  # fmt: skip
    assert cli.main(args) == 0
    size = (tmp_path / "cube.h5").stat().st_size
    assert size <= 12e6, f"{size / 1e6:.1f} MB"
    b = load_bundle(tmp_path / "cube.h5")
    assert b.cube.shape == (256, 256, 28) and b.cube.dtype == np.float32


def test_direct_path_takes_a_colour_coded_aperture(tmp_path):
    from tensor_cosdi import codes

    code = codes.colour_coded_aperture((24, 24), 6, n_filters=3, rng=0)
    sd = tc.systems.SDCASSI(code, n_bands=6, shifts=1, colour=True)
    cube = tc.scenes.colorchecker((24, 24), np.linspace(450, 650, 6))
    np.save(tmp_path / "code.npy", code)
    np.save(tmp_path / "meas.npy", np.asarray(sd.forward(cube)))
    args = [
        "reconstruct", "--system", "sd_cassi", "--mask", str(tmp_path / "code.npy"), "--shift",
        "1", "--bands", "6", "--measurement", str(tmp_path / "meas.npy"), "--out",
        str(tmp_path / "c.h5"), "--method", "gap_tv", "--quiet",
    ]  # fmt: skip
    assert cli.main(args) == 2  # read as 6 shots of a plain code: the measurement does not fit
    assert cli.main(args + ["--system-option", "colour=true"]) == 0
    b = load_bundle(tmp_path / "c.h5")
    assert b.system.colour and b.system.code.shape == (24, 24, 6)


def _write_pair(fmt, d, mask, meas):
    """The (mask, measurement) pair as a user's files of format ``fmt``; returns their specs."""
    import h5py
    import tifffile

    if fmt == "mat73":  # MATLAB v7.3: HDF5 in column-major order behind a 512-byte header
        for name, a in (("mask", mask), ("meas", meas)):
            with h5py.File(d / f"{name}.mat", "w", userblock_size=512) as f:
                f.create_dataset(name, data=a.T).attrs["MATLAB_class"] = np.bytes_("double")
            with open(d / f"{name}.mat", "r+b") as f:
                f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema")
        return str(d / "mask.mat"), str(d / "meas.mat")
    if fmt == "h5":
        with h5py.File(d / "pair.h5", "w") as f:
            f["mask"], f["meas"] = mask, meas
        return str(d / "pair.h5") + ":mask", str(d / "pair.h5") + ":meas"
    if fmt == "tif":
        tifffile.imwrite(d / "mask.tif", mask.astype(np.float32))
        tifffile.imwrite(d / "meas.tif", meas.astype(np.float32))
        return str(d / "mask.tif"), str(d / "meas.tif")
    if fmt == "npz":
        np.savez(d / "pair.npz", mask=mask, meas=meas)
        return str(d / "pair.npz") + ":mask", str(d / "pair.npz") + ":meas"
    scipy.io.savemat(d / "mask.mat", {"mask": mask})  # MATLAB v5
    scipy.io.savemat(d / "meas.mat", {"meas": meas})
    return str(d / "mask.mat"), str(d / "meas.mat")


@pytest.mark.parametrize("fmt", ["mat5", "mat73", "h5", "tif", "npz"])
def test_a_users_pair_of_files_in_any_format_gives_the_same_cube(fmt, tmp_path):
    pytest.importorskip("h5py")
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(24, 24), n_bands=6, rng=0)
    mask, meas = np.asarray(p.system.code, float), np.asarray(p.measurement, np.float32)
    mspec, gspec = _write_pair(fmt, tmp_path, mask, meas)
    args = [
        "reconstruct", "--system", "sd_cassi", "--mask", mspec, "--shift", "1", "--bands", "6",
        "--measurement", gspec, "--out", str(tmp_path / "cube.h5"), "--method", "lsq", "--quiet",
    ]  # fmt: skip
    assert cli.main(args) == 0
    got = load_bundle(tmp_path / "cube.h5").cube
    want = tc.reconstruct(tc.systems.SDCASSI(mask, n_bands=6, shifts=1), meas, "lsq").cube
    np.testing.assert_allclose(got, np.asarray(want, np.float32), rtol=1e-4, atol=1e-5)


def test_a_missing_variable_or_a_folder_as_output_is_one_line_not_a_traceback(files, capsys):
    d, _ = files
    args = _args(d)
    i = args.index("--measurement") + 1
    args[i] = str(d / "meas.mat") + ":meas_real"  # the file holds "meas"
    assert cli.main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "meas_real" in err and "Traceback" not in err
    assert not err.split("error: ", 1)[1].startswith("'"), err  # the message, not a quoted repr
    (d / "folder.h5").mkdir()
    assert cli.main(_args(d, "folder.h5", "--force")) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "folder.h5" in err, err


def test_outputs_that_are_folders_or_unknown_files_are_one_line_errors(files, capsys):
    d, _ = files
    (d / "folder.h5").mkdir()
    assert cli.main(_args(d, "folder.h5", "--force")) == 2
    assert "folder.h5 is a folder; give a file name" in capsys.readouterr().err
    assert cli.main(_args(d, "cube")) == 2
    assert "a reconstruction bundle is an .h5 or .npz file (e.g. cube.h5)" in (
        capsys.readouterr().err
    )
    assert not (d / "cube.npz").exists() and not (d / "cube").exists()


def test_an_output_folder_that_is_missing_is_refused_before_any_work(files, capsys):
    """A typo in ``--out``'s folder surfaced only after the whole reconstruction."""
    d, _ = files
    args = _args(d, "missing/cube.h5")
    args[args.index("--mask") + 1] = str(d / "no_such_mask.mat")  # would fail if read first
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert "the output folder" in err and "missing does not exist" in err, err
    (d / "plain").write_text("")
    assert cli.main(_args(d, "plain/cube.h5")) == 2
    assert "plain is not a folder" in capsys.readouterr().err
    assert cli.main(["preview", str(d / "meas.mat:meas"), "--out", str(d / "gone/p.png")]) == 2
    assert "gone does not exist" in capsys.readouterr().err


def test_damaged_inputs_never_show_a_traceback_or_advise_unpickling(files, capsys):
    d, _ = files
    (d / "bad.hdr").write_text("ENVI\nsamples = 4\n")
    (d / "corrupt.npz").write_bytes(b"PK\x03\x04 not a zip archive")
    np.save(d / "pickled.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    args = _args(d)
    args[args.index("--mask") + 1] = str(d / "bad.hdr")
    assert cli.main(args) == 2
    assert "not a readable ENVI header" in capsys.readouterr().err
    for name in ("corrupt.npz", "pickled.npy"):
        assert cli.main(["preview", str(d / name), "--out", str(d / "p.png")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "allow_pickle" not in err and "Traceback" not in err


def test_wavelengths_as_a_list_a_name_or_a_file(files, tmp_path):
    from tensor_cosdi import datasets
    from tensor_cosdi.cli.files import parse_wavelengths

    np.testing.assert_allclose(parse_wavelengths("kaist", 28), datasets.KAIST_WAVELENGTHS)
    np.testing.assert_allclose(parse_wavelengths("450, 500,550", 3), [450, 500, 550])
    np.savetxt(tmp_path / "wl.txt", [460.0, 520.0])
    np.testing.assert_allclose(parse_wavelengths(str(tmp_path / "wl.txt"), 2), [460, 520])
    with pytest.raises(ValueError, match="gives 28 band centres for 8 bands"):
        parse_wavelengths("kaist", 8)
    with pytest.raises(ValueError, match="micrometres"):
        parse_wavelengths("0.45:0.65", 8)
    with pytest.raises(ValueError, match="START:STOP"):
        parse_wavelengths("blue", 8)
    d, _ = files
    args = _args(d, "kaist.h5")
    args[args.index("--wavelengths") + 1] = ",".join(str(450 + 25 * i) for i in range(8))
    assert cli.main(args) == 0
    wl = load_bundle(d / "kaist.h5").system.wavelengths
    np.testing.assert_allclose(wl, 450 + 25 * np.arange(8))


def test_one_command_from_files_to_cube_and_preview(files, capsys):
    """``reconstruct … --preview``: the bundle and its PNG (sRGB and spectra at --points); an
    existing PNG without --force stops the run before any reconstruction."""
    pytest.importorskip("matplotlib")
    d, _ = files
    assert cli.main(_args(d, "cube.h5", "--preview", "--points", "5,6", "20,30")) == 0
    png = d / "cube_preview.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert "written to" in out and f"wrote {png}" in out
    (d / "cube.h5").unlink()
    before = png.read_bytes()
    assert cli.main(_args(d, "cube.h5", "--preview")) == 2
    assert "--force" in capsys.readouterr().err
    assert not (d / "cube.h5").exists() and png.read_bytes() == before  # nothing was run
    assert cli.main(_args(d, "cube2.h5", "--preview", "--points", "99,1")) == 2
    assert "outside the cube's 32×32 pixels" in capsys.readouterr().err


def test_calibrate_moves_the_mask_to_where_the_capture_says_it_sits(tmp_path, capsys):
    """A capture through the mask moved by (0.6, −1.4) px: ``--calibrate`` prints the estimate,
    records it in the bundle and reconstructs closer to the truth than the mask as filed; a
    capture unrelated to the mask is refused, not guessed at."""
    from tensor_cosdi.io.calibration import shift_code

    mask = tc.codes.random_binary((48, 48), rng=3)
    true = tc.systems.SDCASSI(shift_code(mask, 0.6, -1.4), n_bands=8, shifts=2)
    cube = tc.scenes.colorchecker((48, 48), true.wavelengths)
    scipy.io.savemat(tmp_path / "mask.mat", {"mask": mask})
    scipy.io.savemat(tmp_path / "meas.mat", {"meas": true.simulate(cube, snr_db=30, rng=0)})
    scipy.io.savemat(tmp_path / "noise.mat", {"meas": np.random.default_rng(0).random((48, 62))})

    def args(out, meas="meas.mat", *extra):
        return [
            "reconstruct", "--system", "sd_cassi", "--mask", str(tmp_path / "mask.mat"),
            "--shift", "2", "--bands", "8", "--measurement", str(tmp_path / meas) + ":meas",
            "--out", str(tmp_path / out), "--method", "gap_tv", "--quiet", *extra,
        ]  # fmt: skip

    assert cli.main(args("plain.h5")) == 0
    assert cli.main(args("fixed.h5", "meas.mat", "--calibrate")) == 0
    out = capsys.readouterr().out
    assert "mask registration: rows +0." in out and "columns -1." in out, out
    assert "dispersion as given (evenly spaced shifts" in out, out
    fixed = load_bundle(tmp_path / "fixed.h5")
    reg = fixed.metadata["registration"]
    assert abs(reg["row_offset"] - 0.6) <= 0.25 and abs(reg["col_offset"] + 1.4) <= 0.25
    psnr = {
        name: metrics.psnr(cube, load_bundle(tmp_path / name).cube, data_range=1.0)
        for name in ("plain.h5", "fixed.h5")
    }
    assert psnr["fixed.h5"] > psnr["plain.h5"] + 1.0, psnr
    assert cli.main(args("noise.h5", "noise.mat", "--calibrate")) == 2
    assert "does not stand out" in capsys.readouterr().err
    assert not (tmp_path / "noise.h5").exists()


def test_calibrate_finds_a_mirrored_prism_dispersion_given_per_band_shifts(tmp_path, capsys):
    """``--shift`` as a file of a prism's per-band shifts; the capture was taken with the
    dispersion mirrored and the mask moved: ``--calibrate`` says so, the bundle's system is the
    mirrored one and the reconstruction beats the system as filed."""
    from tensor_cosdi.io.calibration import shift_code

    wl = np.linspace(450, 650, 12)
    shifts = tc.optics.DoubleAmiciPrism().shifts(wl, distance_mm=30, pixel_um=6, integer=True)
    np.savetxt(tmp_path / "shifts.txt", shifts)
    mask = tc.codes.random_binary((48, 48), rng=4)
    true = tc.systems.SDCASSI(shift_code(mask, -0.5, 1.2), n_bands=12, shifts=shifts,
                              wavelengths=wl, shear_direction=-1)  # fmt: skip
    cube = tc.scenes.colorchecker((48, 48), wl)
    scipy.io.savemat(tmp_path / "mask.mat", {"mask": mask})
    scipy.io.savemat(tmp_path / "meas.mat", {"meas": true.simulate(cube, snr_db=30, rng=0)})

    def args(out, shift, *extra):
        return [
            "reconstruct", "--system", "sd_cassi", "--mask", str(tmp_path / "mask.mat"),
            "--shift", shift, "--bands", "12", "--wavelengths", "450:650",
            "--measurement", str(tmp_path / "meas.mat:meas"), "--out", str(tmp_path / out),
            "--method", "gap_tv", "--quiet", *extra,
        ]  # fmt: skip

    assert cli.main(args("plain.h5", str(tmp_path / "shifts.txt"))) == 0
    assert cli.main(args("fixed.h5", ",".join(f"{v:g}" for v in shifts), "--calibrate")) == 0
    out = capsys.readouterr().out
    assert "dispersion mirrored (direction margin" in out, out
    fixed = load_bundle(tmp_path / "fixed.h5")
    np.testing.assert_array_equal(fixed.system.shifts, true.shifts)
    assert fixed.metadata["registration"]["direction"] == -1
    psnr = {
        name: metrics.psnr(cube, load_bundle(tmp_path / name).cube, data_range=1.0)
        for name in ("plain.h5", "fixed.h5")
    }
    assert psnr["fixed.h5"] > psnr["plain.h5"] + 3.0, psnr
    for bad, message in (("1,2", "gives 2 shifts for 12 bands"), ("inf", "--shift must be"),
                         ("two", "--shift must be"), ("1,x,3", "--shift must be")):  # fmt: skip
        assert cli.main(args("bad.h5", bad)) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "bad.h5").exists()
