"""The depth-plane prior (one plane per pixel) for CASSDI-DFA inside GAP-TV and OTD."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.solvers.priors import TV, PlaneSupport


@pytest.fixture(scope="module")
def dfa():
    return tc.studies.make_problem("cassdi_dfa", "coffee", shape=(48, 48), n_bands=6, snr_db=30,
                                   rng=0)  # fmt: skip


@pytest.mark.parametrize("method", ["gap_tv", "otd"])
def test_plane_support_lifts_ssim_and_psnr_on_dfa(dfa, method):
    on = tc.reconstruct(dfa.system, dfa.measurement, method)
    off = tc.reconstruct(dfa.system, dfa.measurement, method, plane_support=False)
    s_on, s_off = tc.studies.score(dfa, on.cube), tc.studies.score(dfa, off.cube)
    assert s_on["ssim"] > s_off["ssim"] + 0.15, (s_on, s_off)
    assert s_on["psnr"] > s_off["psnr"], (s_on, s_off)
    cube = np.asarray(on.cube)
    occupied = (np.abs(cube).sum(axis=2) > 0).sum(axis=2)
    assert occupied.max() == 1  # one plane per pixel


def test_plane_support_projection_and_errors():
    rng = np.random.default_rng(0)
    x = rng.random((4, 5, 3, 2))
    prior = PlaneSupport(TV(1e-9), axis=3, start_at=0)
    prior.setup(x, penalty=1.0, gain=1.0)
    z = prior.prox(x)
    energy = (x**2).sum(axis=2)
    keep = energy.argmax(axis=2)
    for i in range(4):
        for j in range(5):
            k = keep[i, j]
            assert np.allclose(z[i, j, :, 1 - k], 0) and np.allclose(z[i, j, :, k], x[i, j, :, k],
                                                                      atol=1e-6)  # fmt: skip
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, rng=0)
    with pytest.raises(ValueError, match="needs a system with depth planes"):
        tc.reconstruct(p.system, p.measurement, "gap_tv", plane_support=5)
    with pytest.raises(ValueError, match="plane_support must be"):
        tc.reconstruct(p.system, p.measurement, "gap_tv", plane_support="yes")
