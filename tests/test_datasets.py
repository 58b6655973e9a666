"""Real hyperspectral scenes: loading, resampling onto the KAIST bands, the fixed split, errors."""

import numpy as np
import pytest

from tensor_cosdi import datasets


def _scene(tmp_path, name="s.npz"):
    rng = np.random.default_rng(0)
    cube = rng.integers(0, 65535, size=(20, 30, 31), dtype=np.uint16)
    wl = np.arange(400, 701, 10, dtype=np.float32)
    np.savez_compressed(tmp_path / name, cube=cube, wavelengths_nm=wl)
    return cube, wl, tmp_path / name


def test_load_resamples_linearly_and_scales_to_reflectance(tmp_path):
    raw, wl, path = _scene(tmp_path)
    cube, got = datasets.load_hsi(path)
    np.testing.assert_allclose(cube, raw / 65535.0)
    np.testing.assert_array_equal(got, wl)
    k, kw = datasets.load_hsi(path, "kaist")
    assert k.shape == (20, 30, 28) and np.array_equal(kw, datasets.KAIST_WAVELENGTHS)
    # 453.3 nm lies between 450 and 460: linear interpolation of those two bands
    t = (453.3 - 450.0) / 10.0
    np.testing.assert_allclose(
        k[..., 0], (1 - t) * raw[..., 5] / 65535 + t * raw[..., 6] / 65535, rtol=1e-12
    )
    crop, _ = datasets.load_hsi(path, [500.0], shape=(10, 10))
    np.testing.assert_allclose(crop[..., 0], raw[5:15, 10:20, 10] / 65535.0)


def test_errors_name_what_was_wrong(tmp_path):
    _, _, path = _scene(tmp_path)
    with pytest.raises(ValueError, match="lie outside the scene's 400–700 nm"):
        datasets.load_hsi(path, [350.0, 500.0])
    with pytest.raises(ValueError, match="larger than the scene's"):
        datasets.load_hsi(path, shape=(64, 64))
    with pytest.raises(ValueError, match="unknown scene 'lena'"):
        datasets.load_hsi("lena")
    np.savez(tmp_path / "bad.npz", cube=np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match="expected arrays 'cube' and 'wavelengths_nm'"):
        datasets.load_hsi(tmp_path / "bad.npz")
    with pytest.raises(FileNotFoundError, match="looked in"):
        datasets.data_dir(tmp_path / "nowhere")


def test_split_is_fixed_and_disjoint():
    assert len(datasets.KAIST_WAVELENGTHS) == 28 and np.all(np.diff(datasets.KAIST_WAVELENGTHS) > 0)
    assert set(datasets.REPORT_SCENES).isdisjoint(datasets.TUNE_SCENES)
    assert sorted(datasets.REPORT_SCENES + datasets.TUNE_SCENES) == sorted(datasets.HSI_SCENES)
    assert len(datasets.TUNE_SCENES) == 28 and len(datasets.HSI_SCENES) == 31


def test_tune_folds_partition_the_tuning_scenes_reproducibly():
    folds = datasets.tune_folds(4)
    assert [len(f) for f in folds] == [7, 7, 7, 7]
    flat = [s for f in folds for s in f]
    assert sorted(flat) == sorted(datasets.TUNE_SCENES) and len(set(flat)) == 28
    assert datasets.tune_folds(4) == folds and datasets.tune_folds(4, seed=1) != folds
    assert not set(flat) & set(datasets.REPORT_SCENES)
    for bad in (1, 29, True, 2.0):
        with pytest.raises(ValueError, match="k must be an integer"):
            datasets.tune_folds(bad)
    with pytest.raises(ValueError, match="seed"):
        datasets.tune_folds(4, seed=-1)


def test_every_listed_scene_is_in_the_data_folder():
    try:
        folder = datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("../shared/data/hsi_train not present (set TENSOR_COSDI_DATA)")
    assert sorted(p.stem for p in folder.glob("*.npz")) == sorted(datasets.HSI_SCENES)


def test_real_scene_when_the_data_is_present():
    try:
        datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("../shared/data/hsi_train not present (set TENSOR_COSDI_DATA)")
    cube, wl = datasets.load_hsi("balloons", "kaist")
    assert cube.shape == (256, 256, 28) and 0 <= cube.min() and cube.max() <= 1
    assert cube.std(axis=(0, 1)).min() > 0.01  # no band is flat


def test_cave_scenes_reach_every_imager_through_make_problem(tmp_path, monkeypatch):
    # the registry names every hsi_train scene as "cave.<name>"; a folder of our own stands in
    import tensor_cosdi as tc

    assert {f"cave.{n}" for n in datasets.HSI_SCENES} <= set(tc.scenes.SCENES)
    raw, wl, _ = _scene(tmp_path, "face.npz")
    monkeypatch.setenv("TENSOR_COSDI_DATA", str(tmp_path))
    p = tc.studies.make_problem("sd_cassi", "cave.face", shape=(16, 24), n_bands=6, snr_db=None)
    r0, c0 = (20 - 16) // 2, (30 - 24) // 2
    band0 = raw[r0 : r0 + 16, c0 : c0 + 24, 5] / 65535.0  # 450 nm is the 6th band (400 + 5·10)
    np.testing.assert_allclose(np.asarray(p.cube)[..., 0], band0, rtol=1e-6)
    assert p.measurement.shape == (16, 24 + 5)
    with pytest.raises(ValueError, match="larger than the scene's"):
        tc.studies.make_problem("sd_cassi", "cave.face", shape=(32, 32))


def test_data_file_finds_research_files_and_says_where_it_looked(monkeypatch, tmp_path):
    (tmp_path / "masks").mkdir()
    (tmp_path / "masks" / "m.mat").write_bytes(b"x")
    monkeypatch.setenv("TENSOR_COSDI_DATA", str(tmp_path))
    assert datasets.data_file("masks/m.mat") == tmp_path / "masks" / "m.mat"
    with pytest.raises(FileNotFoundError, match=r"masks/nope\.mat.*looked in .*TENSOR_COSDI_DATA"):
        datasets.data_file("masks/nope.mat")


def test_an_installed_package_finds_the_data_from_its_checkout(tmp_path, monkeypatch):
    from tensor_cosdi import datasets

    site = tmp_path / "venv" / "lib" / "site-packages" / "tensor_cosdi" / "datasets.py"
    checkout = tmp_path / "work" / "repo"
    scenes = tmp_path / "work" / "shared" / "data" / "hsi_train"
    for d in (site.parent, checkout, scenes):
        d.mkdir(parents=True)
    np.savez(scenes / "toy.npz", cube=np.zeros((2, 2, 3)))
    monkeypatch.delenv("TENSOR_COSDI_DATA", raising=False)
    monkeypatch.setattr(datasets, "__file__", str(site))
    monkeypatch.chdir(checkout)
    assert datasets.data_dir() == scenes
    monkeypatch.chdir(tmp_path / "venv")  # far from any data: a clear error naming where
    with pytest.raises(FileNotFoundError, match="TENSOR_COSDI_DATA"):
        datasets.data_dir()


def _scene_file(path, cube, wavelengths=None):
    wl = np.linspace(400.0, 700.0, cube.shape[-1]) if wavelengths is None else wavelengths
    np.savez(path, cube=cube, wavelengths_nm=wl)
    return path


@pytest.mark.parametrize(
    "cube, wavelengths, match",
    [
        (np.ones((4, 4, 3), complex), None, "unsigned integers or floats, got complex128"),
        (-np.ones((4, 4, 3), np.int16), None, "unsigned integers or floats, got int16"),
        (np.ones((4, 4, 3), bool), None, "unsigned integers or floats, got bool"),
        (np.full((4, 4, 3), np.nan), None, "NaN or infinite"),
        (-np.ones((4, 4, 3)), None, "negative values"),
        (np.ones((4, 12)), None, r"\(rows, columns, bands\), got shape \(4, 12\)"),
        (np.ones((4, 4, 3)), np.array([0.4, 0.5, 0.6]), "look like micrometres"),
        (np.ones((4, 4, 3)), np.array([500.0, 450.0, 600.0]), "must increase strictly"),
        (np.ones((4, 4, 4)), np.ones((2, 2)) * 500, "must be 1-D numbers"),
        (np.ones((4, 4, 3)), np.linspace(400, 700, 4), r"does not match 4 wavelengths"),
    ],
)
def test_a_scene_file_is_checked_before_use(tmp_path, cube, wavelengths, match):
    path = _scene_file(tmp_path / "scene.npz", cube, wavelengths)
    with pytest.raises(ValueError, match=match):
        datasets.load_hsi(path)


def test_a_scene_file_is_read_bounded_and_only_from_a_regular_file(tmp_path):
    import io
    import zipfile

    bomb = tmp_path / "bomb.npz"  # a member declaring 6.7 GiB, holding a few bytes
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (30000, 30000, 1)}
    )
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("cube.npy", header.getvalue() + b"\0" * 64)
        wl = io.BytesIO()
        np.save(wl, np.array([500.0]))
        z.writestr("wavelengths_nm.npy", wl.getvalue())
    with pytest.raises(ValueError, match="above the 4.00 GiB limit"):
        datasets.load_hsi(bomb)
    (tmp_path / "folder.npz").mkdir()
    with pytest.raises(ValueError, match="not a regular file"):
        datasets.load_hsi(tmp_path / "folder.npz")
    with pytest.raises(FileNotFoundError, match="scene file not found"):
        datasets.load_hsi(tmp_path / "missing.npz")


def test_crop_and_precision_are_checked(tmp_path):
    path = _scene_file(tmp_path / "scene.npz", np.ones((8, 8, 3)))
    with pytest.raises(ValueError, match="shape rows must be an integer ≥ 1, got 2.5"):
        datasets.load_hsi(path, shape=(2.5, 3))
    with pytest.raises(ValueError, match=r"shape must be \(rows, columns\)"):
        datasets.load_hsi(path, shape=4)
    with pytest.raises(ValueError, match="dtype must be"):
        datasets.load_hsi(path, dtype="int8")
    with pytest.raises(ValueError, match="look like micrometres"):
        datasets.load_hsi(path, wavelengths=[0.5, 0.6])
    cube, wl = datasets.load_hsi(path, shape=(4, 4), dtype="float32")
    assert cube.shape == (4, 4, 3) and cube.dtype == np.float32 and wl.size == 3


def test_a_wrong_tensor_cosdi_data_is_an_error_not_a_fallback(monkeypatch, tmp_path):
    # a checkout's ../shared/data may hold the scenes; a TENSOR_COSDI_DATA set to a wrong place
    # must not be passed over for them without a word
    (tmp_path / "a_file").write_text("x")
    for wrong, state in (
        (tmp_path / "a_file", "is not a folder"),
        (tmp_path / "gone", "does not exist"),
    ):
        monkeypatch.setenv("TENSOR_COSDI_DATA", str(wrong))
        with pytest.raises(FileNotFoundError, match=f"TENSOR_COSDI_DATA={wrong} {state}"):
            datasets.data_dir()
        with pytest.raises(FileNotFoundError, match="TENSOR_COSDI_DATA"):
            datasets.data_file("masks/tsa_mask256.mat")
    monkeypatch.setenv("TENSOR_COSDI_DATA", str(tmp_path))  # a folder without scenes: only it
    with pytest.raises(FileNotFoundError, match=f"looked in {tmp_path}/hsi_train, {tmp_path} —"):
        datasets.data_dir()
