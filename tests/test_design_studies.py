"""Colour-coded aperture design study: records, conditioning, errors, and a real-scene ordering."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import codes, datasets, studies


def test_records_hold_the_grid_quality_and_conditioning():
    recs = studies.colour_code_design(
        filters=(1, 3), transmittances=(0.5,), scene="colorchecker", shape=(16, 16), n_bands=6,
        seeds=(0, 1), progress=False, max_iter=5,
    )  # fmt: skip
    assert [(r["n_filters"], r["seed"]) for r in recs] == [(1, 0), (1, 1), (3, 0), (3, 1)]
    code = codes.colour_coded_aperture((16, 16), 6, n_filters=3, transmittance=0.5, rng=1)
    sd = tc.systems.SDCASSI(code, n_bands=6, colour=True)
    want = studies.conditioning(sd)
    assert recs[3]["cond"] == want["cond_nonzero"] and recs[3]["unreached"] == want["zero"]
    for r in recs:
        assert np.isfinite(r["psnr"]) and r["seconds"] >= 0
    with pytest.raises(ValueError, match="every #f must lie in 1…n_bands = 6"):
        studies.colour_code_design(filters=(7,), n_bands=6, scene="colorchecker")
    with pytest.raises(ValueError, match="every κ must lie in"):
        studies.colour_code_design(transmittances=(0,), scene="colorchecker")


def test_a_few_filters_beat_one_narrow_filter_per_band_on_a_real_scene():
    try:
        datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")
    recs = studies.colour_code_design(
        filters=(4, 16), transmittances=(0.25,), shape=(48, 48), progress=False
    )
    psnr = {r["n_filters"]: r["psnr"] for r in recs}
    # 48×48 cave.face at 30 dB: #f = 4 27.62 dB, #f = 16 25.62 dB (an ideal narrow filter per
    # open pixel leaves most detector pixels dark)
    assert psnr[4] > psnr[16] + 1.0, psnr


def test_cs2li_code_design_records_spectra_and_depth():
    recs = studies.cs2li_code_design(
        (1, 4), (0.5,), scene="colorchecker", shape=(16, 16), n_bands=4, seeds=(0, 1),
        progress=False, max_iter=3, pan_iter=3,
    )  # fmt: skip
    assert [(r["n_filters"], r["seed"]) for r in recs] == [(1, 0), (1, 1), (4, 0), (4, 1)]
    for r in recs:
        for key in ("psnr", "ssim", "sam", "rmse", "depth_psnr", "depth_ssim", "depth_rmse"):
            assert np.isfinite(r[key]), (key, r)
    for bad, match in (
        ({"filters": (5,)}, "#f"), ({"filters": (2.5,)}, "#f"), ({"transmittances": (0,)}, "κ"),
        ({"transmittances": (1.5,)}, "κ"), ({"filters": ()}, "at least one"),
        ({"filters": "12"}, "sequences"),
    ):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            studies.cs2li_code_design(**{"n_bands": 4, "scene": "colorchecker", **bad})


def test_cs2li_depth_prefers_a_binary_code_to_one_narrow_filter_per_band():
    try:
        datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")
    recs = studies.cs2li_code_design((1, 8), (0.75,), shape=(32, 32), n_bands=8, progress=False)
    depth = {r["n_filters"]: r["depth_psnr"] for r in recs}
    # 32×32×8 cave.face, 30 dB, OTD: binary 32.50 dB, #f = 8 15.52 dB (Fig. 58B's finding)
    assert depth[1] > depth[8] + 5.0, depth


def test_cs2li_comparison_records_and_bad_inputs():
    recs = studies.cs2li_comparison(
        ("colorchecker",), snrs=(30, 50), shape=(16, 16), n_bands=4, progress=False,
        max_iter=3, pan_iter=3,
    )  # fmt: skip
    assert [(r["imager"], r["snr_db"]) for r in recs] == [
        (i, s) for i in studies.design.CS2LI_IMAGERS for s in (30.0, 50.0)
    ]
    for r in recs:
        assert all(np.isfinite(r[k]) for k in ("depth_psnr", "sam", "phase_mae", "cube_psnr"))
    for bad, match in (
        ({"imagers": ("scci",)}, "imagers must be among"), ({"snrs": ()}, "at least one"),
        ({"snrs": (float("nan"),)}, "SNR|snr"), ({"scenes": "chelsea"}, "not one string"),
    ):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            studies.cs2li_comparison(**{"scenes": ("chelsea",), "n_bands": 4, **bad})


def test_cs2li_depth_beats_pattern_by_pattern_sd_cassi_on_a_real_scene():
    try:
        datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")
    recs = studies.cs2li_comparison(
        ("cave.face",),
        ("cs2li", "sl_sd_cassi"),
        snrs=(30,),
        shape=(32, 32),
        n_bands=8,
        seeds=(1,),
        progress=False,
    )
    depth = {r["imager"]: r["depth_psnr"] for r in recs}
    # 32×32×8 cave.face, 30 dB, fringes across, seed 1: CS2LI 30.95 dB, SL + SD-CASSI 21.42
    assert depth["cs2li"] > depth["sl_sd_cassi"] + 5.0, depth


def test_c3slfi_sparsity_records_and_bad_fractions():
    recs = studies.c3slfi_sparsity("chelsea", shape=(16, 16), views=(2, 2), n_bands=4,
                                   fractions=(0.9, 0.99), max_iter=5, pan_iter=5)  # fmt: skip
    assert [(r["form"], r["basis"]) for r in recs] == [
        ("3d", "wdct"),
        ("3d", "otd"),
        ("5d", "wdct"),
        ("5d", "otd"),
    ]
    for r in recs:
        assert 0 < r["share_0.9"] <= r["share_0.99"] <= 1
        assert len(r["curve"]) == len(studies.design.SPARSITY_POINTS)
        assert np.all(np.diff(r["curve"]) >= 0) and r["curve"][-1] == pytest.approx(1.0)
    whole = studies.c3slfi_sparsity("chelsea", shape=(16, 16), views=(2, 2), n_bands=4,
                                    fractions=(1.0,), max_iter=2, pan_iter=2)  # fmt: skip
    assert all(0 < r["share_1"] <= 1 for r in whole)  # never past the last coefficient
    for bad in ((0,), (1.5,), (), "0.9"):
        with pytest.raises(ValueError, match="fraction"):
            studies.c3slfi_sparsity("chelsea", shape=(16, 16), views=(2, 2), n_bands=4,
                                    fractions=bad)  # fmt: skip


def test_otds_learned_basis_is_sparser_than_wdct_on_a_real_light_field():
    try:
        datasets.data_dir()
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")
    recs = studies.c3slfi_sparsity("cave.face", shape=(32, 32), n_bands=8)
    share = {(r["form"], r["basis"]): r["share_0.999"] for r in recs}
    # 32×32 cave.face, 4×4 views, 8 bands: 99.9 % of the energy in 3-D WDCT 0.20 / OTD 0.05;
    # 5-D 0.40 / 0.10 of the coefficients
    for form in ("3d", "5d"):
        assert share[form, "otd"] < 0.5 * share[form, "wdct"], share
    assert share["3d", "otd"] < share["5d", "otd"], share


@pytest.mark.parametrize("seeds", ["x", (), (1.5,), (-1,), 3])
def test_every_design_study_names_bad_seeds(seeds):
    for study, args in (
        (studies.colour_code_design, {"scene": "colorchecker"}),
        (studies.cs2li_code_design, {"scene": "colorchecker", "n_bands": 4}),
        (studies.cs2li_comparison, {"scenes": ("colorchecker",), "n_bands": 4}),
        (studies.vsi_comparison, {"scenes": ("colorchecker",), "n_bands": 4}),
        (studies.vsi_ratio, {"scenes": ("colorchecker",), "n_bands": 4}),
    ):  # fmt: skip
        with pytest.raises(ValueError, match="seed"):
            study(seeds=seeds, shape=(8, 8), progress=False, **args)


def test_colour_code_design_refuses_a_fractional_filter_count():
    with pytest.raises(ValueError, match="#f must be an integer"):
        studies.colour_code_design(filters=(2.5,), scene="colorchecker", shape=(8, 8), n_bands=4)


def test_cs2li_studies_need_three_phase_steps():
    with pytest.raises(ValueError, match="n_patterns"):
        studies.cs2li_comparison(("colorchecker",), shape=(8, 8), n_bands=4, n_patterns=2,
                                 progress=False)  # fmt: skip
