"""Glasses, the double Amici prism, Zernike polynomials, PSFs and projected patterns (SPEC §8)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi import optics, systems
from tensor_cosdi.optics import DoubleAmiciPrism, Lens


def test_sellmeier_matches_catalogue_nd():
    # catalogue refractive indices at the helium d line (587.56 nm)
    assert optics.refractive_index("N-SK2", 587.56) == pytest.approx(1.60738, abs=2e-5)
    assert optics.refractive_index("SF4", 587.56) == pytest.approx(1.75520, abs=2e-5)
    n = optics.refractive_index("SF4", np.linspace(450, 650, 5))
    assert np.all(np.diff(n) < 0)  # normal dispersion


def test_glass_errors_name_the_problem():
    with pytest.raises(ValueError, match="unknown glass 'BK8'.*N-SK2"):
        optics.refractive_index("BK8", 550)
    with pytest.raises(ValueError, match="nanometres in 200–20000, got -1"):
        optics.refractive_index("SF4", -1)


def test_register_glass_never_replaces_a_catalogue_glass_and_checks_coefficients():
    b, c = (1.03961212, 0.231792344, 1.01046945), (0.00600069867, 0.0200179144, 103.560653)
    with pytest.raises(ValueError, match="'N-BK7' is a built-in glass and cannot be replaced"):
        optics.register_glass("n-bk7", b, c, replace=True)
    with pytest.raises(ValueError, match="Sellmeier B must be 3 finite numbers"):
        optics.register_glass("test-glass", (1.0, np.nan, 1.0), c)
    optics.register_glass("test-glass", b, c)
    try:
        with pytest.raises(ValueError, match="already registered; pass replace=True"):
            optics.register_glass("TEST-GLASS", b, c)
        optics.register_glass("test-glass", b, c, replace=True)
        assert optics.refractive_index("test-glass", 587.6) == pytest.approx(1.5168, abs=1e-4)
    finally:
        optics.GLASSES.unregister("TEST-GLASS")


def test_thesis_prism_deviation_and_shear():
    prism = DoubleAmiciPrism(phi1=85.9, phi3=73.7)
    wl = np.linspace(450, 650, 41)
    # small deviation near the 570 nm design wavelength, field-averaged as well (Alg. 8)
    assert abs(prism.deviation(570.0)) < 0.05
    assert abs(prism.mean_deviation(570.0)) < 0.05
    dev = prism.deviation(wl)
    assert np.all(np.diff(dev) > 0)  # δ grows with λ: S(λ) monotonic
    s = prism.shear(wl, 30.0)
    assert np.all(np.diff(s) < 0)
    assert prism.shear(570.0, 30.0) == 0.0
    px = prism.shifts(wl, distance_mm=30, pixel_um=6)
    assert px[0] == 0 and np.all(np.diff(px) > 0)
    # the thesis measured ~50 px of 6 µm over 450-650 nm at 30 mm; the model gives 58.9 px
    assert 40 < px[-1] < 70


def test_solved_prism_has_zero_deviation():
    for phi1 in (82.0, 85.9):
        p = DoubleAmiciPrism.design(phi1=phi1, center_nm=570.0)
        assert abs(p.deviation(570.0)) < 1e-3
        q = DoubleAmiciPrism.design(phi1=phi1, center_nm=570.0, field_deg=optics.THESIS_FIELD_DEG)
        assert abs(q.mean_deviation(570.0)) < 1e-3
    p = DoubleAmiciPrism.design(phi1=85.9, center_nm=520.0)
    assert abs(p.deviation(520.0)) < 1e-3 and abs(p.deviation(570.0)) > 1e-3


def test_prism_shifts_build_a_system():
    wl = np.linspace(450, 650, 8)
    s = DoubleAmiciPrism().shifts(wl, distance_mm=5, pixel_um=6)
    sd = systems.SDCASSI(np.ones((8, 8)), n_bands=8, shifts=s, wavelengths=wl)
    assert sd.measurement_shape == (8, 8 + int(np.ceil(s[-1])))
    si = DoubleAmiciPrism().shifts(wl, distance_mm=5, pixel_um=6, integer=True)
    assert si.dtype == np.int64 and np.all(np.abs(si - s) <= 0.5)


def test_prism_errors():
    with pytest.raises(ValueError, match="phi1 \\+ phi3 must be < 180"):
        DoubleAmiciPrism(phi1=120, phi3=70)
    with pytest.raises(ValueError, match="strictly increasing"):
        DoubleAmiciPrism().shifts([600, 500], 30, 6)
    with pytest.raises(ValueError, match="no φ3"):
        DoubleAmiciPrism.design(phi1=60.0)
    with pytest.raises(ValueError, match="total internal reflection"):
        DoubleAmiciPrism(phi1=40, phi3=89).deviation(550)


def test_zernike_orthonormal_on_the_disk():
    # numerical inner products on a polar quadrature grid (Gauss-Legendre in ρ, uniform in θ)
    x, w = np.polynomial.legendre.leggauss(40)
    rho, wr = (x + 1) / 2, w / 2
    theta = np.arange(64) * 2 * np.pi / 64
    R, T = np.meshgrid(rho, theta, indexing="ij")
    weights = (wr * rho)[:, None] * (2 * np.pi / 64) / np.pi
    Z = np.stack([optics.zernike(j, R, T) for j in range(1, 29)])
    G = np.einsum("iab,jab,ab->ij", Z, Z, weights)
    assert np.abs(G - np.eye(28)).max() < 1e-3


def test_zernike_named_terms():
    rho, theta = 0.7, 0.3
    assert optics.zernike(4, rho, theta) == pytest.approx(np.sqrt(3) * (2 * rho**2 - 1))
    assert optics.zernike(6, rho, theta) == pytest.approx(np.sqrt(6) * rho**2 * np.cos(2 * theta))
    assert optics.zernike(5, rho, theta) == pytest.approx(np.sqrt(6) * rho**2 * np.sin(2 * theta))
    assert optics.zernike(11, rho, theta) == pytest.approx(
        np.sqrt(5) * (6 * rho**4 - 6 * rho**2 + 1)
    )
    with pytest.raises(ValueError, match="Noll index"):
        optics.zernike(0, rho, theta)


@given(st.integers(1, 66))
def test_noll_indices_are_a_bijection(j):
    n, m = optics.noll_to_nm(j)
    assert (n - abs(m)) % 2 == 0 and abs(m) <= n
    # the inverse: j is the only index in row n with this (n, m)
    row = range(n * (n + 1) // 2 + 1, (n + 1) * (n + 2) // 2 + 1)
    assert [k for k in row if optics.noll_to_nm(k) == (n, m)] == [j]


def test_psf_sums_to_one_and_widens_with_defocus():
    lens = Lens(focal_mm=50, aperture_radius_mm=2.5, focus_mm=1000, pixel_um=6)
    depths = [1000, 1100, 1300, 1600, 2500]
    widths = []
    for z in depths:
        h = optics.psf(550, z, lens=lens, size=31)
        assert h.shape == (31, 31) and np.all(h >= 0) and h.sum() == pytest.approx(1.0, abs=1e-12)
        widths.append(optics.psf_width(h))
    defocus = np.abs(1 / np.array(depths) - 1 / 1000)
    assert np.all(np.diff(defocus) > 0) and np.all(np.diff(widths) > 0)
    # in front of focus as well
    assert optics.psf_width(optics.psf(550, 800, lens=lens, size=31)) > widths[0]


def test_psf_astigmatism_breaks_the_symmetry():
    lens = Lens()

    def spreads(p):
        i = np.arange(p.shape[0]) - p.shape[0] // 2
        return (p.sum(1) * i**2).sum(), (p.sum(0) * i**2).sum()

    # pure defocus stays round
    a, b = spreads(optics.psf(550, 1300, lens=lens, size=31))
    assert abs(a - b) / (a + b) < 1e-6
    # vertical astigmatism (Z6) elongates the defocused PSF along one axis in front of focus and
    # along
    # the other behind it: the asymmetry that tells near from far (what DFA exploits, Sec. 4.3)
    near = optics.psf(550, 900, lens=lens, size=31, zernike={6: 0.5})
    far = optics.psf(550, 1150, lens=lens, size=31, zernike={6: 0.5})
    (an, bn), (af, bf) = spreads(near), spreads(far)
    assert abs(an - bn) / (an + bn) > 0.1 and abs(af - bf) / (af + bf) > 0.1
    assert np.sign(an - bn) != np.sign(af - bf)


def test_psf_stack_feeds_cassdi_dfa():
    wl = [500.0, 550.0, 600.0]
    with pytest.warns(optics.PSFCropWarning, match=r"a 7×7 crop holds \d+% of the PSF's light"):
        P = optics.psf_stack(wl, [800, 1000, 1300], size=7, zernike={6: 0.5})
    assert P.shape == (7, 7, 3, 3)
    assert np.allclose(P.sum(axis=(0, 1)), 1)
    dfa = systems.CASSDIDFA(np.ones((8, 8, 3)), n_bands=3, psfs=P, wavelengths=wl)
    assert dfa.cube_shape == (8, 8, 3, 3)


def test_psf_errors():
    with pytest.raises(ValueError, match="odd"):
        optics.psf(550, 1000, size=10)
    with pytest.raises(ValueError, match="Noll"):
        optics.psf(550, 1000, zernike={0: 1.0})
    with pytest.raises(ValueError, match="focus_mm"):
        Lens(focal_mm=50, focus_mm=40)


def test_fringes_and_gray_codes():
    phase = optics.projector_phase((4, 32), [2.0, 1.0])
    assert phase.shape == (4, 32, 2)
    frames = optics.phase_shift_patterns(phase, 4)
    assert frames.shape == (4, 32, 8) and frames.min() >= 0 and frames.max() <= 1
    # frequency-major: the second frequency's first step is pattern 4
    assert np.allclose(frames[..., 4], 0.5 + 0.5 * np.cos(phase[..., 1]))
    bits = optics.gray_code_patterns(phase[..., 0])
    assert bits.shape == (4, 32, optics.gray_code_bits(2.0))
    labels = optics.gray_to_binary(bits)
    assert np.array_equal(labels, np.floor(phase[..., 0] / np.pi).astype(int))
    # neighbouring half periods differ in exactly one bit (the point of a Gray code)
    changes = np.abs(np.diff(bits[0], axis=0)).sum(axis=1)
    assert set(changes.tolist()) <= {0.0, 1.0}
    with pytest.raises(ValueError, match="n_steps"):
        optics.phase_shift_patterns(phase, 2)
    with pytest.raises(ValueError, match="amplitude"):
        optics.phase_shift_patterns(phase, 4, offset=0.2, amplitude=0.5)


def test_wavelengths_in_micrometres_are_an_error_naming_the_unit():
    from tensor_cosdi.optics import refractive_index

    with pytest.raises(ValueError, match="micrometres"):
        refractive_index("SF4", 0.55)
    with pytest.raises(ValueError, match="nanometres in 200–20000"):
        refractive_index("SF4", [500.0, np.nan])
    assert refractive_index("SF4", 550.0) > 1.7


def test_the_share_of_light_in_a_crop_follows_from_the_pupil():
    """Parseval: the whole image plane holds the pupil's light, so a crop's share needs no
    larger PSF; it grows with the crop towards 1 and is small for a strong aberration."""
    import warnings

    lens = Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
    shares = [optics.psf(450, 800, lens=lens, size=n, return_share=True)[1] for n in (5, 9, 41, 81)]
    assert shares == sorted(shares) and shares[0] < 0.8 and abs(shares[-1] - 1) < 0.02, shares
    h, share = optics.psf(450, 800, lens=lens, size=9, zernike={6: 0.9}, return_share=True)
    assert share < 0.3 and h.sum() == pytest.approx(1.0)  # renormalised, whatever it held
    big = optics.psf(450, 800, lens=lens, size=81, zernike={6: 0.9})
    assert share == pytest.approx(big[36:45, 36:45].sum(), abs=0.02)  # the same light, measured
    with warnings.catch_warnings():
        warnings.simplefilter("error", optics.PSFCropWarning)
        optics.psf_stack([450, 650], [800, 1300], lens=lens, size=41, zernike={6: 0.25})
        optics.psf_stack([450], [800], lens=lens, size=5, zernike={6: 0.9}, min_share=None)


def test_zernike_radial_and_gray_codes_refuse_pairs_and_widths_they_cannot_hold():
    for n, m in ((2, 4), (3, 0), (-2, 0), (2.0, 0), (True, 0)):
        with pytest.raises(ValueError, match="Zernike radial|must be an integer"):
            optics.zernike_radial(n, m, np.ones(3))
    np.testing.assert_allclose(optics.zernike_radial(2, -2, np.array([0.5])), [0.25])
    phase = optics.projector_phase((1, 8), 2.0)[..., 0]
    with pytest.raises(ValueError, match="n_bits must be at most 62, got 80"):
        optics.gray_code_patterns(phase, 80)
    with pytest.raises(ValueError, match="at most 62 Gray-code bits"):
        optics.gray_to_binary(np.zeros((2, 63)))
    assert optics.gray_code_patterns(phase, 62).shape == (1, 8, 62)
