"""Structured inverses against dense solves: every registered operator, μ from
1e-4 to 1e4, and random VSI / multi-shot / C3SLFI-like configurations."""

import numpy as np
import pytest
import tensorly as tl
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi import _backend as B
from tensor_cosdi.operators import (
    Code,
    Diagonal,
    FoldedBanded,
    LightFieldLayout,
    Pad,
    PixelBlocks,
    RowBanded,
    Shear,
    Stack,
    SumAxis,
    TensorOperator,
    conjugate_gradient,
    vec,
    weighted_sum,
)
from tensor_cosdi.operators.gram import Pattern, StructureError, check_structure
from tensor_cosdi.testing import registry

MUS = [1e-4, 1e-2, 1.0, 1e2, 1e4]
NAMES = sorted(registry())

EXPECTED = {  # every registry entry (tests/operators: a new entry must state its structure)
    "blur": type(None),
    "blur_even": type(None),
    "c3slfi": PixelBlocks,
    "c3slfi_3d": PixelBlocks,
    "code": Diagonal,
    "code_axes": Diagonal,
    "code_full": Diagonal,
    "cs2li": Diagonal,
    "dd_cassi": Diagonal,
    "dfa": Diagonal,
    "dfa_psf": type(None),
    "lightfield_interleaved": Diagonal,
    "lightfield_tiled": Diagonal,
    "lightfield_tiled_to_interleaved": Diagonal,
    "mode_product_all": type(None),
    "mode_product_one": PixelBlocks,
    "multishot_cassi": PixelBlocks,
    "pad": Diagonal,
    "replicate": PixelBlocks,
    "scaled_difference": Diagonal,
    "sd_cassi": Diagonal,
    "sd_cassi_adjoint": type(None),
    "sd_cassi_fractional": RowBanded,
    "sd_cassi_step2": Diagonal,
    "shear_axes": Diagonal,
    "shear_fractional": RowBanded,
    "shear_per_band": Diagonal,
    "shear_step1": Diagonal,
    "shear_step2": Diagonal,
    "sum_axis": Diagonal,
    "sum_axis0": Diagonal,
    "system_c3slfi_3d": PixelBlocks,
    "system_c3slfi_5d": PixelBlocks,
    "system_c3slfi_separable": PixelBlocks,
    "system_cassdi_dfa": Diagonal,
    "system_cassdi_dfa_psf": type(None),
    "system_cassi_vsi": RowBanded,
    "system_cs2li": Diagonal,
    "system_ddcassi": Diagonal,
    "system_dual_camera": FoldedBanded,
    "system_lytro_cassi": FoldedBanded,
    "system_mu_cosdi_lf": Diagonal,
    "system_mu_cosdi_sl": Diagonal,
    "system_sdcassi": Diagonal,
    "system_sdcassi_shots": PixelBlocks,
    "transpose": Diagonal,
    "vsi": RowBanded,
}


def dense(op):
    M = op.to_matrix().toarray()
    return M


def rel(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_detected_structure(name):
    op = registry()[name](np.random.default_rng(0))
    assert isinstance(op.gram_dual(), EXPECTED[name])


@pytest.mark.parametrize("name", NAMES)
def test_gram_structure_equals_dense_product(name):
    op = registry()[name](np.random.default_rng(0))
    g = op.gram_dual()
    M = dense(op)
    gram = M @ M.T
    if name not in EXPECTED:  # every registry entry states its structure (None included)
        pytest.fail(f"{name}: add its expected A Aᵀ structure to EXPECTED")
    if EXPECTED[name] is type(None):
        # no structure claimed: A Aᵀ must really couple entries beyond a diagonal (CG is needed)
        assert g is None
        assert np.abs(gram - np.diag(np.diag(gram))).max() > 1e-6
        return
    np.testing.assert_allclose(g.to_dense(), gram, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("mu", MUS)
def test_solves_equal_dense_solve(name, mu):
    op = registry()[name](np.random.default_rng(0))
    M = dense(op)
    g = np.random.default_rng(1)
    b = g.standard_normal(op.output_shape)
    r = g.standard_normal(op.input_shape)
    xd = op.solve_dual(b, mu)
    xn = op.solve_normal(r, mu)
    ref_d = np.linalg.solve(mu * np.eye(M.shape[0]) + M @ M.T, vec(b))
    ref_n = np.linalg.solve(M.T @ M + mu * np.eye(M.shape[1]), vec(r))
    assert rel(vec(xd), ref_d) < 1e-8, f"{name} solve_dual μ={mu}"
    assert rel(vec(xn), ref_n) < 1e-8, f"{name} solve_normal μ={mu}"


@pytest.mark.parametrize("name", ["sd_cassi", "multishot_cassi", "vsi", "c3slfi_3d", "blur"])
def test_solves_on_every_backend(name, backend):
    _, dtype = backend
    op = registry()[name](np.random.default_rng(0))
    M = dense(op)
    r = np.random.default_rng(2).standard_normal(op.input_shape)
    x = op.solve_normal(B.as_tensor(r, dtype), 0.5)
    assert B.real_dtype_name(x) == dtype
    ref = np.linalg.solve(M.T @ M + 0.5 * np.eye(M.shape[1]), vec(r))
    assert rel(vec(x), ref) < (1e-8 if dtype == "float64" else 1e-4)


@given(
    nx=st.integers(1, 4),
    ny=st.integers(2, 7),
    nb=st.integers(1, 5),
    beta=st.integers(0, 4),
    alpha=st.floats(0.0, 1.0),
    mu=st.sampled_from(MUS),
    seed=st.integers(0, 2**16),
)
def test_vsi_row_banded_random(nx, ny, nb, beta, alpha, mu, seed):
    beta = min(beta, nb - 1)
    g = np.random.default_rng(seed)
    shape = (nx, ny, nb)
    code = Code(g.integers(0, 2, (nx, ny)).astype(float), shape)
    shear = Shear(shape, 1)
    dispersed = SumAxis(shear.output_shape, 2) @ shear @ code
    direct = Pad((nx, ny), axis=1, before=beta, after=nb - 1 - beta) @ SumAxis(shape, 2) @ code
    op = weighted_sum([dispersed, direct], [alpha, 1 - alpha])
    gram = op.gram_dual()
    assert isinstance(gram, (RowBanded, Diagonal))
    M = dense(op)
    np.testing.assert_allclose(gram.to_dense(), M @ M.T, atol=1e-12)
    r = g.standard_normal(shape)
    ref = np.linalg.solve(M.T @ M + mu * np.eye(M.shape[1]), vec(r))
    assert rel(vec(op.solve_normal(r, mu)), ref) < 1e-8


@given(
    shape=st.tuples(
        st.integers(1, 4),
        st.integers(1, 4),
        st.integers(1, 5),
        st.integers(1, 3),
        st.integers(1, 3),
    ),
    K=st.integers(1, 5),
    mu=st.sampled_from(MUS),
    seed=st.integers(0, 2**16),
)
def test_pixel_blocks_random_light_field(shape, K, mu, seed):
    """C3SLFI-like: K coded band sums per voxel, on the 3-D interleaved parameterisation."""
    g = np.random.default_rng(seed)
    n1, n2, n3, n4, n5 = shape
    flat = (n1 * n4, n2 * n5, n3)
    codes = g.random(flat + (K,))
    stack = Stack([SumAxis(flat, 2) @ Code(codes[..., k], flat) for k in range(K)])
    op = stack @ LightFieldLayout(shape, "interleaved")
    gram = op.gram_dual()
    assert isinstance(gram, PixelBlocks) and gram.block_size == K
    # Eq. 209-211: Q[k1, k2] = Σ_l T[..., l, k1] T[..., l, k2]
    Q = np.einsum("ijlk,ijlm->ijkm", codes, codes)
    np.testing.assert_allclose(gram.Q, Q, atol=1e-12)
    M = dense(op)
    r = g.standard_normal(shape)
    ref = np.linalg.solve(M.T @ M + mu * np.eye(M.shape[1]), vec(r))
    assert rel(vec(op.solve_normal(r, mu)), ref) < 1e-8


def test_structure_is_cached_and_sd_cassi_diagonal_formula(rng):
    shape = (8, 9, 5)
    c = rng.random(shape[:2])
    shear = Shear(shape, 2)
    op = SumAxis(shear.output_shape, 2) @ shear @ Code(c, shape)
    g = op.gram_dual()
    assert g is op.gram_dual()
    # d[i, j] = Σ_l C[i, j − s_l]²
    d = np.zeros(op.output_shape)
    for l in range(5):
        d[:, 2 * l : 2 * l + 9] += c**2
    np.testing.assert_allclose(g.d, d, atol=1e-14)


def test_conjugate_gradient_matches_dense(rng):
    A = rng.standard_normal((30, 30))
    S = A @ A.T + 0.1 * np.eye(30)
    b = rng.standard_normal(30)
    x = conjugate_gradient(lambda v: S @ v, b, rtol=1e-13, maxiter=500)
    assert rel(x, np.linalg.solve(S, b)) < 1e-8
    assert np.all(conjugate_gradient(lambda v: S @ v, np.zeros(30)) == 0)


def test_band_structure_on_wide_rows():
    """Band probing with 2b + 1 < n (combs with several teeth per row)."""
    g = np.random.default_rng(5)
    shape = (3, 40, 3)
    code = Code(g.random(shape[:2]), shape)
    shear = Shear(shape, 1)
    a = SumAxis(shear.output_shape, 2) @ shear @ code
    b = Pad(shape[:2], axis=1, before=1, after=1) @ SumAxis(shape, 2) @ code
    op = 0.6 * a + 0.4 * b
    gram = op.gram_dual()
    assert isinstance(gram, RowBanded) and gram.bandwidth == 1
    M = dense(op)
    np.testing.assert_allclose(gram.to_dense(), M @ M.T, atol=1e-12)
    assert tl.shape(op.solve_dual(g.standard_normal(op.output_shape), 1e-3)) == op.output_shape


# ---- the runtime self-check of gram_dual (operators/gram.check_structure) ----------------
class _Misrouted(TensorOperator):
    """Wraps an operator and reports a wrong ``A Aᵀ`` pattern (a routing bug in a new primitive)."""

    def __init__(self, op, pattern):
        super().__init__(op.input_shape, op.output_shape)
        self.op, self.pattern = op, pattern

    def _forward(self, x):
        return self.op.apply(x)

    def _adjoint(self, y):
        return self.op.apply_adjoint(y)

    def _gram_pattern(self):
        return self.pattern


@pytest.mark.parametrize(
    "name, pattern",
    [
        ("mode_product_one", Pattern("diag")),  # truly K × K blocks, claimed diagonal
        ("blur", Pattern("blocks", 2)),  # truly spatially coupled, claimed per-pixel blocks
        ("vsi", Pattern("diag")),  # truly banded (b = 1 here), claimed diagonal
        ("system_cassi_vsi", Pattern("band", 1, 1)),  # truly b = S, claimed b = 1
    ],
)
def test_structure_self_check_fires_on_a_misrouted_operator(name, pattern):
    op = _Misrouted(registry()[name](np.random.default_rng(0)), pattern)
    with pytest.raises(StructureError, match="_Misrouted.*does not reproduce A\\(Aᵀ v\\)"):
        op.gram_dual()


def test_structure_self_check_passes_and_reports_the_error():
    op = registry()["vsi"](np.random.default_rng(0))
    assert check_structure(op, op.gram_dual()) < 1e-12
