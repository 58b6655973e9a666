"""
A learned reconstructor for SD-CASSI and for CASSI-VSI
======================================================

The thesis retrains a deep network (λ-net) for each forward model, CASSI
and CASSI-VSI at αT 0.7, with one fixed coded aperture, and finds CASSI-VSI
ahead at 20 and 30 dB (Sec. 3.3.5, Fig. 25-27).  The same experiment with
the package's unrolled network: D-CoSNet, whose x-step is each system's
exact ``(μI + A Aᵀ)⁻¹`` — a division for SD-CASSI, a Cholesky solve of each
detector row's banded block for CASSI-VSI — trained alike for both imagers
on one seeded 64×64 code (the shipped pair,
:data:`tensor_cosdi.studies.learned.IMAGER_STUDY_WEIGHTS`).
:func:`tensor_cosdi.studies.learned_imagers` images one scene with each
imager through that code, tiled, and lets its own network reconstruct it.
``benchmarks/results/thesis_findings.md`` holds the verdict over the report
scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.  It needs
PyTorch (``pip install 'tensor_cosdi[torch]'``).
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
snrs = (20.0, 30.0)
rows = studies.learned_imagers(scenes=(scene,), shape=(128, 128), snrs=snrs, progress=False)
psnr = {(r["system"], r["snr_db"]): r["psnr"] for r in rows}
for (system, snr), value in sorted(psnr.items()):
    print(f"{system:9s} {snr:g} dB: PSNR {value:.2f} dB")

# %%
fig, ax = plt.subplots(figsize=(5, 3.2))
x = np.arange(len(snrs))
for i, (system, label) in enumerate((("sd_cassi", "SD-CASSI"), ("cassi_vsi", "CASSI-VSI"))):
    ax.bar(x + 0.38 * i, [psnr[(system, s)] for s in snrs], 0.38, label=label)
ax.set_xticks(x + 0.19, [f"{s:g} dB" for s in snrs])
ax.set_ylim(min(psnr.values()) - 2, None)
ax.set_ylabel("PSNR dB")
ax.set_title(f"{scene}, 128×128, a network trained for each imager", fontsize=9)
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
