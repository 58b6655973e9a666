"""
Designing the double Amici prism
================================

The thesis' prism (N-SK2 | SF4 | N-SK2, apex angles φ1 = 85.9°, φ3 = 73.7°)
deviates the 570 nm ray by almost nothing while spreading 450-650 nm over
tens of pixels.  Here: its deviation δ(λ) (Alg. 7) on axis and averaged over
the ±1.15° field (Alg. 8), the φ3 that zeroes the deviation for other
apex angles φ1, and the shear S(λ) (Eq. 191) turned into per-band shifts
that build an SD-CASSI.  Then the design grid of App. B
(:func:`tensor_cosdi.studies.prism_grid`): for four glass pairs and a range of
φ1, the zero-deviation φ3, the dispersion over 450-700 nm and a first-order
length, with the thesis' prism marked — and the thesis' fit Eq. 190, which
the ray trace refutes.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi.optics import THESIS_FIELD_DEG, DoubleAmiciPrism

prism = DoubleAmiciPrism(phi1=85.9, phi3=73.7)
wl = np.linspace(450, 650, 101)
fig, axes = plt.subplots(1, 3, figsize=(8, 2.6))
axes[0].plot(wl, prism.deviation(wl), label="θ0 = 0")
axes[0].plot(wl, prism.mean_deviation(wl, field_deg=THESIS_FIELD_DEG), "--", label="field mean")
axes[0].axhline(0, color="k", lw=0.5)
axes[0].set(xlabel="λ (nm)", ylabel="δ (°)", title="deviation")
axes[0].legend(fontsize=7)

# %%
# For each outer apex angle φ1, the middle-wedge angle φ3 that gives δ(570 nm) = 0
phi1s = np.arange(82.0, 88.1, 1.0)
phi3s = [DoubleAmiciPrism.design(phi1=p, center_nm=570.0).phi3 for p in phi1s]
axes[1].plot(phi1s, phi3s, "o-")
axes[1].set(xlabel="φ1 (°)", ylabel="φ3 (°)", title="zero deviation at 570 nm")

# %%
# Shear on a sensor 10-50 mm behind the prism, 6 µm pixels
for x in (10, 30, 50):
    axes[2].plot(wl, prism.shifts(wl, distance_mm=x, pixel_um=6), label=f"{x} mm")
axes[2].set(xlabel="λ (nm)", ylabel="shift (px)", title="per-band shift")
axes[2].legend(fontsize=7)
fig.tight_layout()
print(
    f"450-650 nm at 30 mm with 6 µm pixels: {prism.shifts([450, 650], 30, 6)[-1]:.1f} px "
    "(the thesis measured about 50 px on its prototype)"
)

# %%
# A system built from the prism instead of "one pixel per band"
bands = tc.scenes.default_wavelengths(16)
shifts = prism.shifts(bands, distance_mm=5, pixel_um=6)
sd = tc.systems.SDCASSI(
    tc.codes.random_binary((32, 32), rng=0), n_bands=16, shifts=shifts, wavelengths=bands
)
print("shifts (px):", np.round(shifts, 2))
print("measurement shape:", sd.measurement_shape)

# %%
# The design grid: every glass pair, φ1 from 80° to 88°
rows = [r for r in tc.studies.prism_grid() if np.isfinite(r["phi3"])]
fig, axes = plt.subplots(1, 3, figsize=(8, 2.6))
for pair in dict.fromkeys((r["glass1"], r["glass2"]) for r in rows):
    rs = [r for r in rows if (r["glass1"], r["glass2"]) == pair]
    label = " | ".join(pair)
    for ax, key in zip(axes, ("phi3", "shear_px", "length_mm")):
        ax.plot([r["phi1"] for r in rs], [r[key] for r in rs], "o-", ms=3, label=label)
thesis = next(r for r in rows if r["thesis_design"])
for ax, key, title in zip(
    axes,
    ("phi3", "shear_px", "length_mm"),
    ("zero-deviation φ3 (°)", "450-700 nm at 30 mm (px)", "length, 10 mm aperture"),
):
    ax.plot(thesis["phi1"], thesis[key], "k*", ms=10)
    ax.set(xlabel="φ1 (°)", title=title)
phi1 = np.linspace(80, 88, 9)
axes[0].plot(phi1, tc.optics.design.eq190_phi3(phi1), "k:", label="Eq. 190")
axes[0].legend(fontsize=6)
fig.tight_layout()
print(
    f"thesis prism (★): φ3 = {thesis['phi3']:.2f}° (built: 73.7°), "
    f"{thesis['shear_px']:.1f} px over 450-700 nm, Eq. 190 says {thesis['eq190']:.1f}°"
)
