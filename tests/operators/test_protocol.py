"""Generic tests over every registered operator: dot test, tensor path vs matrix
path, algebra of the protocol, on every backend and dtype."""

import numpy as np
import pytest
import tensorly as tl

from tensor_cosdi import _backend as B
from tensor_cosdi.operators import Code, Composition, OperatorSum, Shear, SumAxis, vec
from tensor_cosdi.testing import dot_test, random_tensor, registry

NAMES = sorted(registry())


def make(name, seed=0):
    return registry()[name](np.random.default_rng(seed))


@pytest.mark.parametrize("name", NAMES)
def test_dot_test(name, backend):
    _, dtype = backend
    op = make(name)
    err = dot_test(op, rng=1, dtype=dtype)
    tol = 1e-10 if dtype == "float64" else 1e-5
    assert err < tol, f"{name}: dot-test relative error {err:.2e} ≥ {tol:.0e}"


@pytest.mark.parametrize("name", NAMES)
def test_forward_and_adjoint_equal_matrix(name, backend):
    _, dtype = backend
    op = make(name)
    M = op.to_matrix()
    assert M.shape == op.shape
    x = random_tensor(op.input_shape, rng=2, dtype=dtype)
    y = random_tensor(op.output_shape, rng=3, dtype=dtype)
    fx, aty = op.forward(x), op.adjoint(y)
    assert tuple(tl.shape(fx)) == op.output_shape
    assert tuple(tl.shape(aty)) == op.input_shape
    assert B.real_dtype_name(fx) == dtype and B.real_dtype_name(aty) == dtype
    ref_f = M @ vec(x).astype(np.float64)
    ref_a = M.T @ vec(y).astype(np.float64)
    tol = 1e-12 if dtype == "float64" else 1e-5
    scale_f = max(np.abs(ref_f).max(), 1.0)
    scale_a = max(np.abs(ref_a).max(), 1.0)
    assert np.abs(vec(fx) - ref_f).max() <= tol * scale_f
    assert np.abs(vec(aty) - ref_a).max() <= tol * scale_a


def test_algebra(rng):
    a, b = make("sd_cassi", 0), make("sd_cassi", 1)
    x = rng.standard_normal(a.input_shape)
    y = rng.standard_normal(a.output_shape)
    np.testing.assert_allclose((a + b).forward(x), a.forward(x) + b.forward(x), atol=1e-13)
    np.testing.assert_allclose((a - b).forward(x), a.forward(x) - b.forward(x), atol=1e-13)
    np.testing.assert_allclose((3.0 * a).adjoint(y), 3.0 * a.adjoint(y), atol=1e-13)
    np.testing.assert_allclose((a / 4).forward(x), a.forward(x) / 4, atol=1e-13)
    np.testing.assert_allclose((-a).forward(x), -a.forward(x), atol=1e-13)
    np.testing.assert_allclose(a.T.forward(y), a.adjoint(y), atol=0)
    assert a.T.T is a
    np.testing.assert_allclose(a @ x, a.forward(x), atol=0)
    np.testing.assert_allclose(sum([a, b]).forward(x), (a + b).forward(x), atol=1e-13)
    assert isinstance(a + b, OperatorSum) and isinstance(a.T @ a, Composition)
    # composition of the adjoint is the adjoint of the composition
    c = a.T @ a
    np.testing.assert_allclose(c.forward(x), a.adjoint(a.forward(x)), atol=1e-12)


def test_fused_plan_matches_unfused(rng):
    """SD-CASSI runs as one fused kernel; the result equals the step-by-step path."""
    shape = (7, 9, 5)
    code = Code(rng.random(shape[:2]), shape)
    shear = Shear(shape, 2)
    op = SumAxis(shear.output_shape, 2) @ shear @ code
    assert len(op._plan) == 1, "sum ∘ shear ∘ code should fuse into one kernel"
    x = rng.standard_normal(shape)
    step = op.factors[0].forward(shear.forward(code.forward(x)))
    np.testing.assert_allclose(op.forward(x), step, rtol=0, atol=1e-13)
    y = rng.standard_normal(op.output_shape)
    step_adj = code.adjoint(shear.adjoint(op.factors[0].adjoint(y)))
    np.testing.assert_allclose(op.adjoint(y), step_adj, rtol=0, atol=1e-13)


def test_operators_are_immutable_and_parameters_follow_input_dtype(rng):
    op = make("sd_cassi")
    x64 = rng.standard_normal(op.input_shape)
    before = op.forward(x64).copy()
    op.forward(x64.astype(np.float32))
    np.testing.assert_array_equal(op.forward(x64), before)
    assert op.forward(x64.astype(np.float32)).dtype == np.float32


def test_aslinearoperator_is_the_matrix_and_scipy_lsqr_agrees_with_lsq():
    from scipy.sparse.linalg import lsqr

    import tensor_cosdi as tc
    from tensor_cosdi.systems import SDCASSI

    rng = np.random.default_rng(0)
    sd = SDCASSI(rng.random((6, 5)), n_bands=4, shifts=1)
    A = sd.operator.aslinearoperator()
    M = sd.operator.to_matrix().toarray()
    v = rng.random(A.shape[1])
    y = rng.random(A.shape[0])
    np.testing.assert_allclose(A.matvec(v), M @ v, rtol=1e-12)
    np.testing.assert_allclose(A.rmatvec(y), M.T @ y, rtol=1e-12)
    g = sd.forward(rng.random(sd.cube_shape))
    mu = 1e-2
    # lsq solves min ‖g − A x‖² + μ s ‖x‖²; lsqr's damp is the square root of that weight
    s = float(np.sum(sd.operator.forward(np.ones(sd.cube_shape)) ** 2) / np.prod(sd.cube_shape))
    x = lsqr(A, g.reshape(-1, order="F"), damp=np.sqrt(mu * s), atol=1e-14, btol=1e-14)[0]
    want = tc.reconstruct(sd, g, "lsq", mu=mu).cube
    np.testing.assert_allclose(x.reshape(sd.cube_shape, order="F"), want, rtol=1e-6, atol=1e-9)


LAYOUTS = {
    "C": lambda x: np.ascontiguousarray(x),
    "F": lambda x: np.asfortranarray(x),
    "band-major": lambda x: np.moveaxis(np.ascontiguousarray(np.moveaxis(x, 2, 0)), 0, 2),
    "(λ, x, y) permuted": lambda x: np.transpose(
        np.ascontiguousarray(x.transpose(1, 2, 0)), (2, 0, 1)
    ),
    "strided view": lambda x: interleaved(x)[:, ::2],
    "reversed view": lambda x: np.ascontiguousarray(x[::-1])[::-1],
}


def interleaved(x):
    big = np.zeros((x.shape[0], 2 * x.shape[1], x.shape[2]), dtype=x.dtype)
    big[:, ::2] = x
    return big


@pytest.mark.parametrize("layout", list(LAYOUTS))
@pytest.mark.parametrize(
    "shifts, colour",
    [(2, False), ([0, 1, 3, 4, 7], False), (1, True)],
    ids=["linear", "uneven", "colour"],
)
@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.float64])
def test_coded_shear_sum_is_the_same_in_every_memory_layout(layout, shifts, colour, dtype, rng):
    """The fused SD-CASSI kernel reads a cube in any memory order (band-major slabs, the sparse
    gather over a C-ordered buffer, the per-band loop) and gives the factor-by-factor result."""
    shape = (6, 9, 5)
    code = Code(
        rng.random(shape if colour else shape[:2]), shape, axes=(0, 1, 2) if colour else (0, 1)
    )
    shear = Shear(shape, shifts)
    op = SumAxis(shear.output_shape, 2) @ shear @ code
    x = rng.random(shape).astype(dtype)
    held = LAYOUTS[layout](x)
    assert np.array_equal(held, x)
    expected = op.factors[0].forward(shear.forward(code.forward(x.astype(np.float64))))
    got = op.forward(held)
    assert got.dtype == dtype and got.shape == op.output_shape
    tol = {np.float16: 5e-3, np.float32: 1e-5, np.float64: 1e-12}[dtype]
    np.testing.assert_allclose(got, expected, rtol=tol, atol=tol)
    y = rng.random(op.output_shape).astype(dtype)  # and the adjoint stays its transpose
    lhs, rhs = np.vdot(got, y), np.vdot(x, op.adjoint(y))
    assert abs(lhs - rhs) <= 10 * tol * abs(lhs)


@pytest.mark.parametrize("rest_order", [(0, 1, 3), (3, 0, 1), (1, 3, 0), (0, 3, 1)])
def test_band_slowest_layouts_of_a_4d_cube_match_the_factor_chain(rest_order, rng):
    """A 4-way cube whose band axis is slowest in memory, the other axes in any order (the
    slab kernel pads each band like the measurement's memory and adds it at a flat offset)."""
    shape = (4, 7, 5, 3)  # (x, y, λ, t), λ summed, y sheared by 2 px per band
    code = Code(rng.random(shape[:2]), shape, axes=(0, 1))
    shear = Shear(shape, 2, axis=1, band_axis=2)
    op = SumAxis(shear.output_shape, 2) @ shear @ code
    x = rng.random(shape)
    mem = (2,) + rest_order  # memory order, slowest first
    held = np.transpose(np.ascontiguousarray(np.transpose(x, mem)), np.argsort(mem))
    assert np.array_equal(held, x)
    expected = op.factors[0].forward(shear.forward(code.forward(x)))
    np.testing.assert_allclose(op.forward(held), expected, rtol=1e-12, atol=1e-12)
