"""relative_change: the compiled one-pass sums against NumPy's difference and dot products."""

import numpy as np
import pytest

from tensor_cosdi.solvers._base import compiled_change, relative_change

numba = pytest.importorskip("numba")


def _numpy(new, old):
    return float(np.linalg.norm((new - old).ravel()) / np.linalg.norm(new.ravel()))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("order", ["C", "F", "mixed"])
def test_compiled_change_is_numpys_in_every_layout(dtype, order, monkeypatch):
    rng = np.random.default_rng(0)
    new = rng.random((40, 30, 7)).astype(dtype)
    old = (new * (1 + 1e-3 * rng.standard_normal(new.shape))).astype(dtype)
    if order == "F":
        new, old = np.asfortranarray(new), np.asfortranarray(old)
    elif order == "mixed":  # no common flat order: NumPy's path
        old = np.asfortranarray(old)
    ref = _numpy(new.astype(np.float64), old.astype(np.float64))
    rel = 1e-5 if dtype == np.float32 else 1e-12
    got = relative_change(new, old)
    assert got == pytest.approx(ref, rel=rel)
    monkeypatch.setenv("TENSOR_COSDI_JIT", "0")  # NumPy's difference and dot products
    assert not compiled_change()
    assert relative_change(new, old) == pytest.approx(got, rel=rel)


def test_compiled_change_edge_values():
    assert compiled_change()
    z, one = np.zeros((4, 3)), np.ones((4, 3))
    assert relative_change(z, one) == float("inf")
    assert relative_change(z, z) == 0.0
    assert relative_change(one, one) == 0.0
    nan = one.copy()
    nan[1, 1] = np.nan
    assert np.isnan(relative_change(nan, one))
    # complex iterates and a dtype mismatch keep NumPy's path, and the same value
    c = np.ones(5) * (1 + 1j)
    assert relative_change(c, c * 0.5) == pytest.approx(0.5)
    assert relative_change(np.ones(5, np.float32), np.zeros(5)) == pytest.approx(1.0)


def test_without_numba_the_change_takes_numpys_path(monkeypatch):
    import sys

    from tensor_cosdi import _backend

    new = np.random.default_rng(1).random((16, 12, 5))
    want = relative_change(new, new * 0.9)
    monkeypatch.setitem(sys.modules, "numba", None)  # as if numba were not installed
    monkeypatch.setattr(_backend, "_NUMBA", {})
    assert not compiled_change()
    assert relative_change(new, new * 0.9) == pytest.approx(want, rel=1e-12)
