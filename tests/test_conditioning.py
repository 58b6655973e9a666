"""studies.conditioning: eigenvalues of A Aᵀ from the derived structure equal the dense ones on
every system; Lanczos agrees where there is no structure; Gershgorin bounds enclose them."""

import numpy as np
import pytest

from tensor_cosdi import studies


@pytest.mark.parametrize(
    "name",
    ["sd_cassi", "cassi_vsi", "c3slfi", "cs2li", "cassdi_dfa", "dual_camera_cassi", "lytro_cassi"],
)
def test_extreme_eigenvalues_match_the_dense_matrix(name):
    opts = {"views": (2, 2), "n_snapshots": 2} if name in ("c3slfi", "lytro_cassi") else {}
    p = studies.make_problem(name, "chelsea", shape=(12, 12), n_bands=4, rng=0, **opts)
    c = studies.conditioning(p.system)
    M = p.system.operator.to_matrix()
    ev = np.linalg.eigvalsh((M @ M.T).toarray())
    assert c["lambda_max"] == pytest.approx(ev.max(), rel=1e-9)
    assert c["lambda_min"] == pytest.approx(ev.min(), abs=1e-9 * ev.max())
    nz = ev[ev > 1e-8 * ev.max()]
    assert c["lambda_min_nonzero"] == pytest.approx(nz.min(), rel=1e-8)
    assert c["zero"] == ev.size - nz.size
    assert c["gershgorin_min"] <= ev.min() + 1e-9 and c["gershgorin_max"] >= ev.max() - 1e-9
    assert c["method"] == "structure"


def test_lanczos_estimates_agree_without_structure():
    from tensor_cosdi.systems import CASSDIDFA

    system = CASSDIDFA.example((6, 6, 2, 3), psf_size=5)  # PSFs: no structure of A Aᵀ
    assert system.gram_dual() is None
    dense = studies.conditioning(system)
    lan = studies.conditioning(system, exact_below=0)
    assert dense["method"] == "dense"
    assert lan["method"] == "lanczos"
    assert lan["lambda_max"] == pytest.approx(dense["lambda_max"], rel=1e-5)
    assert lan["lambda_min"] == pytest.approx(dense["lambda_min"], abs=1e-4 * dense["lambda_max"])


# ---- design sweeps ------------------------------------------------------------------------------
def test_design_sweep_builds_the_system_it_names():
    """Every record is the conditioning of the example built with that value, shape axes
    included (DFA planes replace the cube's fourth axis)."""
    from tensor_cosdi.systems import CASSDIDFA, CASSIVSI

    recs = studies.conditioning_design("cassi_vsi", "beta", [0, 5], cube_shape=(10, 10, 6))
    for r in recs:
        ref = studies.conditioning(CASSIVSI.example((10, 10, 6), rng=0, beta=r["beta"]))
        assert r["cond_nonzero"] == pytest.approx(ref["cond_nonzero"], rel=1e-12)
    assert recs[0]["cond_nonzero"] != pytest.approx(recs[1]["cond_nonzero"], rel=1e-6)
    dfa = studies.conditioning_design("cassdi_dfa", "n_depths", [2, 4], cube_shape=(10, 10, 4, 3))
    for r in dfa:
        ref = studies.conditioning(CASSDIDFA.example((10, 10, 4, r["n_depths"]), rng=0))
        assert r["lambda_max"] == pytest.approx(ref["lambda_max"], rel=1e-12)
    # more planes share one detector: the spread of A Aᵀ grows
    assert dfa[1]["cond_nonzero"] > dfa[0]["cond_nonzero"]


def test_design_sweep_alpha_t_orders_as_the_thesis():
    recs = studies.conditioning_design("cassi_vsi", "alpha_t", [0.1, 0.5, 0.9])
    kappa = [r["cond_nonzero"] for r in recs]
    assert kappa[0] > kappa[1] > kappa[2]


@pytest.mark.parametrize(
    "args, match",
    [
        (("cassi_vsi", "n_depths", [2]), "not a design parameter of 'cassi_vsi'"),
        (("cassdi_dfa", "n_depths", [0]), "positive integer"),
        (("cassi_vsi", "alpha_t", []), "values is empty"),
        (("cs2li", "n_patterns", [2], (8, 8, 4)), "has 4 axes"),
    ],
)
def test_design_sweep_errors(args, match):
    name, param, values, *shape = args
    with pytest.raises(ValueError, match=match):
        studies.conditioning_design(name, param, values, cube_shape=shape[0] if shape else None)


def test_vsi_arms_against_explicit_matrices():
    """κ(H Dᵀ) from the row probes equals the dense product with Dᵀ; the arm SNRs follow the
    arms' energies; the dynamic-range error is the mean over pixels both arms light."""
    from tensor_cosdi import scenes
    from tensor_cosdi.codes import random_binary
    from tensor_cosdi.systems import CASSIVSI, wavelengths_for

    (r,) = studies.vsi_arms(("colorchecker",), (0.6,), shape=(6, 7), n_bands=3, snr_db=25.0)
    wl = wavelengths_for(None, 3)
    vsi = CASSIVSI(random_binary((6, 7), transmittance=0.5, rng=0), n_bands=3, alpha_t=0.6,
                   wavelengths=wl)  # fmt: skip
    H = vsi.operator.to_matrix().toarray()
    cols = []
    for k in range(6 * 7):  # Dᵀ e_k: the panchromatic pixel k spread over every band
        z = np.zeros((6, 7, 3))
        z.reshape(-1, 3)[k] = 1.0
        cols.append(np.asarray(vsi.forward(z)).ravel())
    s = np.linalg.svd(np.stack(cols, axis=1), compute_uv=False)
    # to_matrix is column-major: band l of pixel k is column k + 42 l
    dense = np.linalg.svd(H @ np.tile(np.eye(42), (3, 1)), compute_uv=False)
    assert np.allclose(s, dense)
    s = s[s > 1e-8 * s.max()]
    assert r["cond_HDt"] == pytest.approx((s.max() / s.min()) ** 2, rel=1e-9)
    cube = np.asarray(scenes.scene_cube("colorchecker", (6, 7), wl))
    gt = 0.6 * np.asarray(vsi.arms[0].forward(cube))
    gr = 0.4 * np.asarray(vsi.arms[1].forward(cube))
    # both arms see the same noise: their SNR difference is their energy ratio
    assert r["snr_t"] - r["snr_r"] == pytest.approx(10 * np.log10((gt**2).sum() / (gr**2).sum()))
    assert r["snr_mean"] == pytest.approx((r["snr_t"] + r["snr_r"]) / 2)
    lit = (gt > 0) & (gr > 0)
    assert r["range_error"] == pytest.approx(np.abs(gt[lit] / gr[lit] - gr[lit] / gt[lit]).mean())


def test_vsi_arms_reproduces_the_thesis_trends():
    """Seeded 32×32×8 on a real scene: κ(H) falls and κ(H Dᵀ) rises with αT; the arm SNRs
    cross and the dynamic range balances between 0.5 and 0.8 (thesis: 0.6 and 0.7)."""
    alphas = (0.1, 0.3, 0.5, 0.6, 0.7, 0.8, 0.9)
    recs = studies.vsi_arms((studies_scene(),), alphas, shape=(32, 32), n_bands=8)
    h = [r["cond_H"] for r in recs]
    hd = [r["cond_HDt"] for r in recs]
    assert all(a > b for a, b in zip(h, h[1:])) and all(a < b for a, b in zip(hd, hd[1:]))
    best_snr = alphas[int(np.argmax([r["snr_mean"] for r in recs]))]
    best_range = alphas[int(np.argmin([r["range_error"] for r in recs]))]
    assert 0.5 <= best_snr <= 0.8 and 0.5 <= best_range <= 0.8
    with pytest.raises(ValueError, match="fractions in"):
        studies.vsi_arms(("colorchecker",), (1.2,))


def studies_scene():
    from tensor_cosdi import datasets

    try:
        return datasets.scene_or("cave.face", "chelsea")[0]
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")


def test_conditioning_options_are_checked():
    p = studies.make_problem("sd_cassi", shape=(8, 8), n_bands=4)
    with pytest.raises(ValueError, match="exact_below must be an integer ≥ 0"):
        studies.conditioning(p.system, exact_below=-1)
    with pytest.raises(ValueError, match="tol must be"):
        studies.conditioning(p.system, tol=0.0)
