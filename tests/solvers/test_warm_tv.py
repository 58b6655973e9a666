"""WarmTV: scikit-image's Chambolle iteration, with its dual carried from call to call."""

import importlib.util

import numpy as np
import pytest
from skimage.restoration import denoise_tv_chambolle

from tensor_cosdi.solvers.denoisers import WarmTV


@pytest.mark.parametrize("shape", [(40, 30), (40, 30, 3), (24, 20, 2, 3)])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cold_start_is_scikit_image(shape, dtype):
    x = np.random.default_rng(0).random(shape).astype(dtype)
    for n in (1, 2, 7, 30):
        ref = denoise_tv_chambolle(
            x.reshape(shape[:2] + (-1,)), weight=0.1, max_num_iter=n, eps=0, channel_axis=-1
        ).reshape(shape)
        out = WarmTV(n)(x, 0.1)
        assert out.shape == x.shape and out.dtype == dtype
        np.testing.assert_allclose(out, ref, atol=1e-5 if dtype == np.float32 else 1e-12)


def test_warm_start_reaches_the_converged_denoiser_in_few_steps_per_call():
    rng = np.random.default_rng(1)
    clean = np.kron(rng.random((6, 6, 2)), np.ones((8, 8, 1)))
    x = clean + 0.1 * rng.standard_normal(clean.shape)
    converged = denoise_tv_chambolle(x, weight=0.1, max_num_iter=2000, eps=0, channel_axis=-1)
    warm = WarmTV(5)
    for _ in range(40):  # 40 calls × 5 steps: the dual keeps improving
        out = warm(x, 0.1)
    cold5 = WarmTV(5)(x, 0.1)
    # on a fixed input, 40 warm calls of 5 steps are exactly 200 cold steps
    np.testing.assert_allclose(out, WarmTV(200)(x, 0.1), atol=1e-12)
    assert np.abs(out - converged).max() < 0.25 * np.abs(cold5 - converged).max()
    warm.reset()
    np.testing.assert_array_equal(warm(x, 0.1), cold5)
    # a new shape starts cold instead of failing
    assert warm(x[:20, :20], 0.1).shape == (20, 20, 2)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_planes_held_column_by_column_are_stepped_as_they_lie(dtype):
    """A Fortran-ordered cube is stepped as its transposed planes, without copies: the same
    warm iterates as its C-ordered copy bit for bit (compiled and NumPy steps), returned in
    its own order, and a dual that follows the input from one layout to the other mid-run."""
    rng = np.random.default_rng(5)
    xs = [rng.random((24, 20, 3)).astype(dtype) for _ in range(4)]
    for compiled in (False, "auto"):
        c_warm, f_warm = WarmTV(3, compiled=compiled), WarmTV(3, compiled=compiled)
        for k, x in enumerate(xs):
            fx = np.asfortranarray(x) if k != 2 else x  # the third call in C order
            ref, out = c_warm(x, 0.1), f_warm(fx, 0.1)
            np.testing.assert_array_equal(out, ref)
            assert out.flags.f_contiguous == (k != 2) and out.dtype == dtype
        assert np.abs(ref - xs[-1]).max() > 1e-3  # the steps did change the cube
    # the transposed image's TV is the TV's transpose (the dual's halves traded): a square
    # image and its transpose, both warm over calls, to float rounding (another sum order)
    sq = rng.random((16, 16, 2)).astype(dtype)
    a, b = WarmTV(4), WarmTV(4)
    for _ in range(3):
        out_a = a(np.asfortranarray(sq), 0.2)
        out_b = b(np.ascontiguousarray(sq.transpose(1, 0, 2)), 0.2)
    tol = 1e-5 if dtype == np.float32 else 1e-12
    np.testing.assert_allclose(out_a, out_b.transpose(1, 0, 2), atol=tol, rtol=0)


def test_planes_split_over_threads_step_exactly_as_in_one_call(monkeypatch):
    """Each plane takes its steps on its own, in whatever chunk a thread gets: the warm dual
    and the result are those of one single-thread call, bit for bit."""
    from tensor_cosdi.solvers import denoisers

    x = np.random.default_rng(3).random((32, 24, 7)).astype(np.float32)
    outs = {}
    for workers in (1, 3):
        monkeypatch.setattr(denoisers, "_workers", lambda n, w=workers: min(n, w))
        warm = WarmTV(3)
        outs[workers] = [warm(x * (1 + 0.1 * k), 0.05) for k in range(3)]
        outs[workers].append(warm.p.copy())
    for a, b in zip(outs[1], outs[3]):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(outs[1][0], outs[1][1])  # the calls did differ


def test_warm_tv_errors():
    with pytest.raises(ValueError, match="n_iter"):
        WarmTV(0)
    with pytest.raises(TypeError, match="n_iter"):
        WarmTV(2.5)
    with pytest.raises(ValueError, match="sigma"):
        WarmTV(2)(np.ones((4, 4)), 0.0)


@pytest.mark.parametrize("accelerator", [False, True])
def test_torch_tensors_stay_torch_and_match_numpy(accelerator, monkeypatch):
    """CPU tensors take the NumPy steps through a view; tensors on an accelerator (forced here)
    step in backend operations."""
    torch = pytest.importorskip("torch")
    from tensor_cosdi import _backend

    monkeypatch.setattr(_backend, "on_accelerator", lambda a: accelerator and torch.is_tensor(a))
    x = np.random.default_rng(2).random((20, 18, 2, 3))
    ref, got = WarmTV(4), WarmTV(4)
    import tensorly as tl

    with tl.backend_context("pytorch"):
        for _ in range(3):  # warm calls carry the dual on both paths
            a, b = ref(x, 0.1), got(torch.from_numpy(x), 0.1)
    assert isinstance(b, torch.Tensor) and b.shape == x.shape
    np.testing.assert_allclose(b.numpy(), a, atol=1e-12)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_tv_on_an_accelerator_is_scikit_images_tv_with_its_stopping_rule(dtype, monkeypatch):
    """``tv`` on a tensor on an accelerator (forced here: no GPU in CI) runs in backend
    operations on its device and matches scikit-image, whose per-channel energy test stops some
    channels early (a constant one at once)."""
    torch = pytest.importorskip("torch")
    import tensorly as tl
    from skimage.restoration import denoise_tv_chambolle

    from tensor_cosdi import _backend
    from tensor_cosdi.solvers.denoisers import tv

    monkeypatch.setattr(_backend, "on_accelerator", torch.is_tensor)
    rng = np.random.default_rng(4)
    x = (rng.random((24, 20, 5)) * np.linspace(0.05, 1, 5)).astype(dtype)
    x[..., 4] = 0.5
    ref = denoise_tv_chambolle(x, weight=0.1, max_num_iter=200, channel_axis=2)
    # the stopping rule matters: 200 steps without it are a different image
    assert np.abs(WarmTV(200)(x, 0.1) - ref).max() > 1e-4
    seen = []
    with tl.backend_context("pytorch"), pytest.MonkeyPatch.context() as mp:
        real = _backend.to_numpy
        mp.setattr(_backend, "to_numpy", lambda a: seen.append(tuple(a.shape)) or real(a))
        got = tv(torch.from_numpy(x), 0.1, n_iter=200)
    assert isinstance(got, torch.Tensor) and got.dtype == torch.from_numpy(x).dtype
    np.testing.assert_allclose(got.numpy(), ref, atol=1e-6 if dtype == np.float32 else 1e-12)
    assert seen and max(seen) == (5,)  # only the channels' energies came to the host


def test_threads_follow_the_environments_limit(monkeypatch):
    """FFTs and TV chunks use ``OMP_NUM_THREADS`` where it is set (a single-threaded Dask worker)
    and the CPUs the process may use otherwise; the TV result does not depend on it."""
    from unittest import mock

    import scipy.fft

    from tensor_cosdi import _backend
    from tensor_cosdi.solvers.denoisers import tv

    x = np.random.default_rng(0).random((24, 20, 6))
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    free = _backend.thread_limit()
    assert free >= 1
    many = tv(x, 0.1)
    for value, want in (("1", 1), ("3", 3), ("0", free), ("lots", free), ("", free)):
        monkeypatch.setenv("OMP_NUM_THREADS", value)
        assert _backend.thread_limit() == want, value
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    np.testing.assert_array_equal(tv(x, 0.1), many)
    with mock.patch.object(scipy.fft, "rfftn", wraps=scipy.fft.rfftn) as spy:
        _backend.rfftn(x, s=(32, 32), axes=(0, 1))
    assert spy.call_args.kwargs["workers"] == 1


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(40, 30, 3), (1, 7, 2), (6, 1, 2), (1, 1), (33, 17, 4)])
def test_compiled_steps_are_the_numpy_steps_bit_for_bit(shape, dtype):
    """The numba kernel (the ``fast`` extra) rewrites the dual in place in one sweep a step;
    its primal and dual equal the NumPy steps' exactly, warm calls included, edges included
    (one row, one column, one pixel)."""
    pytest.importorskip("numba")
    x = np.random.default_rng(5).random(shape).astype(dtype)
    plain, fast = WarmTV(4, compiled=False), WarmTV(4, compiled=True)
    for w in (0.07, 0.3, 0.07):  # three warm calls, the weight changing between them
        a, b = plain(x, w), fast(x, w)
        assert b.dtype == dtype
        np.testing.assert_array_equal(b, a)
        np.testing.assert_array_equal(fast.p, plain.p)
    # the steps moved the dual (a single pixel has no gradient: its dual stays 0)
    assert (np.abs(plain.p).max() > 0) == (shape[0] * shape[1] > 1)


def test_compiled_option_and_environment(monkeypatch):
    from tensor_cosdi.solvers.denoisers import compiled_tv

    with pytest.raises(ValueError, match="compiled must be True, False or 'auto', got 'yes'"):
        WarmTV(3, compiled="yes")
    x = np.random.default_rng(6).random((20, 16, 3)).astype(np.float32)
    plain = WarmTV(3, compiled=False)(x, 0.1)
    monkeypatch.setenv("TENSOR_COSDI_JIT", "0")
    assert compiled_tv() is False
    np.testing.assert_array_equal(WarmTV(3)(x, 0.1), plain)
    monkeypatch.setenv("TENSOR_COSDI_JIT", "yes")
    with pytest.raises(ValueError, match="TENSOR_COSDI_JIT must be 0 or 1, got 'yes'"):
        WarmTV(3)(x, 0.1)
    monkeypatch.setenv("TENSOR_COSDI_JIT", "1")
    assert compiled_tv() is (importlib.util.find_spec("numba") is not None)
    np.testing.assert_array_equal(WarmTV(3)(x, 0.1), plain)


def test_compiled_true_without_numba_names_the_extra(monkeypatch):
    import sys

    from tensor_cosdi import _backend
    from tensor_cosdi.solvers import denoisers

    monkeypatch.setitem(sys.modules, "numba", None)  # as if numba were not installed
    monkeypatch.setattr(_backend, "_NUMBA", {})
    with pytest.raises(ImportError, match=r"needs numba: pip install 'tensor_cosdi\[fast\]'"):
        WarmTV(3, compiled=True)
    assert denoisers.compiled_tv() is False
