"""Code generators: seeded, complementary where promised, the #f/κ limiting cases."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi import codes


def test_random_binary_is_seeded_with_its_transmittance():
    a = codes.random_binary((200, 200), transmittance=0.3, rng=4)
    np.testing.assert_array_equal(a, codes.random_binary((200, 200), transmittance=0.3, rng=4))
    assert set(np.unique(a)) == {0.0, 1.0}
    assert abs(a.mean() - 0.3) < 0.01
    assert codes.depth_codes((6, 7), 4, rng=0).shape == (6, 7, 4)


@given(n_bands=st.integers(1, 40), n_filters=st.integers(1, 40))
def test_passbands_partition_the_bands(n_bands, n_filters):
    if n_filters > n_bands:
        with pytest.raises(ValueError):
            codes.filter_passbands(n_bands, n_filters)
        return
    P = codes.filter_passbands(n_bands, n_filters)
    np.testing.assert_array_equal(P.sum(0), 1)  # every band in exactly one filter
    assert (P.sum(1) >= n_bands // n_filters).all()  # near-equal widths
    idx = [np.flatnonzero(row) for row in P]
    assert all(np.all(np.diff(i) == 1) for i in idx)  # contiguous
    assert all(idx[f][-1] < idx[f + 1][0] for f in range(n_filters - 1))  # ordered by wavelength


@given(
    K=st.integers(2, 5),
    extra=st.integers(0, 4),
    n_bands=st.integers(5, 12),
    five=st.booleans(),
    seed=st.integers(0, 999),
)
def test_complementary_codes(K, extra, n_bands, five, seed):
    n_filters = min(K + extra, n_bands)
    shape = (3, 4, n_bands, 2, 2) if five else (5, 4, n_bands)
    T = codes.complementary_colour_codes(shape, K, n_filters=n_filters, rng=seed)
    assert T.shape == shape + (K,)
    assert codes.is_complementary(T)
    assert set(np.unique(T)) <= {0.0, 1.0}
    # every snapshot gets ⌊F/K⌋ or ⌈F/K⌉ filters at every pixel (balanced light)
    P = codes.filter_passbands(n_bands, n_filters)
    per_filter = np.einsum("...lk,fl->...fk", np.moveaxis(T, 2, -2), P) / P.sum(1)[:, None]
    counts = per_filter.sum(-2)
    assert counts.min() >= n_filters // K and counts.max() <= -(-n_filters // K)


def test_complementary_codes_vary_per_pixel():
    T = codes.complementary_colour_codes((16, 16, 6), 2, rng=0)
    first = T[:, :, 0, 0]
    assert 0.3 < first.mean() < 0.7  # snapshot of the first filter is random per pixel


def test_colour_coded_aperture_limits():
    C = codes.colour_coded_aperture((20, 30), 8, n_filters=1, transmittance=1.0, rng=0)
    np.testing.assert_array_equal(C, 1.0)  # #f = 1, κ = 100 %: an all-ones aperture
    C = codes.colour_coded_aperture((100, 100), 8, n_filters=8, transmittance=0.25, rng=0)
    per_pixel = C.sum(-1)
    assert set(np.unique(per_pixel)) == {0.0, 1.0}  # #f = Nλ: one ideal narrow filter where open
    assert abs(per_pixel.mean() - 0.25) < 0.02
    C = codes.colour_coded_aperture((100, 100), 12, n_filters=6, transmittance=0.5, rng=1)
    assert set(np.unique(C.sum(-1))) == {0.0, 2.0}
    assert abs((C.sum(-1) > 0).mean() - 0.5) < 0.02
    # all six filters occur, about equally often
    filters = C[C.sum(-1) > 0].reshape(-1, 12)
    assert len({tuple(f) for f in filters}) == 6
