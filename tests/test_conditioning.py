"""studies.conditioning: eigenvalues of A Aᵀ from the derived structure equal the dense ones on
every system; Lanczos agrees where there is no structure; Gershgorin bounds enclose them."""

import numpy as np
import pytest

from tensor_cosdi import studies


@pytest.mark.parametrize(
    "name", ["sd_cassi", "cassi_vsi", "c3slfi", "cs2li", "cassdi_dfa", "dual_camera_cassi"]
)
def test_extreme_eigenvalues_match_the_dense_matrix(name):
    opts = {"views": (2, 2), "n_snapshots": 2} if name == "c3slfi" else {}
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
    assert c["method"] == ("dense" if name == "dual_camera_cassi" else "structure")


def test_lanczos_estimates_agree_without_structure():
    p = studies.make_problem("dual_camera_cassi", "chelsea", shape=(10, 10), n_bands=3, rng=0)
    dense = studies.conditioning(p.system)
    lan = studies.conditioning(p.system, exact_below=0)
    assert lan["method"] == "lanczos"
    assert lan["lambda_max"] == pytest.approx(dense["lambda_max"], rel=1e-5)
    assert lan["lambda_min"] == pytest.approx(dense["lambda_min"], abs=1e-4 * dense["lambda_max"])
