"""CASSDI-DFA's focal sweep (5-D PSFs; its explicit matrix is checked in test_matrix.py): the
loop of its definition, the thesis' per-plane model as its diagonal, the sweep PSFs, state and
errors."""

import numpy as np
import pytest

from tensor_cosdi import optics
from tensor_cosdi.systems import CASSDIDFA, System


def test_sweep_is_the_loop_of_its_definition():
    # G[i, j + l] = Σ_k Σ_l C[i, j, k] Σ_z (F[:, :, l, z] ⊛ h[l, z, k])[i, j], integer shifts
    g = np.random.default_rng(3)
    nx, ny, nl, nz, steps = 5, 6, 3, 2, 3
    code = g.random((nx, ny, steps))
    h = g.random((3, 3, nl, nz, steps))
    f = g.random((nx, ny, nl, nz))
    want = np.zeros((nx, ny + nl - 1))
    pad = np.pad(f, ((1, 1), (1, 1), (0, 0), (0, 0)))
    for k in range(steps):
        for l in range(nl):
            img = np.zeros((nx, ny))
            for z in range(nz):
                for a in range(3):
                    for b in range(3):  # y[i, j] = Σ h[a, b] x[i − a + 1, j − b + 1]
                        img += h[a, b, l, z, k] * pad[2 - a : 2 - a + nx, 2 - b : 2 - b + ny, l, z]
            want[:, l : l + ny] += code[:, :, k] * img
    system = CASSDIDFA(code, n_bands=nl, shifts=1, psfs=h)
    np.testing.assert_allclose(system.forward(f), want, atol=1e-12)


def test_the_per_plane_model_is_the_sweeps_diagonal():
    """Plane z seen only at step z (the 4-D model) = a sweep whose off-diagonal PSFs carry a
    vanishing weight."""
    g = np.random.default_rng(4)
    code, f = g.random((6, 7, 3)), g.random((6, 7, 4, 3))
    h4 = g.random((3, 3, 4, 3))
    h5 = np.full((3, 3, 4, 3, 3), 1e-300)
    for z in range(3):
        h5[..., z, z] = h4[..., z]
    per_plane = CASSDIDFA(code, n_bands=4, psfs=h4).forward(f)
    np.testing.assert_allclose(CASSDIDFA(code, n_bands=4, psfs=h5).forward(f), per_plane)


def test_sweep_psfs_are_sharpest_where_the_step_focuses_on_the_plane():
    lens = optics.Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
    depths = [800.0, 1000.0, 1300.0]
    p = optics.sweep_psf_stack([500, 600], depths, depths, lens=lens, size=41)
    assert p.shape == (41, 41, 2, 3, 3)
    np.testing.assert_allclose(p.sum(axis=(0, 1)), 1)
    peak = p[20, 20]  # (band, plane, step)
    for z in range(3):
        assert np.argmax(peak[:, z, :], axis=1).tolist() == [z, z]
    # at its own step every plane is in focus: the same PSF whatever the depth
    np.testing.assert_allclose(p[..., 0, 0], p[..., 2, 2], atol=1e-12)
    with pytest.raises(ValueError, match="non-empty 1-D"):
        optics.sweep_psf_stack([500], [], depths)


def test_sweep_state_and_errors():
    g = np.random.default_rng(5)
    sweep = CASSDIDFA(g.random((4, 4, 2)), n_bands=3, psfs=g.random((3, 3, 3, 4, 2)))
    back = System.from_state(sweep.to_state())
    f = g.random(sweep.cube_shape)
    np.testing.assert_array_equal(back.forward(f), sweep.forward(f))
    assert back.sweep and back.n_depths == 4
    with pytest.raises(ValueError, match="K = 2 focal steps"):
        CASSDIDFA(g.random((4, 4, 2)), n_bands=3, psfs=g.random((3, 3, 3, 4, 3)))
    with pytest.raises(ValueError, match=r"Nλ in \(1, 3\)"):
        CASSDIDFA(g.random((4, 4, 2)), n_bands=3, psfs=g.random((3, 3, 2, 4, 2)))
    with pytest.raises(ValueError, match="≥ 0"):
        CASSDIDFA(g.random((4, 4, 2)), n_bands=3, psfs=-g.random((3, 3, 3, 4, 2)))
