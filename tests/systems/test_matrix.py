"""Tensor path equals the thesis' explicit sensing matrix (SPEC §11), over random systems.

Hypothesis draws shapes, codes, shifts (step, per-band integer, fractional)
and system parameters; ``matrix()`` is built from the equations, not from
the operator, so these tests compare two independent implementations.
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tensor_cosdi import codes
from tensor_cosdi.operators import parse_shifts, vec
from tensor_cosdi.systems import (
    C3SLFI,
    CASSDIDFA,
    CASSIVSI,
    CS2LI,
    DDCASSI,
    SDCASSI,
    DualCameraCASSI,
    MuCoSDI,
)
from tensor_cosdi.testing import dot_test

size = st.integers(1, 5)
bands = st.integers(1, 5)
seeds = st.integers(0, 2**32 - 1)


@st.composite
def shifts(draw, n_bands):
    kind = draw(st.sampled_from(["step", "integer", "fractional"]))
    if kind == "step":
        return draw(st.integers(0, 2))
    if kind == "integer":
        return np.cumsum(
            [0] + draw(st.lists(st.integers(0, 2), min_size=n_bands - 1, max_size=n_bands - 1))
        )
    steps = draw(
        st.lists(
            st.floats(0, 1.75, allow_nan=False).map(lambda v: round(v * 4) / 4),
            min_size=n_bands - 1,
            max_size=n_bands - 1,
        )
    )
    return np.cumsum([0.0] + steps)


def extra_width(s, n_bands):
    """``⌈max s_l⌉``: the columns the dispersion adds."""
    return int(np.ceil(parse_shifts(s, n_bands).max()))


def check(system, seed):
    """vec(A F) = H vec(F), vec(Aᵀ G) = Hᵀ vec(G) to 1e-12, and the dot test below 1e-10."""
    g = np.random.default_rng(seed)
    H = system.matrix()
    assert H.shape == (np.prod(system.measurement_shape), np.prod(system.cube_shape))
    F = g.standard_normal(system.cube_shape)
    G = g.standard_normal(system.measurement_shape)
    ref_f, ref_a = H @ vec(F), H.T @ vec(G)
    np.testing.assert_allclose(
        vec(system.forward(F)), ref_f, rtol=0, atol=1e-12 * max(1, np.abs(ref_f).max())
    )
    np.testing.assert_allclose(
        vec(system.adjoint(G)), ref_a, rtol=0, atol=1e-12 * max(1, np.abs(ref_a).max())
    )
    assert dot_test(system.operator, rng=seed) < 1e-10


@given(nx=size, ny=size, nl=bands, shots=st.integers(1, 3), data=st.data(), seed=seeds)
def test_sdcassi(nx, ny, nl, shots, data, seed):
    s = data.draw(shifts(nl))
    code = np.random.default_rng(seed).random((nx, ny) if shots == 1 else (nx, ny, shots))
    check(SDCASSI(code, n_bands=nl, shifts=s), seed)


@given(nx=size, ny=size, nl=bands, shots=st.integers(1, 2), data=st.data(), seed=seeds)
def test_ddcassi(nx, ny, nl, shots, data, seed):
    s = data.draw(shifts(nl))
    w = ny + extra_width(s, nl)
    code = np.random.default_rng(seed).random((nx, w) if shots == 1 else (nx, w, shots))
    check(DDCASSI(code, n_bands=nl, shifts=s), seed)


@given(nx=size, ny=size, nl=bands, data=st.data(), seed=seeds)
def test_dual_camera(nx, ny, nl, data, seed):
    s = data.draw(shifts(nl))
    check(DualCameraCASSI(np.random.default_rng(seed).random((nx, ny)), n_bands=nl, shifts=s), seed)


@given(nx=size, ny=size, nl=bands, alpha=st.floats(0, 1), data=st.data(), seed=seeds)
def test_cassi_vsi(nx, ny, nl, alpha, data, seed):
    s = data.draw(shifts(nl))
    beta = data.draw(st.integers(0, extra_width(s, nl)))
    code = codes.random_binary((nx, ny), rng=seed)
    check(CASSIVSI(code, n_bands=nl, alpha_t=alpha, beta=beta, shifts=s), seed)


@given(
    nx=size,
    ny=size,
    nl=bands,
    nz=st.integers(1, 3),
    psf=st.integers(0, 4),
    data=st.data(),
    seed=seeds,
)
def test_cassdi_dfa(nx, ny, nl, nz, psf, data, seed):
    s = data.draw(shifts(nl))
    g = np.random.default_rng(seed)
    psfs = None
    if psf:
        shared = data.draw(st.sampled_from([(nl, nz), (1, nz), (nl, 1), ()]))
        psfs = g.random((psf, data.draw(st.integers(1, 4))) + shared)
    check(CASSDIDFA(codes.depth_codes((nx, ny), nz, rng=g), n_bands=nl, shifts=s, psfs=psfs), seed)


@given(
    n1=st.integers(1, 3),
    n2=st.integers(1, 3),
    nl=bands,
    n4=st.integers(1, 3),
    n5=st.integers(1, 3),
    K=st.integers(2, 4),
    form=st.sampled_from(["3d", "5d"]),
    raw=st.sampled_from(["interleaved", "tiled"]),
    complementary=st.booleans(),
    seed=seeds,
)
def test_c3slfi(n1, n2, nl, n4, n5, K, form, raw, complementary, seed):
    shape = (n1 * n4, n2 * n5, nl) if form == "3d" else (n1, n2, nl, n4, n5)
    T = np.random.default_rng(seed).random(shape + (K,))
    if complementary and nl >= K:
        T = codes.complementary_colour_codes(shape, K, rng=seed)
    elif complementary:  # fewer bands than snapshots: continuous complementary codes
        T = T / T.sum(-1, keepdims=True)
    views = (n4, n5) if form == "3d" else None
    check(C3SLFI(T, layout=form, views=views, raw_layout=raw, complementary=complementary), seed)


@given(n1=size, n2=size, nl=bands, K=st.integers(1, 4), five=st.booleans(), seed=seeds)
def test_c3slfi_separable(n1, n2, nl, K, five, seed):
    phi = np.random.default_rng(seed).random((K, nl))
    shape = (n1, n2, nl, 2, 1) if five else (n1, n2, nl)
    system = C3SLFI.separable(phi, shape, complementary=False)
    check(system, seed)
    # the n-mode form equals the Hadamard form with the broadcast codes
    full = C3SLFI(np.array(system.codes), layout=system.layout, complementary=False)
    assert abs(full.matrix() - system.matrix()).max() == 0


@given(
    nx=size,
    ny=size,
    nl=bands,
    nt=st.integers(1, 3),
    colour=st.booleans(),
    data=st.data(),
    seed=seeds,
)
def test_cs2li(nx, ny, nl, nt, colour, data, seed):
    s = data.draw(shifts(nl))
    w = ny + extra_width(s, nl)
    g = np.random.default_rng(seed)
    code = g.random((nx, w, nl)) if colour else g.random((nx, w))
    check(CS2LI(code, n_bands=nl, n_patterns=nt, shifts=s), seed)


@given(
    nx=size,
    ny=size,
    nl=bands,
    modality=st.sampled_from(["sl", "lf", "monocular"]),
    data=st.data(),
    seed=seeds,
)
def test_mu_cosdi(nx, ny, nl, modality, data, seed):
    s = data.draw(shifts(nl))
    opts = {}
    if modality == "sl":
        opts["n_patterns"] = data.draw(st.integers(1, 3))
    if modality == "lf":
        nu, nv = data.draw(st.integers(1, 3)), data.draw(st.integers(1, 3))
        nx, ny = nx * nu, ny * nv
        opts.update(views=(nu, nv), raw_layout=data.draw(st.sampled_from(["interleaved", "tiled"])))
    code = codes.random_binary((nx, ny + extra_width(s, nl)), rng=seed)
    check(MuCoSDI(code, n_bands=nl, modality=modality, shifts=s, **opts), seed)


def test_matrix_detects_a_wrong_operator():
    """The comparison can fail: a VSI whose grayscale arm lands one column off differs from Eq.
    44."""
    a = CASSIVSI.example((4, 5, 3), beta=0)
    b = CASSIVSI(a.code, n_bands=3, beta=1)
    F = np.random.default_rng(0).standard_normal(a.cube_shape)
    assert np.abs(vec(b.forward(F)) - a.matrix() @ vec(F)).max() > 1e-3


@given(
    nx=st.integers(1, 5), ny=st.integers(1, 5), nl=st.integers(1, 4), nz=st.integers(1, 3),
    steps=st.integers(1, 3), psf=st.integers(1, 3), shared=st.booleans(), data=st.data(),
    seed=st.integers(0, 2**32 - 1),
)  # fmt: skip
def test_sweep_matches_its_explicit_matrix(nx, ny, nl, nz, steps, psf, shared, data, seed):
    g = np.random.default_rng(seed)
    psfs = g.random((psf, data.draw(st.integers(1, 3)), 1 if shared else nl, nz, steps))
    system = CASSDIDFA(
        codes.depth_codes((nx, ny), steps, rng=g), n_bands=nl, shifts=data.draw(shifts(nl)),
        psfs=psfs,
    )  # fmt: skip
    assert system.sweep and system.n_depths == nz and system.cube_shape == (nx, ny, nl, nz)
    check(system, seed)


@pytest.mark.parametrize(
    "system",
    [
        SDCASSI.example(),
        SDCASSI.example(shots=2),
        DDCASSI.example(),
        CASSIVSI.example(),
        CASSDIDFA.example(),
        C3SLFI.example(),
        CS2LI.example(),
        MuCoSDI.example(),
        MuCoSDI.example(modality="lf"),
    ],
    ids=lambda s: type(s).__name__,
)
def test_examples_match_their_matrix(system):
    check(system, 7)


@given(nx=size, ny=size, nl=bands, shots=st.integers(1, 3), data=st.data(), seed=seeds)
def test_colour_coded_sdcassi(nx, ny, nl, shots, data, seed):
    s = data.draw(shifts(nl))
    g = np.random.default_rng(seed)
    code = g.random((nx, ny, nl) if shots == 1 else (nx, ny, nl, shots))
    check(SDCASSI(code, n_bands=nl, shifts=s, colour=True), seed)


def test_colour_coded_sdcassi_against_the_loop_of_its_definition():
    # G[i, j + s_l, k] = Σ_l C[i, j, l, k] F[i, j, l], integer shifts, written out
    g = np.random.default_rng(5)
    nx, ny, nl, k = 4, 5, 3, 2
    code, cube, s = g.random((nx, ny, nl, k)), g.random((nx, ny, nl)), [0, 2, 3]
    ref = np.zeros((nx, ny + 3, k))
    for i, j, l, t in np.ndindex(nx, ny, nl, k):
        ref[i, j + s[l], t] += code[i, j, l, t] * cube[i, j, l]
    sd = SDCASSI(code, n_bands=nl, shifts=s, colour=True)
    np.testing.assert_allclose(sd.forward(cube), ref, rtol=1e-12)
    # a band-constant colour code is the plain code
    flat = np.repeat(code[:, :, :1, 0], nl, axis=2)
    plain = SDCASSI(code[:, :, 0, 0], n_bands=nl, shifts=s)
    np.testing.assert_allclose(
        SDCASSI(flat, n_bands=nl, shifts=s, colour=True).forward(cube), plain.forward(cube)
    )
