"""Hypothesis property tests: tensor path == explicit matrix path (1e-12) and the
dot test (< 1e-10) over random shapes, shifts, codes and axes (float64)."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi.operators import (
    Blur,
    BlurSum,
    Code,
    LightFieldLayout,
    ModeProduct,
    Pad,
    Replicate,
    Shear,
    Stack,
    SumAxis,
    Transpose,
    vec,
    weighted_sum,
)
from tensor_cosdi.testing import dot_test

sizes = st.integers(1, 6)


def check_matrix_path(op, seed):
    g = np.random.default_rng(seed)
    M = op.to_matrix()
    x = g.standard_normal(op.input_shape)
    y = g.standard_normal(op.output_shape)
    fx = M @ vec(x)
    ay = M.T @ vec(y)
    assert np.abs(vec(op.forward(x)) - fx).max() <= 1e-12 * max(1.0, np.abs(fx).max())
    assert np.abs(vec(op.adjoint(y)) - ay).max() <= 1e-12 * max(1.0, np.abs(ay).max())
    assert dot_test(op, rng=seed) < 1e-10


@st.composite
def shifts_for(draw, n_bands, fractional=False):
    kind = draw(st.sampled_from(["step", "list"]))
    if kind == "step":
        step = draw(st.integers(0, 3))
        return step
    incs = draw(st.lists(st.integers(0, 3), min_size=n_bands - 1, max_size=n_bands - 1))
    s = np.concatenate([[draw(st.integers(0, 2))], incs]).cumsum().astype(float)
    if fractional:
        s = s + np.sort(draw(st.lists(st.floats(0, 0.99), min_size=n_bands, max_size=n_bands)))
        s = np.maximum.accumulate(s)
    return s.tolist()


@given(
    shape=st.tuples(sizes, sizes, sizes),
    seed=st.integers(0, 2**16),
    data=st.data(),
)
def test_code_shear_sum_compositions(shape, seed, data):
    g = np.random.default_rng(seed)
    frac = data.draw(st.booleans())
    shifts = data.draw(shifts_for(shape[2], fractional=frac))
    code = Code(g.integers(0, 2, shape[:2]).astype(float), shape)
    shear = Shear(shape, shifts)
    op = SumAxis(shear.output_shape, 2) @ shear @ code
    check_matrix_path(op, seed)
    check_matrix_path(shear, seed)


@given(
    shape=st.lists(sizes, min_size=2, max_size=4),
    seed=st.integers(0, 2**16),
    data=st.data(),
)
def test_code_broadcasting_and_sums(shape, seed, data):
    g = np.random.default_rng(seed)
    nd = len(shape)
    k = data.draw(st.integers(1, nd))
    axes = data.draw(st.permutations(range(nd)))[:k]
    code_shape = [data.draw(st.sampled_from([1, shape[a]])) for a in axes]
    op = Code(g.standard_normal(code_shape), shape, axes=axes)
    check_matrix_path(op, seed)
    axis = data.draw(st.integers(0, nd - 1))
    if nd >= 2:
        check_matrix_path(SumAxis(shape, axis), seed)
    check_matrix_path(Replicate(shape, data.draw(st.integers(0, nd)), data.draw(sizes)), seed)
    check_matrix_path(Transpose(shape, data.draw(st.permutations(range(nd)))), seed)
    check_matrix_path(
        Pad(
            shape,
            axis=axis,
            before=data.draw(st.integers(0, 3)),
            after=data.draw(st.integers(0, 3)),
        ),
        seed,
    )


@given(shape=st.lists(sizes, min_size=1, max_size=4), seed=st.integers(0, 2**16), data=st.data())
def test_mode_products(shape, seed, data):
    g = np.random.default_rng(seed)
    nd = len(shape)
    modes = data.draw(st.lists(st.integers(0, nd - 1), min_size=1, max_size=nd, unique=True))
    mats = {m: g.standard_normal((data.draw(sizes), shape[m])) for m in modes}
    check_matrix_path(ModeProduct(shape, mats), seed)


@given(
    shape=st.tuples(st.integers(2, 7), st.integers(2, 7), st.integers(1, 3)),
    psf=st.tuples(st.integers(1, 4), st.integers(1, 4)),
    per_slice=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_blur(shape, psf, per_slice, seed):
    g = np.random.default_rng(seed)
    p = g.random(psf + ((shape[2],) if per_slice else ()))
    check_matrix_path(Blur(shape, p), seed)


@given(
    shape=st.tuples(st.integers(2, 6), st.integers(2, 6), st.integers(1, 5), st.integers(1, 5)),
    psf=st.tuples(st.integers(1, 4), st.integers(1, 4)),
    steps=st.integers(1, 5),
    data=st.data(),
    seed=st.integers(0, 2**16),
)
def test_blur_sum_is_the_blurred_stack_summed(shape, psf, steps, data, seed):
    """The fused Fourier-domain map against the explicit matrix of SumAxis ∘ Blur ∘
    Replicate, with any spatial pair, summed axis and PSFs shared along either rest axis;
    planes × steps on either side of 16 (slab-by-slab mixing or a product per frequency)."""
    g = np.random.default_rng(seed)
    axes = data.draw(st.permutations(range(4)))[:2]
    rest = [a for a in range(4) if a not in axes]
    sum_axis = data.draw(st.sampled_from(rest))
    sizes_ = tuple(data.draw(st.sampled_from((1, shape[a]))) for a in rest)
    spatial = tuple(shape[a] for a in axes)
    op = BlurSum(shape, g.random(psf + sizes_ + (steps,)), sum_axis=sum_axis, axes=axes)
    assert op.output_shape == tuple(n for a, n in enumerate(shape) if a != sum_axis) + (steps,)
    assert tuple(op.output_shape[a] for a in op.out_axes) == spatial
    check_matrix_path(op, seed)


@given(
    shape=st.tuples(st.integers(2, 6), st.integers(2, 6), st.integers(1, 3), st.integers(1, 3)),
    psf=st.tuples(st.integers(1, 4), st.integers(1, 4)),
    data=st.data(),
    seed=st.integers(0, 2**16),
)
def test_a_blur_of_copies_runs_fused_and_equals_its_factors(shape, psf, data, seed):
    """Blur ∘ Replicate (one or two copied axes, any spatial pair): the fused plan (one
    transform of the input) against the explicit matrix of the factors."""
    g = np.random.default_rng(seed)
    axes = tuple(data.draw(st.permutations(range(4)))[:2])
    rest = [a for a in range(4) if a not in axes]
    sizes_ = tuple(data.draw(st.sampled_from((1, shape[a]))) for a in rest)
    blur = Blur(shape, g.random(psf + sizes_), axes=axes)
    op = blur @ Replicate(tuple(n for a, n in enumerate(shape) if a != rest[1]), rest[1],
                          shape[rest[1]])  # fmt: skip
    if data.draw(st.booleans()):  # copy a second axis too
        inner = op.input_shape
        op = op @ Replicate(tuple(n for a, n in enumerate(inner) if a != rest[0]), rest[0],
                            inner[rest[0]])  # fmt: skip
    copied = [rest[1]] + ([rest[0]] if len(op.input_shape) == 2 else [])
    varies = [sizes_[rest.index(a)] == shape[a] for a in copied]  # a PSF per copy
    names = [type(f).__name__ for f in op._plan]
    # fused while every copy has its own PSF, from the innermost copy outwards
    assert names.count("_ReplicatedBlur") == varies[0], names
    assert len(names) == 1 + (not varies[0]) + (len(copied) == 2 and not all(varies)), names
    check_matrix_path(op, seed)


@given(
    n=st.tuples(sizes, sizes, st.integers(1, 3), sizes, sizes),
    layout=st.sampled_from(["interleaved", "tiled"]),
    seed=st.integers(0, 2**16),
)
def test_light_field_layouts(n, layout, seed):
    op = LightFieldLayout(n, layout)
    check_matrix_path(op, seed)
    x = np.random.default_rng(seed).standard_normal(n)
    # permutation: the adjoint inverts it exactly
    np.testing.assert_array_equal(op.adjoint(op.forward(x)), x)
    # explicit index formulas of SPEC §3.3
    N1, N2, C, N4, N5 = n
    y = op.forward(x)
    j1, j2, c = (np.random.default_rng(seed + 1).integers(0, m) for m in (N1 * N4, N2 * N5, C))
    if layout == "interleaved":
        assert y[j1, j2, c] == x[j1 // N4, j2 // N5, c, j1 % N4, j2 % N5]
    else:
        assert y[j1, j2, c] == x[j1 % N1, j2 % N2, c, j1 // N1, j2 // N2]


@given(
    shape=st.tuples(sizes, sizes, st.integers(1, 4)),
    K=st.integers(1, 4),
    axis=st.integers(-3, 2),
    seed=st.integers(0, 2**16),
)
def test_stacks_and_weighted_sums(shape, K, axis, seed):
    g = np.random.default_rng(seed)
    ops = []
    for _ in range(K):
        shear = Shear(shape, 1)
        ops.append(SumAxis(shear.output_shape, 2) @ shear @ Code(g.random(shape[:2]), shape))
    check_matrix_path(Stack(ops, axis=axis), seed)
    check_matrix_path(weighted_sum(ops, g.standard_normal(K)), seed)
