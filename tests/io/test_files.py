"""read_cube / read_array / write_cube: every format round-trips, MATLAB v7.3 is transposed back,
keys are found or listed, reads are bounded, writes are atomic and never overwrite unasked."""

import json

import numpy as np
import pytest

from tensor_cosdi.io import files
from tensor_cosdi.io.files import read_array, read_cube, split_key, write_cube

WL = np.linspace(450.0, 650.0, 5)


def _cube(dtype=np.float32):
    return np.random.default_rng(0).random((6, 7, 5)).astype(dtype)


@pytest.mark.parametrize("suffix", [".h5", ".hdf5", ".nc", ".mat", ".npz", ".tif", ".hdr"])
def test_every_format_round_trips_cube_and_wavelengths(tmp_path, suffix):
    pytest.importorskip("spectral") if suffix == ".hdr" else None
    pytest.importorskip("h5netcdf") if suffix == ".nc" else None
    cube = _cube()
    path = write_cube(tmp_path / f"c{suffix}", cube, WL, metadata={"scene": "x"})
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, cube)
    assert back.dtype == cube.dtype
    np.testing.assert_allclose(wl, WL)


def test_netcdf_is_what_xarray_reads_and_needs_its_libraries_to_write(tmp_path, monkeypatch):
    """A NetCDF-4 cube opens in xarray with its dims, the wavelength coordinate in nm and the
    metadata; without h5netcdf, writing one is a one-line ImportError naming the extra and
    nothing is written."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path = write_cube(tmp_path / "c.nc", _cube(), WL, metadata={"scene": "x"})
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert ds["cube"].dims == ("rows", "columns", "wavelength")
        np.testing.assert_allclose(ds["wavelength"].values, WL)
        assert ds["wavelength"].attrs["units"] == "nm"
        assert json.loads(ds.attrs["metadata"]) == {"scene": "x"}
        np.testing.assert_array_equal(ds["cube"].values, _cube())
    monkeypatch.setitem(__import__("sys").modules, "h5netcdf", None)
    with pytest.raises(ImportError, match=r"tensor_cosdi\[xarray\]"):
        write_cube(tmp_path / "d.nc", _cube(), WL)
    assert not (tmp_path / "d.nc").exists()


def test_npy_holds_the_cube_only(tmp_path):
    cube = _cube(np.float64)
    write_cube(tmp_path / "c.npy", cube)
    back, wl = read_cube(tmp_path / "c.npy")
    np.testing.assert_array_equal(back, cube)
    assert wl is None
    with pytest.raises(ValueError, match="use .npz or .h5"):
        write_cube(tmp_path / "d.npy", cube, WL)
    with pytest.raises(ValueError, match="key must be None"):
        read_array(tmp_path / "c.npy", key="cube")


def test_matlab_v73_is_read_in_matlab_order(tmp_path):
    h5py = pytest.importorskip("h5py")
    cube = np.arange(6 * 7 * 5, dtype=np.float64).reshape(6, 7, 5)
    path = tmp_path / "v73.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        # MATLAB writes column-major: the HDF5 dataset holds the transpose
        f.create_dataset("meas", data=cube.T).attrs["MATLAB_class"] = np.bytes_("double")
        f.create_dataset("wavelengths", data=WL.reshape(5, 1))  # a 1×5 row vector in MATLAB
        f.create_dataset("name", data=np.frombuffer(b"abc", np.uint8)).attrs["MATLAB_class"] = (
            np.bytes_("char")
        )
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Nov 23 2026 HDF5 schema")
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, cube)
    np.testing.assert_allclose(wl, WL)
    np.testing.assert_array_equal(read_array(path, "meas"), cube)


def test_keys_are_found_alone_or_listed(tmp_path):
    np.savez(tmp_path / "two.npz", a=np.zeros((4, 4)), b=np.ones((4, 4, 3)), wavelengths=WL[:3])
    back, wl = read_cube(tmp_path / "two.npz")  # the only 3-D array is the cube
    assert back.shape == (4, 4, 3) and wl is not None
    with pytest.raises(ValueError, match=r"a \(4, 4\).*b \(4, 4, 3\).*pass key=NAME"):
        read_array(tmp_path / "two.npz")
    np.testing.assert_array_equal(read_array(tmp_path / "two.npz", "a"), np.zeros((4, 4)))
    with pytest.raises(KeyError, match="no array 'c'.*a \\(4, 4\\)"):
        read_array(tmp_path / "two.npz", "c")
    import scipy.io

    scipy.io.savemat(tmp_path / "m.mat", {"mask": np.eye(3), "meas": np.ones((3, 5))})
    with pytest.raises(ValueError, match="mask \\(3, 3\\), meas \\(3, 5\\)"):
        read_array(tmp_path / "m.mat")
    np.testing.assert_array_equal(read_array(tmp_path / "m.mat", "mask"), np.eye(3))
    assert split_key(str(tmp_path / "m.mat") + ":mask") == (str(tmp_path / "m.mat"), "mask")
    assert split_key(str(tmp_path / "m.mat")) == (str(tmp_path / "m.mat"), None)


def test_reads_are_bounded_before_allocation(tmp_path):
    np.save(tmp_path / "big.npy", np.zeros((100, 100)))
    with pytest.raises(ValueError, match="= 78.12 KiB, above the 1000 B limit"):
        read_array(tmp_path / "big.npy", max_bytes=1000)
    write_cube(tmp_path / "c.h5", _cube())
    with pytest.raises(ValueError, match="'cube' declares shape \\(6, 7, 5\\)"):
        read_cube(tmp_path / "c.h5", max_bytes=100)


def test_bad_inputs_are_clear_errors(tmp_path):
    with pytest.raises(ValueError, match="unknown file type '.xyz'"):
        read_cube(tmp_path / "a.xyz")
    with pytest.raises(FileNotFoundError, match="file not found"):
        read_cube(tmp_path / "missing.h5")
    with pytest.raises(ValueError, match="micrometres"):
        write_cube(tmp_path / "c.h5", _cube(), WL / 1000)
    with pytest.raises(ValueError, match="5 wavelengths for a cube of 4 bands"):
        write_cube(tmp_path / "c.h5", _cube()[:, :, :4], WL)
    with pytest.raises(ValueError, match="rows, columns, bands"):
        write_cube(tmp_path / "c.h5", np.zeros((3, 3)))
    with pytest.raises(ValueError, match="JSON"):
        write_cube(tmp_path / "c.h5", _cube(), metadata={"x": object()})
    np.savez(tmp_path / "um.npz", cube=_cube(), wavelengths=WL / 1000)
    with pytest.raises(ValueError, match="micrometres"):
        read_cube(tmp_path / "um.npz")


def test_writes_never_overwrite_unasked_and_a_failed_write_keeps_the_old_file(
    tmp_path, monkeypatch
):
    path = write_cube(tmp_path / "c.npz", _cube(), WL)
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_cube(path, _cube() * 2, WL)

    def boom(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez_compressed", boom)
    with pytest.raises(OSError, match="No space"):
        write_cube(path, _cube() * 2, WL, overwrite=True)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npz"]  # no temporary left behind
    monkeypatch.undo()
    write_cube(path, _cube() * 2, WL, overwrite=True)
    np.testing.assert_array_equal(read_cube(path)[0], _cube() * 2)


def test_envi_units_are_converted(tmp_path):
    pytest.importorskip("spectral")
    write_cube(tmp_path / "c.hdr", _cube(), WL)
    hdr = (tmp_path / "c.hdr").read_text()
    hdr = hdr.replace("wavelength units = nm", "wavelength units = micrometers")
    hdr = hdr.replace("450", "0.45").replace("500", "0.5").replace("550", "0.55")
    hdr = hdr.replace("600", "0.6").replace("650", "0.65")
    (tmp_path / "c.hdr").write_text(hdr)
    _, wl = read_cube(tmp_path / "c.hdr")
    np.testing.assert_allclose(wl, WL)
    with pytest.raises(FileExistsError):
        write_cube(tmp_path / "c.hdr", _cube(), WL)


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("data type", "6", "ENVI data type 6 holds complex64 values; a cube of light is real"),
        ("interleave", "xyz", "interleave 'xyz'; ENVI knows bsq, bil and bip"),
        ("byte order", "7", "byte order '7'; ENVI knows 0"),
        ("header offset", "-5", "header offset -5; expected ≥ 0"),
        ("samples", "0", "the header declares an empty cube"),
    ],
)
def test_envi_headers_that_spectral_reads_without_complaint_are_refused(
    tmp_path, field, value, message
):
    """Each of these read a cube: complex values, an unknown interleave read as bsq, ..."""
    pytest.importorskip("spectral")
    write_cube(tmp_path / "c.hdr", _cube(), WL)
    lines = [
        f"{field} = {value}" if line.split("=")[0].strip() == field else line
        for line in (tmp_path / "c.hdr").read_text().splitlines()
    ]
    if not any(line.startswith(f"{field} =") for line in lines):
        lines.append(f"{field} = {value}")
    (tmp_path / "c.hdr").write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=message):
        read_cube(tmp_path / "c.hdr")


def test_an_envi_data_file_that_links_elsewhere_is_refused(tmp_path):
    """A header and a link named like its data would read any file on the machine as a cube."""
    pytest.importorskip("spectral")
    write_cube(tmp_path / "c.hdr", _cube(), WL)
    secret = tmp_path / "elsewhere.bin"
    (tmp_path / "c.img").rename(secret)
    (tmp_path / "c.img").symlink_to(secret)
    with pytest.raises(ValueError, match="c.img is a symbolic link"):
        read_cube(tmp_path / "c.hdr")


def test_metadata_is_stored(tmp_path):
    h5py = pytest.importorskip("h5py")
    write_cube(tmp_path / "c.h5", _cube(), WL, metadata={"scene": "face"})
    with h5py.File(tmp_path / "c.h5") as f:
        assert json.loads(f.attrs["metadata"]) == {"scene": "face"}
        assert f["cube"].compression == "gzip"
    assert files.WAVELENGTH_RANGE_NM == (200.0, 20000.0)


def test_hdf5_bundles_round_trip_and_read_without_the_library(tmp_path):
    h5py = pytest.importorskip("h5py")
    from tensor_cosdi.io import load_bundle, save_bundle
    from tensor_cosdi.systems import SDCASSI

    system = SDCASSI(np.random.default_rng(0).random((6, 7)), n_bands=5, shifts=1, wavelengths=WL)
    g = system.forward(_cube(np.float64))
    path = save_bundle(
        tmp_path / "r.h5", system=system, measurement=g, cube=_cube(),
        calibration={"white": np.ones((6, 7, 5))}, metadata={"exposure_ms": 20},
    )  # fmt: skip
    b = load_bundle(path)
    np.testing.assert_array_equal(b.measurement, g)
    np.testing.assert_array_equal(b.cube, _cube())
    assert b.metadata == {"exposure_ms": 20} and b.system.measurement_shape == (6, 11)
    np.testing.assert_array_equal(b.system.forward(_cube(np.float64)), g)
    with h5py.File(path) as f:  # plain HDF5: named datasets, groups, attributes
        assert f["cube"].shape == (6, 7, 5) and f["cube"].compression == "gzip"
        np.testing.assert_allclose(f["wavelengths"][()], WL)
        assert "code" in f["system"] and "white" in f["calibration"]
        assert json.loads(f.attrs["metadata"]) == {"exposure_ms": 20}
    with pytest.raises(FileExistsError):
        save_bundle(path, cube=_cube())
    with pytest.raises(ValueError, match="above the 100 B limit"):
        load_bundle(path, max_bytes=100)
    write_cube(tmp_path / "plain.h5", _cube())
    with pytest.raises(ValueError, match="without the tensor_cosdi_bundle"):
        load_bundle(tmp_path / "plain.h5")


@pytest.mark.parametrize("bands", [3, 4])
def test_tiff_with_three_or_four_bands_is_grey_pages_not_rgb(tmp_path, bands):
    import tifffile

    cube = _cube()[..., :bands]
    path = write_cube(tmp_path / "c.tif", cube, WL[:bands])
    with tifffile.TiffFile(path) as tif:
        assert tif.pages[0].photometric == tifffile.PHOTOMETRIC.MINISBLACK
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, cube)
    np.testing.assert_allclose(wl, WL[:bands])


def test_hdf5_cube_carries_dims_and_units(tmp_path):
    import h5py

    path = write_cube(tmp_path / "c.h5", _cube(), WL)
    with h5py.File(path, "r") as f:
        assert list(f["cube"].attrs["dims"]) == ["rows", "columns", "bands"]
        assert f["wavelengths"].attrs["units"] == "nm"
        assert f["cube"].dims[2].keys() == ["wavelength"]  # a dimension scale (netCDF-4 style)
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, _cube())
    np.testing.assert_allclose(wl, WL)
