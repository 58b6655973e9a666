"""Metrics of SPEC §9 against direct formulas and scikit-image."""

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from tensor_cosdi.metrics import combined_error, psnr, rmse, sam, ssim


def test_psnr_and_rmse_formulas():
    g = np.random.default_rng(0)
    t = g.random((8, 9, 4))
    e = t + 0.01 * g.standard_normal(t.shape)
    per_band = [10 * np.log10(1 / np.mean((t[:, :, l] - e[:, :, l]) ** 2)) for l in range(4)]
    assert psnr(t, e, data_range=1.0) == pytest.approx(np.mean(per_band), rel=1e-12)
    assert rmse(t, e) == pytest.approx(np.sqrt(np.mean((t - e) ** 2)), rel=1e-12)


def test_ssim_is_per_band_average():
    g = np.random.default_rng(1)
    t = g.random((20, 24, 3))
    e = np.clip(t + 0.1 * g.standard_normal(t.shape), 0, 1)
    ref = np.mean([structural_similarity(t[..., l], e[..., l], data_range=1.0) for l in range(3)])
    assert ssim(t, e, data_range=1.0) == pytest.approx(ref, rel=1e-12)
    assert ssim(t, t) == 1.0
    assert ssim(t, e) < 0.99
    # band axis elsewhere and extra axes (a 4-D cube: every (λ, z) image counts)
    assert ssim(
        np.moveaxis(t, 2, 0), np.moveaxis(e, 2, 0), channel_axis=0, data_range=1.0
    ) == pytest.approx(ref)
    four = np.stack([t, t], axis=3)
    assert ssim(four, np.stack([e, e], axis=3), data_range=1.0) == pytest.approx(ref)
    assert 0 < ssim(t[:5, :5], e[:5, :5], data_range=1.0) < 1  # window shrinks to 5
    with pytest.raises(ValueError, match="at least 3 × 3"):
        ssim(t[:2, :2], e[:2, :2])


def test_sam_degrees():
    t = np.zeros((1, 3, 2))
    t[0, 0] = [1, 0]
    t[0, 1] = [1, 1]
    t[0, 2] = [0, 0]  # skipped: no true spectrum
    e = np.zeros((1, 3, 2))
    e[0, 0] = [0, 2]  # 90°
    e[0, 1] = [3, 3]  # 0°: the scale does not matter
    e[0, 2] = [5, 1]
    assert sam(t, e) == pytest.approx(45.0)
    e[0, 0] = 0  # nothing recovered: 90°
    assert sam(t, e) == pytest.approx(45.0)
    with pytest.raises(ValueError, match="every true spectrum is zero"):
        sam(np.zeros((2, 2, 3)), np.ones((2, 2, 3)))


def test_combined_error_picks_the_best_setting():
    g = np.random.default_rng(2)
    psnrs = 30 + g.random((5, 4))
    psnrs[:, 2] += 3  # setting 2 is best on every metric
    ssims = 0.8 + 0.01 * g.random((5, 4))
    ssims[:, 2] += 0.1
    rmses = 0.1 + 0.01 * g.random((5, 4))
    rmses[:, 2] -= 0.05
    sams = 8 + g.random((5, 4))
    sams[:, 2] -= 3
    p = combined_error(psnrs, ssims, rmses, sams)
    assert p.shape == (4,) and p.argmin() == 2 and p[2] == 0.0
    # Eq. 49 by hand for setting 0
    by_hand = (
        (
            np.abs(psnrs.max(1) - psnrs[:, 0]) / psnrs.max(1)
            + np.abs(ssims.max(1) - ssims[:, 0]) / ssims.max(1)
            + np.abs(rmses.min(1) - rmses[:, 0]) / rmses.min(1)
            + np.abs(sams.min(1) - sams[:, 0]) / sams.min(1)
        ).sum()
        * 100
        / 20
    )
    assert p[0] == pytest.approx(by_hand)
    with pytest.raises(ValueError, match="one shape"):
        combined_error(psnrs, ssims, rmses, sams[:, :3])


def test_metric_input_errors():
    with pytest.raises(ValueError, match="shape"):
        rmse(np.zeros((2, 2)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="finite"):
        sam(np.ones((2, 2, 2)), np.full((2, 2, 2), np.nan))
    with pytest.raises(ValueError, match="data_range"):
        psnr(np.ones((2, 2, 2)), np.zeros((2, 2, 2)))
    # a complex estimate is refused, not scored on its real part
    for metric in (psnr, ssim, sam, rmse):
        with pytest.raises(ValueError, match="image_test must hold real numbers, got dtype compl"):
            metric(np.ones((8, 8, 2)), np.ones((8, 8, 2)) + 1j)


def test_channel_axis_is_scikit_image_s_name_and_band_axis_still_works():
    import warnings

    from tensor_cosdi import metrics

    rng = np.random.default_rng(0)
    a = rng.random((3, 12, 12))  # bands first
    b = a + 0.01 * rng.standard_normal(a.shape)
    moved = (np.moveaxis(a, 0, 2), np.moveaxis(b, 0, 2))
    for f in (metrics.psnr, metrics.ssim, metrics.sam):
        assert f(a, b, channel_axis=0) == pytest.approx(f(*moved))
        with pytest.warns(DeprecationWarning, match="use channel_axis"):
            assert f(a, b, band_axis=0) == pytest.approx(f(*moved))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        metrics.psnr(*moved)  # the default warns about nothing
    with pytest.raises(ValueError, match="channel_axis 5 is out of range"):
        metrics.psnr(a, b, channel_axis=5)
    with pytest.raises(ValueError, match="channel_axis must be an integer"):
        metrics.sam(a, b, channel_axis=True)
