"""
CASSI-VSI's beam-splitting ratio at three noise levels
======================================================

CASSI-VSI splits the light ``αT`` : ``1 − αT`` between a dispersed and a
grayscale arm on one sensor.  :func:`tensor_cosdi.studies.vsi_ratio` sweeps
``αT`` at equal light (one absolute noise level, the one that puts
SD-CASSI at the given SNR) and scores each OTD reconstruction; the combined
error of Eq. 49 (:func:`tensor_cosdi.metrics.combined_error`) fuses PSNR,
SSIM, RMSE and SAM into one number per ratio.  The thesis (Sec. 3.3.2-3.3.3,
Fig. 21-22, 102) finds the least combined error near ``αT = 0.7`` at 15, 20
and 30 dB, and the panchromatic estimate best as ``αT → 0``;
``benchmarks/results/thesis_findings.md`` holds the verdicts over three
seeds and the report scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, metrics, studies

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
alphas, snrs, seeds = (0.1, 0.3, 0.5, 0.7, 0.9, 1.0), (15.0, 20.0, 30.0), (0, 1, 2)
runs = {
    snr: studies.vsi_ratio((scene,), alphas, shape=(32, 32), n_bands=12, snr_db=snr,
                           seeds=seeds, progress=False)
    for snr in snrs
}  # fmt: skip


def column(rows, key):
    """``key`` as a (seeds, ratios) array: each seed (code and noise) plays a scene of Eq. 49."""
    return np.array([[r[key] for r in rows if r["seed"] == q] for q in seeds])


combined = {
    snr: metrics.combined_error(*(column(rows, k) for k in ("psnr", "ssim", "rmse", "sam")))
    for snr, rows in runs.items()
}
for snr, comb in combined.items():
    best = alphas[int(np.argmin(comb))]
    print(f"{snr:g} dB: least combined error at αT = {best} ({comb.min():.1f} %)")

# %%
fig, axes = plt.subplots(1, 3, figsize=(11, 3.2))
for snr, rows in runs.items():
    axes[0].plot(alphas, column(rows, "psnr").mean(0), "o-", label=f"{snr:g} dB")
    axes[1].plot(alphas, combined[snr], "o-", label=f"{snr:g} dB")
    axes[2].plot(alphas, column(rows, "pan_psnr").mean(0), "o-", label=f"{snr:g} dB")
for ax, title in zip(axes, ("cube PSNR dB", "combined error % (Eq. 49)", "panchromatic PSNR dB")):
    ax.set_xlabel("αT")
    ax.set_title(title, fontsize=9)
axes[0].legend(fontsize=8)
fig.suptitle(f"CASSI-VSI on {scene}, 32×32×12, OTD, equal light, {len(seeds)} seeds")
fig.tight_layout()
plt.show()
