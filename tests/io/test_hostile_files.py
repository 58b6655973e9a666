"""Files built to make a reader fetch data from elsewhere or inflate past its limit, and files
whose content is not what it looks like: each is refused with a one-line error naming why."""

import os
import zipfile

import h5py
import numpy as np
import pytest
import scipy.io

from tensor_cosdi.io import load_bundle, save_bundle
from tensor_cosdi.io.files import read_array, read_cube, write_cube
from tensor_cosdi.io.frames import read_frame
from tensor_cosdi.systems import SDCASSI
from tensor_cosdi.testing import edit_bundle_document, hostile_files, rgb_values


@pytest.fixture
def hostile(tmp_path):
    return hostile_files(tmp_path)


def test_hdf5_external_raw_storage_is_refused(hostile):
    for read in (read_array, read_cube):
        with pytest.raises(ValueError, match="external raw files"):
            read(hostile["hdf5_external"])


def test_hdf5_virtual_dataset_is_refused(hostile):
    with pytest.raises(ValueError, match="virtual dataset"):
        read_cube(hostile["hdf5_virtual"])
    # a missing source would read as the fill value: still refused
    with pytest.raises(ValueError, match="virtual dataset"):
        read_array(hostile["hdf5_virtual_missing"])


def test_hdf5_links_out_of_the_file_are_refused(hostile):
    # an external link is never followed: the file holds no array of its own
    # and the error says what the name is instead of that it is missing
    with pytest.raises(ValueError, match="no arrays; not read: cube .an external link"):
        read_array(hostile["hdf5_link"])
    with pytest.raises(ValueError, match="'cube' is an external link, which points into"):
        read_array(hostile["hdf5_link"], "cube")


def test_hdf5_soft_links_and_non_numeric_datasets_are_named(tmp_path):
    path = tmp_path / "odd.h5"
    with h5py.File(path, "w") as f:
        f["cube"] = np.ones((2, 2, 2))
        f["alias"] = h5py.SoftLink("/cube")
        f["label"] = np.array([b"abc", b"def"])
        f["pairs"] = np.zeros(3, dtype=[("a", "f4"), ("b", "f4")])
        f["phase"] = np.ones(3, dtype=np.complex128)
    np.testing.assert_array_equal(read_array(path), np.ones((2, 2, 2)))  # the one number array
    with pytest.raises(ValueError, match="'alias' is a soft link to 'cube' .* pass key='cube'"):
        read_array(path, "alias")
    with pytest.raises(ValueError, match=r"'label' is text of dtype \|S3, not a numeric array"):
        read_array(path, "label")
    with pytest.raises(ValueError, match="'pairs' is compound records"):
        read_array(path, "pairs")
    with pytest.raises(ValueError, match="'phase' is complex values of dtype <c16"):
        read_cube(path, "phase")
    with pytest.raises(KeyError, match=r"no array 'nope'; it holds cube \(2, 2, 2\); not read: "):
        read_array(path, "nope")


def test_matlab_text_and_cells_are_named(tmp_path):
    path = tmp_path / "v5.mat"
    scipy.io.savemat(
        path, {"mask": np.ones((4, 4)), "note": "hi", "c": np.array([[1, "a"]], dtype=object)}
    )
    with pytest.raises(ValueError, match=r"'note' is MATLAB text \(char\)"):
        read_array(path, "note")
    with pytest.raises(ValueError, match="'c' is a MATLAB cell"):
        read_array(path, "c")
    np.testing.assert_array_equal(read_array(path), np.ones((4, 4)))


def test_hdf5_chunks_larger_than_the_limit_are_refused(hostile):
    np.testing.assert_array_equal(read_cube(hostile["hdf5_chunks"])[0], np.ones((2, 2, 2)))
    with pytest.raises(ValueError, match="chunks, above the 100000-byte limit"):
        read_cube(hostile["hdf5_chunks"], max_bytes=100_000)


def test_bundle_with_an_external_link_is_refused(tmp_path):
    system = SDCASSI((np.arange(36).reshape(6, 6) % 2).astype(float), n_bands=3)
    path = save_bundle(
        tmp_path / "b.h5", system=system, measurement=np.ones(system.measurement_shape)
    )
    with h5py.File(path, "r+") as f:
        del f["measurement"]
        f["measurement"] = h5py.ExternalLink(str(tmp_path / "elsewhere.h5"), "/m")
    with pytest.raises(ValueError, match="ExternalLink"):
        load_bundle(path)


def test_npz_member_that_inflates_past_the_limit_is_refused(hostile):
    path = hostile["npz_bomb"]  # 4 MiB of zeros, a few KiB stored
    assert path.stat().st_size < 20_000
    with pytest.raises(ValueError, match="inflates to 4194432 bytes"):
        read_cube(path, max_bytes=1 << 20)
    assert read_cube(path)[0].shape == (256, 256, 8)


def test_mat_variable_that_inflates_past_the_limit_is_refused(hostile):
    with pytest.raises(ValueError, match="inflates to more than 1048576 bytes"):
        read_cube(hostile["mat_bomb"], max_bytes=1 << 20)
    assert read_cube(hostile["mat_bomb"])[0].shape == (128, 128, 16)
    # a declared-tiny element padded with 8 MiB after its data
    with pytest.raises(ValueError, match="inflates"):
        read_array(hostile["mat_padded"], max_bytes=1 << 20)


def test_mat_sparse_matrix_is_named(hostile):
    with pytest.raises(ValueError, match=r"'mask' is a MATLAB sparse matrix; save it with full"):
        read_array(hostile["mat_sparse"])


def test_tiff_with_pages_of_two_shapes_is_refused(hostile):
    with pytest.raises(ValueError, match=r"4 pages in \d image series"):
        read_cube(hostile["tiff_mixed"])


def test_rgb_tiff_is_a_three_band_cube(hostile):
    cube, wl = read_cube(hostile["tiff_rgb"])
    np.testing.assert_array_equal(cube, rgb_values(0))
    assert wl is None


def test_complex_cube_and_wrong_wavelength_count_are_refused(hostile):
    with pytest.raises(ValueError, match="complex128 values; a cube is real"):
        read_cube(hostile["npz_complex"])
    with pytest.raises(ValueError, match="3 wavelengths for a cube of 4 bands"):
        read_cube(hostile["npz_wavelengths"])


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs and /dev/zero need POSIX")
def test_devices_and_fifos_are_never_opened(hostile):
    for name in ("fifo", "dev_zero"):
        with pytest.raises(ValueError, match="not a regular file"):
            read_array(hostile[name])
        with pytest.raises(ValueError, match="not a regular file"):
            read_frame(hostile[name])
    with pytest.raises(FileNotFoundError, match="file not found"):
        read_array(hostile["fifo"].parent / "nothing_here.npy")
    with pytest.raises(ValueError, match="not a regular file"):
        load_bundle(hostile["fifo"].parent)  # a folder named as a bundle
    with pytest.raises(FileNotFoundError, match="bundle not found"):
        load_bundle(hostile["fifo"].parent / "nothing_here.npz")


def test_a_complex_matlab_v5_cube_is_refused(tmp_path):
    """MATLAB v5's listing says 'double' for a complex variable: checked after loading."""
    import scipy.io

    scipy.io.savemat(tmp_path / "c.mat", {"cube": np.ones((4, 4, 3)) + 1j})
    with pytest.raises(ValueError, match="complex128 values; a cube is real"):
        read_cube(tmp_path / "c.mat")


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

    path = _small_bundle(tmp_path / f"b{suffix}")
    assert load_bundle(path).system.n_bands == 3
    if suffix == ".npz":
        edit_bundle_document(path, lambda doc: doc.update(metadata={"exposure_ms": 5}))
    else:
        edit_bundle_document(path, lambda doc: doc["system"].update(shifts=2))
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


def test_a_tiff_of_pages_appended_one_by_one_is_one_stack(tmp_path):
    import tifffile

    path = tmp_path / "appended.tif"
    for band in range(4):
        tifffile.imwrite(path, np.full((8, 8), band, np.float32), append=True)
    cube, _ = read_cube(path)
    assert cube.shape == (8, 8, 4)
    np.testing.assert_array_equal(cube[0, 0], [0, 1, 2, 3])  # not the first page alone


def test_a_matlab_v4_file_still_reads(tmp_path):
    import scipy.io

    scipy.io.savemat(tmp_path / "v4.mat", {"mask": np.eye(3)}, format="4")
    np.testing.assert_array_equal(read_array(tmp_path / "v4.mat", "mask"), np.eye(3))


def test_json_nested_past_the_parsers_stack_is_a_one_line_error(hostile):
    """A plan, frame log or bundle document of 200,000 nested brackets raised RecursionError."""
    from tensor_cosdi.io import AcquisitionPlan, read_log
    from tensor_cosdi.io.bundle import bundle_document

    deep = "the JSON is nested too deeply to be read"
    with pytest.raises(ValueError, match=f"not an acquisition plan .*{deep}"):
        AcquisitionPlan.load(hostile["plan_deep"])
    with pytest.raises(ValueError, match="line 1 is not JSON; is this a frame log"):
        read_log(hostile["log_deep"])
    for key in ("bundle_deep_npz", "bundle_deep_h5"):
        for read in (load_bundle, bundle_document):
            with pytest.raises(ValueError, match=f"bundle_deep.*the bundle's document: {deep}"):
                read(hostile[key])
    # a TIFF description is only a place wavelengths may be: one that is not JSON is ignored
    cube, wavelengths = read_cube(hostile["tiff_deep"])
    assert cube.shape == (4, 4, 3) and wavelengths is None


def test_commands_and_frame_names_longer_than_a_line_or_a_file_name_are_refused():
    from tensor_cosdi.io import AcquisitionPlan, Step

    with pytest.raises(ValueError, match="a command is at most 1024 characters, got 1000000 s"):
        AcquisitionPlan((Step({"k": 0}, ("X" * 10**6,), "f.tif"),))
    with pytest.raises(ValueError, match="a frame name is at most 255 bytes .*, got 304 s"):
        AcquisitionPlan((Step({"k": 0}, ("DMD 0",), "f" * 300 + ".tif"),))


def test_a_cube_is_asked_for_by_its_axes(tmp_path):
    path = tmp_path / "mask.npz"
    np.savez(path, mask=np.ones((4, 4)))
    with pytest.raises(ValueError, match=r"no candidate for a cube \(3 axes or more\) \(mask"):
        read_cube(path)
    np.testing.assert_array_equal(read_array(path), np.ones((4, 4)))
