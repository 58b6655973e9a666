"""Inconsistent parameters are clear errors at construction, naming what was wrong."""

import numpy as np
import pytest

from tensor_cosdi import codes
from tensor_cosdi.studies import make_problem
from tensor_cosdi.systems import (
    C3SLFI,
    CASSDIDFA,
    CASSIVSI,
    CS2LI,
    DDCASSI,
    SDCASSI,
    DualCameraCASSI,
    MuCoSDI,
)

ones = np.ones

CASES = [
    # codes: shape, values
    (lambda: SDCASSI(ones(5), n_bands=3), r"code must have 2 or 3 axes, got shape \(5,\)"),
    (lambda: SDCASSI(-ones((4, 5)), n_bands=3), "transmittances and must be ≥ 0"),
    (lambda: SDCASSI(np.full((4, 5), np.nan), n_bands=3), "NaN"),
    (lambda: SDCASSI(np.array([["a"]]), n_bands=3), "real array"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=0), "n_bands must be an integer ≥ 1"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=2.5), "n_bands must be an integer"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, wavelengths=[500, 600]), "expected 3 wavelengths"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, wavelengths=[600, 500, 550]), "strictly increasing"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=2, wavelengths=[0, 500]), "must be nanometres in 200"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=2, wavelengths=[0.5, 0.6]), "look like micrometres"),
    # shifts
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, shifts=[0, 2, 1]), "monotone"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, shifts=[0, 1]), "expected 3 per-band shifts"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, shifts=-1), "≥ 0"),
    (lambda: DDCASSI(ones((4, 5)), n_bands=4, shifts=2), r"shifts do not fit.*Ny \+ 6"),
    (lambda: CS2LI(ones((4, 3)), n_bands=3, n_patterns=2, shifts=[0, 1, 3]), "shifts do not fit"),
    (lambda: MuCoSDI(ones((4, 4)), n_bands=5, n_patterns=2), "shifts do not fit"),
    # CASSI-VSI
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, alpha_t=1.2), "alpha_t must be .* ≥ 0 and ≤ 1"),
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, alpha_t=-0.1), "alpha_t must be .* ≥ 0 and ≤ 1"),
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, alpha_t="much"), "alpha_t must be a finite number"),
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, alpha_t="0.5"), "alpha_t must be a finite number"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=2**40), "n_bands must be an integer ≥ 1 and ≤ 10000"),
    (lambda: SDCASSI(ones((4, 5)), n_bands=3, shifts=1e15), "shifts the last band by 2e\\+15 px"),
    (
        lambda: CASSIVSI(ones((4, 5)), n_bands=3, beta=3),
        r"beta must be an integer column offset in \[0, 2\]",
    ),
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, beta=-1), "beta must be"),
    (lambda: CASSIVSI(ones((4, 5)), n_bands=3, beta=1.5), "beta must be"),
    (lambda: CASSIVSI(ones((4, 5, 2)), n_bands=3), "code must have 2 axes"),
    # CASSDI-DFA
    (lambda: CASSDIDFA(ones((4, 5)), n_bands=3), r"codes must have 3 axes, got shape \(4, 5\)"),
    (
        lambda: CASSDIDFA(ones((4, 5, 2)), n_bands=3, psfs=ones((3, 3, 2, 2))),
        r"psfs shape \(3, 3, 2, 2\) does not match the cube: expected \(h, w, 3, 2\)",
    ),
    (
        lambda: CASSDIDFA(ones((4, 5, 2)), n_bands=3, psfs=ones((3, 3, 3))),
        r"psfs must have shape \(h, w\)",
    ),
    (lambda: CASSDIDFA(ones((4, 5, 2)), n_bands=3, psfs=-ones((3, 3))), "intensities"),
    (lambda: CASSDIDFA(ones((4, 5, 2)), n_bands=3, psfs=np.zeros((3, 3))), "positive sum"),
    # C3SLFI
    (lambda: C3SLFI(ones((4, 4, 5, 2)) / 2, layout="4d"), r"layout must be one of \('3d', '5d'\)"),
    (lambda: C3SLFI(ones((4, 4, 5, 2)) / 2, raw_layout="zigzag"), "raw_layout must be one of"),
    (lambda: C3SLFI(ones((4, 4, 5, 2)) / 2, layout="5d"), r"codes must have 6 axes"),
    (lambda: C3SLFI(ones((4, 4, 5, 2)) / 2, views=(3, 2)), "do not divide the 3-D image"),
    (lambda: C3SLFI(ones((4, 4, 5, 2)) / 2, views=(2,)), "views must be a pair"),
    (lambda: C3SLFI(ones((2, 2, 5, 2, 2, 2)) / 2, layout="5d", views=(3, 3)), "contradicts"),
    (lambda: C3SLFI(ones((4, 4, 5, 1))), "needs K ≥ 2"),
    (lambda: C3SLFI(ones((4, 4, 5, 3)) / 2), "not complementary"),
    (lambda: C3SLFI.separable(ones((2, 4)) / 2, (4, 4, 5)), r"needs \(K, N3\) with N3 = 5"),
    (lambda: C3SLFI.separable(ones((2, 5)) / 2, (4, 4)), "3 or 5 positive sizes"),
    # CS2LI / Mu-CoSDI
    (lambda: CS2LI(ones((4, 7, 2)), n_bands=3, n_patterns=2), "has 2 bands, expected n_bands = 3"),
    (lambda: CS2LI(ones((4, 7)), n_bands=3, n_patterns=0), "n_patterns must be an integer ≥ 1"),
    (
        lambda: make_problem("cs2li", "colorchecker", shape=(8, 8), n_bands=3, n_filters=0),
        "n_filters must be an integer ≥ 1, got 0",
    ),
    (lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="stereo"), "modality must be one of"),
    (
        lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="sl"),
        r"needs the option\(s\) \['n_patterns'\]",
    ),
    (
        lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="lf", n_patterns=3),
        r"unknown option.*valid: \['raw_layout', 'views'\]",
    ),
    (
        lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="lf", views=(3, 2)),
        "do not divide the lenslet image",
    ),
    (
        lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="lf", views=(2, 0)),
        "views must be an integer ≥ 1",
    ),
    (lambda: MuCoSDI(ones((4, 7)), n_bands=3, modality="monocular", depth_estimator=3), "callable"),
    (lambda: DualCameraCASSI(ones((4, 5, 2)), n_bands=3), "code must have 2 axes"),
    # code generators
    (
        lambda: codes.random_binary((4, 5), transmittance=0),
        r"transmittance must be a finite number > 0 and ≤ 1",
    ),
    (lambda: codes.random_binary((4, -5)), "positive integers"),
    (lambda: codes.complementary_colour_codes((4, 4, 5), 1), "n_snapshots must be an integer ≥ 2"),
    (lambda: codes.complementary_colour_codes((4, 4, 3), 4), "n_snapshots ≤ n_filters ≤ n_bands"),
    (
        lambda: codes.complementary_colour_codes((4, 4, 3), 2, band_axis=3),
        "band_axis must be an integer in -3…2",
    ),
    (lambda: codes.colour_coded_aperture((4, 5), 6, n_filters=7), "cannot exceed n_bands"),
    (lambda: codes.colour_coded_aperture((4, 5), 6, transmittance=1.5), "transmittance"),
]


@pytest.mark.parametrize("build, message", CASES, ids=[f"case{i}" for i in range(len(CASES))])
def test_constructor_errors(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_shape_errors_name_both_shapes():
    sd = SDCASSI.example((4, 5, 3))
    with pytest.raises(
        ValueError,
        match=r"SDCASSI.forward: .*cube of shape \(4, 5, 3\) \(axes x, y, λ\).*\(4, 5, 4\)",
    ):
        sd.forward(np.zeros((4, 5, 4)))
    with pytest.raises(
        ValueError, match=r"SDCASSI.adjoint: .*measurement of shape \(4, 7\).*\(4, 5\)"
    ):
        sd.adjoint(np.zeros((4, 5)))
    with pytest.raises(ValueError, match=r"CS2LI.panchromatic: .*\(axes x, y, t\)"):
        CS2LI.example().panchromatic(np.zeros((16, 16)))
    with pytest.raises(ValueError, match="SDCASSI.solve_normal"):
        sd.solve_normal(np.zeros((4, 7)), 1.0)


def test_monocular_depth_estimator():
    mono = MuCoSDI.example(
        (4, 5, 3), modality="monocular", depth_estimator=lambda cube: cube.sum(2)
    )
    cube = np.ones(mono.cube_shape)
    np.testing.assert_array_equal(mono.estimate_depth(cube), np.full((4, 5), 3.0))
    with pytest.raises(ValueError, match="no depth_estimator"):
        MuCoSDI.example((4, 5, 3), modality="monocular").estimate_depth(cube)
    with pytest.raises(ValueError, match="tensor_cosdi.depth"):
        MuCoSDI.example().estimate_depth(cube)
    with pytest.raises(ValueError, match="only for modality 'lf'"):
        MuCoSDI.example().to_views(cube)


def test_lenslet_views_round_trip():
    lf = MuCoSDI.example((6, 8, 3), modality="lf", views=(3, 2))
    L = np.random.default_rng(0).standard_normal((2, 4, 3, 3, 2))
    cube = lf.from_views(L)
    assert cube.shape == lf.cube_shape
    np.testing.assert_array_equal(lf.to_views(cube), L)
    assert cube[4, 5, 1] == L[4 // 3, 5 // 2, 1, 4 % 3, 5 % 2]  # interleaved, Eq. 85


def test_colour_coded_sdcassi_errors_name_the_expected_shape():
    with pytest.raises(ValueError, match=r"has 4 bands, expected n_bands = 3 \(shape \(Nx, Ny, 3"):
        SDCASSI(np.ones((4, 5, 4)), n_bands=3, colour=True)
    with pytest.raises(ValueError, match="colour-coded aperture must have 3 or 4 axes"):
        SDCASSI(np.ones((4, 5)), n_bands=3, colour=True)
    with pytest.raises(ValueError, match="colour must be True or False"):
        SDCASSI(np.ones((4, 5)), n_bands=3, colour="yes")
