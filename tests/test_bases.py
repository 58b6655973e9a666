"""Orthonormal per-mode bases: exact inverses, agreement with SciPy/PyWavelets, learned bases."""

import warnings

import numpy as np
import pytest
import pywt
import scipy.fft
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi import _backend as B
from tensor_cosdi.bases import (
    KroneckerBasis,
    Wavelet,
    dct,
    identity,
    is_orthonormal,
    svd_basis,
    tucker_bases,
    wavelet,
    wavelet_level,
)


@given(n=st.integers(1, 70))
def test_dct_is_orthonormal_and_is_scipys(n):
    psi = dct(n)
    assert np.abs(psi.T @ psi - np.eye(n)).max() < 1e-13
    x = np.random.default_rng(n).standard_normal(n)
    np.testing.assert_allclose(psi.T @ x, scipy.fft.dct(x, norm="ortho"), atol=1e-12)


@pytest.mark.parametrize(
    "n, name", [(256, "sym8"), (64, "sym8"), (48, "db4"), (28, "haar"), (28, "sym8"), (7, "sym8")]
)
def test_wavelet_is_orthonormal_and_is_pywts(n, name):
    x = np.random.default_rng(0).standard_normal(n)
    for mode in ("auto", "boundary"):
        psi = wavelet(n, name, level=mode)
        assert np.abs(psi.T @ psi - np.eye(n)).max() < 1e-14
        if mode == "boundary":
            level = pywt.dwt_max_level(n, pywt.Wavelet(name).dec_len)
        else:  # the deepest periodised level: the largest power of two dividing n
            level = int(np.log2(n & -n))
        while level and n % 2**level:
            level -= 1
        assert wavelet_level(n, name, mode) == level
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pywt warns of levels deeper than its boundary rule
            ref = np.concatenate(pywt.wavedec(x, name, mode="periodization", level=level))
        np.testing.assert_allclose(psi.T @ x, ref if level else x, atol=1e-11)


def test_wavelet_levels_and_errors():
    assert np.array_equal(
        wavelet(28, level="boundary"), np.eye(28)
    )  # Symlet-8 has no boundary-free level on 28 samples
    assert wavelet_level(28) == 2 and wavelet_level(96) == 5 and wavelet_level(7) == 0
    assert np.array_equal(wavelet(64, level=None), wavelet(64, level="boundary"))
    assert Wavelet(64).level == 6 and "level=6" in repr(Wavelet(64))
    for bad in ("deep", 1.5, True, -1):
        with pytest.raises(ValueError, match="level must be"):
            wavelet(16, level=bad)
    assert not np.array_equal(wavelet(256), np.eye(256))
    assert is_orthonormal(wavelet(32, level=5))
    with pytest.raises(ValueError, match="divisible by 8"):
        wavelet(28, level=3)
    with pytest.raises(ValueError, match="not orthogonal"):
        wavelet(16, "bior2.2")
    with pytest.raises(ValueError, match="unknown wavelet"):
        wavelet(16, "nope")
    with pytest.raises(ValueError, match="positive integer"):
        dct(0)


def test_sparse_signal_in_its_basis():
    """A smooth signal is compressible: 12 of 64 DCT atoms keep 99.99 % of its energy."""
    t = np.linspace(0, 1, 64)
    x = np.exp(-((t - 0.4) ** 2) / 0.02)
    c = np.sort(np.abs(dct(64).T @ x))[::-1]
    assert np.sum(c[:12] ** 2) / np.sum(c**2) > 0.9999


def test_learned_bases_are_complete_and_ordered():
    g = np.random.default_rng(0)
    Z = g.standard_normal((12, 3)) @ g.standard_normal((3, 20))  # rank 3, 12 × 20
    psi = svd_basis(Z)
    assert psi.shape == (12, 12) and is_orthonormal(psi)
    energy = np.sum((psi.T @ Z) ** 2, axis=1)
    assert np.all(np.diff(energy) <= 1e-9)  # strongest atoms first
    assert energy[3:].max() < 1e-20 * energy[0]  # rank 3: the rest carries nothing
    # HOSVD of a Tucker tensor of multilinear rank (2, 3, 2) recovers its subspaces
    ranks = (2, 3, 2)
    core = g.standard_normal(ranks)
    U = [np.linalg.qr(g.standard_normal((n, r)))[0] for n, r in zip((6, 7, 5), ranks)]
    X = np.einsum("abc,ia,jb,kc->ijk", core, *U)
    bases = tucker_bases(X)
    for mode, (u, r) in enumerate(zip(U, ranks)):
        lead = bases[mode][:, :r]
        np.testing.assert_allclose(lead @ lead.T, u @ u.T, atol=1e-10)


def test_kronecker_basis_round_trip_on_backends(backend):
    _, dtype = backend
    shape = (16, 8, 6)
    basis = KroneckerBasis(shape, {0: wavelet(16, "db2"), 2: dct(6)})
    F = B.as_tensor(np.random.default_rng(1).standard_normal(shape), dtype)
    theta = basis.analysis(F)
    tol = 1e-12 if dtype == "float64" else 1e-5
    np.testing.assert_allclose(B.to_numpy(basis.synthesis(theta)), B.to_numpy(F), atol=tol)
    # orthonormal: energy is preserved
    assert (
        abs(float(np.sum(B.to_numpy(theta) ** 2)) / float(np.sum(B.to_numpy(F) ** 2)) - 1)
        < tol * 10
    )
    # mode 1 untouched, mode 2 is the DCT
    ref = scipy.fft.dct(np.asarray(B.to_numpy(F), dtype=np.float64), norm="ortho", axis=2)
    ref = np.einsum("ij,jkl->ikl", wavelet(16, "db2").T, ref)
    np.testing.assert_allclose(B.to_numpy(theta), ref, atol=tol * 10)


def test_kronecker_basis_errors_and_update():
    with pytest.raises(ValueError, match="must be 4 × 4"):
        KroneckerBasis((4, 5), {0: np.eye(5)})
    with pytest.raises(ValueError, match="not orthonormal"):
        KroneckerBasis((4, 5), {0: 2 * np.eye(4)})
    with pytest.raises(ValueError, match="mode 3"):
        KroneckerBasis((4, 5), {3: np.eye(4)})
    b = KroneckerBasis((4, 5), [identity(4), dct(5)])
    b2 = b.with_mode(1, wavelet(5, "haar", level=0))
    x = np.random.default_rng(0).random((4, 5))
    np.testing.assert_allclose(b2.analysis(x), x)
    np.testing.assert_allclose(b.analysis(x), scipy.fft.dct(x, norm="ortho", axis=1), atol=1e-14)


def test_a_dense_basis_refuses_values_it_cannot_apply():
    from tensor_cosdi.bases import BlockDense, Dense, as_transform

    with pytest.raises(ValueError, match="finite values"):
        Dense(np.full((2, 2), np.nan))
    with pytest.raises(ValueError, match="finite values"):
        BlockDense([np.eye(2), np.full((1, 1), np.inf)])
    with pytest.raises(ValueError, match="real numbers, got dtype complex128"):
        Dense(np.eye(2, dtype=complex))
    with pytest.raises(ValueError, match="matrix of size 3 given for a mode of size 4"):
        as_transform(4, np.eye(3))
    assert as_transform(3, np.eye(3)).n == 3
