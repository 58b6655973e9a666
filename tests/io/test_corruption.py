"""Damaged files and bad arguments get one clear error naming them, never a wrong result
(the cases `benchmarks/robustness.py` found obscure or silent, pinned)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tensor_cosdi as tc
from tensor_cosdi import noise, studies
from tensor_cosdi.io import load_bundle, save_bundle
from tensor_cosdi.io.files import read_array, read_cube, write_cube

CUBE = np.random.default_rng(1).random((12, 10, 5)).astype(np.float32)
WL = np.linspace(450.0, 650.0, 5)


@pytest.mark.parametrize("suffix", [".h5", ".npz", ".mat", ".tif", ".npy"])
@pytest.mark.parametrize("cut", [0.0, 0.1, 0.5, 0.9])
def test_truncated_files_are_one_clear_error(tmp_path, suffix, cut):
    good = write_cube(tmp_path / f"c{suffix}", CUBE, None if suffix == ".npy" else WL)
    raw = good.read_bytes()
    bad = tmp_path / f"bad{suffix}"
    bad.write_bytes(raw[: int(cut * len(raw))])
    for reader in (read_array, read_cube):
        try:
            out = reader(bad)
        except ValueError as exc:
            assert str(bad) in str(exc)
        else:  # a cut that spared the data must give the data, nothing else
            got = out[0] if isinstance(out, tuple) else out
            np.testing.assert_array_equal(got, CUBE)


def test_a_truncated_tiff_is_not_read_as_fewer_pages(tmp_path):
    good = write_cube(tmp_path / "c.tif", CUBE, WL)
    raw = good.read_bytes()
    bad = tmp_path / "bad.tif"
    bad.write_bytes(raw[: 9 * len(raw) // 10])
    with pytest.raises(ValueError, match="bad.tif"):
        read_array(bad)


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bundle")
    p = studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4)
    cube = np.asarray(p.cube, dtype=np.float32)
    path = save_bundle(folder / "b.h5", system=p.system, cube=cube, measurement=p.measurement)
    return path.read_bytes(), cube, np.asarray(p.measurement)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_a_bit_flip_in_an_hdf5_bundle_is_caught_or_harmless(tmp_path, bundle, data):
    raw, cube, g = bundle
    pos = data.draw(st.integers(0, len(raw) - 1))
    bit = data.draw(st.integers(0, 7))
    flipped = bytearray(raw)
    flipped[pos] ^= 1 << bit
    path = tmp_path / f"flip_{pos}_{bit}.h5"
    path.write_bytes(bytes(flipped))
    try:
        b = load_bundle(path)
    except ValueError as exc:
        assert str(path) in str(exc)
    else:
        np.testing.assert_array_equal(b.cube, cube)
        np.testing.assert_array_equal(np.asarray(b.measurement), g)


@pytest.mark.parametrize(
    "kw, word",
    [
        ({"shape": (16,)}, "shape"),
        ({"shape": (16, 16, 16)}, "shape"),
        ({"shape": "16x16"}, "shape"),
        ({"shape": (16.5, 16)}, "shape"),
        ({"snr_db": "30"}, "snr_db"),
        ({"snr_db": True}, "snr_db"),
        ({"shifts": "1"}, "shifts"),
        ({"shifts": True}, "shifts"),
    ],
)
def test_make_problem_arguments(kw, word):
    with pytest.raises(ValueError, match=word):
        studies.make_problem("sd_cassi", "colorchecker", **{"shape": (16, 16), "n_bands": 4, **kw})


def test_valid_edge_arguments_still_work():
    p = studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4, snr_db=-5.0)
    assert np.isfinite(np.asarray(p.measurement)).all()  # noise stronger than the signal is fine
    s = tc.systems.SDCASSI(np.ones((8, 8)), n_bands=4, shifts=1.5)  # fractional: interpolated
    assert s.measurement_shape == (8, 13)


def test_add_noise_arguments():
    x = np.ones((8, 8))
    with pytest.raises(ValueError, match="snr_db"):
        noise.add_noise(x, "30", rng=0)
    with pytest.raises(ValueError, match="NaN or inf"):
        noise.add_noise(np.full((8, 8), np.nan), 30.0, rng=0)
    assert noise.add_noise(x, None) is x  # documented: no noise


@pytest.fixture(scope="module")
def small_problem():
    p = studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4)
    return p.system, p.measurement


@pytest.mark.parametrize(
    "method, kw, word",
    [
        ("gap_tv", {"progress": None}, "progress must be True or False, got None"),
        ("otd", {"nonneg": None}, "nonneg must be True or False, got None"),
        # the guard is accelerated GAP's; on the ADMM splitting it is unused, yet still checked
        ("pnp_gap", {"denoiser": "tv", "splitting": "admm", "guard": 0.5}, "guard must be"),
        ("pnp_gap", {"denoiser": "tv", "splitting": "gap", "guard": True}, "guard must be"),
        ("wdct", {"wavelet_name": 3}, "wavelet must be a PyWavelets name"),
        ("wdct", {"wavelet_name": float("nan")}, "wavelet must be a PyWavelets name"),
    ],
)
def test_a_flag_given_none_a_guard_unused_and_a_wavelet_that_is_no_name(
    small_problem, method, kw, word
):
    system, g = small_problem
    with pytest.raises(ValueError, match=word):
        tc.reconstruct(system, g, method, **kw)


def test_a_guard_of_none_and_a_wavelet_in_capitals_still_work(small_problem):
    system, g = small_problem
    tc.reconstruct(system, g, "pnp_gap", denoiser="tv", splitting="admm", guard=None, max_iter=2)
    assert tc.solvers.engine.check_guard(np.int64(3)) == 3.0  # a NumPy integer is a ratio too
    a = tc.reconstruct(system, g, "wdct", wavelet_name="SYM4", max_iter=3).cube  # PyWavelets' case
    b = tc.reconstruct(system, g, "wdct", wavelet_name="sym4", max_iter=3).cube
    np.testing.assert_array_equal(a, b)
