"""The prism design grid (thesis App. B) reproduces the built prism and refutes Eq. 190."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.optics import DoubleAmiciPrism, refractive_index
from tensor_cosdi.optics.design import eq190_phi3


def test_the_grid_marks_and_reproduces_the_thesis_prism():
    rows = tc.studies.prism_grid()
    mine = [r for r in rows if r["thesis_design"]]
    assert len(mine) == 1
    r = mine[0]
    assert (r["glass1"], r["glass2"], r["phi1"]) == ("N-SK2", "SF4", 85.9)
    assert r["phi3"] == pytest.approx(73.7, abs=0.15)  # the built prism: φ3 = 73.7°
    prism = DoubleAmiciPrism(r["phi1"], r["phi3"])
    assert abs(prism.deviation(570.0)) < 1e-6  # the row's φ3 really zeroes the deviation
    assert r["dispersion_deg"] == pytest.approx(prism.deviation(700) - prism.deviation(450))
    assert r["shear_px"] == pytest.approx(prism.shifts([450, 700], 30, 6)[-1])


def test_trends_across_the_grid():
    rows = [r for r in tc.studies.prism_grid() if np.isfinite(r["phi3"])]
    for pair in {(r["glass1"], r["glass2"]) for r in rows}:
        rs = sorted(
            (r for r in rows if (r["glass1"], r["glass2"]) == pair), key=lambda r: r["phi1"]
        )
        # larger φ1 → thinner wedges → less dispersion and a shorter prism
        assert all(a["dispersion_deg"] > b["dispersion_deg"] for a, b in zip(rs, rs[1:]))
        assert all(a["length_mm"] > b["length_mm"] for a, b in zip(rs, rs[1:]))
        assert all(abs(r["field_deviation_deg"]) < 0.01 for r in rs)


def test_eq190_does_not_describe_the_zero_deviation_curve():
    # at φ1 = 85.9° the fit asks for 90.2° (no middle wedge), the ray trace for 73.8°
    assert eq190_phi3(85.9) == pytest.approx(90.22, abs=0.01)
    assert DoubleAmiciPrism.design(phi1=85.9).phi3 < eq190_phi3(85.9) - 15


def test_no_solution_is_a_row_that_says_so_and_bad_bands_are_errors():
    rows = tc.studies.prism_grid(phi1=[90.0], glass_pairs=[("N-SK2", "SF4")])
    assert np.isnan(rows[0]["phi3"]) and "no φ3" in rows[0]["note"]
    with pytest.raises(ValueError, match="band_nm"):
        tc.studies.prism_grid(band_nm=(0.45, 0.7))  # µm, not nm


@pytest.mark.parametrize(
    "glass, n_d", [("N-SK16", 1.62041), ("N-F2", 1.62005), ("N-SF5", 1.67271), ("N-SF11", 1.78472)]
)
def test_added_glasses_give_their_catalogue_index(glass, n_d):
    assert float(refractive_index(glass, 587.5618)) == pytest.approx(n_d, abs=2e-5)


def test_bad_inputs_are_errors_not_rows_without_a_design():
    """An unknown glass or a NaN angle is an error; only a valid prism without a φ3 that zeroes
    the deviation becomes a row with a note (``NoDesign``)."""
    from tensor_cosdi.optics import NoDesign

    with pytest.raises(ValueError, match="unknown glass 'X'"):
        tc.studies.prism_grid(glass_pairs=(("X", "SF4"),))
    with pytest.raises(ValueError, match="phi1 must be a finite number"):
        tc.studies.prism_grid(phi1=(np.nan,))
    with pytest.raises(ValueError, match="aperture_mm must be a finite number > 0"):
        tc.studies.prism_grid(aperture_mm=-1.0)
    with pytest.raises(ValueError, match="look like micrometres"):
        DoubleAmiciPrism.design(center_nm=0.57)
    with pytest.raises(NoDesign, match="no φ3"):
        DoubleAmiciPrism.design(phi1=90.0)
    rows = tc.studies.prism_grid(phi1=(90.0,), glass_pairs=(("N-SK2", "SF4"),))
    assert np.isnan(rows[0]["phi3"]) and rows[0]["note"].startswith("no φ3")
