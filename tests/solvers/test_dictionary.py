"""The DL-3D baseline: Batch-OMP, K-SVD, the patch-dictionary denoiser and method "dl"."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import datasets, studies
from tensor_cosdi.solvers.dictionary import PatchDictionary, omp, omp_codes, train_dictionary


def _dictionary(rng, dim=40, k=80):
    D = rng.standard_normal((dim, k))
    return D / np.linalg.norm(D, axis=0)


def test_omp_recovers_sparse_codes_and_stops_at_the_tolerance():
    rng = np.random.default_rng(0)
    D = _dictionary(rng)
    X = np.zeros((80, 300))
    for n in range(300):
        X[rng.choice(80, 3, replace=False), n] = rng.choice([-1, 1], 3) * (1 + rng.random(3))
    got = omp(D, D @ X, n_nonzero=3, chunk=64)  # chunks must not change anything
    assert np.mean(np.all(np.abs(got - X) < 1e-8, axis=0)) > 0.95
    Y = rng.standard_normal((40, 200))
    tol = 15.0
    codes = omp(D, Y, n_nonzero=30, tol=tol)
    resid = ((Y - D @ codes) ** 2).sum(axis=0)
    used = (codes != 0).sum(axis=0)
    assert np.all(resid <= tol + 1e-8)
    # one atom fewer would not have been enough: the greedy prefix had a residual above tol
    for n in np.flatnonzero(used > 1)[:20]:
        fewer = omp(D, Y[:, [n]], n_nonzero=int(used[n]) - 1)
        assert ((Y[:, n] - D @ fewer[:, 0]) ** 2).sum() > tol


def test_omp_codes_are_the_dense_codes_and_the_denoiser_synthesises_them():
    rng = np.random.default_rng(2)
    D = _dictionary(rng, dim=4 * 4 * 3, k=96)
    Y = rng.standard_normal((48, 150))
    idx, coef, used = omp_codes(D, Y, n_nonzero=6, tol=20.0, chunk=32)
    X = omp(D, Y, n_nonzero=6, tol=20.0)
    assert used.min() >= 1 and used.max() <= 6 and 1 < used.mean() < 6  # stops vary
    dense = np.zeros_like(X)
    for j in range(Y.shape[1]):
        assert np.all(coef[j, used[j] :] == 0)
        dense[idx[j, : used[j]], j] = coef[j, : used[j]]
    np.testing.assert_array_equal(dense, X)
    # the denoiser's sparse synthesis equals averaging the dense codes' patches
    d = PatchDictionary(D, 4, 3, stride=2, max_nonzero=6)
    cube = rng.random((10, 12, 3))
    sigma = 0.2
    grid = [np.r_[np.arange(0, n - 4, 2), n - 4] for n in cube.shape[:2]]  # stride 2, to the edge
    patches = np.stack([cube[r : r + 4, c : c + 4].ravel() for r in grid[0] for c in grid[1]], 1)
    codes = omp(d.atoms, patches, n_nonzero=6, tol=48 * (1.15 * sigma) ** 2)
    synth = (d.atoms @ codes).T
    want, weight = np.zeros_like(cube), np.zeros(cube.shape[:2])
    for n, (r, c) in enumerate((r, c) for r in grid[0] for c in grid[1]):
        want[r : r + 4, c : c + 4] += synth[n].reshape(4, 4, 3)
        weight[r : r + 4, c : c + 4] += 1
    np.testing.assert_allclose(d(cube, sigma), want / weight[:, :, None], atol=1e-12)


def test_ksvd_lowers_the_representation_error():
    rng = np.random.default_rng(1)
    atoms = _dictionary(rng, dim=4 * 4 * 2, k=20)
    codes = np.zeros((20, 600))
    for n in range(600):
        codes[rng.choice(20, 2, replace=False), n] = rng.random(2) + 0.5
    patches = (atoms @ codes).T.reshape(600, 4, 4, 2)
    cubes = list(patches)  # one 4×4×2 patch per cube: every sample is 2-sparse in `atoms`

    def error(d):
        Y = patches.reshape(600, 32).T
        return np.linalg.norm(Y - d.atoms @ omp(d.atoms, Y, n_nonzero=2)) / np.linalg.norm(Y)

    first = train_dictionary(cubes, patch=4, n_atoms=20, sparsity=2, n_patches=1200, n_iter=1)
    more = train_dictionary(cubes, patch=4, n_atoms=20, sparsity=2, n_patches=1200, n_iter=15)
    assert error(more) < 0.7 * error(first)


@pytest.fixture(scope="module")
def light_fields():
    """Seeded 32×32 lenslet light fields (2×2 views, 8 bands): tuning scenes to train on and a
    report scene to score; photo scenes without the research data."""
    try:
        datasets.data_dir()
        train, test = [f"cave.{s}" for s in datasets.TUNE_SCENES[:4]], "cave.face"
    except FileNotFoundError:
        train, test = ["chelsea", "coffee", "astronaut", "rocket"], "colorchecker"
    opts = {"shape": (32, 32), "n_bands": 8, "rng": 0, "n_snapshots": 2, "views": (2, 2)}
    cubes = [studies.make_problem("c3slfi", s, **opts).cube for s in train]
    d = train_dictionary(cubes, patch=6, n_patches=1500, n_iter=3)
    return d, studies.make_problem("c3slfi", test, snr_db=20.0, **opts)


def test_dl_beats_its_warm_start_on_real_spectra(light_fields):
    """Floor on a seeded crop: measured 28.0 dB on cave.face, where its GAP-TV start reaches
    22.9 dB and WDCT 25.6 dB; an identity prior would stay near the start."""
    d, p = light_fields
    start = tc.reconstruct(p.system, p.measurement, "gap_tv", max_iter=20).cube
    res = tc.reconstruct(p.system, p.measurement, "dl", dictionary=d)
    gain = studies.score(p, res.cube)["psnr"] - studies.score(p, start)["psnr"]
    assert gain > 3.0
    if p.name.endswith("cave.face"):
        assert studies.score(p, res.cube)["psnr"] > 27.0


def test_denoiser_and_file_round_trip(light_fields, tmp_path):
    d, p = light_fields
    rng = np.random.default_rng(0)
    clean = np.asarray(p.cube)
    sigma = 0.05 * clean.max()
    noisy = clean + sigma * rng.standard_normal(clean.shape)
    out = d(noisy, sigma)
    assert np.linalg.norm(out - clean) < 0.7 * np.linalg.norm(noisy - clean)  # measured 0.61
    path = d.save(tmp_path / "dl.npz")
    again = PatchDictionary.load(path)
    assert np.allclose(again(noisy, sigma), out)
    with pytest.raises(FileExistsError):
        d.save(path)
    res = tc.reconstruct(p.system, p.measurement, "dl", dictionary=str(path), max_iter=2)
    assert res.cube.shape == p.system.cube_shape


def test_dl_errors(light_fields):
    d, p = light_fields
    with pytest.raises(ValueError, match="needs dictionary="):
        tc.reconstruct(p.system, p.measurement, "dl")
    other = studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, rng=0)
    with pytest.raises(ValueError, match=r"6×6×8 patches: the cube must be \(≥6, ≥6, 8\)"):
        tc.reconstruct(other.system, other.measurement, "dl", dictionary=d)
    with pytest.raises(ValueError, match="atoms must be"):
        PatchDictionary(np.ones((10, 4)), 2, 3)
    with pytest.raises(ValueError, match="one C"):
        train_dictionary([np.ones((8, 8, 2)), np.ones((8, 8, 3))], patch=4)
    with pytest.raises(ValueError, match="smaller than"):
        train_dictionary([np.ones((3, 8, 2))], patch=4)


def test_aligned_training_patches_are_whole_lenslets():
    """``align``: training patches start on multiples of ``align`` (DL-5D's whole lenslets).
    On a light field whose lenslets all hold the same 4×4 block, every aligned 8×8 patch is the
    same, so every atom is that patch; patches anywhere see 16 different ones.  A coding stride
    that would break the alignment is refused."""
    rng = np.random.default_rng(0)
    block = rng.random((4, 4, 3)) + 0.5
    cube = np.tile(block, (8, 6, 1))  # 32×24 lenslet image of identical lenslets

    def spread(**kw):
        d = train_dictionary([cube], patch=8, n_patches=200, n_iter=1, n_atoms=12,
                             sparsity=1, **kw)  # fmt: skip
        gram = np.abs(d.atoms.T @ d.atoms)
        return d, float(gram.min())

    d, aligned = spread(align=4)
    assert aligned > 1 - 1e-6 and d.stride == 4  # one patch, up to the atoms' 1e-6 jitter
    _, anywhere = spread()
    assert anywhere < 0.99
    _, rows_only = spread(align=(4, 1))
    assert rows_only < 0.99  # columns still anywhere
    with pytest.raises(ValueError, match="multiple of align"):
        train_dictionary([cube], patch=8, n_patches=50, n_iter=1, align=4, stride=2)
    for bad in (0, -4, 1.5, True, (4, 0)):
        with pytest.raises(ValueError, match="align"):
            train_dictionary([cube], patch=8, n_patches=50, n_iter=1, align=bad)


def test_a_dictionary_file_is_read_bounded_and_checked(tmp_path):
    import io
    import zipfile

    good = np.random.default_rng(0).random((27, 10))
    cases = {
        "meta3.npz": ({"atoms": good, "meta": np.array([3, 3, 1])}, "'meta' must be 4 integers"),
        "metaf.npz": (
            {"atoms": good, "meta": np.array([3.7, 3, 1, 2])},
            "'meta' must be 4 integers.*got float64",
        ),
        "stride.npz": ({"atoms": good, "meta": np.array([3, 3, -1, 2])}, "stride must be"),
        "nan.npz": ({"atoms": np.full((27, 10), np.nan), "meta": np.array([3, 3, 1, 2])}, "finite"),
        "text.npz": ({"atoms": np.array(["a"]), "meta": np.array([3, 3, 1, 2])}, "real numbers"),
        "other.npz": ({"cube": good}, "not a PatchDictionary file"),
    }
    for name, (arrays, match) in cases.items():
        np.savez(tmp_path / name, **arrays)
        with pytest.raises(ValueError, match=match):
            PatchDictionary.load(tmp_path / name)
    header = io.BytesIO()  # atoms declaring 6.7 GiB in a file of a few bytes
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (30000, 30000)}
    )
    meta = io.BytesIO()
    np.save(meta, np.array([3, 3, 1, 2]))
    with zipfile.ZipFile(tmp_path / "bomb.npz", "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("atoms.npy", header.getvalue() + b"\0" * 64)
        z.writestr("meta.npy", meta.getvalue())
    with pytest.raises(ValueError, match="above the 4.00 GiB limit"):
        PatchDictionary.load(tmp_path / "bomb.npz")
    (tmp_path / "folder.npz").mkdir()
    with pytest.raises(ValueError, match="not a regular file"):
        PatchDictionary.load(tmp_path / "folder.npz")
    with pytest.raises(FileNotFoundError, match="dictionary file not found"):
        PatchDictionary.load(tmp_path / "missing.npz")
    with pytest.raises(ValueError, match="patch must be an integer ≥ 1, got 2.5"):
        PatchDictionary(good, 2.5, 3)
