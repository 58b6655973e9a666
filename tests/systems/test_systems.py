"""Systems: Gram structures, structured solves, Lemma 1, layouts, real masks, simulate,
panchromatic."""

import os
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
import tensorly as tl

import tensor_cosdi as tc
from tensor_cosdi import _backend as B
from tensor_cosdi import codes
from tensor_cosdi.noise import snr_db
from tensor_cosdi.operators import Diagonal, FoldedBanded, PixelBlocks, RowBanded, vec
from tensor_cosdi.systems import (
    C3SLFI,
    CASSDIDFA,
    CASSIVSI,
    CS2LI,
    DDCASSI,
    SDCASSI,
    DualCameraCASSI,
    LytroCASSI,
    MuCoSDI,
    fringe_cube,
)
from tensor_cosdi.testing import dot_test

# the project's real data: $TENSOR_COSDI_DATA, else ../shared/data next to the repository
DATA = Path(
    os.environ.get(
        "TENSOR_COSDI_DATA", Path(__file__).resolve().parents[2] / ".." / "shared" / "data"
    )
)
MASKS = DATA / "masks"
needs_masks = pytest.mark.skipif(
    not MASKS.is_dir(), reason=f"{MASKS} is not present (set TENSOR_COSDI_DATA to the data folder)"
)

# (id, factory, structure of A Aᵀ by SPEC §4)
SYSTEMS = [
    ("sdcassi", lambda: SDCASSI.example((6, 7, 5)), Diagonal),
    ("sdcassi_shots", lambda: SDCASSI.example((5, 6, 4), shots=3, shifts=2), PixelBlocks),
    ("sdcassi_fractional", lambda: SDCASSI.example((5, 6, 4), shifts=[0, 0.5, 1.5, 2]), RowBanded),
    ("ddcassi", lambda: DDCASSI.example((6, 7, 5)), Diagonal),
    ("dual_camera", lambda: DualCameraCASSI.example((5, 6, 4)), FoldedBanded),
    ("lytro_cassi", lambda: LytroCASSI.example((6, 8, 4), n_snapshots=3), FoldedBanded),
    ("cassi_vsi", lambda: CASSIVSI.example((6, 7, 5), beta=2), RowBanded),
    ("cassdi_dfa", lambda: CASSDIDFA.example((5, 6, 4, 3)), Diagonal),
    ("cassdi_dfa_psf", lambda: CASSDIDFA.example((5, 5, 3, 2), psf_size=3), type(None)),
    ("c3slfi_3d", lambda: C3SLFI.example((6, 6, 5), n_snapshots=3, views=(3, 2)), PixelBlocks),
    ("c3slfi_5d", lambda: C3SLFI.example((2, 3, 4, 2, 2)), PixelBlocks),
    (
        "c3slfi_separable",
        lambda: C3SLFI.separable(np.eye(3)[[0, 1, 2, 0]].T, (4, 4, 4)),
        PixelBlocks,
    ),
    ("cs2li", lambda: CS2LI.example((5, 6, 4, 3), n_filters=2), Diagonal),
    ("mu_cosdi_sl", lambda: MuCoSDI.example((5, 6, 4, 2)), Diagonal),
    ("mu_cosdi_lf", lambda: MuCoSDI.example((4, 6, 3), modality="lf"), Diagonal),
    ("mu_cosdi_monocular", lambda: MuCoSDI.example((5, 6, 4), modality="monocular"), Diagonal),
]
IDS = [s[0] for s in SYSTEMS]


@pytest.mark.parametrize("factory, structure", [s[1:] for s in SYSTEMS], ids=IDS)
def test_gram_structure(factory, structure):
    system = factory()
    assert type(system.gram_dual()) is structure


@pytest.mark.parametrize("factory", [s[1] for s in SYSTEMS], ids=IDS)
@pytest.mark.parametrize("mu", [1e-3, 1.0, 1e2])
def test_solve_normal_equals_dense_solve(factory, mu):
    system = factory()
    H = system.matrix().toarray()
    r = np.random.default_rng(3).standard_normal(system.cube_shape)
    ref = np.linalg.solve(H.T @ H + mu * np.eye(H.shape[1]), vec(r))
    got = vec(system.solve_normal(r, mu))
    assert np.linalg.norm(got - ref) <= 1e-8 * np.linalg.norm(ref)


def test_vsi_banded_width_is_the_dispersion_width():
    vsi = CASSIVSI.example((4, 9, 6), beta=3)  # S = 5 columns of coupling
    assert vsi.gram_dual().bandwidth <= 5


# ---- C3SLFI: Lemma 1, complementarity, layouts ---------------------------------------
@pytest.mark.parametrize("shape", [(6, 8, 7), (3, 4, 7, 2, 2)])
@pytest.mark.parametrize("K", [2, 3, 5])
def test_lemma1_sum_of_snapshots_is_the_panchromatic(shape, K):
    system = C3SLFI.example(shape, n_snapshots=K, rng=K)
    F = np.random.default_rng(K).random(shape)
    G = system.forward(F)
    Z = F.sum(axis=2)
    np.testing.assert_allclose(G.sum(axis=2), Z, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(system.panchromatic(G), Z, rtol=1e-13, atol=1e-13)


def test_lemma1_fails_without_complementary_codes():
    T = codes.complementary_colour_codes((6, 6, 5), 2, rng=0)
    T[2, 3, 1, :] = 0.0  # one voxel no longer passes in any snapshot
    system = C3SLFI(T, views=(2, 2), complementary=False)
    F = np.random.default_rng(0).random(system.cube_shape) + 0.5
    G = system.forward(F)
    assert abs(G.sum(axis=2) - F.sum(axis=2)).max() > 0.4
    # the panchromatic estimate falls back to least squares (not Lemma 1)
    assert system.panchromatic(G).shape == (6, 6)


def test_non_complementary_codes_are_an_error_where_required():
    T = codes.complementary_colour_codes((4, 4, 5), 2, rng=0)
    T[1, 2, 3] = [0.7, 1.0]
    with pytest.raises(ValueError, match=r"not complementary.*1\.7 at index \(1, 2, 3\)"):
        C3SLFI(T)
    with pytest.raises(ValueError, match="K ≥ 2"):
        C3SLFI(np.ones((4, 4, 5, 1)))
    C3SLFI(np.ones((4, 4, 5, 1)), complementary=False)  # allowed when asked
    with pytest.raises(ValueError, match="not complementary"):
        C3SLFI.separable(np.full((2, 5), 0.4), (4, 4, 5))


@pytest.mark.parametrize("raw", ["interleaved", "tiled"])
def test_3d_5d_round_trips(raw):
    five = C3SLFI.example((3, 4, 5, 2, 3), n_snapshots=3, rng=1)
    three = five.as_3d(raw)
    assert three.cube_shape == (6, 12, 5) and three.views == (2, 3)
    F5 = np.random.default_rng(2).standard_normal(five.cube_shape)
    F3 = three.to_3d(F5)
    np.testing.assert_array_equal(three.to_5d(F3), F5)
    np.testing.assert_array_equal(three.to_3d(three.to_5d(F3)), F3)
    # the two parameterisations are the same system: sensing commutes with the layouts
    G5 = five.forward(F5)
    np.testing.assert_array_equal(three.forward(F3), three.measurement_to_3d(G5))
    np.testing.assert_array_equal(three.measurement_to_5d(three.forward(F3)), G5)
    np.testing.assert_array_equal(three.as_5d().codes, five.codes)
    # the interleaved layout is Eq. 85
    if raw == "interleaved":
        j1, j2, l = 3, 7, 4
        assert F3[j1, j2, l] == F5[j1 // 2, j2 // 3, l, j1 % 2, j2 % 3]
    else:
        j1, j2, l = 4, 9, 2
        assert F3[j1, j2, l] == F5[j1 % 3, j2 % 4, l, j1 // 3, j2 // 4]


def test_tiled_interleaved_round_trip():
    inter = C3SLFI.example((6, 6, 4), views=(2, 3), rng=3)
    tiled = inter.as_3d("tiled")
    back = tiled.as_3d("interleaved")
    np.testing.assert_array_equal(back.codes, inter.codes)
    F = np.random.default_rng(4).standard_normal(inter.cube_shape)
    Ft = tiled.to_3d(inter.to_5d(F))
    np.testing.assert_array_equal(inter.to_3d(tiled.to_5d(Ft)), F)
    np.testing.assert_array_equal(
        tiled.measurement_to_5d(tiled.forward(Ft)), inter.measurement_to_5d(inter.forward(F))
    )


def test_separable_round_trip_keeps_the_n_mode_form():
    phi = codes.filter_passbands(6, 2)
    s3 = C3SLFI.separable(phi, (4, 6, 6), views=(2, 2))
    s5 = s3.as_5d()
    assert s5.phi is not None and s5.cube_shape == (2, 3, 6, 2, 2)
    F = np.random.default_rng(0).standard_normal(s5.cube_shape)
    np.testing.assert_array_equal(s3.forward(s3.to_3d(F)), s3.measurement_to_3d(s5.forward(F)))


def test_conversion_needs_views():
    with pytest.raises(ValueError, match="views"):
        C3SLFI.example((4, 4, 5), views=None).as_5d()


def test_fig103_tensor_block_inverse_equals_matrix_inverse():
    """Appendix D, Fig. 103: the K×K-block tensor inverse equals the matrix inverse, 200 trials.

    Ñ1 = Ñ2 = 32, N3 = 8, K = 4, random (non-complementary) colour codes and
    a random μ per trial; the matrix side is a sparse LU of ``μI + HHᵀ`` and of
    ``HᵀH + μI`` built from Eq. 206-207.
    """
    from scipy.sparse.linalg import splu

    g = np.random.default_rng(103)
    worst_dual = worst_normal = 0.0
    for _ in range(200):
        system = C3SLFI(g.random((32, 32, 8, 4)), complementary=False)
        mu = 10.0 ** g.uniform(-3, 1)
        H = system.matrix()
        b = g.standard_normal(system.measurement_shape)
        r = g.standard_normal(system.cube_shape)
        x_tensor = vec(system.operator.solve_dual(b, mu))
        x_matrix = splu((mu * sp.identity(H.shape[0]) + H @ H.T).tocsc()).solve(vec(b))
        worst_dual = max(worst_dual, np.linalg.norm(x_tensor - x_matrix) / np.linalg.norm(x_matrix))
        y_tensor = vec(system.solve_normal(r, mu))
        y_matrix = splu((H.T @ H + mu * sp.identity(H.shape[1])).tocsc()).solve(vec(r))
        worst_normal = max(
            worst_normal, np.linalg.norm(y_tensor - y_matrix) / np.linalg.norm(y_matrix)
        )
    assert worst_dual < 1e-12, worst_dual
    assert worst_normal < 1e-10, worst_normal


# ---- real masks -------------------------------------------------------------------
@needs_masks
@pytest.mark.parametrize(
    "name, shift, n_bands, expected",
    [("tsa_mask256.mat", 2, 28, (256, 310)), ("pnp_mask256.mat", 1, 31, (256, 286))],
)
def test_real_masks(name, shift, n_bands, expected):
    mask = scipy.io.loadmat(MASKS / name)["mask"]
    system = SDCASSI(mask, n_bands=n_bands, shifts=shift)
    assert system.cube_shape == (256, 256, n_bands)
    assert system.measurement_shape == expected
    assert dot_test(system.operator) < 1e-10
    # band l of a point lands 2l (or l) columns to the right, weighted by the mask there
    F = np.zeros(system.cube_shape)
    F[10, 20, n_bands - 1] = 1.0
    G = system.forward(F)
    assert G[10, 20 + shift * (n_bands - 1)] == pytest.approx(mask[10, 20])
    assert np.count_nonzero(G) == (mask[10, 20] != 0)


@pytest.mark.parametrize(
    "mask, shift, n_bands, expected",
    [
        (
            np.random.default_rng(0).uniform(0.0066, 1, (256, 256)).astype(np.float32),
            2,
            28,
            (256, 310),
        ),
        (codes.random_binary((256, 256), rng=1), 1, 31, (256, 286)),
    ],
    ids=["tsa_like", "pnp_like"],
)
def test_standard_protocol_geometry(mask, shift, n_bands, expected):
    """The geometry of the two standard CASSI protocols, with masks like the real ones (always
    runs)."""
    system = SDCASSI(mask, n_bands=n_bands, shifts=shift)
    assert system.measurement_shape == expected
    F = np.ones(system.cube_shape, dtype=np.float32)
    G = system.forward(F)
    assert G.dtype == np.float32 and G.shape == expected
    np.testing.assert_allclose(G[:, 0], mask[:, 0], rtol=1e-6)  # only band 0 reaches column 0


# ---- simulate, panchromatic ---------------------------------------------------------
@pytest.mark.parametrize("factory", [s[1] for s in SYSTEMS], ids=IDS)
def test_simulate_noise_level_and_seed(factory):
    system = factory()
    F = np.random.default_rng(0).random(system.cube_shape) + 0.1
    clean = system.forward(F)
    np.testing.assert_array_equal(system.simulate(F), clean)
    a = system.simulate(F, 20.0, rng=5)
    np.testing.assert_array_equal(a, system.simulate(F, 20.0, rng=5))
    assert not np.array_equal(a, system.simulate(F, 20.0, rng=6))
    if isinstance(system, DualCameraCASSI):
        ny = system.cube_shape[1]
        np.testing.assert_array_equal(a[:, :ny, 1], clean[:, :ny, 1])  # noise-free side information
        np.testing.assert_array_equal(a[:, ny:, 1], 0.0)
        a, clean = a[:, :, 0], clean[:, :, 0]
    assert abs(snr_db(clean, a) - 20.0) < 3.0  # tiny sizes: a few hundred samples


def test_simulate_snr_on_a_large_measurement():
    system = SDCASSI.example((128, 128, 8))
    F = np.random.default_rng(1).random(system.cube_shape)
    assert abs(snr_db(system.forward(F), system.simulate(F, 25.0, rng=0)) - 25.0) < 0.1


@pytest.mark.parametrize(
    "system",
    [
        DDCASSI.example((6, 7, 5), transmittance=0.9),
        CS2LI.example((6, 7, 5, 3), n_filters=1, transmittance=0.9),
        MuCoSDI.example((6, 7, 5), modality="monocular", transmittance=0.9),
    ],
    ids=["dd", "cs2li", "mu_cosdi"],
)
def test_panchromatic_is_exact_for_flat_spectra_on_aligned_systems(system):
    """Dual-disperser measurements are per pixel: a spectrally flat cube gives Z back wherever a
    band is open."""
    g = np.random.default_rng(0)
    shape = system.cube_shape
    Z = g.random(shape[:2] + shape[3:]) + 0.5
    F = np.repeat(np.expand_dims(Z, 2), shape[2], axis=2) / shape[2]
    est = system.panchromatic(system.forward(F), mu=1e-12)
    open_ = (
        np.sum(
            system.effective_code
            if hasattr(system, "effective_code")
            else system.effective_codes[0],
            2,
        )
        > 0
    )
    open_ = open_.reshape(open_.shape + (1,) * (Z.ndim - 2))
    np.testing.assert_allclose(np.where(open_, est, Z), Z, rtol=1e-8)


@pytest.mark.parametrize(
    "system",
    [
        SDCASSI.example((5, 6, 4)),
        CASSIVSI.example((5, 6, 4)),
        CASSDIDFA.example((4, 5, 3, 2), psf_size=3),
    ],
    ids=["sd", "vsi", "dfa_psf"],
)
def test_panchromatic_is_the_tikhonov_solution_of_the_decimated_model(system):
    """``Z = argmin ‖G − A Dᵀ Z / n‖² + μ s ‖Z‖²`` (SPEC §5 step 1), checked against a dense
    solve."""
    g = np.random.default_rng(1)
    G = g.standard_normal(system.measurement_shape)
    D = system.decimation.to_matrix()
    n = D.shape[1] / D.shape[0]
    M = (system.matrix() @ D.T).toarray() / n
    s = np.sum((M @ np.ones(M.shape[1])) ** 2) / M.shape[1]
    mu = 1e-2
    ref = np.linalg.solve(M.T @ M + mu * s * np.eye(M.shape[1]), M.T @ vec(G))
    got = system.panchromatic(G, mu=mu)
    assert got.shape == system.panchromatic_shape
    np.testing.assert_allclose(vec(got), ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max())


def test_panchromatic_shapes():
    assert CASSDIDFA.example().panchromatic_shape == (
        16,
        16,
    )  # all-in-focus grayscale (λ and z summed)
    assert CS2LI.example().panchromatic_shape == (16, 16, 4)  # grayscale fringe images
    assert C3SLFI.example((2, 3, 4, 2, 2)).panchromatic_shape == (2, 3, 2, 2)
    dual = DualCameraCASSI.example((4, 5, 3))
    F = np.random.default_rng(0).random(dual.cube_shape)
    np.testing.assert_allclose(dual.panchromatic(dual.forward(F)), F.sum(2), rtol=1e-14)


def test_panchromatic_checks_its_input():
    sd = SDCASSI.example((4, 5, 3))
    with pytest.raises(ValueError, match=r"\(4, 7\)"):
        sd.panchromatic(np.zeros((4, 5)))
    with pytest.raises(ValueError, match="mu"):
        sd.panchromatic(np.zeros((4, 7)), mu=-1)
    bad = np.zeros((4, 7))
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        sd.panchromatic(bad)


# ---- fringes -------------------------------------------------------------------
def test_fringe_cube_physics():
    g = np.random.default_rng(0)
    F = g.random((5, 6, 4))
    phases = g.uniform(-np.pi, np.pi, (5, 6, 2))
    P = fringe_cube(F, phases, n_steps=4, offset=1.0, amplitude=0.8)
    assert P.shape == (5, 6, 4, 8)
    # a full phase cycle sums to K · offset · F (the panchromatic of SPEC §5)
    np.testing.assert_allclose(P[..., :4].sum(-1), 4 * F, rtol=1e-12)
    np.testing.assert_allclose(P[..., 4:].sum(-1), 4 * F, rtol=1e-12)
    # pattern t = f·K + k is F · (b + a cos(φ_f + 2πk/K))
    np.testing.assert_allclose(
        P[2, 3, 1, 6], F[2, 3, 1] * (1 + 0.8 * np.cos(phases[2, 3, 1] + np.pi))
    )
    system = CS2LI.example((5, 6, 4, 8))
    assert system.forward(P).shape == (5, 6, 8)


def test_fringe_cube_errors():
    with pytest.raises(ValueError, match="n_steps"):
        fringe_cube(np.ones((2, 2, 3)), np.zeros((2, 2)), n_steps=2)
    with pytest.raises(ValueError, match="amplitude ≤ offset"):
        fringe_cube(np.ones((2, 2, 3)), np.zeros((2, 2)), offset=0.5)
    with pytest.raises(ValueError, match="phases must have shape"):
        fringe_cube(np.ones((2, 2, 3)), np.zeros((3, 2)))


# ---- immutability, backends ------------------------------------------------------------
def test_systems_are_frozen():
    sd = SDCASSI.example()
    with pytest.raises(AttributeError, match="immutable"):
        sd.shifts = 3
    with pytest.raises(ValueError, match="read-only"):
        sd.code[0, 0] = 5.0
    code = codes.random_binary((4, 5), rng=0)
    sd = SDCASSI(code, n_bands=3)
    code[:] = 0  # the caller's array is copied
    assert sd.code.sum() > 0


@pytest.mark.parametrize("factory", [s[1] for s in SYSTEMS], ids=IDS)
def test_backends_agree(factory, backend):
    _, dtype = backend
    system = factory()
    g = np.random.default_rng(0)
    F = g.standard_normal(system.cube_shape)
    G = g.standard_normal(system.measurement_shape)
    tol = 1e-12 if dtype == "float64" else 1e-4
    fwd = B.to_numpy(system.forward(B.as_tensor(F, dtype)))
    adj = B.to_numpy(system.adjoint(B.as_tensor(G, dtype)))
    H = system.matrix()
    np.testing.assert_allclose(vec(fwd), H @ vec(F), atol=tol * np.abs(H @ vec(F)).max())
    np.testing.assert_allclose(vec(adj), H.T @ vec(G), atol=tol * np.abs(H.T @ vec(G)).max())
    assert tl.is_tensor(
        system.panchromatic(
            B.as_tensor(np.asarray(H @ vec(F)).reshape(system.measurement_shape, order="F"), dtype)
        )
    )


@pytest.mark.parametrize("factory", [s[1] for s in SYSTEMS], ids=IDS)
def test_systems_pickle(factory):
    """Systems travel to Dask workers: a pickled copy senses identically."""
    import pickle

    system = factory()
    copy = pickle.loads(pickle.dumps(system))
    F = np.random.default_rng(0).random(system.cube_shape)
    np.testing.assert_array_equal(copy.forward(F), system.forward(F))
    with pytest.raises(AttributeError):
        copy.operator = None


@pytest.mark.parametrize("name", ["sd_cassi", "cassi_vsi", "c3slfi", "cs2li"])
def test_micrometre_wavelengths_are_refused_at_the_door(name):
    cls = tc.systems.REGISTRY[name]
    good = cls.example(rng=0)
    n = len(good.wavelengths)
    with pytest.raises(ValueError, match="look like micrometres"):
        cls.example(rng=0, wavelengths=np.asarray(good.wavelengths) / 1000.0)
    assert len(cls.example(rng=0, wavelengths=good.wavelengths).wavelengths) == n


def test_a_mirrored_dispersion_measures_the_band_reversed_cube(rng):
    """``shear_direction=-1`` shifts the first band most; it measures the band-reversed cube
    exactly as the usual direction measures the cube (why a fit cannot find the direction),
    keeps its explicit matrix, adjoint and diagonal ``A Aᵀ``, and survives a state round
    trip."""
    code = rng.random((6, 7))
    fwd = SDCASSI(code, n_bands=5, shifts=2)
    mir = SDCASSI(code, n_bands=5, shifts=2, shear_direction=-1)
    assert fwd.shear_direction == 1 and mir.shear_direction == -1
    assert mir.shifts.tolist() == [8, 6, 4, 2, 0] and mir.measurement_shape == (6, 15)
    cube = rng.random((6, 7, 5))
    np.testing.assert_allclose(mir.forward(cube[:, :, ::-1]), fwd.forward(cube), atol=1e-12)
    assert not np.allclose(mir.forward(cube), fwd.forward(cube))
    np.testing.assert_allclose(vec(mir.forward(cube)), mir.matrix() @ vec(cube), atol=1e-12)
    assert dot_test(mir.operator) < 1e-12
    assert isinstance(mir.gram_dual(), Diagonal)
    back = SDCASSI.from_state(mir.to_state())
    assert back.shear_direction == -1 and back.shifts.tolist() == mir.shifts.tolist()
    for bad in (0, 2, True, "-1"):
        with pytest.raises(ValueError, match="shear_direction must be 1 or -1"):
            SDCASSI(code, n_bands=5, shifts=2, shear_direction=bad)
