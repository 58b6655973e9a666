"""pnp_gap's automatic last denoiser level follows the noise and the run's length."""

import importlib.util
import inspect
from unittest import mock

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.noise import snr_schedule
from tensor_cosdi.solvers.snr import estimate_snr

M = importlib.import_module("tensor_cosdi.solvers.pnp_gap")


@pytest.fixture(scope="module")
def levels():
    """``{options: (sigma_end, n_steps)}`` that pnp_gap hands its denoiser prior (TV denoiser,
    a 30-dB problem)."""
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    seen = {}
    cases = {
        "plain gap, 40": dict(splitting="gap", accelerate=False),
        "admm, 40": dict(max_iter=40),
        "admm, auto": dict(),
        "accelerated, 40": dict(accelerate=True, max_iter=40),
        "accelerated, 200": dict(accelerate=True),
    }
    for name, opts in cases.items():
        with mock.patch.object(M, "Denoiser", side_effect=M.Denoiser) as spy:
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", **opts)
        kw = spy.call_args.kwargs
        seen[name] = (kw["sigma_end"], kw["n_steps"])
    return seen, estimate_snr(p.system, p.measurement).snr_db


def test_short_and_long_runs_and_plain_gap_keep_their_tables(levels):
    seen, snr = levels
    assert seen["admm, 40"] == (snr_schedule(snr, M.SIGMA_END_ADMM_SHORT), 40)
    assert seen["admm, auto"] == (
        snr_schedule(snr, M.SIGMA_END_ADMM),
        round(snr_schedule(snr, M.ADMM_ITER)),
    )
    assert seen["admm, auto"][1] > 50  # a long run: the long table
    assert seen["accelerated, 40"] == (snr_schedule(snr, M.SIGMA_END_SHORT), 40)
    assert seen["accelerated, 200"] == (snr_schedule(snr, M.SIGMA_END), 200)
    # plain GAP's default (20 iterations of two calls, now 40 of one) was tuned with the long
    # table
    assert seen["plain gap, 40"] == (snr_schedule(snr, M.SIGMA_END), 40)
    # a short accelerated run ends higher; pnp_fast's short ADMM run at 30 dB was chosen on
    # the RMS scale with a level just under the long run's (cv_pnp_fast_sigma_scale.md)
    assert seen["accelerated, 40"][0] > seen["accelerated, 200"][0]
    assert seen["admm, 40"][0] != seen["admm, auto"][0]


def test_admm_runs_half_as_long_at_20_db_even_when_nothing_else_needs_the_estimate():
    """At 20 dB the level stays at its floor and more iterations over-smooth: ``max_iter="auto"``
    follows the estimated SNR (80 at a 20-dB reading), also when every other setting is given."""
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=20)
    snr = estimate_snr(p.system, p.measurement).snr_db
    assert snr < 23
    for opts in ({}, dict(splitting="admm", accelerate=False, eps=0.1, sigma_end=0.2)):
        with mock.patch.object(M, "Denoiser", side_effect=M.Denoiser) as spy:
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", **opts)
        n = spy.call_args.kwargs["n_steps"]
        assert n == round(snr_schedule(snr, M.ADMM_ITER)) and 80 <= n < 110, (opts, n)


@pytest.mark.parametrize("option", ["pan_iter", "pan_tv_steps", "pan_atoms"])
def test_first_stage_options_reach_the_otd_start_and_other_starts_refuse_them(option):
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    otd = importlib.import_module("tensor_cosdi.solvers.otd")
    seen = []
    real = otd.online_tucker_admm

    def spy(*args, **kw):
        seen.append(kw.get(option, "default"))
        return real(*args, **kw)

    with mock.patch.object(otd, "online_tucker_admm", side_effect=spy):
        for value in ("auto", 7):
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=2,
                           warm_iter=2, **{option: value})  # fmt: skip
        if option != "pan_iter" and importlib.util.find_spec("torch"):  # pnp_fast passes
            # its first-stage options on too (it needs the learned denoiser, so torch)
            tc.reconstruct(p.system, p.measurement, "pnp_fast", max_iter=1, warm_iter=2,
                           **{option: 5})  # fmt: skip
            assert seen.pop() == 5
    # pnp_gap's own start takes 10 TV steps where OTD's default is 20 (START_PAN_TV_STEPS)
    assert seen == [M.START_PAN_TV_STEPS if option == "pan_tv_steps" else "default", 7]
    with pytest.raises(ValueError, match=f"{option} sets the first stage of the OTD start"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", warm="gap_tv",
                       **{option: 30})  # fmt: skip
    for bad in (0, 2.5, "many", True):
        with pytest.raises(ValueError, match=option):
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", **{option: bad})


def test_pan_spectrum_reaches_the_otd_start_and_other_starts_refuse_it():
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    otd = importlib.import_module("tensor_cosdi.solvers.otd")
    seen = []
    real = otd.online_tucker_admm

    def spy(*args, **kw):
        seen.append(kw["pan_spectrum"])
        return real(*args, **kw)

    with mock.patch.object(otd, "online_tucker_admm", side_effect=spy):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=2, warm_iter=2)
        for value in ("auto", "fitted"):
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=2,
                           warm_iter=2, pan_spectrum=value)  # fmt: skip
        if importlib.util.find_spec("torch"):  # pnp_fast passes it on (the learned denoiser)
            tc.reconstruct(p.system, p.measurement, "pnp_fast", max_iter=1, warm_iter=2,
                           pan_spectrum="fitted_z")  # fmt: skip
            assert seen.pop() == "fitted_z"
    assert seen == [M.PAN_SPECTRUM, "auto", "fitted"]
    with pytest.raises(ValueError, match="pan_spectrum sets the first stage of the OTD start"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", warm="gap_tv",
                       pan_spectrum="auto")  # fmt: skip
    for bad in ("led", None, 1):
        with pytest.raises(ValueError, match=r"pan_spectrum must be one of \('flat'"):
            tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", pan_spectrum=bad)


def test_fast_settings_resolve_the_start_as_pnp_fast_does():
    """``fast_settings(system, g)``: ``pnp_fast``'s own pnp_gap options — its 3 TV steps and
    gated first stage with the OTD start; another start keeps ``pan_tv_steps="auto"`` and takes
    ``"gated"`` as a gate that stays shut (it has no first stage), while ``"fitted"`` is
    refused there; an unknown option is named."""
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    own = M.fast_settings(p.system, p.measurement)
    assert own["pan_tv_steps"] == M.FAST_PAN_TV_STEPS == 3
    assert own["pan_spectrum"] == M.FAST_PAN_SPECTRUM == "gated"
    other = M.fast_settings(p.system, p.measurement, warm="gap_tv")
    assert other["pan_spectrum"] == "gated" and other["pan_tv_steps"] == "auto"
    # the first level is pnp_gap's unless given (a given one reaches pnp_gap)
    assert own["sigma"] == inspect.signature(M.pnp_gap).parameters["sigma"].default == 0.1
    assert M.fast_settings(p.system, p.measurement, sigma=0.2)["sigma"] == 0.2
    for bad in (0, -0.1, float("nan")):
        with pytest.raises(ValueError, match="sigma"):
            M.pnp_fast(p.system, p.measurement, sigma=bad)
    with pytest.raises(ValueError, match=r"\['denoiser'\] are not options of pnp_fast"):
        M.fast_settings(p.system, p.measurement, denoiser="tv")
    run = {**other, "precision": "float32", "max_iter": 1, "warm_iter": 2}
    gated = tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", **run)
    flat = tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv",
                          **{**run, "pan_spectrum": "flat"})  # fmt: skip
    np.testing.assert_array_equal(gated.cube, flat.cube)
    with pytest.raises(ValueError, match="pan_spectrum sets the first stage of the OTD start"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv",
                       **{**run, "pan_spectrum": "fitted"})  # fmt: skip


def test_fast_budget_spends_the_start_on_iterations_on_clean_data_only():
    """``pnp_fast``'s budget: on a clean measurement from OTD's first stage (any number of
    axes), that stage's cube alone and :data:`FAST_ITER_CLEAN` iterations; on a noisy one,
    without a first stage (an exact panchromatic image) or from another start, 10 ADMM
    iterations of the start and 46; given values are kept; a bad start is named."""
    clean = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)  # reads 41.5 dB
    noisy = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=30)
    assert estimate_snr(clean.system, clean.measurement).snr_db > M.ACCELERATE_ABOVE_DB
    fast, slow = (M.FAST_WARM_ITER_CLEAN, M.FAST_ITER_CLEAN), (M.FAST_WARM_ITER, M.FAST_ITER)
    assert fast == (0, M.FAST_ITER_CLEAN) and slow == (10, 46) and M.FAST_ITER_CLEAN > 46

    def budget(p, **kw):  # the budget of a network in bfloat16 (float32 on a CPU: below)
        s = M.fast_settings(p.system, p.measurement, precision="bfloat16", **kw)
        return s["warm_iter"], s["max_iter"], s["sigma_end"]

    assert budget(clean) == (*fast, M.FAST_SIGMA_END_CLEAN) and budget(noisy) == (*slow, "auto")
    assert budget(clean, warm="gap_tv") == (*slow, "auto")
    assert budget(clean, max_iter=10) == (0, 10, 0.04)
    assert budget(clean, warm_iter=3, sigma_end=0.1) == (3, fast[1], 0.1)
    dual = tc.systems.DualCameraCASSI.example((8, 8, 4))
    g = dual.simulate(np.random.default_rng(0).random(dual.cube_shape))
    assert M.fast_budget(dual, g, precision="bfloat16") == {
        "warm_iter": 10, "max_iter": 46, "sigma_end": "auto"
    }  # fmt: skip
    phases = tc.studies.make_problem("cs2li", "colorchecker", snr_db=None)  # four axes
    assert estimate_snr(phases.system, phases.measurement).snr_db > M.ACCELERATE_ABOVE_DB
    assert (
        M.fast_budget(phases.system, phases.measurement, precision="bfloat16")["max_iter"]
        == M.FAST_ITER_CLEAN
    )
    with pytest.raises(ValueError, match="warm must be one of"):
        M.fast_budget(clean.system, clean.measurement, warm="tv")


def test_fast_budget_spends_fewer_calls_where_the_network_runs_in_float32_on_a_cpu(monkeypatch):
    """Where the learned denoiser's network runs in float32 on a CPU (a call about twice as
    long as in bfloat16) ``pnp_fast`` takes the float32 budgets, fewer iterations than the
    bfloat16 ones on clean and on noisy data; on CUDA float32 keeps the full budget; given
    values are still kept and a bad precision is named."""
    torch = pytest.importorskip("torch")
    from tensor_cosdi.learn import spectral_net

    clean = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)
    noisy = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=30)
    full_clean = M.fast_budget(clean.system, clean.measurement, precision="bfloat16")
    full_noisy = M.fast_budget(noisy.system, noisy.measurement, precision="bfloat16")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)  # a CPU-only machine
    assert M.float32_on_cpu(clean.measurement, "float32")
    assert not M.float32_on_cpu(clean.measurement, "bfloat16")
    assert M.float32_on_cpu(clean.measurement) == (not spectral_net.bfloat16_is_fast())
    low_clean = M.fast_budget(clean.system, clean.measurement, precision="float32")
    low_noisy = M.fast_budget(noisy.system, noisy.measurement, precision="float32")
    snr = estimate_snr(noisy.system, noisy.measurement).snr_db
    assert low_clean == M.FAST_CLEAN_FLOAT32
    assert low_noisy == {
        "warm_iter": round(snr_schedule(snr, M.FAST_WARM_ITER_FLOAT32)),
        "max_iter": round(snr_schedule(snr, M.FAST_ITER_FLOAT32)),
        "sigma_end": round(snr_schedule(snr, M.FAST_SIGMA_END_FLOAT32), 4),
    }
    assert 5 <= low_noisy["warm_iter"] <= 10 and 18 <= low_noisy["max_iter"] <= 22
    assert 0.055 <= low_noisy["sigma_end"] <= 0.2  # between the SNR anchors
    # the level is on the RMS scale: on the peak scale it stays pnp_gap's own "auto"
    peak = M.fast_budget(noisy.system, noisy.measurement, precision="float32", sigma_scale="peak")
    assert peak == {**low_noisy, "sigma_end": "auto"}
    assert M.fast_settings(noisy.system, noisy.measurement, precision="float32",
                           sigma_scale="peak")["sigma_end"] == "auto"  # fmt: skip
    with pytest.raises(ValueError, match="sigma_scale must be 'auto' or one of"):
        M.fast_budget(noisy.system, noisy.measurement, precision="float32", sigma_scale="max")
    assert low_clean["max_iter"] < full_clean["max_iter"]
    assert low_noisy["max_iter"] < full_noisy["max_iter"]
    assert low_clean["warm_iter"] == full_clean["warm_iter"] == 0  # the first stage alone
    s = M.fast_settings(noisy.system, noisy.measurement, precision="float32", max_iter=40)
    assert (s["max_iter"], s["warm_iter"]) == (40, low_noisy["warm_iter"])
    auto = M.fast_settings(noisy.system, noisy.measurement)
    assert auto["max_iter"] == (low_noisy if M.float32_on_cpu(noisy.measurement) else
                                full_noisy)["max_iter"]  # fmt: skip
    with pytest.raises(ValueError, match="precision must be one of"):
        M.fast_budget(noisy.system, noisy.measurement, precision="half")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)  # the network on CUDA
    assert not M.float32_on_cpu(clean.measurement, "float32")
    assert M.fast_budget(clean.system, clean.measurement, precision="float32") == full_clean
    cpu_tensor = torch.as_tensor(np.asarray(clean.measurement))  # a CPU tensor stays there
    assert M.float32_on_cpu(cpu_tensor, "float32")


@pytest.mark.parametrize(
    "options, message",
    [
        ({"warm": "gap_tv", "warm_iter": 0}, "warm='gap_tv' needs warm_iter ≥ 1"),
        ({"warm_iter": -1}, "warm_iter must be an integer ≥ 0, got -1"),
        ({"warm_iter": "short"}, "warm_iter must be 'auto' or an integer ≥ 0, got 'short'"),
    ],
)
def test_bad_warm_iter_is_named(options, message):
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    with pytest.raises(ValueError, match=message):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", **options)


def test_warm_iter_auto_is_the_first_stage_alone_on_clean_data_only(monkeypatch):
    """``pnp_gap(warm_iter="auto")``: OTD's first stage alone (``admm_iter=0``) on a clean
    measurement run with accelerated GAP; OTD's own ADMM stage on noisy data, with plain GAP,
    or where a value is given."""
    from tensor_cosdi.solvers import otd

    seen, real = [], otd.online_tucker_admm

    def spy(*args, **kwargs):
        seen.append(kwargs["admm_iter"])
        return real(*args, **kwargs)

    monkeypatch.setattr(otd, "online_tucker_admm", spy)
    clean = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=None)  # reads 41.5 dB
    noisy = tc.studies.make_problem("sd_cassi", "colorchecker", snr_db=30)
    run = {"denoiser": "tv", "max_iter": 1}
    for p, extra in ((clean, {}), (noisy, {}), (clean, {"accelerate": False}),
                     (clean, {"warm_iter": 3})):  # fmt: skip
        tc.reconstruct(p.system, p.measurement, "pnp_gap", **run, **extra)
    assert seen == [M.WARM_ITER_CLEAN, "auto", "auto", 3] and M.WARM_ITER_CLEAN == 0


def test_warm_iter_0_starts_from_the_first_stage_alone(monkeypatch):
    """``warm="otd", warm_iter=0``: the denoiser's iterations start from OTD's first-stage cube
    (what ``otd(admm_iter=0)`` returns); refused, naming the system, where there is no first
    stage."""
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    first = tc.reconstruct(p.system, p.measurement, "otd", admm_iter=0, pan_spectrum="flat",
                           pan_tv_steps=M.START_PAN_TV_STEPS)  # fmt: skip
    starts, real = [], M.engine.gap

    def gap(operator, g, prior, *, start=None, **kwargs):
        if not isinstance(prior, M.Denoiser):  # the first stage's own GAP
            return real(operator, g, prior, start=start, **kwargs)
        starts.append(np.asarray(start))
        return start, {k: [] for k in ("objective", "residual", "change", "seconds")}, False

    monkeypatch.setattr(M.engine, "gap", gap)
    tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", warm_iter=0,
                   pan_spectrum="flat", max_iter=1, splitting="gap")  # fmt: skip
    assert len(starts) == 1  # the methods see the measurement scaled to a peak of 1
    peak = float(np.abs(np.asarray(p.measurement)).max())
    np.testing.assert_allclose(starts[0] * peak, np.asarray(first.cube), rtol=1e-6, atol=1e-9)
    dual = tc.systems.DualCameraCASSI.example((8, 8, 4))
    g = dual.simulate(np.random.default_rng(0).random(dual.cube_shape))
    with pytest.raises(ValueError, match="DualCameraCASSI has none"):
        tc.reconstruct(dual, g, "pnp_gap", denoiser="tv", warm_iter=0)


def test_gated_first_stage_is_the_plain_one_where_no_gate_can_be_read():
    """A system with two panchromatic axes (CASSDI-DFA) or few bands has no gate to read:
    ``pan_spectrum="gated"`` and ``"gated_clean"`` run the plain stage there (``"fitted"``
    refuses two axes)."""
    from tensor_cosdi.solvers.panchromatic import panchromatic_estimate

    for name, bands in (("cassdi_dfa", 8), ("sd_cassi", 8)):
        p = tc.studies.make_problem(name, "chelsea", shape=(32, 32), n_bands=bands)
        flat = panchromatic_estimate(p.system, p.measurement, pan_iter=5, pan_spectrum="flat")
        for value in ("gated", "gated_clean"):
            gated = panchromatic_estimate(p.system, p.measurement, pan_iter=5, pan_spectrum=value)
            np.testing.assert_array_equal(gated[0], flat[0])
    with pytest.raises(ValueError, match="needs one panchromatic axis"):
        p = tc.studies.make_problem("cassdi_dfa", "chelsea", shape=(32, 32), n_bands=28)
        panchromatic_estimate(p.system, p.measurement, pan_iter=5, pan_spectrum="fitted")


def test_denoiser_level_follows_the_peak_or_the_mean_brightness():
    """``scale="peak"``: the level is relative to the start's robust peak, whatever its mean;
    ``scale="rms"``: to PEAK_PER_RMS times its RMS, so a darker scene with the same highlights
    gets a lower level (as the noise of a measurement at a given SNR is lower)."""
    from tensor_cosdi.solvers import priors

    rng = np.random.default_rng(0)
    bright = rng.uniform(0.4, 0.6, (32, 32, 8))
    bright[:4, :4] = 1.0  # the highlights: above the 99.9th percentile either way
    dark = bright.copy()
    dark[4:] *= 0.25
    levels = {}
    for scale in priors.LEVEL_SCALES:
        for name, start in (("bright", bright), ("dark", dark)):
            d = priors.Denoiser("tv", sigma=0.1, scale=scale)
            d.setup(start, penalty=1.0, gain=1.0)
            levels[scale, name] = d.current_sigma()
    assert levels["peak", "bright"] == pytest.approx(0.1 * priors.robust_peak(bright))
    assert levels["peak", "dark"] == pytest.approx(levels["peak", "bright"])
    for name, start in (("bright", bright), ("dark", dark)):
        assert levels["rms", name] == pytest.approx(0.1 * priors.PEAK_PER_RMS * priors.rms(start))
    ratio = priors.rms(dark) / priors.rms(bright)
    assert ratio < 0.5
    assert levels["rms", "dark"] / levels["rms", "bright"] == pytest.approx(ratio)


@pytest.mark.parametrize("bad", ["max", "RMS", None, 1.0])
def test_a_level_scale_that_is_not_one_of_the_two_is_refused(bad):
    from tensor_cosdi.solvers import priors

    with pytest.raises(ValueError, match="scale must be one of"):
        priors.Denoiser("tv", sigma=0.1, scale=bad)
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    with pytest.raises(ValueError, match="sigma_scale must be 'auto' or one of"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", sigma_scale=bad)


def test_sigma_scale_auto_follows_the_splitting():
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
    seen = {}
    for splitting in ("gap", "admm"):
        for scale in ("auto", "peak", "rms"):
            with mock.patch.object(M, "Denoiser", side_effect=M.Denoiser) as spy:
                tc.reconstruct(
                    p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=3,
                    splitting=splitting, sigma_scale=scale,
                )  # fmt: skip
            seen[splitting, scale] = spy.call_args.kwargs["scale"]
    for splitting in ("gap", "admm"):
        assert seen[splitting, "auto"] == M.SIGMA_SCALE[splitting]
        assert seen[splitting, "peak"] == "peak" and seen[splitting, "rms"] == "rms"


def test_a_cube_with_more_axes_keeps_the_peak_and_its_own_tables():
    """The RMS scale is for spectral cubes (x, y, λ); CASSDI-DFA's depth planes dilute the RMS
    by the planes a pixel does not occupy, so such a cube keeps the peak and the levels chosen
    on it; a forced ``sigma_scale="peak"`` takes those levels on a spectral cube too."""
    seen = {}
    for name in ("sd_cassi", "cassdi_dfa"):
        p = tc.studies.make_problem(name, "chelsea", shape=(32, 32), n_bands=8, snr_db=30)
        snr = estimate_snr(p.system, p.measurement).snr_db
        for scale in ("auto", "peak"):
            with mock.patch.object(M, "Denoiser", side_effect=M.Denoiser) as spy:
                tc.reconstruct(
                    p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=3,
                    splitting="admm", sigma_scale=scale,
                )  # fmt: skip
            kw = spy.call_args.kwargs
            seen[name, scale] = (kw["scale"], kw["sigma_end"], snr)
    s3 = seen["sd_cassi", "auto"][2]
    s4 = seen["cassdi_dfa", "auto"][2]
    assert seen["sd_cassi", "auto"][:2] == ("rms", snr_schedule(s3, M.SIGMA_END_ADMM_SHORT))
    assert seen["sd_cassi", "peak"][:2] == ("peak", snr_schedule(s3, M.SIGMA_END_ADMM_SHORT_PEAK))
    for scale in ("auto", "peak"):
        assert seen["cassdi_dfa", scale][:2] == (
            "peak",
            snr_schedule(s4, M.SIGMA_END_ADMM_SHORT_PEAK),
        )
