"""Mask-to-sensor registration from the capture alone (io.estimate_registration)."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import datasets
from tensor_cosdi.io import estimate_registration
from tensor_cosdi.io.calibration import shift_code


def real_problem(n=96):
    try:
        cube, wl = datasets.load_hsi("balloons", "kaist", shape=(n, n))  # a tuning scene
        mask_file = datasets.data_file("masks/tsa_mask256.mat")
    except FileNotFoundError:
        pytest.skip("research data (hsi_train, TSA mask) not found: TENSOR_COSDI_DATA")
    mask = tc.io.read_frame(mask_file, key="mask").astype(np.float64)
    return cube, wl, mask


def test_a_misregistered_real_mask_is_found_to_a_quarter_pixel_and_the_fit_improves():
    """The real TSA mask moved by seeded offsets of up to 2 px under a real scene at 30 dB: every
    offset recovered within 0.25 px; GAP-TV through the corrected system beats GAP-TV through
    the mask as filed by more than 1 dB and comes within 1 dB of GAP-TV through the true one."""
    n = 96
    cube, wl, mask = real_problem(n)
    rng = np.random.default_rng(7)
    gains = []
    for trial in range(5):
        true = rng.uniform(-2, 2, size=2)
        sensor = shift_code(mask, *true)[80 : 80 + n, 80 : 80 + n]
        g = tc.systems.SDCASSI(sensor, n_bands=28, shifts=2, wavelengths=wl).simulate(
            cube, snr_db=30, rng=trial
        )
        filed = tc.systems.SDCASSI(mask[80 : 80 + n, 80 : 80 + n], n_bands=28, shifts=2,
                                   wavelengths=wl)  # fmt: skip
        reg = estimate_registration(filed, g)
        assert abs(reg.row_offset - true[0]) <= 0.25, (trial, true, reg)
        assert abs(reg.col_offset - true[1]) <= 0.25, (trial, true, reg)
        assert reg.reliable, reg
        if trial < 2:
            fixed = reg.apply(filed)
            truth = tc.systems.SDCASSI(sensor, n_bands=28, shifts=2, wavelengths=wl)
            psnr = [
                tc.metrics.psnr(cube, tc.reconstruct(s, g, "gap_tv", max_iter=30).cube,
                                data_range=1.0)
                for s in (filed, fixed, truth)
            ]  # fmt: skip
            gains.append(psnr)
    assert all(fixed > filed + 1.0 and fixed > truth - 1.0 for filed, fixed, truth in gains)


def test_a_registered_capture_reads_zero_offset_and_a_flat_one_is_refused():
    mask = tc.codes.random_binary((40, 40), rng=1)
    sd = tc.systems.SDCASSI(mask, n_bands=6, shifts=1)
    g = sd.simulate(tc.scenes.colorchecker((40, 40), sd.wavelengths), snr_db=40, rng=0)
    reg = estimate_registration(sd, g)
    assert abs(reg.row_offset) <= 0.25 and abs(reg.col_offset) <= 0.25, reg
    assert (0, 0) in reg.grid and reg.grid[(0, 0)] == max(reg.grid.values())
    assert reg.reliable
    noise = np.random.default_rng(0).random(sd.measurement_shape)  # unrelated to the code
    assert not estimate_registration(sd, noise).reliable
    with pytest.raises(ValueError, match="no texture"):
        estimate_registration(sd, np.ones(sd.measurement_shape))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"max_offset": 0}, "max_offset must be between 1"),
        ({"max_offset": 2.5}, "max_offset must be an integer"),
        ({"max_offset": True}, "max_offset must be an integer"),
    ],
)
def test_bad_search_ranges_are_refused(kwargs, message):
    sd = tc.systems.SDCASSI(tc.codes.random_binary((16, 16), rng=0), n_bands=4, shifts=1)
    with pytest.raises(ValueError, match=message):
        estimate_registration(sd, np.random.default_rng(0).random(sd.measurement_shape), **kwargs)


def test_only_movable_single_codes_and_the_right_measurement():
    sd = tc.systems.SDCASSI(tc.codes.random_binary((16, 16), rng=0), n_bands=4, shifts=1)
    with pytest.raises(ValueError, match="measurement of shape"):
        estimate_registration(sd, np.ones((16, 16)))
    g = np.random.default_rng(0).random(sd.measurement_shape)
    g[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        estimate_registration(sd, g)
    with pytest.raises(ValueError, match="real numbers"):
        estimate_registration(sd, g.astype(str))
    vsi = tc.systems.REGISTRY["cassi_vsi"].example((16, 16, 4))
    with pytest.raises(ValueError, match="movable code"):
        estimate_registration(vsi, np.ones(vsi.measurement_shape))


def prism_shifts(wl):
    """The thesis' double Amici prism 30 mm before a 6-µm sensor, whole pixels: unevenly spaced
    (steps of 2 or 3 px over the KAIST bands)."""
    return tc.optics.DoubleAmiciPrism().shifts(wl, distance_mm=30, pixel_um=6, integer=True)


def test_a_prism_dispersion_in_either_direction_is_found_with_the_offset():
    """The real TSA mask moved by seeded offsets under a real scene at 20 dB, through a prism's
    unevenly spaced shifts, the dispersion as filed or mirrored: the search names the true
    direction and both offsets within 0.25 px, and the corrected system is the true one."""
    n = 96
    cube, wl, mask = real_problem(n)
    shifts = prism_shifts(wl)
    assert not tc.io.mirror_symmetric(shifts)
    rng = np.random.default_rng(11)
    w = (slice(80, 80 + n), slice(80, 80 + n))
    for trial, direction in enumerate((1, -1, -1, 1)):
        true = rng.uniform(-2, 2, size=2)
        truth = tc.systems.SDCASSI(shift_code(mask, *true)[w], n_bands=28, shifts=shifts,
                                   wavelengths=wl, shear_direction=direction)  # fmt: skip
        g = truth.simulate(cube, snr_db=20, rng=trial)
        filed = tc.systems.SDCASSI(mask[w], n_bands=28, shifts=shifts, wavelengths=wl)
        reg = estimate_registration(filed, g, direction="search")
        assert reg.direction == direction, (trial, reg)
        assert reg.direction_margin >= reg.MIN_DIRECTION_MARGIN and reg.reliable, reg
        assert abs(reg.row_offset - true[0]) <= 0.25 and abs(reg.col_offset - true[1]) <= 0.25
        fixed = reg.apply(filed)
        np.testing.assert_array_equal(fixed.shifts, truth.shifts)
        assert fixed.shear_direction == direction
    kept = estimate_registration(filed, g)  # "keep": the direction as filed, not searched
    assert kept.direction == 1 and kept.direction_margin is None


def test_evenly_spaced_shifts_refuse_a_direction_search_with_the_reason():
    sd = tc.systems.SDCASSI(tc.codes.random_binary((24, 24), rng=0), n_bands=6, shifts=2)
    g = sd.simulate(tc.scenes.colorchecker((24, 24), sd.wavelengths), snr_db=40, rng=0)
    with pytest.raises(ValueError, match="evenly spaced shifts"):
        estimate_registration(sd, g, direction="search")
    # …because the mirrored system measures the band-reversed cube exactly
    cube = np.random.default_rng(0).random(sd.cube_shape)
    np.testing.assert_allclose(sd.mirrored().forward(cube[:, :, ::-1]), sd.forward(cube))
    for bad in ("mirror", 1, None):
        with pytest.raises(ValueError, match="direction must be one of"):
            estimate_registration(sd, g, direction=bad)


def test_mirrored_twice_is_the_system_and_symmetry_is_tested_on_the_shift_set():
    sd = tc.systems.SDCASSI(tc.codes.random_binary((8, 8), rng=0), n_bands=4, shifts=[0, 1, 3, 6])
    once = sd.mirrored()
    assert once.shifts.tolist() == [6, 5, 3, 0] and once.shear_direction == -1
    np.testing.assert_array_equal(once.mirrored().shifts, sd.shifts)
    np.testing.assert_array_equal(once.wavelengths, sd.wavelengths)
    assert tc.io.mirror_symmetric([0, 2, 4, 6]) and tc.io.mirror_symmetric([0, 1, 5, 6])
    assert not tc.io.mirror_symmetric([0, 1, 3, 6])
    for bad in ([0, np.nan], [], "abc", [[0, 1], [2]]):
        with pytest.raises(ValueError, match="shifts must be finite numbers"):
            tc.io.mirror_symmetric(bad)
    for tol in (-0.1, np.nan, "0.1", True):
        with pytest.raises(ValueError, match="tol must be"):
            tc.io.mirror_symmetric([0, 1, 3], tol=tol)
