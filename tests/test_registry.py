"""Registry-driven tests: every registered system × every registered method, state and frame round
trips.

A sixth imager registered in ``tensor_cosdi.systems.REGISTRY`` (or a method in
``tensor_cosdi.solvers.METHODS``) is picked up here without editing this file.
"""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import studies
from tensor_cosdi._registry import Registry, UnknownNameError
from tensor_cosdi.systems import REGISTRY, System

SYSTEMS = list(REGISTRY)
#: Methods written for some systems only (the thesis' own algorithms, the Lytro baseline), from
#: the registry's metadata.
OWN = {n: set(m.systems) for n, m in tc.solvers.METHODS.items() if m.systems}
#: Methods whose defaults are weights trained for one configuration (tested in tests/learn, with
#: a clear error for any other system).
TRAINED = {"dcosnet"}
#: Methods for systems with PSFs only (the problems here have none): tests/solvers/test_split_tv.py.
NEEDS_PSFS = {"split_tv"}
#: Methods that need a learned patch dictionary of (Nx, Ny, C) cubes: trained here on another
#: scene of the same system; 4-D cubes get a clear error.
NEEDS_DICTIONARY = {"dl"}
#: (method, system) pairs measured *not* to beat LSQ at 32×32×8, 30 dB, chelsea, seed 0; they must
#: still stay within 1.5 dB of LSQ.  (WDCT was here on four systems while its wavelet had 1 level
#: at 32 px; with the periodised-depth default it beats LSQ everywhere, PSNR dB WDCT vs LSQ:
#: SD-CASSI 20.30 vs 11.43, CS2LI 19.99 vs 12.14, CASSDI-DFA 15.36 vs 14.98, dual camera 26.34
#: vs 20.15.)
NOT_BETTER = {
    ("twist", "lytro_cassi"),  # 23.46 vs 23.55
}
#: Lytro-CASSI's A Aᵀ is ill-conditioned (κ ≈ 8e7 here): accelerated GAP with ε = 1e-6 fits the
#: noise along its weak directions; the system's ``gap_eps`` (0.1) is what GAP-based methods use
#: by default.  Pairs still below LSQ with it are listed here and measured below.
ILL_CONDITIONED: set = set()


def _problem(name, scene="chelsea"):
    opts = {"views": (2, 2), "n_snapshots": 2} if name in ("c3slfi", "lytro_cassi") else {}
    return studies.make_problem(name, scene, shape=(32, 32), n_bands=8, snr_db=30, rng=0, **opts)


def _dl(channels, name=None):
    """A small K-SVD dictionary learned on coffee (the problems show chelsea)."""
    if name is None:
        cube = tc.scenes.scene_cube("coffee", (32, 32), tc.scenes.default_wavelengths(channels))
    else:
        cube = _problem(name, "coffee").cube
    return tc.solvers.train_dictionary([cube], patch=4, n_patches=2000, n_iter=3)


@pytest.fixture(scope="module")
def table():
    out = {}
    for name in SYSTEMS:
        p = _problem(name)
        row = {}
        for method, entry in tc.solvers.METHODS.items():
            if method in OWN and name not in OWN[method] or method in TRAINED | NEEDS_PSFS:
                continue
            if not entry.available:  # its defaults need an optional module: a clear error
                with pytest.raises(ImportError, match="pip install"):
                    tc.reconstruct(p.system, p.measurement, method)
                continue
            opts = {}
            if method in NEEDS_DICTIONARY:
                if len(p.system.cube_shape) != 3:
                    with pytest.raises(ValueError, match="the cube must be"):
                        tc.reconstruct(p.system, p.measurement, method, dictionary=_dl(3))
                    continue
                opts["dictionary"] = _dl(p.system.cube_shape[2], name)
            res = tc.reconstruct(p.system, p.measurement, method, **opts)
            assert (
                tuple(res.cube.shape) == p.system.cube_shape
                and np.isfinite(np.asarray(res.cube)).all()
            )
            row[method] = studies.score(p, res.cube)["psnr"]
        out[name] = row
    return out


@pytest.mark.parametrize("name", SYSTEMS)
def test_every_method_beats_least_squares(table, name):
    row = dict(table[name])  # the fixture is shared: leave it whole
    lsq = row.pop("lsq")
    assert row, f"no method ran on {name}"
    for method, psnr in row.items():
        if (method, name) in ILL_CONDITIONED:
            continue
        if (method, name) in NOT_BETTER:
            assert psnr > lsq - 1.5, f"{method} on {name}: {psnr:.2f} dB, LSQ {lsq:.2f} dB"
        else:
            assert psnr > lsq + 0.1, (
                f"{method} on {name}: {psnr:.2f} dB does not beat LSQ {lsq:.2f} dB"
            )


def test_gap_overfits_noise_on_lytro_cassi_without_its_eps(table):
    """With ε = 1e-6 accelerated GAP-TV falls far below least squares on Lytro-CASSI; with the
    system's ``gap_eps`` (the default) it beats least squares by more than 3 dB."""
    p = _problem("lytro_cassi")
    tiny = tc.reconstruct(p.system, p.measurement, "gap_tv", eps=1e-6)
    row = table["lytro_cassi"]
    assert studies.score(p, tiny.cube)["psnr"] < row["lsq"] - 5 < row["gap_tv"] - 8, row


def test_admm_reconstructs_lytro_cassi(table):
    """ADMM's (AᵀA + ρI)⁻¹ does not amplify the weak directions: the same DL prior as the failing
    GAP run, and the Lytro baseline (RGB-learned ⊗ DCT dictionary), beat LSQ by > 4 dB."""
    p = _problem("lytro_cassi")
    dl = tc.reconstruct(p.system, p.measurement, "dl", dictionary=_dl(8, "lytro_cassi"),
                        splitting="admm", warm="otd")  # fmt: skip
    lsq = table["lytro_cassi"]["lsq"]
    assert studies.score(p, dl.cube)["psnr"] > lsq + 4
    assert table["lytro_cassi"]["lytro"] > lsq + 4


@pytest.mark.parametrize("method", sorted(OWN))
def test_thesis_algorithms_refuse_the_other_systems(method):
    other = next(n for n in SYSTEMS if n not in OWN[method])
    p = _problem(other)
    with pytest.raises(ValueError, match=f"'{method}' reconstructs"):
        tc.reconstruct(p.system, p.measurement, method)


@pytest.mark.parametrize("name", SYSTEMS)
def test_state_round_trip_gives_a_bit_identical_forward(name):
    p = _problem(name)
    state = p.system.to_state()
    assert state["system"] == name and set(state) == {"system", "class", "params", "arrays"}
    import json

    json.dumps(state["params"])  # JSON-able
    for rebuilt in (System.from_state(state), REGISTRY[name].from_state(state)):
        assert type(rebuilt) is type(p.system)
        np.testing.assert_array_equal(
            np.asarray(rebuilt.forward(p.cube)), np.asarray(p.system.forward(p.cube))
        )
    other = next(n for n in SYSTEMS if n != name)
    with pytest.raises(ValueError, match=f"describes a {name!r} system, not {other!r}"):
        REGISTRY[other].from_state(state)


@pytest.mark.parametrize("name", SYSTEMS)
def test_frames_round_trip(name):
    p = _problem(name)
    frames = p.system.measurement_to_frames(p.measurement)
    assert frames.ndim == 3 and frames.shape[2] == p.system.frame_count
    np.testing.assert_array_equal(p.system.frames_to_measurement(frames), np.asarray(p.measurement))
    np.testing.assert_array_equal(
        p.system.frames_to_measurement([frames[..., k] for k in range(frames.shape[2])]),
        np.asarray(p.measurement),
    )
    with pytest.raises(ValueError, match="frame"):
        p.system.frames_to_measurement(np.concatenate([frames, frames[..., :1]], axis=2))


@pytest.mark.parametrize("name", SYSTEMS)
def test_depth_channel_matches_the_depth_kind(name):
    p = _problem(name)
    d = p.system.depth_from_cube(p.cube)
    assert (d is None) == (p.system.depth_kind is None)
    assert p.system.has_depth or d is None
    if d is not None:
        scores = p.system.score_depth(d, p)
        assert scores, f"{name}: no depth score for the truth"
        # the truth's own depth channel scores (near) perfectly
        value = next(iter(scores.values()))
        assert value > 0.95 if "planes_right" in scores else value < 0.25


def test_registries_list_valid_names_and_do_not_clobber_builtins():
    with pytest.raises(
        UnknownNameError, match=r"unknown system 'sd-cassi'; valid names: \['c3slfi'"
    ):
        REGISTRY["sd-cassi"]
    with pytest.raises(ValueError, match="is now called 'dual_camera_cassi'"):
        studies.make_problem("dual_camera")
    with pytest.raises(ValueError, match="'sd_cassi' is a built-in system and cannot be replaced"):
        REGISTRY.register_class(tc.systems.SDCASSI, replace=True)
    with pytest.raises(ValueError, match=r"sd_cassi: unknown option\(s\) \['views'\]"):
        studies.make_problem("sd_cassi", views=(2, 2))
    with pytest.raises(UnknownNameError, match="unknown scene 'nope'"):
        studies.make_problem("sd_cassi", "nope")
    r = Registry("thing")
    with pytest.raises(ValueError, match="a thing name must be"):
        r.register("../x", 1)
    r.register("a", 1)
    with pytest.raises(ValueError, match="already registered"):
        r.register("a", 2)
    r.register("a", 2, replace=True)
    assert dict(r) == {"a": 2} and "b" not in r and 3 not in r


def test_no_module_outside_systems_names_a_system_class():
    """The target of the architecture issue: 0 isinstance checks on system classes outside
    systems/."""
    import re
    from pathlib import Path

    root = Path(tc.__file__).parent
    classes = "|".join(cls.__name__ for cls in REGISTRY.values())
    pattern = re.compile(rf"isinstance\([^)]*\b({classes})\b")
    hits = [
        f"{p.relative_to(root)}:{i}"
        for p in root.rglob("*.py")
        if "systems" not in p.parts
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if pattern.search(line)
    ]
    assert hits == []
