"""Block-diagonal learned bases: exact against their dense matrix, orthonormal, re-learned with
their blocks by OTD."""

import numpy as np
import pytest
import tensorly as tl

import tensor_cosdi as tc
from tensor_cosdi.bases import (
    BlockDense,
    KroneckerBasis,
    block_hosvd,
    block_sizes,
    is_orthonormal,
    tucker_bases,
)


def test_block_sizes_cut_near_equal_runs():
    assert block_sizes(660, 256) == [220, 220, 220]
    assert block_sizes(10, 4) == [4, 3, 3]
    assert block_sizes(5, 8) == [5]
    with pytest.raises(ValueError, match="max_block"):
        block_sizes(5, 0)


@pytest.mark.parametrize("order", ["C", "F"])
def test_block_basis_equals_its_dense_block_diagonal_matrix(order):
    x = np.random.default_rng(0).random((23, 17, 5)).astype(np.float32)
    t0, t1 = block_hosvd(x, 0, block_sizes(23, 8)), block_hosvd(x, 1, [9, 8])
    assert t0.sizes == [8, 8, 7] and is_orthonormal(t0.matrix) and is_orthonormal(t1.matrix)
    assert np.count_nonzero(t0.matrix[:8, 8:]) == 0  # block diagonal
    basis = KroneckerBasis(x.shape, {0: t0, 1: t1, 2: "dct"})
    xin = np.asarray(x, order=order)
    theta = basis.analysis(xin)
    dense = tl.tenalg.multi_mode_dot(
        x.astype(np.float64), [basis.matrices[m].T for m in range(3)], modes=[0, 1, 2]
    )
    np.testing.assert_allclose(theta, dense, atol=2e-6)
    np.testing.assert_allclose(basis.synthesis(theta), x, atol=2e-6)


def test_one_block_is_the_hosvd_basis_and_blocks_span_their_rows():
    x = np.random.default_rng(1).random((12, 10, 3))
    whole = block_hosvd(x, 0, [12]).matrix
    ref = tucker_bases(x, modes=[0])[0]
    np.testing.assert_allclose(np.abs(whole), np.abs(ref), atol=1e-8)  # up to signs
    # block k's strongest atom is the top left singular vector of that run of rows
    blk = block_hosvd(x, 0, [6, 6]).blocks[1].matrix
    u = np.linalg.svd(x[6:].reshape(6, -1))[0][:, 0]
    assert abs(abs(blk[:, 0] @ u) - 1) < 1e-8


def test_block_basis_errors():
    with pytest.raises(ValueError, match="square"):
        BlockDense([np.ones((2, 3))])
    with pytest.raises(ValueError, match="do not cut"):
        block_hosvd(np.ones((6, 4)), 0, [3, 2])
    with pytest.raises(ValueError, match="NaN"):
        block_hosvd(np.full((6, 4), np.nan), 0, [3, 3])


def test_otd_with_spatial_blocks_keeps_and_relearns_its_blocks(monkeypatch):
    from tensor_cosdi.solvers import priors

    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(40, 40), n_bands=8, snr_db=30)
    seen = []
    update = priors.TuckerDictionary.update

    def spy(self, x, it):
        update(self, x, it)
        seen.append({m: type(t).__name__ for m, t in self.basis.transforms.items()})

    monkeypatch.setattr(priors.TuckerDictionary, "update", spy)
    res = tc.reconstruct(p.system, p.measurement, "otd", spatial_block=16, max_iter=21)
    assert seen and all(s[0] == s[1] == "BlockDense" for s in seen)
    ref = tc.reconstruct(p.system, p.measurement, "otd", max_iter=21)
    q, qref = (tc.metrics.psnr(p.cube, r.cube) for r in (res, ref))
    assert q > qref - 2.0 and q > 20.0, (q, qref)
    with pytest.raises(ValueError, match="spatial_block"):
        tc.reconstruct(p.system, p.measurement, "otd", spatial_block=1)


def test_hosvd_of_a_tensor_on_an_accelerator_brings_only_the_gram_to_the_host(monkeypatch):
    """Forced here (no GPU in CI): the path a CUDA tensor takes."""
    torch = pytest.importorskip("torch")
    from tensor_cosdi import _backend
    from tensor_cosdi.bases import block_hosvd, tucker_bases, unfolding_gram

    monkeypatch.setattr(_backend, "on_accelerator", torch.is_tensor)
    x = np.random.default_rng(5).random((12, 10, 6)).astype(np.float32)
    t = torch.from_numpy(x).permute(1, 0, 2)  # not contiguous: a strided view
    seen = []
    real = _backend.to_numpy
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_backend, "to_numpy", lambda a: seen.append(tuple(a.shape)) or real(a))
        got = tucker_bases(t)
        blocks = block_hosvd(t, 1, [6, 6])
        gram = unfolding_gram(t, 2)
    assert all(len(s) == 2 for s in seen)  # Grams and bases only: the tensor never converts
    ref = tucker_bases(np.ascontiguousarray(x.transpose(1, 0, 2)))
    for m in range(3):  # eigenvectors are defined up to sign
        np.testing.assert_allclose(np.abs(got[m].T @ ref[m]), np.eye(ref[m].shape[0]), atol=1e-6)
    np.testing.assert_allclose(gram, unfolding_gram(t.numpy(), 2), rtol=1e-10)
    ref_blocks = block_hosvd(t.numpy(), 1, [6, 6])
    np.testing.assert_allclose(np.abs(blocks.matrix.T @ ref_blocks.matrix), np.eye(12), atol=1e-6)
