"""The divergence guard of accelerated GAP (``engine.gap(guard=…)``, on by default in PnP-GAP)."""

import numpy as np
import pytest
import tensorly as tl
from scipy.ndimage import gaussian_filter

import tensor_cosdi as tc
from tensor_cosdi.solvers import engine
from tensor_cosdi.solvers.priors import Denoiser


def _sharpen(x, sigma):
    """An expansive 'denoiser' (unsharp masking): accelerated GAP's feedback diverges with it."""
    return x + 0.6 * (x - gaussian_filter(x, (1, 1, 0)))


@pytest.fixture(scope="module")
def problem():
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(32, 32), n_bands=8, rng=0)
    return p.system.operator, np.asarray(p.measurement, dtype=np.float64)


def _residual(op, x, g):
    return float(tl.norm(op.forward(x) - g)) / float(tl.norm(g))


def test_unguarded_accelerated_gap_diverges_with_an_expansive_prior(problem):
    op, g = problem
    x, hist, conv = engine.gap(op, g, Denoiser(_sharpen, sigma=0.1), max_iter=30)
    assert not conv
    assert hist["residual"][-1] > 3 * min(hist["residual"])  # the failure the guard is for


def test_guard_returns_the_lowest_residual_iterate(problem):
    op, g = problem
    x, hist, conv = engine.gap(op, g, Denoiser(_sharpen, sigma=0.1), max_iter=30, guard=1.3)
    assert not conv
    assert len(hist["residual"]) < 30  # stopped early
    best = min(hist["residual"])
    assert _residual(op, x, g) == pytest.approx(best, rel=1e-9)
    after = hist["residual"][hist["residual"].index(best) :]
    assert after[-1] > 1.3 * best  # why it stopped: three rises in a row, above the guard
    assert all(b > a for a, b in zip(after[-4:], after[-3:]))


def test_guard_does_not_change_a_converging_run(problem):
    op, g = problem
    prior = lambda: Denoiser("tv", sigma=0.05)  # noqa: E731
    a, ha, _ = engine.gap(op, g, prior(), max_iter=20)
    b, hb, _ = engine.gap(op, g, prior(), max_iter=20, guard=1.3)
    assert len(ha["residual"]) == len(hb["residual"])
    assert np.array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("bad", [1.0, 0.5, -2.0])
def test_guard_must_be_a_ratio_above_one(problem, bad):
    op, g = problem
    with pytest.raises(ValueError, match="guard must be a finite number > 1"):
        engine.gap(op, g, Denoiser("tv", sigma=0.05), guard=bad)


# ---- geometric self-ensemble of a denoiser (pnp_gap(ensemble=…)) ------------------------------
def test_self_ensemble_averages_over_the_symmetries():
    from tensor_cosdi.solvers.denoisers import self_ensemble

    x = np.random.default_rng(1).random((6, 5, 3))
    # a denoiser that is not symmetric: it shifts the image down by one row
    down = lambda v, s: np.roll(v, 1, axis=0)  # noqa: E731
    two = self_ensemble(down, 2)(x, 0.1)
    flipped = np.roll(x[::-1], 1, axis=0)[::-1]  # = rolled up by one row
    assert np.allclose(two, (np.roll(x, 1, axis=0) + flipped) / 2)
    assert not np.allclose(two, down(x, 0.1))
    # a symmetric (pointwise) denoiser is unchanged by any ensemble, transposes included
    for n in (1, 2, 4, 8):
        assert np.allclose(self_ensemble(lambda v, s: v**2, n)(x, 0.1), x**2)


@pytest.mark.parametrize("n", [1, 2, 4])
def test_cycled_self_ensemble_moves_through_the_eight_symmetries(n):
    """Call ``i`` sees symmetries ``n·i … n·i + n − 1`` (mod 8), undoes each, and hands back the
    input's memory order; a call averages its ``n`` terms as without cycling."""
    from tensor_cosdi.solvers.denoisers import self_ensemble

    def symmetry(v, k):  # the documented order: flip rows, flip columns, then transpose
        v = v[::-1] if k & 1 else v
        v = v[:, ::-1] if k & 2 else v
        return np.swapaxes(v, 0, 1) if k & 4 else v

    x = np.asfortranarray(np.random.default_rng(4).random((6, 6, 3)))
    seen = []

    def record(v, s):
        seen.append(next(k for k in range(8) if np.array_equal(v, symmetry(x, k))))
        return 2 * v

    den = self_ensemble(record, n, cycle=True)
    for _ in range(10 // n + 1):
        out = den(x, 0.1)
        assert np.allclose(out, 2 * x) and out.flags.f_contiguous
    assert seen == [k % 8 for k in range(len(seen))] and len(seen) > 8
    # the same wrapper without cycling starts at the identity every call
    seen.clear()
    plain = self_ensemble(record, n)
    plain(x, 0.1), plain(x, 0.1)
    assert seen == list(range(n)) * 2
    # a denoiser with no symmetry (it shifts by one row and two columns): cycling changes what
    # a call returns, from the second call on
    down = lambda v, s: np.roll(v, (1, 2), axis=(0, 1))  # noqa: E731
    cyc, fixed = self_ensemble(down, n, cycle=True), self_ensemble(down, n)
    assert np.allclose(cyc(x, 0.1), fixed(x, 0.1))
    assert not np.allclose(cyc(x, 0.1), fixed(x, 0.1))
    with pytest.raises(ValueError, match="cycle must be True or False"):
        self_ensemble(down, n, cycle="yes")


def test_pnp_gap_cycle_is_checked_and_changes_the_result():
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4)
    down = lambda v, s: 0.5 * (v + np.roll(v, 1, axis=0))  # noqa: E731  (not symmetric)
    kw = {"denoiser": down, "warm": "none", "max_iter": 4}
    on = tc.reconstruct(p.system, p.measurement, "pnp_gap", cycle=True, **kw).cube
    off = tc.reconstruct(p.system, p.measurement, "pnp_gap", cycle=False, **kw).cube
    assert not np.allclose(on, off)
    with pytest.raises(ValueError, match="cycle must be True or False"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", cycle=1, **kw)


@pytest.mark.parametrize("bad", [0, 3, 16, True, "2", "fast"])
def test_self_ensemble_sizes(bad):
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4)
    with pytest.raises(ValueError, match="ensemble size must be"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", warm="none", ensemble=bad)


def test_pnp_gap_ensemble_runs_the_denoiser_n_times():
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(16, 16), n_bands=4)
    calls = []

    def den(x, s):
        calls.append(x.shape)
        return x

    run = lambda splitting: tc.reconstruct(  # noqa: E731
        p.system, p.measurement, "pnp_gap", denoiser=den, warm="none", max_iter=3, ensemble=8,
        splitting=splitting,
    )  # fmt: skip
    run("gap")
    assert len(calls) == 3 * 8
    run("admm")  # ADMM denoises its start too
    assert len(calls) == 3 * 8 + 4 * 8


# ---- plug-and-play ADMM on noisy data, non-negative denoiser output ----------------------------
def test_denoiser_prior_projects_onto_nonnegative_values_when_asked():
    x = np.random.default_rng(2).standard_normal((6, 5, 3))
    shift = lambda v, s: v - 0.5  # noqa: E731  (a biased "denoiser" with negative output)
    for nonneg in (False, True):
        prior = Denoiser(shift, sigma=0.1, nonneg=nonneg)
        prior.setup(np.abs(x), penalty=1.0, gain=1.0)
        out = prior.prox(x)
        assert np.allclose(out, np.maximum(x - 0.5, 0) if nonneg else x - 0.5)


def test_nonnegativity_keeps_pnp_admm_bounded_on_weakly_coded_pixels():
    # A code with a patch of 1 % transmission (like the TSA mask's dark patch): those voxels are
    # almost unobserved, so x ≈ z − u there and a denoiser with a negative bias drives z down by
    # the bias every iteration.  With z ≥ 0 the patch stays bounded.
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(24, 24), n_bands=4, rng=0)
    code = np.asarray(p.system.code, dtype=float).copy()
    code[8:16, 8:16] = 0.01
    system = tc.systems.SDCASSI(code, n_bands=4, shifts=1)
    g = system.simulate(np.asarray(p.cube), snr_db=20, rng=0)
    biased = lambda v, s: v - 0.02  # noqa: E731
    runs = {}
    for nonneg in (False, True):
        runs[nonneg] = tc.reconstruct(
            system, g, "pnp_gap", denoiser=biased, warm="none", splitting="admm",
            max_iter=60, nonneg=nonneg,
        ).cube  # fmt: skip
    patch = (slice(8, 16), slice(8, 16))
    assert float(np.min(runs[True])) >= 0
    assert float(np.min(runs[False][patch])) < -0.5  # drifted 60 × 0.02 below the truth
    err = {k: float(np.abs(v[patch] - np.asarray(p.cube)[patch]).mean()) for k, v in runs.items()}
    assert err[True] < 0.5 * err[False], err


def test_pnp_gap_splits_by_the_estimated_snr(monkeypatch):
    seen = []
    real_gap, real_admm = engine.gap, engine.admm

    def spy_gap(*args, **kwargs):
        seen.append(("gap", kwargs["accelerate"]))
        return real_gap(*args, **kwargs)

    def spy_admm(*args, **kwargs):
        seen.append(("admm", kwargs["rho"]))
        return real_admm(*args, **kwargs)

    monkeypatch.setattr(engine, "gap", spy_gap)
    monkeypatch.setattr(engine, "admm", spy_admm)
    from tensor_cosdi.solvers.pnp_gap import ACCELERATE_ABOVE_DB, RHO

    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(24, 24), n_bands=4, rng=0)
    run = lambda g, **kw: tc.reconstruct(  # noqa: E731
        p.system, g, "pnp_gap", denoiser="tv", warm="none", max_iter=2, **kw
    )
    from tensor_cosdi.solvers.snr import SNREstimate

    def reads(db):
        return lambda system, g, **kw: SNREstimate(db, db, db)

    monkeypatch.setattr("tensor_cosdi.solvers.snr.estimate_snr", reads(ACCELERATE_ABOVE_DB + 5))
    run(p.measurement)
    monkeypatch.setattr("tensor_cosdi.solvers.snr.estimate_snr", reads(25.0))
    run(p.measurement)
    run(p.measurement, splitting="gap")  # explicit GAP: plain GAP on noisy data
    run(p.measurement, accelerate=False)  # an explicit GAP setting picks GAP
    run(p.measurement, rho=0.5)
    assert seen == [("gap", True), ("admm", RHO), ("gap", False), ("gap", False), ("admm", 0.5)]
    for bad, match in (
        ({"splitting": "fista"}, "splitting must be one of"),
        ({"rho": -1}, "rho must be"),
        ({"rho": "big"}, "rho must be"),
        ({"nonneg": "yes"}, "nonneg must be True or False"),
    ):
        with pytest.raises(ValueError, match=match):
            run(p.measurement, **bad)


def test_a_step_takes_the_place_of_the_prox_and_its_change(problem):
    """``engine.gap(step=…)``: a step computing ``prior.prox(x + w)`` and its relative change
    gives the default run's iterates bit for bit; a step that damps the update gives another
    run; a step that is not callable is refused before any work."""
    from tensor_cosdi.solvers._base import relative_change
    from tensor_cosdi.solvers.priors import TV

    op, g = problem
    ref, ref_hist, _ = engine.gap(op, g, TV(0.05), max_iter=8)
    prior, seen = TV(0.05), []

    def step(x, w):
        seen.append(w.shape)
        x_new = prior.prox(x + w)
        return x_new, relative_change(x_new, x)

    got, hist, _ = engine.gap(op, g, prior, max_iter=8, step=step)
    np.testing.assert_array_equal(got, ref)
    assert hist["change"] == ref_hist["change"] and len(seen) == 8
    damped, _, _ = engine.gap(
        op, g, TV(0.05), max_iter=8, step=lambda x, w: (x + 0.5 * w, 0.5)
    )  # fmt: skip
    assert np.linalg.norm(damped - ref) > 1e-3 * np.linalg.norm(ref)
    with pytest.raises(ValueError, match="step must be a callable"):
        engine.gap(op, g, TV(0.05), step="prox")
