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
