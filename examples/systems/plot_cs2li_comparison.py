"""
CS2LI against structured light captured with an SD-CASSI
========================================================

The thesis (Sec. 6.3.1, Fig. 56) compares CS2LI with a binary and with a
colour-coded aperture against structured light captured pattern by pattern
with a spectral imager, at 20, 30 and 50 dB.
:func:`tensor_cosdi.studies.cs2li_comparison` gives each the same scene,
fringes (across the dispersion, four phase steps), light and frame count,
reconstructs with OTD and scores the reflectance and the height map (the
wrapped phase of the estimate, unwrapped with the true phase so that only
the reconstruction is judged).  ``benchmarks/results/thesis_findings.md``
holds the verdicts over three seeds and the report scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies
from tensor_cosdi.studies.design import CS2LI_IMAGERS

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
snrs = (20.0, 30.0, 50.0)
recs = studies.cs2li_comparison((scene,), snrs=snrs, shape=(32, 32), n_bands=8, progress=False)
labels = {"cs2li": "CS2LI, binary", "cs2li_colour": "CS2LI, colour #f 6 κ 0.5",
          "sl_sd_cassi": "SL + SD-CASSI"}  # fmt: skip


def series(imager, key):
    return np.array([r[key] for s in snrs for r in recs if r["imager"] == imager
                     and r["snr_db"] == s])  # fmt: skip


for imager in CS2LI_IMAGERS:
    depth, sam = series(imager, "depth_psnr"), series(imager, "sam")
    cells = ", ".join(
        f"{s:g} dB: depth {d:.2f} dB, SAM {a:.2f}°" for s, d, a in zip(snrs, depth, sam)
    )
    print(f"{labels[imager]:26s} {cells}")

# %%
fig, axes = plt.subplots(1, 2, figsize=(9, 3.2))
for imager in CS2LI_IMAGERS:
    axes[0].plot(snrs, series(imager, "depth_psnr"), "o-", label=labels[imager])
    axes[1].plot(snrs, series(imager, "sam"), "o-", label=labels[imager])
axes[0].set_ylabel("height map PSNR dB")
axes[1].set_ylabel("reflectance SAM °")
for ax in axes:
    ax.set_xlabel("measurement SNR dB")
axes[0].legend(fontsize=8)
fig.suptitle(f"{scene}, 32×32×8, 4 phase steps, OTD")
fig.tight_layout()
plt.show()
