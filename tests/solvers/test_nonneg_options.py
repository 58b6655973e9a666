"""Non-negativity is an option of every method: on by default for a cube of light (except the
closed-form ``lsq``), and ``nonneg=False`` keeps a signed cube signed."""

import importlib.util

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import codes, optics, scenes
from tensor_cosdi.systems import CASSDIDFA, MuCoSDI

HAS_TORCH = importlib.util.find_spec("torch") is not None

#: Methods whose default is off, and why (the others project by default).
OFF_BY_DEFAULT = {"lsq": "the closed-form linear baseline"}
#: Options that keep each run short.
QUICK = {"max_iter": 8}
LYTRO = {"n_patches": 500, "n_iter": 2}


def test_every_method_has_a_boolean_nonneg_option():
    for name in tc.solvers.methods():
        default = tc.solvers.METHODS[name].defaults.get("nonneg")
        assert isinstance(default, bool), f"{name}: no nonneg option"
        assert default is (name not in OFF_BY_DEFAULT), name


def _system(method):
    """A small system the method reconstructs, and a light cube for it."""
    rng = np.random.default_rng(0)
    if method == "split_tv":
        wl = scenes.default_wavelengths(6)
        lens = optics.Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
        psfs = optics.psf_stack(
            wl, [800.0, 1300.0], lens=lens, zernike={6: 0.25}, size=7, min_share=None
        )
        system = CASSDIDFA(
            codes.depth_codes((24, 24), 2, rng=0), n_bands=6, psfs=psfs, wavelengths=wl
        )
        return system, rng.random(system.cube_shape)
    if method == "pnp_admm":  # the single-cube path (no pattern axis) can hold a signed cube
        code = codes.random_binary((24, 24 + 5), rng=0)
        system = MuCoSDI(code, n_bands=6, modality="monocular")
        return system, scenes.photo("chelsea", (24, 24), system.wavelengths)
    if method == "dcosnet":
        p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=28, shifts=2)
        return p.system, np.asarray(p.cube)
    imager = (tc.solvers.METHODS[method].systems or ("sd_cassi",))[0]
    p = tc.studies.make_problem(imager, "chelsea", shape=(24, 24), n_bands=6)
    return p.system, np.asarray(p.cube)


def _run(method, system, g, **options):
    extra = {} if method == "dcosnet" else dict(QUICK)
    if method == "lytro":
        extra.update(LYTRO)
    return np.asarray(tc.reconstruct(system, g, method, **extra, **options).cube)


METHODS = ["lsq", "avsi", "dfa", "split_tv", "otd_nl", "lytro", "pnp_admm"]
METHODS += ["dcosnet"] if HAS_TORCH else []


@pytest.mark.parametrize("method", METHODS)
def test_nonneg_projects_a_noisy_light_cube_and_off_keeps_a_signed_cube(method):
    """Measured (these sizes): with ``nonneg=False`` a light cube at 30 dB comes back with
    0.03-1.2 % negative voxels, the cube minus its mean with 18-60 % of its non-zero ones."""
    system, cube = _system(method)
    g = system.simulate(cube, snr_db=30, rng=0)
    on = _run(method, system, g, nonneg=True)
    assert on.min() >= 0 and np.isfinite(on).all()
    signed = cube - cube.mean()
    g_signed = system.forward(signed)
    off = _run(method, system, g_signed, nonneg=False)
    lit = off[off != 0]  # a DFA cube is zero off each pixel's plane
    assert np.mean(lit < 0) > 0.15, (method, np.mean(lit < 0))
    assert _run(method, system, g_signed, nonneg=True).min() >= 0
    if method != "dcosnet":  # the network was trained on light only
        # measured 0.14 (dfa, whose layer model assumes light) to 0.99 (lytro)
        assert np.corrcoef(off.ravel(), signed.ravel())[0, 1] > 0.1


def test_nonneg_lsq_solves_the_constrained_problem():
    """KKT of ``min ‖g − A f‖² + λ‖f‖², f ≥ 0``: the gradient vanishes on the support and is
    ≥ 0 where ``f = 0``; the clipped unconstrained solution is not optimal."""
    from tensor_cosdi.operators import sensing_gain

    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4, snr_db=10)
    op, g = p.system.operator, p.measurement
    res = tc.reconstruct(p.system, g, "lsq", nonneg=True, max_iter=2000, tol=1e-12)
    f = np.asarray(res.cube)
    lam = 1e-2 * sensing_gain(op, g)
    grad = np.asarray(op.adjoint(op.forward(f) - g)) + lam * f
    scale = np.abs(np.asarray(op.adjoint(g))).max()
    assert np.abs(grad[f > 1e-9 * f.max()]).max() < 1e-4 * scale
    assert grad[f == 0].min() > -1e-4 * scale
    assert (f == 0).any()  # the constraint is active somewhere

    def cost(x):
        return float(np.sum((op.forward(x) - g) ** 2) + lam * np.sum(x**2))

    free = np.asarray(tc.reconstruct(p.system, g, "lsq").cube)
    assert (free < 0).any()
    assert cost(f) < cost(np.clip(free, 0, None))


@pytest.mark.parametrize("method", ["lsq", "avsi", "dfa", "otd_nl", "pnp_admm"])
def test_nonneg_must_be_a_boolean(method):
    system, cube = _system(method)
    g = system.forward(cube)
    with pytest.raises(ValueError, match="nonneg must be True or False"):
        tc.reconstruct(system, g, method, nonneg="yes")
