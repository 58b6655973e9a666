"""
CASSI-VSI against SD-CASSI and the dual-arm CASSI
=================================================

The thesis compares its single-sensor CASSI-VSI (Sec. 3.3.4, Fig. 23) with
SD-CASSI and with the dual-arm CASSI, which adds a second camera for a
panchromatic image.  :func:`tensor_cosdi.studies.vsi_comparison` images one
scene through the same seeded binary code with all three, each measurement
at 30 dB of its own signal and the dual arm's panchromatic image noise-free
and registered (the thesis' simulation), and reconstructs each with OTD.
The thesis reads CASSI-VSI as comparable to the dual arm and better than
SD-CASSI, and the dual arm as best in SAM;
``benchmarks/results/thesis_findings.md`` holds the verdicts over three
seeds and the report scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies
from tensor_cosdi.studies.imagers import VSI_COMPARISON_SYSTEMS

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
seeds = (0, 1)
rows = studies.vsi_comparison(
    (scene,), shape=(48, 48), n_bands=16, snr_db=30, alpha_t=0.7, seeds=seeds, progress=False
)
mean = {
    s: {k: np.mean([r[k] for r in rows if r["system"] == s]) for k in ("psnr", "ssim", "sam")}
    for s in VSI_COMPARISON_SYSTEMS
}
for s, m in mean.items():
    print(f"{s:18s} PSNR {m['psnr']:.2f} dB  SSIM {m['ssim']:.3f}  SAM {m['sam']:.2f}°")

# %%
labels = ["SD-CASSI", "CASSI-VSI (αT 0.7)", "dual-arm CASSI"]
fig, axes = plt.subplots(1, 2, figsize=(9, 3.2))
for ax, key, unit in ((axes[0], "psnr", "PSNR dB"), (axes[1], "sam", "SAM °")):
    ax.bar(labels, [mean[s][key] for s in VSI_COMPARISON_SYSTEMS], color=["C0", "C3", "C2"])
    ax.set_ylabel(unit)
    ax.tick_params(axis="x", labelsize=8)
axes[0].set_ylim(min(m["psnr"] for m in mean.values()) - 2, None)
axes[0].set_title(f"{scene}, 30 dB, OTD, mean of {len(seeds)} seeds")
fig.tight_layout()
plt.show()
