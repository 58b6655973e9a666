"""Design grids for the double Amici prism (thesis App. B): which apex angles and glass pairs give
zero deviation at the centre wavelength, how much they disperse, and how long they get.

``tensor_cosdi.studies.prism_grid`` is :func:`prism_grid`.
"""

from __future__ import annotations

import numpy as np

from ..validate import number, real_array
from .prism import THESIS_FIELD_DEG, DoubleAmiciPrism, NoDesign

__all__ = ["prism_grid", "eq190_phi3", "THESIS_DESIGN"]

#: The prism built for the thesis (App. B, Fig. 98): N-SK2 | SF4 | N-SK2, φ1 = 85.9°, φ3 = 73.7°.
THESIS_DESIGN = {"phi1": 85.9, "phi3": 73.7, "glass1": "N-SK2", "glass2": "SF4"}


def eq190_phi3(phi1):
    """Equation 190, the thesis' fit of the zero-deviation curve: ``φ3 = 0.3544 (φ1 − 50) + 77.5``.

    It does not describe Alg. 7's zero-deviation curve: at the built prism's
    φ1 = 85.9° it gives 90.2° (no middle wedge at all) where the ray trace
    and the built prism have 73.7-73.8°; see :func:`prism_grid`'s ``eq190``
    column.
    """
    return 0.3544 * (real_array("phi1", phi1, finite=False) - 50.0) + 77.5


def prism_grid(
    phi1=(80.0, 82.0, 84.0, 85.9, 88.0, 90.0),
    glass_pairs=(("N-SK2", "SF4"), ("N-BK7", "SF4"), ("N-SK16", "N-SF11"), ("N-BK7", "N-F2")),
    *,
    center_nm: float = 570.0,
    band_nm=(450.0, 700.0),
    distance_mm: float = 30.0,
    pixel_um: float = 6.0,
    aperture_mm: float = 10.0,
    field_deg: float = THESIS_FIELD_DEG,
) -> list[dict]:
    """One row per ``(glass pair, φ1)``: the ``φ3`` that zeroes the on-axis deviation at
    ``center_nm`` and what that prism does.

    Parameters
    ----------
    phi1 : float or sequence of float
        Outer apex parameters φ1 to try (degrees).
    glass_pairs : sequence of (str, str)
        ``(outer glass, middle glass)`` names of :data:`tensor_cosdi.optics.GLASSES`.
    center_nm : float
        Wavelength of zero deviation (thesis: 570 nm).
    band_nm : (float, float)
        Band whose dispersion and shear are reported, nm (thesis: 450-700).
    distance_mm, pixel_um : float
        Prism–sensor distance and pixel pitch for the shear in pixels.
    aperture_mm : float
        Aperture height for the first-order length.
    field_deg : float
        Full field of view for the field-averaged deviation (Alg. 8).

    Returns
    -------
    list of dict
        Columns: ``glass1``, ``glass2``, ``phi1``, ``phi3`` (degrees; NaN where
        no φ3 in (45°, 90°) zeroes the deviation — ``note`` then says why),
        ``alpha1`` / ``alpha2`` (outer and middle apex angles),
        ``dispersion_deg`` (Eq. 187, ``δ(λmax) − δ(λmin)`` over ``band_nm``),
        ``shear_px`` (Eq. 191, the band's spread on the sensor),
        ``field_deviation_deg`` (deviation at ``center_nm`` averaged over the
        field — what the on-axis design leaves off axis), ``length_mm``
        (first-order: base thicknesses of three symmetric wedges of height
        ``aperture_mm``, ``h·(4 tan(α1/2) + 2 tan(α2/2))`` — an estimate, the
        real length depends on how the wedges are cut), ``eq190`` (the thesis'
        fit for this φ1) and ``thesis_design`` (True on the built prism's row).

    Examples
    --------
    >>> rows = prism_grid(phi1=[85.9], glass_pairs=[("N-SK2", "SF4")])
    >>> round(rows[0]["phi3"], 1), rows[0]["thesis_design"]
    (73.8, True)
    """
    lo, hi = (float(v) for v in band_nm)
    if not 200 <= lo < center_nm < hi <= 20000:
        raise ValueError(f"need 200 ≤ band_nm[0] < center_nm < band_nm[1] (nm), got {band_nm}")
    for name, v in (("distance_mm", distance_mm), ("pixel_um", pixel_um),
                    ("aperture_mm", aperture_mm)):  # fmt: skip
        number(name, v, low=0, low_open=True)
    rows = []
    for g1, g2 in glass_pairs:
        for p1 in np.atleast_1d(real_array("phi1", phi1, finite=False)):
            row = {"glass1": g1, "glass2": g2, "phi1": float(p1), "eq190": float(eq190_phi3(p1))}
            try:
                prism = DoubleAmiciPrism.design(
                    phi1=float(p1), center_nm=center_nm, glass1=g1, glass2=g2
                )
            except NoDesign as exc:  # valid inputs, no such prism: a row that says why
                rows.append({**row, "phi3": np.nan, "note": str(exc).split(";")[0]})
                continue
            a1, a2 = prism.apex_angles
            h = float(aperture_mm)
            row.update(
                phi3=prism.phi3,
                alpha1=a1,
                alpha2=a2,
                dispersion_deg=float(prism.deviation(hi) - prism.deviation(lo)),
                shear_px=float(prism.shifts([lo, hi], distance_mm, pixel_um)[-1]),
                field_deviation_deg=float(prism.mean_deviation(center_nm, field_deg=field_deg)),
                length_mm=float(
                    h * (4 * np.tan(np.deg2rad(a1) / 2) + 2 * np.tan(np.deg2rad(a2) / 2))
                ),
                note="",
            )
            rows.append(row)
    for row in rows:
        row["thesis_design"] = bool(
            (row["glass1"], row["glass2"]) == (THESIS_DESIGN["glass1"], THESIS_DESIGN["glass2"])
            and abs(row["phi1"] - THESIS_DESIGN["phi1"]) < 1e-9
        )
    return rows
