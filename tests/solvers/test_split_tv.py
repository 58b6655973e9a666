"""split_tv: ADMM-TV for CASSDI-DFA with PSFs, the blur split off (every step closed form)."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import codes, metrics, optics, scenes
from tensor_cosdi.systems import CASSDIDFA


def problem(n=32, nl=6, size=15, snr=30):
    wl = scenes.default_wavelengths(nl)
    lens = optics.Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
    psfs = optics.psf_stack(
        wl, [800.0, 1300.0], lens=lens, zernike={6: 0.25}, size=size, min_share=None
    )
    planes = scenes.depth_planes(scenes.motorcycle((n, n), [550.0])[1], 2)
    cube = scenes.depth_layers(scenes.photo("chelsea", (n, n), wl), planes, 2)
    system = CASSDIDFA(codes.depth_codes((n, n), 2, rng=0), n_bands=nl, psfs=psfs, wavelengths=wl)
    return system, cube, system.simulate(cube, snr_db=snr, rng=0)


def test_split_tv_beats_least_squares_on_a_blurred_coded_scene():
    system, cube, g = problem()
    with pytest.warns(tc.solvers.SlowSolveWarning, match="methods without such solves"):
        lsq = tc.reconstruct(system, g, "lsq").cube  # the slow solve it warns of
    psnr = {
        m: metrics.psnr(cube, np.asarray(x), data_range=1.0)
        for m, x in (("lsq", lsq), ("split_tv", tc.reconstruct(system, g, "split_tv").cube))
    }
    assert psnr["split_tv"] > psnr["lsq"] + 1.5, psnr  # prints 23.9 vs 21.9


def test_the_padded_circular_blur_is_the_systems_blur():
    """Zero-pad at the top-left, convolve circularly on the padded grid, crop at the PSF's
    centre: the system's zero-boundary blur, to rounding; and ``conv(·, adjoint=True)`` is its
    transpose."""
    from tensor_cosdi.operators import Blur
    from tensor_cosdi.solvers.split_blur import padded_blur

    g = np.random.default_rng(1)
    psfs, f = g.random((5, 3, 4, 2)), g.random((9, 11, 4, 2))
    conv, pad, (c0, c1), power = padded_blur(psfs, (9, 11), f)
    e = np.zeros(pad + (4, 2))
    e[:9, :11] = f
    np.testing.assert_allclose(conv(e)[c0 : c0 + 9, c1 : c1 + 11], Blur(f.shape, psfs).forward(f))
    a, b = g.random(pad + (4, 2)), g.random(pad + (4, 2))
    assert np.vdot(conv(a), b) == pytest.approx(np.vdot(a, conv(b, adjoint=True)), rel=1e-12)
    assert power.shape == (pad[0], pad[1] // 2 + 1, 4, 2)


def test_split_tv_does_not_depend_on_the_measurement_units():
    system, _, g = problem(n=16, nl=4, size=9)
    g = np.asarray(g)
    ref = np.asarray(tc.reconstruct(system, g, "split_tv", max_iter=10).cube)
    for scale in (1e-300, 1e-5, 1e300):
        cube = np.asarray(tc.reconstruct(system, g * scale, "split_tv", max_iter=10).cube)
        assert np.isfinite(cube).all()
        assert np.linalg.norm(cube / scale - ref) < 1e-6 * np.linalg.norm(ref), scale


def test_split_tv_refuses_what_it_cannot_split():
    sd = tc.systems.SDCASSI.example()
    with pytest.raises(ValueError, match="'split_tv' reconstructs cassdi_dfa systems, got SDCASSI"):
        tc.reconstruct(sd, sd.forward(np.ones(sd.cube_shape)), "split_tv")
    plain = CASSDIDFA.example()
    with pytest.raises(ValueError, match="without PSFs use 'gap_tv' or 'otd'"):
        tc.reconstruct(plain, plain.forward(np.ones(plain.cube_shape)), "split_tv")
    g = np.random.default_rng(0)
    sweep = CASSDIDFA(g.random((8, 8, 2)), n_bands=2, psfs=g.random((3, 3, 2, 2, 2)))
    with pytest.raises(ValueError, match="with a focal sweep"):
        tc.reconstruct(sweep, sweep.forward(np.ones(sweep.cube_shape)), "split_tv")


def test_methods_that_would_solve_by_cg_warn_and_name_the_closed_form():
    system, _, g = problem(n=16, nl=3, size=7)
    with pytest.warns(tc.solvers.SlowSolveWarning, match="'lsq' solves it by conjugate gradients"
                      ".*methods without such solves: .*split_tv"):  # fmt: skip
        tc.reconstruct(system, g, "lsq")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", tc.solvers.SlowSolveWarning)
        tc.reconstruct(system, g, "split_tv", max_iter=2)
