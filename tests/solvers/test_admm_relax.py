"""ADMM's over-relaxation (``engine.admm(relax=…)``) and its option in the plug-and-play methods."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.solvers import engine
from tensor_cosdi.solvers.priors import NonNegative, Ridge


@pytest.fixture(scope="module")
def problem():
    p = tc.studies.make_problem(
        "sd_cassi", "colorchecker", shape=(16, 16), n_bands=4, snr_db=30, rng=0
    )
    return p.system.operator, np.asarray(p.measurement, dtype=np.float64)


def _solve(op, g, relax, n):
    # a penalty well above the problem's curvature: plain ADMM creeps, the regime relaxation is for
    x, hist, _ = engine.admm(
        op, g, NonNegative(Ridge(0.05)), rho=5.0, max_iter=n, tol=1e-14, relax=relax
    )
    return np.asarray(x), hist


def test_over_relaxation_reaches_the_same_minimiser_sooner(problem):
    op, g = problem  # non-negative ridge: strongly convex, one minimiser
    ref, _ = _solve(op, g, 1.0, 3000)
    again, _ = _solve(op, g, 1.8, 3000)
    assert np.linalg.norm(again - ref) < 1e-6 * np.linalg.norm(ref)
    err = {a: np.linalg.norm(_solve(op, g, a, 10)[0] - ref) for a in (1.0, 1.5, 1.8)}
    assert err[1.8] < 0.7 * err[1.5] and err[1.5] < 0.5 * err[1.0], err


def test_under_relaxation_is_slower_and_one_is_plain_admm(problem):
    op, g = problem
    ref, _ = _solve(op, g, 1.0, 3000)
    plain = np.linalg.norm(_solve(op, g, 1.0, 10)[0] - ref)
    assert np.linalg.norm(_solve(op, g, 0.6, 10)[0] - ref) > 2 * plain
    x, _, _ = engine.admm(op, g, NonNegative(Ridge(0.05)), rho=5.0, max_iter=10, tol=1e-14)
    assert np.array_equal(np.asarray(x), _solve(op, g, 1.0, 10)[0])


@pytest.mark.parametrize("bad", [0, 2, 2.5, -1, True, float("nan"), "fast", None])
def test_admm_refuses_a_relaxation_outside_0_2(problem, bad):
    op, g = problem
    with pytest.raises(ValueError, match=r"relax must be a number in \(0, 2\)"):
        engine.admm(op, g, Ridge(0.05), rho=0.5, max_iter=2, relax=bad)


@pytest.fixture
def seen(monkeypatch):
    """The ``relax`` of every ``engine.admm`` call, in order."""
    calls, real = [], engine.admm

    def spy(*args, **kwargs):
        calls.append(kwargs.get("relax"))
        return real(*args, **kwargs)

    monkeypatch.setattr(engine, "admm", spy)
    return calls


#: A two-iteration PnP-ADMM with the TV denoiser from the least-norm start.
QUICK_ADMM = {"denoiser": "tv", "warm": "none", "max_iter": 2, "splitting": "admm"}


def test_the_plug_and_play_methods_hand_their_relaxation_to_admm(seen):
    from tensor_cosdi.solvers.pnp_gap import FAST_RELAX, RELAX

    p = tc.studies.make_problem(
        "sd_cassi", "colorchecker", shape=(24, 24), n_bands=4, snr_db=25, rng=0
    )
    kw = QUICK_ADMM
    tc.reconstruct(p.system, p.measurement, "pnp_gap", **kw)
    tc.reconstruct(p.system, p.measurement, "pnp_gap", relax=1.3, **kw)
    from tensor_cosdi.noise import snr_schedule
    from tensor_cosdi.solvers.pnp_gap import fast_settings
    from tensor_cosdi.solvers.snr import estimate_snr

    snr = estimate_snr(p.system, p.measurement).snr_db
    assert 19.5 < snr < 28.5  # between the anchors: log-linear, rounded
    assert fast_settings(p.system, p.measurement)["relax"] == round(
        snr_schedule(snr, FAST_RELAX), 2
    )
    assert fast_settings(p.system, p.measurement, relax=1.2)["relax"] == 1.2
    assert seen == [round(snr_schedule(snr, RELAX), 2), 1.3]
    for bad in (2, 0, "big", True, float("inf")):
        with pytest.raises(ValueError, match="relax must be 'auto' or a number in"):
            tc.reconstruct(p.system, p.measurement, "pnp_gap", relax=bad, **kw)
        with pytest.raises(ValueError, match="relax must be 'auto' or a number in"):
            fast_settings(p.system, p.measurement, relax=bad)


def test_a_system_that_opts_out_keeps_plain_admm(seen):
    """C3SLFI (``admm_relax = False``: over-relaxation cost PSNR there) takes ``relax=1`` under
    ``"auto"`` in both methods; a value given is still used."""
    from tensor_cosdi.solvers.pnp_gap import fast_settings

    p = tc.studies.make_problem("c3slfi", "colorchecker", shape=(16, 16), n_bands=4, snr_db=25)
    assert p.system.admm_relax is False
    assert tc.systems.SDCASSI(np.ones((8, 8)), n_bands=4).admm_relax is True
    assert fast_settings(p.system, p.measurement)["relax"] == 1.0
    assert fast_settings(p.system, p.measurement, relax=1.7)["relax"] == 1.7
    kw = QUICK_ADMM
    tc.reconstruct(p.system, p.measurement, "pnp_gap", **kw)
    tc.reconstruct(p.system, p.measurement, "pnp_gap", relax=1.7, **kw)
    assert seen == [1.0, 1.7]
