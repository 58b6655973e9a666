"""The non-local Tucker prior: block matching, group shrinkage, the method on a real crop."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.solvers.nonlocal_prior import NonlocalTucker, block_match, group_low_rank


def test_block_match_finds_an_exact_copy_and_puts_the_reference_first():
    rng = np.random.default_rng(0)
    guide = rng.random((32, 32, 2)).astype(np.float32)
    guide[12:18, 16:22] = guide[4:10, 4:10]  # a copy of the reference patch at (4, 4)
    rows, cols = block_match(guide, patch=6, stride=4, window=12, step=2, group=4)
    ref = np.flatnonzero((rows[:, 0] == 4) & (cols[:, 0] == 4))
    assert ref.size == 1
    assert (rows[ref[0], 1], cols[ref[0], 1]) == (12, 16)  # the copy: distance 0, next after itself
    # every group starts with its own reference, which lies on the stride-4 grid (plus the last row)
    assert set(np.unique(rows[:, 0])) == {0, 4, 8, 12, 16, 20, 24, 26}
    # members are valid patch corners
    assert rows.min() >= 0 and rows.max() <= 26 and cols.min() >= 0 and cols.max() <= 26


def test_group_low_rank_is_singular_value_soft_thresholding():
    rng = np.random.default_rng(1)
    groups = rng.standard_normal((5, 6, 40))
    tau = 3.0
    got = group_low_rank(groups, tau)
    for g, out in zip(groups, got):
        u, s, vt = np.linalg.svd(g, full_matrices=False)
        np.testing.assert_allclose(out, (u * np.maximum(s - tau, 0)) @ vt, atol=1e-9)


def test_prox_keeps_a_spectrally_low_rank_repetitive_cube_and_removes_noise():
    rng = np.random.default_rng(2)
    base = rng.random((8, 8, 3))
    spatial = np.tile(base, (5, 5, 1))  # 40 × 40, every 8 × 8 block repeats
    spectra = rng.random((3, 16))
    clean = spatial @ spectra  # rank 3 along the bands
    noisy = clean + 0.05 * rng.standard_normal(clean.shape)
    # σ is relative to the peak (≈ 2.5 here): 0.05 · 2.5 ≈ 2.5× the true noise, so c = 0.5
    prior = NonlocalTucker(
        sigma=0.05,
        sigma_end=0.05,
        rank=3,
        patch=6,
        stride=3,
        window=8,
        step=1,
        group=8,
        c=0.5,
        n_steps=1,
    )
    prior.setup(noisy, penalty=1.0, gain=1.0)
    out = prior.prox(noisy)
    err = lambda x: np.linalg.norm(x - clean) / np.linalg.norm(clean)  # noqa: E731
    assert err(out) < 0.5 * err(noisy)  # measured: 0.021 vs 0.065


def test_otd_nl_options_are_checked():
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=6)
    with pytest.raises(ValueError, match="warm must be one of"):
        tc.reconstruct(p.system, p.measurement, "otd_nl", warm="bm3d")
    with pytest.raises(ValueError, match="patch 20 is larger"):
        tc.reconstruct(p.system, p.measurement, "otd_nl", patch=20)
