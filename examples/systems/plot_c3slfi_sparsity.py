"""
How sparse is a spectral light field, and in which basis?
=========================================================

The thesis (Sec. 5.3.1, Fig. 45) measures a basis by how few of its sorted
coefficients hold most of a spectral light field's energy, in the 3-D
lenslet form and in the 5-D one, for the fixed WDCT basis (Symlet-8 ⊗
Symlet-8 ⊗ DCT, identity on the views) and for OTD's learned basis.
:func:`tensor_cosdi.studies.c3slfi_sparsity` takes OTD's basis from its own
reconstruction of a C3SLFI measurement (the HOSVD of the estimate, what OTD
learns), not from the truth.  ``benchmarks/results/thesis_findings.md``
holds the verdicts over three seeds and the report scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.
"""

# %%
import matplotlib.pyplot as plt

from tensor_cosdi import datasets, studies
from tensor_cosdi.studies.design import SPARSITY_POINTS

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
recs = studies.c3slfi_sparsity(scene, shape=(32, 32), views=(4, 4), n_bands=8)
for r in recs:
    print(f"{r['form']} {r['basis']:4s}: 99.9 % of the energy in {100 * r['share_0.999']:.2f} % "
          f"of the coefficients")  # fmt: skip

# %%
fig, ax = plt.subplots(figsize=(5.5, 3.4))
for r in recs:
    style = "-" if r["form"] == "3d" else ":"
    colour = "C3" if r["basis"] == "otd" else "C0"
    ax.semilogx(SPARSITY_POINTS, r["curve"], style, color=colour,
                label=f"{r['basis'].upper()}, {r['form'].upper()}")  # fmt: skip
ax.set_xlabel("share of the sorted coefficients")
ax.set_ylabel("share of the energy")
ax.set_ylim(0.9, 1.001)
ax.set_title(f"{scene}: 32×32 lenslet image, 4×4 views, 8 bands", fontsize=9)
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
