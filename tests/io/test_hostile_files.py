"""Files built to make a reader fetch data from elsewhere or inflate past its limit, and files
whose content is not what it looks like: each is refused with a one-line error naming why."""

import struct
import zipfile
import zlib

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.sparse

from tensor_cosdi.io import load_bundle, save_bundle
from tensor_cosdi.io.files import read_array, read_cube, write_cube
from tensor_cosdi.io.frames import read_frame
from tensor_cosdi.systems import SDCASSI


@pytest.fixture
def secret(tmp_path):
    """A file the process can read that no reader was asked for."""
    path = tmp_path / "secret.bin"
    np.full(64, 7.0).tofile(path)
    return path


def test_hdf5_external_raw_storage_is_refused(tmp_path, secret):
    path = tmp_path / "ext.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("cube", shape=(4, 4, 4), dtype="f8", external=[(str(secret), 0, 512)])
    for read in (read_array, read_cube):
        with pytest.raises(ValueError, match="external raw files"):
            read(path)


def test_hdf5_virtual_dataset_is_refused(tmp_path):
    source = tmp_path / "source.h5"
    with h5py.File(source, "w") as f:
        f["data"] = np.ones((4, 4, 4))
    layout = h5py.VirtualLayout(shape=(4, 4, 4), dtype="f8")
    layout[:] = h5py.VirtualSource(str(source), "data", shape=(4, 4, 4))
    path = tmp_path / "vds.h5"
    with h5py.File(path, "w") as f:
        f.create_virtual_dataset("cube", layout, fillvalue=0)
    with pytest.raises(ValueError, match="virtual dataset"):
        read_cube(path)
    source.unlink()  # a missing source would read as the fill value: still refused
    with pytest.raises(ValueError, match="virtual dataset"):
        read_array(path)


def test_hdf5_links_out_of_the_file_are_refused(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["cube"] = np.ones((4, 4, 4))
    path = tmp_path / "links.h5"
    with h5py.File(path, "w") as f:
        f["outside"] = h5py.ExternalLink(str(other), "/cube")
    # an external link is never followed: the file holds no array of its own
    with pytest.raises(ValueError, match="no arrays"):
        read_array(path)
    with pytest.raises(KeyError, match="no array 'outside'; it holds no arrays"):
        read_array(path, "outside")


def test_hdf5_chunks_larger_than_the_limit_are_refused(tmp_path):
    path = tmp_path / "chunk.h5"
    with h5py.File(path, "w") as f:
        ds = f.create_dataset(
            "cube", shape=(2, 2, 2), maxshape=(None, None, None), chunks=(64, 64, 64),
            dtype="f8", compression="gzip",
        )  # fmt: skip
        ds[...] = 1.0
    np.testing.assert_array_equal(read_cube(path)[0], np.ones((2, 2, 2)))
    with pytest.raises(ValueError, match="chunks, above the 100000-byte limit"):
        read_cube(path, max_bytes=100_000)


def test_bundle_with_an_external_link_is_refused(tmp_path, secret):
    system = SDCASSI((np.arange(36).reshape(6, 6) % 2).astype(float), n_bands=3)
    path = save_bundle(
        tmp_path / "b.h5", system=system, measurement=np.ones(system.measurement_shape)
    )
    with h5py.File(path, "r+") as f:
        del f["measurement"]
        f["measurement"] = h5py.ExternalLink(str(tmp_path / "elsewhere.h5"), "/m")
    with pytest.raises(ValueError, match="ExternalLink"):
        load_bundle(path)


def test_npz_member_that_inflates_past_the_limit_is_refused(tmp_path):
    path = tmp_path / "bomb.npz"
    np.savez_compressed(path, cube=np.zeros((256, 256, 8)))  # 4 MiB of zeros, a few KiB stored
    assert path.stat().st_size < 20_000
    with pytest.raises(ValueError, match="inflates to 4194432 bytes"):
        read_cube(path, max_bytes=1 << 20)
    assert read_cube(path)[0].shape == (256, 256, 8)


def _mat_with_compressed_payload(path, payload: bytes):
    """A MATLAB v5 file: header, then one miCOMPRESSED element holding ``payload``."""
    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    data = zlib.compress(payload, 9)
    path.write_bytes(head + struct.pack("<II", 15, len(data)) + data)


def test_mat_variable_that_inflates_past_the_limit_is_refused(tmp_path):
    path = tmp_path / "bomb.mat"
    scipy.io.savemat(path, {"cube": np.zeros((128, 128, 16))}, do_compression=True)
    with pytest.raises(ValueError, match="inflates to more than 1048576 bytes"):
        read_cube(path, max_bytes=1 << 20)
    assert read_cube(path)[0].shape == (128, 128, 16)
    odd = tmp_path / "odd.mat"  # a declared-tiny element padded with 8 MiB after its data
    _mat_with_compressed_payload(odd, b"\0" * (8 << 20))
    with pytest.raises(ValueError, match="inflates"):
        read_array(odd, max_bytes=1 << 20)


def test_mat_sparse_matrix_is_named(tmp_path):
    path = tmp_path / "sp.mat"
    scipy.io.savemat(path, {"mask": scipy.sparse.eye(4, format="csc")})
    with pytest.raises(ValueError, match=r"'mask' is a MATLAB sparse matrix; save it with full"):
        read_array(path)


def test_tiff_with_pages_of_two_shapes_is_refused(tmp_path):
    import tifffile

    path = tmp_path / "mixed.tif"
    with tifffile.TiffWriter(path) as w:
        for shape in ((8, 8), (8, 8), (4, 4), (8, 8)):
            w.write(np.ones(shape, np.float32), metadata=None)
    with pytest.raises(ValueError, match=r"4 pages in \d image series"):
        read_cube(path)


def test_rgb_tiff_is_a_three_band_cube(tmp_path):
    import tifffile

    rgb = np.random.default_rng(0).integers(0, 255, (12, 16, 3), dtype=np.uint8)
    tifffile.imwrite(tmp_path / "rgb.tif", rgb, photometric="rgb")
    cube, wl = read_cube(tmp_path / "rgb.tif")
    np.testing.assert_array_equal(cube, rgb)
    assert wl is None


def test_complex_cube_and_wrong_wavelength_count_are_refused(tmp_path):
    z = np.ones((4, 4, 3), complex)
    np.savez(tmp_path / "z.npz", cube=z)
    with pytest.raises(ValueError, match="complex128 values; a cube is real"):
        read_cube(tmp_path / "z.npz")
    np.savez(tmp_path / "w.npz", cube=np.ones((4, 4, 4)), wavelengths=[450.0, 500.0, 550.0])
    with pytest.raises(ValueError, match="3 wavelengths for a cube of 4 bands"):
        read_cube(tmp_path / "w.npz")


def test_frames_share_the_inflation_limit(tmp_path):
    np.savez_compressed(tmp_path / "f.npz", frame=np.zeros((1024, 1024)))
    with pytest.raises(ValueError, match="inflates"):
        read_frame(tmp_path / "f.npz", max_bytes=1 << 20)


def test_writer_output_still_reads(tmp_path):
    cube = np.random.default_rng(1).random((6, 7, 5))
    for suffix in (".h5", ".mat", ".npz"):
        back, _ = read_cube(write_cube(tmp_path / f"c{suffix}", cube))
        np.testing.assert_array_equal(back, cube)
    assert zipfile.is_zipfile(tmp_path / "c.npz")


def _small_bundle(path):
    system = SDCASSI((np.arange(36).reshape(6, 6) % 2).astype(float), n_bands=3)
    return save_bundle(path, system=system, measurement=np.ones(system.measurement_shape))


@pytest.mark.parametrize("suffix", [".npz", ".h5"])
def test_an_edited_bundle_document_is_noticed(tmp_path, suffix):
    import json

    path = _small_bundle(tmp_path / f"b{suffix}")
    assert load_bundle(path).system.n_bands == 3
    if suffix == ".npz":
        with np.load(path) as z:
            data = {k: z[k] for k in z.files}
        doc = json.loads(str(data["__bundle__"]))
        doc["metadata"] = {"exposure_ms": 5}
        data["__bundle__"] = np.array(json.dumps(doc))
        path.unlink()
        np.savez(path, **data)
    else:
        with h5py.File(path, "r+") as f:
            doc = json.loads(f.attrs["tensor_cosdi_bundle"])
            doc["system"]["shifts"] = 2
            f.attrs["tensor_cosdi_bundle"] = json.dumps(doc)
    with pytest.raises(ValueError, match="document does not match its SHA-256"):
        load_bundle(path)


def test_a_bundle_never_writes_what_it_would_refuse_to_read(tmp_path):
    system = SDCASSI((np.arange(36).reshape(6, 6) % 2).astype(float), n_bands=3)
    g = np.ones(system.measurement_shape)
    g[0, 0] = np.nan
    with pytest.raises(ValueError, match="measurement holds NaN"):
        save_bundle(tmp_path / "b.npz", system=system, measurement=g)
    assert not (tmp_path / "b.npz").exists()


def test_an_npz_bundle_is_bounded_too(tmp_path):
    system = SDCASSI(np.ones((64, 64)), n_bands=3)
    path = save_bundle(tmp_path / "b.npz", system=system, cube=np.zeros(system.cube_shape))
    with pytest.raises(ValueError, match="inflates to .* above the 1000-byte limit"):
        load_bundle(path, max_bytes=1000)
