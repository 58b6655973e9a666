"""
CASSDI-DFA: which aberration encodes depth, and how large a PSF must be
=======================================================================

The deformable mirror of CASSDI-DFA adds one Zernike mode to the focal
sweep (the thesis: vertical astigmatism, Noll 6, ≈ 0.9-1 wave).  A PSF cut
to a few pixels and renormalised is a different PSF: the study records the
share of each PSF's light inside the crop (``energy``) and compares the
aberrations at a crop that holds nearly all of it.

``studies.zernike_design`` runs the grid (pure defocus is always in it);
``plot.study`` draws it.  A real CAVE scene is used where the research data
are (``$TENSOR_COSDI_DATA`` or ``../shared/data``), the ColorChecker where
not.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, optics, plot, studies
from tensor_cosdi.studies.zernike import DEPTHS_MM, default_lens

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)

# %%
# The PSF of a point 200 mm in front of focus at 550 nm, cut to 9 and to 41 pixels
fig, axes = plt.subplots(2, 3, figsize=(7, 4.6))
for row, size in enumerate((9, 41)):
    for col, zern in enumerate([None, {6: 0.25}, {6: 0.9}]):
        h = optics.psf(550, DEPTHS_MM[0], lens=default_lens(), zernike=zern, size=size)
        big = optics.psf(550, DEPTHS_MM[0], lens=default_lens(), zernike=zern, size=81)
        share = big[40 - size // 2 : 41 + size // 2, 40 - size // 2 : 41 + size // 2].sum()
        axes[row, col].imshow(h, cmap="magma")
        name = "defocus" if zern is None else f"Z6 {zern[6]} wave"
        axes[row, col].set_title(f"{name}, {size}×{size}: {share:.0%} of the light", fontsize=7)
        axes[row, col].axis("off")
fig.tight_layout()

# %%
# The study: astigmatism (Z6) and coma (Z8) at two amplitudes, crops of 9 and 41 pixels
recs = studies.zernike_design(
    modes=(6, 8), amplitudes=(0.25, 0.9), psf_sizes=(9, 41), scene=scene, shape=(32, 32),
    n_bands=8, snr_db=30, progress=False,
)  # fmt: skip
for r in recs:
    print(
        f"Z{r['mode']} {r['amplitude']:.2f} wave, crop {r['psf_size']:2d}: light in crop "
        f"{r['energy']:.0%}, depth planes right {r['depth_accuracy']:.0%}, "
        f"PSNR {r['psnr']:.2f} dB, PSF separation {r['separation']:.2f}"
    )
full = [r for r in recs if r["psf_size"] == 41]
best = max(full, key=lambda r: r["depth_accuracy"])
print(f"best at the 41-pixel crop: Z{best['mode']} {best['amplitude']} wave (Z0 = pure defocus)")

# %%
fig, axes = plt.subplots(1, 2, figsize=(9, 3.2))
for r in recs:
    r["aberration"] = "defocus" if r["mode"] == 0 else f"Z{r['mode']} {r['amplitude']}"
plot.study(recs, "psf_size", "depth_accuracy", by="aberration", ax=axes[0])
plot.study(recs, "psf_size", "psnr", by="aberration", ax=axes[1])
axes[0].set_xlabel("PSF crop (pixels)")
axes[0].set_ylabel("depth planes right")
axes[0].set_title(f"{scene}, 30 dB", fontsize=9)
axes[1].set_xlabel("PSF crop (pixels)")
axes[1].set_ylabel("PSNR dB (4-D cube)")
fig.tight_layout()
plt.show()
depth_accuracy = np.array([r["depth_accuracy"] for r in recs])
