"""The reconstruction harness: registry, option checking, Result, regularised least squares."""

import importlib.util
import warnings

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.operators import vec
from tensor_cosdi.systems import C3SLFI, CASSIVSI, SDCASSI, DualCameraCASSI


def test_registry_lists_methods_and_rejects_unknown_ones():
    assert "lsq" in tc.reconstruct.methods()
    sd = SDCASSI.example((6, 7, 4))
    g = np.random.default_rng(0).random(sd.measurement_shape)
    with pytest.raises(ValueError, match=r"unknown method 'nope'; valid names: \[.*'lsq'"):
        tc.reconstruct(sd, g, method="nope")
    with pytest.raises(
        ValueError,
        match=r"unknown option\(s\) \['iters'\] for method 'lsq'; valid options: "
        r"\['max_iter', 'mu', 'nonneg', 'tol'\]",
    ):
        tc.reconstruct(sd, g, method="lsq", iters=3)
    with pytest.raises(
        ValueError, match=r"SDCASSI.reconstruct: expected a measurement of shape \(6, 10\)"
    ):
        tc.reconstruct(sd, np.zeros((6, 7)), method="lsq")
    with pytest.raises(ValueError, match="mu must be a finite number > 0"):
        tc.reconstruct(sd, g, method="lsq", mu=0)
    with pytest.raises(ValueError, match="'lsq' is a built-in method and cannot be replaced"):
        tc.solvers.register_method("lsq", lambda s, g: None, {}, replace=True)
    tc.solvers.register_method("user_lsq_test", lambda s, g, **o: None, {})
    try:
        with pytest.raises(ValueError, match="already registered; pass replace=True"):
            tc.solvers.register_method("user_lsq_test", lambda s, g, **o: None, {})
        tc.solvers.register_method("user_lsq_test", lambda s, g, **o: None, {"a": 1}, replace=True)
        assert tc.solvers.METHODS["user_lsq_test"].defaults == {"a": 1}
    finally:
        tc.solvers.METHODS.unregister("user_lsq_test")
    assert "user_lsq_test" not in tc.solvers.METHODS


@pytest.mark.parametrize(
    "system",
    [
        SDCASSI.example((5, 6, 4)),
        CASSIVSI.example((5, 6, 4)),
        C3SLFI.example((4, 4, 5)),
        DualCameraCASSI.example((4, 5, 3)),
    ],
    ids=["sd", "vsi", "c3slfi", "dual"],
)
def test_lsq_equals_the_dense_tikhonov_solution(system):
    g = np.random.default_rng(0).standard_normal(system.measurement_shape)
    H = system.matrix().toarray()
    s = np.sum((H @ np.ones(H.shape[1])) ** 2) / H.shape[1]
    ref = np.linalg.solve(H.T @ H + 1e-2 * s * np.eye(H.shape[1]), H.T @ vec(g))
    res = tc.reconstruct(system, g, method="lsq", mu=1e-2)
    assert isinstance(res, tc.Result)
    np.testing.assert_allclose(vec(res.cube), ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max())
    want = {"mu": 1e-2, "nonneg": False, "max_iter": 100, "tol": 1e-5}  # every option recorded
    assert res.options == want and res.method == "lsq" and res.converged
    assert res.iterations == 1 and set(res.history) == {
        "objective",
        "residual",
        "change",
        "seconds",
    }
    assert res.seconds >= 0
    if not isinstance(system, tc.systems.C3SLFI):  # spectral-only systems have no depth channel
        assert res.depth is None


def test_more_shots_give_a_better_lsq_estimate():
    """Quality floor on a seeded scene: 4 shots beat 1 shot by ≥ 2 dB at 30 dB SNR."""
    cube = tc.scenes.colorchecker((32, 48), tc.scenes.default_wavelengths(8))
    code = tc.codes.random_binary((32, 48, 4), rng=0)
    quality = []
    for system in (SDCASSI(code[:, :, 0], n_bands=8, shifts=1), SDCASSI(code, n_bands=8, shifts=1)):
        g = system.simulate(cube, 30.0, rng=1)
        quality.append(
            tc.metrics.psnr(cube, tc.reconstruct(system, g, method="lsq").cube, data_range=1.0)
        )
    assert quality[1] > quality[0] + 2.0, quality


@pytest.mark.parametrize(
    "make",
    [
        lambda c: SDCASSI(c, n_bands=8, shifts=1),
        lambda c: CASSIVSI(c, n_bands=8, alpha_t=0.7),
    ],
    ids=["sd", "vsi"],
)
def test_gap_tv_beats_least_squares(make):
    """Quality floor on a seeded 48×48×8 ColorChecker at 30 dB: GAP-TV ≥ LSQ + 6 dB."""
    cube = tc.scenes.colorchecker((48, 48), tc.scenes.default_wavelengths(8))
    system = make(tc.codes.random_binary((48, 48), rng=0))
    g = system.simulate(cube, 30.0, rng=1)
    lsq = tc.metrics.psnr(cube, tc.reconstruct(system, g, method="lsq").cube, data_range=1.0)
    res = tc.reconstruct(system, g, method="gap_tv", max_iter=40)
    gap = tc.metrics.psnr(cube, res.cube, data_range=1.0)
    assert gap > lsq + 6.0, (gap, lsq)
    assert res.iterations <= 40 and len(res.history["seconds"]) == res.iterations
    assert res.history["residual"][-1] < 0.1


def test_gap_tv_on_blocks_and_options(backend):
    name, dtype = backend
    system = C3SLFI.example((16, 16, 6), n_snapshots=3)
    cube = tc.scenes.colorchecker((16, 16), system.wavelengths)
    g = system.forward(tc._backend.as_tensor(cube, dtype))
    res = tc.reconstruct(system, g, method="gap_tv", max_iter=5, tol=1e-12)
    assert tc._backend.real_dtype_name(res.cube) == dtype and not res.converged
    assert res.options["max_iter"] == 5 and res.iterations == 5
    with pytest.raises(ValueError, match="max_iter must be an integer ≥ 1"):
        tc.reconstruct(system, g, method="gap_tv", max_iter=0)
    with pytest.raises(ValueError, match="tv_weight"):
        tc.reconstruct(system, g, method="gap_tv", tv_weight=-1)


def _scale_problem():
    return tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, rng=0)


@pytest.mark.parametrize(
    "method",
    [
        m
        for m, e in tc.solvers.METHODS.items()
        if e.available
        and m not in ("avsi", "dfa", "pnp_admm", "dcosnet", "split_tv", "lytro")  # other systems
    ],
)
def test_results_do_not_depend_on_the_measurement_units(method):
    p = _scale_problem()
    g = np.asarray(p.measurement)
    opts = {}
    if method == "dl":  # needs a dictionary: one learned on another scene
        other = tc.scenes.scene_cube("coffee", (16, 16), p.system.wavelengths)
        opts["dictionary"] = tc.solvers.train_dictionary([other], patch=4, n_iter=2)
    runs = [(opts, 1e-6)]
    if method == "pnp_fast":  # bfloat16 where native: its rounding, not the units, moves the
        # cube (measured 1.6e-3); in float32 the units do not matter either
        runs = [({"precision": "auto"}, 1e-2), ({"precision": "float32"}, 1e-6)]
    for opts, tolerance in runs:
        ref = np.asarray(tc.reconstruct(p.system, g, method, **opts).cube)
        for scale in (1e-300, 1e-5, 1e300):
            cube = np.asarray(tc.reconstruct(p.system, g * scale, method, **opts).cube)
            assert np.isfinite(cube).all()
            rel = np.linalg.norm(cube / scale - ref) / np.linalg.norm(ref)
            assert rel < tolerance, (method, opts, scale, rel)


def test_zero_constant_and_overflowing_measurements_are_clear_errors():
    p = _scale_problem()
    shape = p.system.measurement_shape
    with pytest.raises(ValueError, match="all zero"):
        tc.reconstruct(p.system, np.zeros(shape), "gap_tv")
    with pytest.raises(ValueError, match="constant"):
        tc.reconstruct(p.system, np.full(shape, 2.0), "lsq")
    with pytest.raises(ValueError, match="NaN or inf"):
        tc.reconstruct(p.system, np.full(shape, np.nan), "lsq")
    # a float32 measurement near the top of its range: the cube (≈ g / code sums · bands) may not
    # fit; then the error says so instead of returning inf
    g32 = (np.asarray(p.measurement) / np.max(p.measurement) * 3e38).astype(np.float32)
    try:
        cube = tc.reconstruct(p.system, g32, "lsq").cube
        assert np.isfinite(cube).all()
    except OverflowError as e:
        assert "rescale the measurement" in str(e)


def test_defaults_are_written_once_in_each_signature():
    import inspect

    for name in tc.solvers.methods():
        entry = tc.solvers.METHODS[name]
        params = list(inspect.signature(entry.func).parameters.values())[2:]
        assert entry.defaults == {p.name: p.default for p in params}, name
    # wdct through reconstruct and called directly agree (they once differed: mu 0.05 vs 0.2)
    assert (
        inspect.signature(tc.solvers.wdct_admm).parameters["mu"].default
        == (tc.solvers.METHODS["wdct"].defaults["mu"])
    )


def test_a_user_method_registers_from_its_signature():
    def mine(system, measurement, *, mu: float = 0.5, progress: bool = False):
        return system.adjoint(measurement) * mu, {"residual": [0.0]}, True

    tc.solvers.register_method("user_sig_test", mine, summary="a test method", replace=True)
    try:
        assert tc.solvers.METHODS["user_sig_test"].defaults == {"mu": 0.5, "progress": False}
    finally:
        tc.solvers.METHODS.unregister("user_sig_test")
    with pytest.raises(ValueError, match="option b has no default"):
        tc.solvers.register_method("user_bad", lambda s, g, b: None)
    with pytest.raises(ValueError, match="options are named one by one"):
        tc.solvers.register_method("user_bad", lambda s, g, **o: None)


def test_a_float16_measurement_is_promoted_to_float32():
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, rng=0)
    g = np.asarray(p.measurement)
    r32 = tc.reconstruct(p.system, g.astype(np.float32), "gap_tv")
    r16 = tc.reconstruct(p.system, g.astype(np.float16), "gap_tv")
    assert r16.cube.dtype == np.float32
    psnr = [tc.studies.score(p, r.cube)["psnr"] for r in (r32, r16)]
    assert abs(psnr[0] - psnr[1]) < 0.2, psnr  # only the input's rounding differs


#: Methods that need more than a measurement (trained weights for 28 bands at 2 px, a dictionary).
_NEED_MORE = ("dcosnet", "dl")


@pytest.mark.parametrize(
    "system, kw",
    [("sd_cassi", {}), ("cassi_vsi", {}), ("cassdi_dfa", {}),
     ("c3slfi", {"n_snapshots": 2, "views": (2, 2)})],
)  # fmt: skip
def test_every_method_keeps_a_float32_measurement_float32(system, kw):
    """A float32 measurement gives a float32 cube with every method: NumPy 2 keeps the type
    of a NumPy float64 scalar, so an ``np.sqrt`` step size once turned TwIST's and FISTA's
    iterates (and everything after them) into float64."""
    p = tc.studies.make_problem(system, "chelsea", shape=(16, 16), n_bands=4, rng=0, **kw)
    op, g = p.system, np.asarray(p.measurement, dtype=np.float32)
    methods = [m for m in tc.solvers.methods(op) if m not in _NEED_MORE]
    if system == "cassdi_dfa":  # with PSFs (band, plane): the methods without CG solves
        psfs = np.random.default_rng(0).random((3, 3, 4, 3)) + 0.1
        op = tc.systems.CASSDIDFA(op.codes, n_bands=4, psfs=psfs)
        g = np.asarray(op.simulate(p.cube, snr_db=30.0, rng=0), dtype=np.float32)
        methods = ["dfa", "split_tv", "twist"]
    for m in methods:
        opts = {"max_iter": 3} if "max_iter" in tc.solvers.METHODS[m].defaults else {}
        with warnings.catch_warnings():  # TwIST's CG solves on blurred DFA: warned, expected
            warnings.simplefilter("ignore", tc.solvers.SlowSolveWarning)
            assert tc.reconstruct(op, g, m, **opts).cube.dtype == np.float32, m


def test_method_metadata_says_which_systems_and_what_is_needed():
    vsi = tc.studies.make_problem("cassi_vsi", "chelsea", shape=(16, 16), n_bands=4)
    sd = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    assert "avsi" in tc.solvers.methods(vsi.system) and "avsi" not in tc.solvers.methods("sd_cassi")
    assert tc.solvers.METHODS["avsi"].systems == ("cassi_vsi",)
    for call in (
        lambda: tc.reconstruct(sd.system, sd.measurement, "avsi"),
        lambda: tc.solvers.avsi(sd.system, sd.measurement),  # called directly: the same check
    ):
        with pytest.raises(ValueError, match="'avsi' reconstructs cassi_vsi systems, got SDCASSI; "
                           "methods for sd_cassi: .*otd"):  # fmt: skip
            call()
    with pytest.raises(ValueError, match="method 'dl' needs dictionary=: a PatchDictionary"):
        tc.reconstruct(sd.system, sd.measurement, "dl", max_iter=0)


def test_a_method_returns_a_method_output_or_the_tuple():
    from tensor_cosdi.solvers import MethodOutput

    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)

    def typed(system, measurement, *, scale: float = 1.0):
        return MethodOutput(system.adjoint(measurement) * scale, {"residual": [0.5]}, True)

    def wrong(system, measurement):
        return system.adjoint(measurement)

    for name, f in (("user_typed_test", typed), ("user_wrong_test", wrong)):
        tc.solvers.register_method(name, f, replace=True)
    try:
        assert tc.reconstruct(p.system, p.measurement, "user_typed_test").converged
        with pytest.raises(TypeError, match="'user_wrong_test' returned ndarray; a method returns"):
            tc.reconstruct(p.system, p.measurement, "user_wrong_test")
    finally:
        for name in ("user_typed_test", "user_wrong_test"):
            tc.solvers.METHODS.unregister(name)


def test_labelled_and_lazy_measurements():
    xr = pytest.importorskip("xarray")
    da = pytest.importorskip("dask.array")
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    g = np.asarray(p.measurement)
    plain = tc.reconstruct(p.system, g, "lsq").cube
    labelled = tc.reconstruct(p.system, xr.DataArray(g, dims=("x", "y")), "lsq").cube
    assert isinstance(labelled, xr.DataArray) and labelled.dims == ("x", "y", "λ")
    np.testing.assert_allclose(labelled["λ"].values, p.system.wavelengths)
    assert labelled["λ"].attrs["units"] == "nm" and labelled.attrs["method"] == "lsq"
    np.testing.assert_array_equal(labelled.values, plain)
    lazy = da.from_array(g, chunks=8)
    with pytest.raises(ValueError, match=r"dask.*compute\(\).*reconstruct_tiled"):
        tc.reconstruct(p.system, lazy, "lsq")
    np.testing.assert_array_equal(tc.reconstruct(p.system, lazy.compute(), "lsq").cube, plain)


CHEAP = ("otd", "gap_tv", "lsq", "wdct", "twist", "avsi", "dfa", "pnp_admm", "otd_nl", "lytro")
CHEAP += ("pnp_gap",) if importlib.util.find_spec("torch") else ()


@pytest.mark.parametrize("system", sorted(tc.systems.REGISTRY))
def test_every_imager_gives_the_same_cube_in_any_measurement_units(system):
    """Every imager, with every cheap method written for it (the thesis' A-VSI, DFA and PnP-ADMM
    on their imagers): a measurement ×1e±300 gives the cube ×1e±300 within 1e-6 (dual-camera
    CASSI's OTD once moved by 22-25 %); 1e-5 for the float32 learned denoiser."""
    p = tc.studies.make_problem(system, "colorchecker", shape=(16, 16), n_bands=4, rng=0)
    g = np.asarray(p.measurement)
    for method in [m for m in tc.solvers.methods(p.system) if m in CHEAP]:
        opts = {"max_iter": 5} if "max_iter" in tc.solvers.METHODS[method].defaults else {}
        if method == "lytro":  # a small K-SVD dictionary
            opts.update(n_patches=500, n_iter=2)
        ref = np.asarray(tc.reconstruct(p.system, g, method, **opts).cube)
        for scale in (1e-300, 1e300):
            cube = np.asarray(tc.reconstruct(p.system, g * scale, method, **opts).cube)
            assert np.isfinite(cube).all(), (system, method, scale)
            rel = np.linalg.norm(cube / scale - ref) / np.linalg.norm(ref)
            # the learned denoiser runs in float32: rounding alone reached 1.1e-6 on one CPU
            assert rel < (1e-5 if method == "pnp_gap" else 1e-6), (system, method, scale, rel)
