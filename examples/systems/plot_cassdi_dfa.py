"""
CASSDI-DFA: one exposure of a focal sweep with one code per depth
=================================================================

Depth from aberrations (SPEC §3.2, thesis Ch. 4).  The scene is split into
three depth planes; during the exposure a deformable mirror steps the focus
through them while the DMD shows one random code per step, and the sensor
integrates the dispersed, coded, blurred planes.  Here each plane's PSF is a
Gaussian whose width grows with the distance from the focused plane — a
stand-in for the Zernike PSFs of :mod:`tensor_cosdi.optics`.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi.codes import depth_codes
from tensor_cosdi.scenes import colorchecker
from tensor_cosdi.systems import CASSDIDFA

nx, ny, nl, nz = 64, 96, 16, 3
planes = np.minimum(np.arange(ny) * nz // ny, nz - 1)  # left third near, right third far
depth_mask = (planes[None, :, None] == np.arange(nz)).astype(float)  # (1, Ny, Nz)
scene = colorchecker((nx, ny), np.linspace(450, 650, nl))
cube = scene[:, :, :, None] * depth_mask[:, :, None, :]  # (Nx, Ny, Nλ, Nz)

# one Gaussian PSF per focal step, same for every band
r = np.arange(-3, 4)
psfs = np.empty((7, 7, 1, nz))
for z, sigma in enumerate([0.5, 1.2, 2.0]):
    k = np.exp(-(r[:, None] ** 2 + r[None, :] ** 2) / (2 * sigma**2))
    psfs[:, :, 0, z] = k / k.sum()

dfa = CASSDIDFA(depth_codes((nx, ny), nz, rng=0), n_bands=nl, shifts=1, psfs=psfs)
g = dfa.simulate(cube, 30.0, rng=1)
print(dfa, "\nA Aᵀ structure:", dfa.gram_dual(), "(PSFs → conjugate gradients)")
print("all-in-focus grayscale estimate:", dfa.panchromatic(g).shape)

# %%
fig, axes = plt.subplots(1, 3, figsize=(8, 2.4))
axes[0].imshow(planes[None, :].repeat(nx, 0), cmap="viridis")
axes[0].set_title("depth plane")
axes[1].imshow(dfa.codes[:, :, 0], cmap="gray")
axes[1].set_title("code of focal step 0")
axes[2].imshow(g, cmap="gray")
axes[2].set_title("measurement")
for ax in axes:
    ax.set_axis_off()
fig.tight_layout()
plt.show()
