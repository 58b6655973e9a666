"""The PyTorch backend end to end: a seeded problem, reconstruction, scores, metrics and figures
give what NumPy gives, for every imager."""

import importlib.util

import numpy as np
import pytest
import tensorly as tl

import tensor_cosdi as tc

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="PyTorch is not installed"
)

METHODS = {"lsq": {}, "gap_tv": {"max_iter": 5}, "otd": {"max_iter": 5, "pan_iter": 5}}


def run(backend, system):
    previous = tl.get_backend()
    tl.set_backend(backend)
    try:
        p = tc.studies.make_problem(system, "coffee", shape=(32, 32), n_bands=8, snr_db=30)
        out = {"problem": p, "g": np.array(tc._backend.to_numpy(p.measurement))}
        for m, opts in METHODS.items():
            r = tc.reconstruct(p.system, p.measurement, m, **opts)
            out[m] = (r.cube, np.array(tc._backend.to_numpy(r.cube)), tc.studies.score(p, r.cube))
        return out
    finally:
        tl.set_backend(previous)


@pytest.mark.parametrize("system", list(tc.systems.REGISTRY))
def test_every_imager_runs_on_torch_as_on_numpy(system):
    import torch

    assert_same(run("numpy", system), run("pytorch", system), torch)


@pytest.mark.parametrize("system", ["sd_cassi", "cs2li"])
def test_the_accelerator_path_gives_what_numpy_gives(system, monkeypatch):
    """TV, HOSVD Grams, percentiles and TV objectives in backend operations: the path a CUDA
    tensor takes, forced here on CPU tensors (no GPU in CI)."""
    import torch

    monkeypatch.setattr(tc._backend, "on_accelerator", torch.is_tensor)
    assert_same(run("numpy", system), run("pytorch", system), torch)


def assert_same(ref, got, torch):
    assert isinstance(got["problem"].measurement, torch.Tensor)
    assert isinstance(got["problem"].cube, torch.Tensor)
    np.testing.assert_allclose(got["g"], ref["g"], rtol=1e-6, atol=1e-9)
    for m in METHODS:
        cube, host, score = got[m]
        assert isinstance(cube, torch.Tensor), m
        np.testing.assert_allclose(host, ref[m][1], rtol=1e-3, atol=1e-4 * np.abs(ref[m][1]).max())
        assert score["psnr"] == pytest.approx(ref[m][2]["psnr"], abs=0.05), m


def test_metrics_and_figures_take_torch_tensors():
    import matplotlib

    matplotlib.use("Agg")
    torch = pytest.importorskip("torch")
    p = tc.studies.make_problem("sd_cassi", "coffee", shape=(32, 32), n_bands=8, snr_db=30)
    est = tc.reconstruct(p.system, p.measurement, "lsq").cube
    t_truth, t_est = torch.from_numpy(np.asarray(p.cube)), torch.from_numpy(np.asarray(est))
    for f in (tc.metrics.psnr, tc.metrics.ssim, tc.metrics.sam):
        assert f(t_truth, t_est) == pytest.approx(f(p.cube, est), rel=1e-9)
    a = tc.plot.preview(t_est, p.wavelengths).images[0].get_array()
    b = tc.plot.preview(est, p.wavelengths).images[0].get_array()
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    titles = [ax.get_title() for ax in tc.plot.compare(t_truth, {"lsq": t_est}, p.wavelengths).axes]
    score = f"{tc.metrics.psnr(p.cube, est, data_range=float(np.max(p.cube))):.2f} dB"
    assert any(t.startswith("lsq") and score in t for t in titles), titles


def test_tv_objective_and_robust_peak_stay_on_an_accelerator():
    torch = pytest.importorskip("torch")
    from tensor_cosdi import _backend
    from tensor_cosdi.solvers.priors import robust_peak, total_variation

    x = np.random.default_rng(6).standard_normal((30, 20, 7)).astype(np.float32)
    t = torch.from_numpy(x)
    with pytest.MonkeyPatch.context() as mp, tl.backend_context("pytorch"):
        mp.setattr(_backend, "on_accelerator", torch.is_tensor)  # a CUDA tensor's path
        mp.setattr(_backend, "to_numpy", lambda a: pytest.fail("copied to the host"))
        peak, tv = robust_peak(t), total_variation(t)
    assert peak == robust_peak(x)  # the same order statistic, exactly
    assert tv == pytest.approx(total_variation(x), rel=1e-6)
