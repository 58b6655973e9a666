"""Depth from fringes, light-field views and focal stacks (SPEC §7) on rendered scenes with known
truth."""

import numpy as np
import pytest
from scipy import ndimage, signal

from tensor_cosdi import depth, optics, scenes
from tensor_cosdi.noise import add_noise


@pytest.fixture(scope="module")
def sl_scene():
    # two frequencies whose beat (0.8 period) covers the field once: heterodyne gives the absolute
    # phase
    return scenes.structured_light(
        (64, 64), [550.0], frequencies=(8.0, 7.2), phase_per_height=2.0, rng=3
    )


def _frames(phase, K):
    return optics.phase_shift_patterns(phase, K)


@pytest.mark.parametrize("K", [3, 4, 8])
def test_wrapped_phase_exact_on_noise_free_fringes(sl_scene, K):
    phi = sl_scene.phase[..., 0]
    frames = _frames(phi, K)
    est = depth.wrapped_phase(frames)
    assert np.abs(depth.wrap(est - phi)).max() < 1e-9
    assert est.min() > -np.pi and est.max() <= np.pi
    # any offset/amplitude, any step axis
    est2 = depth.wrapped_phase(
        np.moveaxis(3 + 2 * np.cos(phi[..., None] + 2 * np.pi * np.arange(K) / K), -1, 0), axis=0
    )
    assert np.abs(depth.wrap(est2 - phi)).max() < 1e-9


def test_modulation_and_confidence(sl_scene):
    frames = _frames(sl_scene.phase[..., 0], 4)
    a, b, conf = depth.fringe_modulation(frames)
    assert np.allclose(a, 0.5) and np.allclose(b, 0.5) and np.allclose(conf, 1.0)
    a, b, conf = depth.fringe_modulation(np.full((3, 3, 4), 0.7))  # no fringe: zero confidence
    assert np.allclose(b, 0) and np.allclose(conf, 0)


def _wrapped_pair(scene, K=4, snr_db=None, rng=0):
    out = []
    for f in range(2):
        frames = _frames(scene.phase[..., f], K)
        if snr_db is not None:
            frames = add_noise(frames, snr_db, rng=rng + f)
        out.append(depth.wrapped_phase(frames))
    return np.stack(out, -1)


def test_heterodyne_exact_on_noise_free(sl_scene):
    w = _wrapped_pair(sl_scene)
    Phi = depth.heterodyne_unwrap(w, sl_scene.frequencies)
    assert np.abs(Phi - sl_scene.phase[..., 0]).max() < 1e-9


def test_heterodyne_three_frequency_chain():
    Phi = optics.projector_phase((2, 256), [12.0, 11.0, 10.1])  # beats 1.0, 0.9 → 0.1
    w = depth.wrap(Phi)
    assert np.abs(depth.heterodyne_unwrap(w, [12.0, 11.0, 10.1]) - Phi[..., 0]).max() < 1e-9
    Phi = optics.projector_phase((2, 64), [4.0, 1.0])  # lowest already absolute: hierarchical
    assert np.abs(depth.heterodyne_unwrap(depth.wrap(Phi), [4.0, 1.0]) - Phi[..., 0]).max() < 1e-9


def test_heterodyne_refuses_ambiguous_frequencies():
    Phi = optics.projector_phase((2, 64), [14.0, 2.0])  # the thesis pair: beat of 12 periods
    with pytest.raises(ValueError, match="no frequency or heterodyne beat has ≤ 1 period"):
        depth.heterodyne_unwrap(depth.wrap(Phi), [14.0, 2.0])


def test_heterodyne_at_30db_few_wrong_orders(sl_scene):
    w = _wrapped_pair(sl_scene, snr_db=30, rng=11)
    Phi = depth.heterodyne_unwrap(w, sl_scene.frequencies)
    order_err = np.round((Phi - sl_scene.phase[..., 0]) / (2 * np.pi)) != 0
    assert order_err.mean() < 0.005


def test_gray_code_exact_and_robust(sl_scene):
    phi = sl_scene.phase[..., 0]
    bits = optics.gray_code_patterns(phi)
    labels = depth.decode_gray_code(bits)
    w = depth.wrapped_phase(_frames(phi, 4))
    assert np.abs(depth.unwrap_gray_code(w, labels) - phi).max() < 1e-9
    # 30 dB on the fringes and on the code frames; per-pixel threshold from the fringe offset
    frames = add_noise(_frames(phi, 4), 30, rng=5)
    a, _, _ = depth.fringe_modulation(frames)
    labels = depth.decode_gray_code(add_noise(bits * 0.9 + 0.05, 30, rng=6), threshold=a)
    Phi = depth.unwrap_gray_code(depth.wrapped_phase(frames), labels)
    order_err = np.round((Phi - phi) / (2 * np.pi)) != 0
    assert order_err.mean() < 0.005
    # a label off by one at a stripe edge does not change the order
    edge = np.abs(np.abs(w) - np.pi) < 0.05  # near a wrap: half-period boundary of odd labels
    bumped = np.where(edge & (labels % 2 == 1), labels - 1, labels)
    assert np.abs(depth.unwrap_gray_code(w, bumped) - phi).max() < 1e-9


def test_spatial_unwrap_and_height(sl_scene):
    phi = sl_scene.phase[..., 0]
    w = depth.wrap(phi)
    Phi = depth.spatial_unwrap(w, reference=((0, 0), phi[0, 0]))
    assert np.abs(Phi - phi).max() < 1e-9
    ref = optics.projector_phase((64, 64), 8.0)[..., 0]
    h = depth.phase_to_height(Phi, ref, phase_per_height=sl_scene.phase_per_height)
    assert np.abs(h - sl_scene.height).max() < 1e-9


def test_calibrate_phase_to_height():
    ref = optics.projector_phase((8, 8), 4.0)[..., 0]
    heights = np.array([0.5, 1.0, 2.0])
    phases = ref + 1.7 * heights[:, None, None]
    assert depth.calibrate_phase_to_height(phases, ref, heights) == pytest.approx(1.7)
    with pytest.raises(ValueError, match="one map per height"):
        depth.calibrate_phase_to_height(phases[:2], ref, heights)


def test_structured_light_errors():
    with pytest.raises(ValueError, match="K ≥ 3"):
        depth.wrapped_phase(np.zeros((4, 4, 2)))
    with pytest.raises(ValueError, match="NaN"):
        depth.wrapped_phase(np.full((2, 2, 4), np.nan))
    with pytest.raises(ValueError, match="same shape"):
        depth.unwrap_gray_code(np.zeros((2, 2)), np.zeros((2, 3), int))


def _layers(n=64):
    """Three depth layers: a background plane, a rectangle and a disk."""
    d = np.full((n, n), -0.5)
    d[n // 4 : 3 * n // 4, n // 5 : 5 * n // 8] = 0.8
    yy, xx = np.indices((n, n))
    d[(yy - 5 * n // 8) ** 2 + (xx - 23 * n // 32) ** 2 < (n // 6) ** 2] = 0.2
    return d


@pytest.mark.parametrize("photo", ["astronaut", "coffee"])
def test_disparity_from_5x5_views(photo):
    d = _layers()
    img = scenes.photo(photo, d.shape, np.linspace(450, 650, 4))
    lf = scenes.light_field(img, d, views=(5, 5))  # (H, W, C, U, V)
    est = depth.disparity_from_views(np.moveaxis(lf, (3, 4), (0, 1)), max_disparity=1.5)
    tex = depth.textured_mask(img)
    err = np.abs(est - d)[tex]
    assert tex.mean() > 0.5
    assert err.mean() < 0.1  # measured 0.04 (astronaut), 0.04 (coffee)


def test_depth_from_disparity():
    z = depth.depth_from_disparity(np.array([2.0, 1.0, 0.0]), baseline_mm=1.0, focal_px=1000.0)
    assert z.tolist() == [500.0, 1000.0, np.inf]


def test_depth_from_focus_on_a_rendered_stack():
    d = _layers(96)
    planes = np.digitize(d, [-0.2, 0.5])  # three layers → plane 0, 1, 2 ...
    planes[:8] = 3  # ... and a strip on a fourth plane
    img = scenes.photo("chelsea", planes.shape, [550.0])[..., 0]
    depths = [700.0, 850.0, 1000.0, 1200.0]
    stack = []
    for focus in depths:
        lens = optics.Lens(focal_mm=50, aperture_radius_mm=3.0, focus_mm=focus, pixel_um=6)
        im = np.zeros_like(img)
        for z, dz in enumerate(depths):
            im += (planes == z) * signal.fftconvolve(
                img, optics.psf(550, dz, lens=lens, size=21), mode="same"
            )
        stack.append(im)
    est = depth.depth_from_focus(np.stack(stack, -1))
    tex = depth.textured_mask(img)
    assert est.min() >= 0 and est.max() <= 3
    assert np.mean(np.round(est)[tex] == planes[tex]) >= 0.9


def test_spatial_unwrap_with_a_mask(sl_scene):
    phi = sl_scene.phase[..., 0]
    mask = np.zeros(phi.shape, bool)
    mask[10:14, 10:14] = True  # e.g. a shadow: no fringe there
    out = depth.spatial_unwrap(depth.wrap(phi), mask=mask, reference=((0, 0), phi[0, 0]))
    assert np.isnan(out[mask]).all()
    assert np.abs(out[~mask] - phi[~mask]).max() < 1e-9


def test_depth_from_focus_confidence():
    rng = np.random.default_rng(0)
    sharp = rng.random((32, 32))
    sharp[:, 16:] = 0.5  # textureless half
    stack = np.stack([ndimage.gaussian_filter(sharp, s) for s in (2.0, 0.0, 2.0)], -1)
    est, conf = depth.depth_from_focus(stack, return_confidence=True)
    assert conf[:, 4:12].min() > 1.5 and np.allclose(
        conf[:, 28:], 1.0
    )  # texture blurs up to column 25
    assert np.all(np.round(est[:, 4:12]) == 1)


def test_spatial_unwrap_masks_non_finite_phase_instead_of_hanging():
    from tensor_cosdi.depth import spatial_unwrap

    yy, xx = np.mgrid[0:32, 0:32]
    true = 0.4 * xx + 0.2 * yy
    wrapped = np.angle(np.exp(1j * true))
    wrapped[5, 7] = np.nan
    wrapped[20, 3] = np.inf
    out = spatial_unwrap(wrapped, reference=((0, 0), 0.0))
    assert np.isnan(out[5, 7]) and np.isnan(out[20, 3])
    ok = np.isfinite(out)
    assert ok.sum() == 32 * 32 - 2
    np.testing.assert_allclose(out[ok], true[ok], atol=1e-9)
    with pytest.raises(ValueError, match="every pixel"):
        spatial_unwrap(np.full((4, 4), np.nan))


def _occluding_scene(n=64):
    """A slanted photo background and a nearer, slanted disc of another photo (5×5 views)."""
    wl = [450.0, 550.0, 650.0]
    yy, xx = np.indices((n, n))
    disc = (yy - n / 2) ** 2 + (xx - n / 2.5) ** 2 < (n / 5) ** 2
    layers = [
        scenes.LightFieldLayer(scenes.photo("astronaut", (n, n), wl), (-0.8, 0.004, -0.003)),
        scenes.LightFieldLayer(scenes.photo("coffee", (n, n), wl), (0.9, 0.0, 0.002), disc),
    ]
    return scenes.layered_light_field(layers, views=(5, 5)), disc


def test_layered_light_field_follows_the_disparity_convention():
    tex = np.random.default_rng(0).random((20, 24, 2))
    lf, d = scenes.layered_light_field([scenes.LightFieldLayer(tex, 1.0)], views=(3, 3))
    assert lf.shape == (3, 3, 20, 24, 2) and np.all(d == 1.0)
    # I[u, v](y − (u − uc)·d, x − (v − vc)·d) = I[uc, vc](y, x), d = 1 px per view step
    np.testing.assert_allclose(lf[2, 1, 2:-3], lf[1, 1, 3:-2], atol=1e-12)
    np.testing.assert_allclose(lf[1, 0, :, 3:-2], lf[1, 1, :, 2:-3], atol=1e-12)


def test_layered_light_field_hides_the_far_plane_behind_the_near_one():
    (lf, d), disc = _occluding_scene(48)
    assert np.allclose(d[disc], 0.9 + 0.002 * (np.indices(d.shape)[1][disc] - 23.5))
    assert np.all(d[~disc] < 0)
    # the near disc moves further between views than the background behind it
    centre, right = lf[2, 2, ..., 0], lf[2, 3, ..., 0]
    row = int(np.argmax(disc.sum(axis=1)))
    assert not np.allclose(centre[row], right[row])


@pytest.mark.parametrize(
    "layers, kw, match",
    [
        ([], {}, "non-empty"),
        ([scenes.LightFieldLayer(np.zeros((4, 4)))], {"supersample": 2}, "odd"),
        ([scenes.LightFieldLayer(np.zeros((4, 4)), 1.0, np.ones((4, 4), bool))], {}, "no layer"),
        ([scenes.LightFieldLayer(np.zeros((4, 4)), (0.0, 1.0, 0.0))], {}, "too steep"),
        ([scenes.LightFieldLayer(np.zeros((4, 4)), 0.0, np.ones((3, 4), bool))], {}, "mask"),
        ([scenes.LightFieldLayer(np.full((4, 4), np.nan))], {}, "finite"),
        ([scenes.LightFieldLayer(np.zeros((4, 4)), (1.0, 2.0))], {}, "disparity"),
    ],
)
def test_layered_light_field_errors(layers, kw, match):
    with pytest.raises(ValueError, match=match):
        scenes.layered_light_field(layers, views=(3, 3), **kw)


def test_occlusion_aware_disparity_beats_plain_ssd_at_occlusions():
    (lf, d), disc = _occluding_scene()
    errs = {}
    for method in ("occlusion", "ssd"):
        est = depth.disparity_from_views(lf, max_disparity=1.5, method=method)
        errs[method] = np.abs(est - d)[8:-8, 8:-8]
    # measured: occlusion-aware 0.033 px MAE, 6.7 % off by > 0.07 px; plain SSD 0.095, 14.6 %
    assert errs["occlusion"].mean() < 0.05 and (errs["occlusion"] > 0.07).mean() < 0.08
    assert errs["occlusion"].mean() < 0.5 * errs["ssd"].mean()


def test_disparity_options_are_checked():
    lf = np.zeros((3, 3, 8, 8))
    with pytest.raises(ValueError, match="method"):
        depth.disparity_from_views(lf, method="sad")
    with pytest.raises(ValueError, match="half_ratio"):
        depth.disparity_from_views(lf, half_ratio=0)
    with pytest.raises(ValueError, match="radius"):
        depth.disparity_from_views(lf, radius=-1)
    with pytest.raises(ValueError, match="max_disparity"):
        depth.disparity_from_views(lf, max_disparity=True)


def test_guided_filter_keeps_an_edge_of_the_guide():
    guide = np.zeros((16, 16))
    guide[:, 8:] = 1.0
    src = guide + np.random.default_rng(0).normal(0, 0.05, guide.shape)
    out = depth.guided_filter(guide, src, radius=3, eps=1e-3)
    assert abs(out[:, :7].mean()) < 0.02 and abs(out[:, 9:].mean() - 1) < 0.02
    assert out[:, 7].mean() < 0.1 and out[:, 8].mean() > 0.9  # no blur across the edge
    assert np.std(out[:, :7]) < 0.5 * np.std(src[:, :7])  # smoothed within a side


def test_values_that_would_give_a_meaningless_depth_are_errors():
    rng = np.random.default_rng(0)
    img = rng.random((8, 8))
    with pytest.raises(ValueError, match="threshold must be finite"):
        depth.decode_gray_code(rng.random((8, 8, 3)), threshold=np.nan)
    with pytest.raises(ValueError, match="labels count half periods from 0"):
        depth.unwrap_gray_code(img, -np.ones((8, 8), int))
    with pytest.raises(ValueError, match="heights must be finite"):
        depth.calibrate_phase_to_height([img], img, [np.nan])
    bad = img.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="mask those pixels"):
        depth.calibrate_phase_to_height([bad], img, [1.0])
    mask = np.zeros((1, 8, 8), bool)
    mask[0, 0, 0] = True  # the NaN pixel masked: a finite fit
    assert np.isfinite(depth.calibrate_phase_to_height([bad], img, [1.0], mask=mask))
    with pytest.raises(ValueError, match="finite values"):
        depth.guided_filter(bad, img)
    with pytest.raises(ValueError, match="threshold must be"):
        depth.textured_mask(img, threshold=-1.0)
    with pytest.raises(ValueError, match="finite values"):
        depth.textured_mask(bad)
    with pytest.raises(ValueError, match="sigma must be"):
        depth.depth_from_focus(rng.random((8, 8, 3)), sigma=-1.0)
    with pytest.raises(ValueError, match="window must be a positive integer"):
        depth.disparity_from_views(rng.random((3, 3, 8, 8)), window=0)
