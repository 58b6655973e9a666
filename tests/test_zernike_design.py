"""Zernike design study of CASSDI-DFA: the crop's share of the PSF's light, the depth
separation of the optics, the records, and the errors."""

import numpy as np
import pytest

from tensor_cosdi import optics, studies
from tensor_cosdi.studies.zernike import DEPTHS_MM, default_lens, zernike_run

SMALL = dict(scene="colorchecker", shape=(16, 16), n_bands=4, reference_size=41, max_iter=3)


def test_energy_is_the_share_of_the_reference_psf_inside_the_crop():
    full = zernike_run((6, 0.9), 41, **SMALL)
    assert full["energy"] == pytest.approx(1.0)
    crops = [zernike_run((6, 0.9), s, **SMALL)["energy"] for s in (5, 9, 21)]
    assert crops == sorted(crops) and crops[0] < 0.2 < crops[-1] < 1.0, crops
    # the least share over bands and planes, computed independently
    wl = np.linspace(450, 650, 4)
    ref = optics.psf_stack(wl, DEPTHS_MM, lens=default_lens(), zernike={6: 0.9}, size=41)
    want = ref[16:25, 16:25].sum(axis=(0, 1)).min()
    assert zernike_run((6, 0.9), 9, **SMALL)["energy"] == pytest.approx(want, rel=1e-9)


def test_separation_measures_how_distinct_the_depth_planes_psfs_are():
    same = zernike_run((6, 0.5), 9, depths_mm=(1000.0, 1000.0), **SMALL)
    assert same["separation"] == pytest.approx(0.0, abs=1e-12)
    apart = zernike_run((6, 0.5), 9, depths_mm=(600.0, 1000.0, 3000.0), **SMALL)
    near = zernike_run((6, 0.5), 9, depths_mm=(980.0, 1000.0, 1020.0), **SMALL)
    assert 0 < near["separation"] < apart["separation"] <= 1


def test_records_cover_pure_defocus_and_every_mode_amplitude_and_crop():
    recs = studies.zernike_design((5, 6), (0.3,), (9, 15), seeds=(0,), progress=False, **SMALL)
    keys = [(r["mode"], r["amplitude"], r["psf_size"]) for r in recs]
    assert keys == [(0, 0.0, 9), (0, 0.0, 15), (5, 0.3, 9), (5, 0.3, 15), (6, 0.3, 9), (6, 0.3, 15)]
    for r in recs:
        assert 0 <= r["depth_accuracy"] <= 1 and np.isfinite(r["psnr"]) and 0 < r["energy"] <= 1


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"modes": (1,)}, "Noll indices"),
        ({"amplitudes": (0.0,)}, "amplitudes must be > 0"),
        ({"psf_sizes": (10,)}, "psf_sizes must be odd"),
        ({"psf_sizes": (99,)}, "psf_sizes must be odd, 1…reference_size=81"),
        ({"dtype": "float16"}, "dtype must be 'float32' or 'float64'"),
    ],
)
def test_bad_designs_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        studies.zernike_design(**{"progress": False, **kwargs})


def test_in_the_focal_sweep_the_codes_no_longer_tell_the_planes_apart():
    """Pure defocus: the per-plane model finds 80 % of the planes from its codes, the sweep
    model (every plane seen at every step) 27 % (ColorChecker, 32×32×8, 41-pixel PSFs)."""
    kw = dict(scene="colorchecker", shape=(32, 32), n_bands=8, progress=False)
    per_plane = studies.zernike_design((6,), (0.9,), (41,), **kw)
    sweep = studies.zernike_design((6,), (0.9,), (41,), sweep=True, **kw)
    assert sweep[0]["depth_accuracy"] < per_plane[0]["depth_accuracy"] - 0.3
    assert sweep[0]["energy"] == pytest.approx(per_plane[0]["energy"], abs=0.02)
    # there the aberration is what encodes depth (prints 0.625 against 0.265)
    assert sweep[1]["depth_accuracy"] > sweep[0]["depth_accuracy"] + 0.2


def test_a_float32_measurement_stays_float32_and_scores_as_float64():
    """The multiresolution DFA keeps a float32 measurement's precision through every FISTA
    stage (a float64 momentum scalar once promoted every iterate) and scores within 0.01 dB
    and 1 % of the depth planes of the float64 run."""
    from tensor_cosdi import codes, solvers
    from tensor_cosdi.systems import CASSDIDFA

    rng = np.random.default_rng(0)
    dfa = CASSDIDFA(codes.depth_codes((16, 16), 3, rng=0), n_bands=4,
                    psfs=rng.random((5, 5, 4, 3)) + 0.1)  # fmt: skip
    g = dfa.simulate(rng.random(dfa.cube_shape), snr_db=30.0, rng=0)
    res = solvers.reconstruct(dfa, g.astype(np.float32), "dfa", max_iter=5)
    assert res.cube.dtype == np.float32 and res.depth.dtype == np.float32
    kw = dict(SMALL, max_iter=20)
    hi = zernike_run((6, 0.9), 9, **kw)
    lo = zernike_run((6, 0.9), 9, dtype="float32", **kw)
    assert lo["psnr"] == pytest.approx(hi["psnr"], abs=0.01)
    assert lo["depth_accuracy"] == pytest.approx(hi["depth_accuracy"], abs=0.01)
