"""
CASSDI-DFA: Zernike PSFs and the depth map
==========================================

The deformable mirror adds vertical astigmatism (Z6) to the focal sweep, so a
point in front of focus blurs along one axis and a point behind it along the
other (Sec. 4.3).  Here: the PSF of three depth planes with pure defocus and
with Z6, a CASSDI-DFA built from those PSFs, and the multiresolution
reconstruction (thesis Alg. 2-4) with its depth map.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import optics, scenes

lens = optics.Lens(focal_mm=50, aperture_radius_mm=1.5, focus_mm=1000, pixel_um=6)
depths = [800.0, 1000.0, 1300.0]
fig, axes = plt.subplots(2, 3, figsize=(6, 4))
for row, zern in enumerate([None, {6: 0.9}]):
    for k, z in enumerate(depths):
        h = optics.psf(550, z, lens=lens, zernike=zern, size=15)
        axes[row, k].imshow(h, cmap="magma")
        axes[row, k].set_title(
            f"{'defocus' if zern is None else 'Z6 + defocus'}, {z:.0f} mm", fontsize=7
        )
        axes[row, k].axis("off")
fig.tight_layout()

# %%
# A spectral-depth scene (photograph in 3 depth planes of the Middlebury disparity) and the system
n, nl = 48, 12
wl = scenes.default_wavelengths(nl)
_, disp = scenes.motorcycle((n, n), [550.0])
planes = scenes.depth_planes(disp, 3)
cube = scenes.depth_layers(scenes.photo("chelsea", (n, n), wl), planes, 3)
# 41 × 41 pixels hold ≥ 96 % of these PSFs' light (9 × 9: 9 %, a different PSF once
# renormalised — see plot_zernike_design.py)
psfs = optics.psf_stack(wl, depths, lens=lens, zernike={6: 0.9}, size=41)
dfa = tc.systems.CASSDIDFA(
    tc.codes.depth_codes((n, n), 3, rng=0), n_bands=nl, psfs=psfs, wavelengths=wl
)
g = dfa.simulate(cube, snr_db=30, rng=0)
res = tc.reconstruct(dfa, g, "dfa")
print(
    f"depth planes right: {np.mean(res.depth == planes):.1%}, "
    f"PSNR {tc.metrics.psnr(cube.reshape(n, n, -1), np.asarray(res.cube).reshape(n, n, -1)):.2f} dB"
)

# %%
fig, axes = plt.subplots(1, 3, figsize=(7, 2.5))
axes[0].imshow(g, cmap="gray")
axes[0].set_title("measurement", fontsize=8)
axes[1].imshow(planes, vmin=0, vmax=2)
axes[1].set_title("true depth plane", fontsize=8)
axes[2].imshow(res.depth, vmin=0, vmax=2)
axes[2].set_title("reconstructed", fontsize=8)
for ax in axes:
    ax.axis("off")
fig.tight_layout()
