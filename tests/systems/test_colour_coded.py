"""Colour-coded SD-CASSI: one transmittance per pixel and band, reconstructed by the same closed-
form steps, kept in bundles, and a colour code that helps on a real scene."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import codes, datasets, metrics
from tensor_cosdi.systems import SDCASSI, System


def test_closed_form_normal_solve_and_state_round_trip():
    code = codes.colour_coded_aperture((12, 10), 6, n_filters=3, transmittance=0.5, rng=1)
    sd = SDCASSI(code, n_bands=6, shifts=1, colour=True)
    op = sd.operator
    b = np.random.default_rng(0).random(sd.cube_shape)
    x = op.solve_normal(b, 0.3)
    r = op.adjoint(op.forward(x)) + 0.3 * x - b
    assert np.linalg.norm(r) < 1e-10 * np.linalg.norm(b)
    again = System.from_state(sd.to_state())
    assert again.colour and np.array_equal(again.forward(b), sd.forward(b))
    assert "colour" not in SDCASSI(code[..., 0], n_bands=6).to_state()["params"]  # old states


def test_colour_code_beats_the_binary_code_on_a_real_crop():
    try:
        cube = datasets.load_hsi("face", np.linspace(450, 650, 16), shape=(64, 64))[0]
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")
    binary = codes.random_binary((64, 64), transmittance=0.5, rng=0)
    colour = codes.colour_coded_aperture((64, 64), 16, n_filters=6, transmittance=0.5, rng=0)
    psnr = {}
    for name, code, c in (("binary", binary, False), ("colour", colour, True)):
        sd = SDCASSI(code, n_bands=16, shifts=1, colour=c)
        g = sd.simulate(cube, snr_db=30, rng=0)
        est = tc.reconstruct(sd, g, "otd").cube
        psnr[name] = metrics.psnr(cube, np.asarray(est), data_range=1.0)
        lsq = tc.reconstruct(sd, g, "lsq").cube
        assert psnr[name] > metrics.psnr(cube, np.asarray(lsq), data_range=1.0) + 3, name
    assert psnr["colour"] > psnr["binary"], psnr  # 34.84 against 33.45 dB


def test_cs2li_example_problem_takes_a_binary_code():
    """``n_filters=1``: the same seeded problem through a binary code (one 2-D code for every
    band); the default keeps the colour code."""
    kw = dict(shape=(8, 8), n_bands=4, snr_db=None, rng=0)
    colour = tc.studies.make_problem("cs2li", "colorchecker", **kw)
    binary = tc.studies.make_problem("cs2li", "colorchecker", n_filters=1, **kw)
    assert colour.system.code.ndim == 3 and binary.system.code.ndim == 2
    np.testing.assert_array_equal(binary.cube, colour.cube)  # same scene and fringes
    assert set(np.unique(binary.system.code)) <= {0.0, 1.0}
    assert binary.system.otd_lam_anchors is None and colour.system.otd_lam_anchors is not None
