"""
C3SLFI: complementary colour-coded snapshots of a spectral light field
======================================================================

The colour-coded compressive spectral light field imager (SPEC §3.3,
thesis Ch. 5).  A 3 × 3-view spectral light field is rendered from the
ColorChecker by shifting each view by one pixel per view step; ``K = 2``
complementary colour-coded apertures (a low-pass and a high-pass filter per
pixel, swapped at random) take two snapshots.  Lemma 1: their sum is the
panchromatic light field, exactly.  The same system on the 3-D lenslet
parameterisation of Eq. 85 gives the raw sensor images.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi.codes import complementary_colour_codes
from tensor_cosdi.scenes import colorchecker
from tensor_cosdi.systems import C3SLFI

n1, n2, n3, n4, n5 = 32, 48, 16, 3, 3
base = colorchecker((n1 + 4, n2 + 4), np.linspace(450, 650, n3))
views = np.stack(
    [
        np.stack(
            [base[2 + u - 1 : 2 + u - 1 + n1, 2 + v - 1 : 2 + v - 1 + n2] for v in range(n5)], -1
        )
        for u in range(n4)
    ],
    -2,
)  # (N1, N2, N3, N4, N5): one pixel of disparity per view step
five = C3SLFI(complementary_colour_codes(views.shape, 2, rng=0), layout="5d")
G = five.simulate(views, 30.0, rng=1)
print(five, "\nA Aᵀ:", five.gram_dual())
print("Lemma 1 error (noise-free):", np.abs(five.forward(views).sum(2) - views.sum(2)).max())

# %%
# The 3-D lenslet parameterisation (Eq. 85): what the sensor records
three = five.as_3d("interleaved")
raw = three.measurement_to_3d(G)  # (N1·N4, N2·N5, K)
pan = three.panchromatic(raw)  # Lemma 1: Σ_k G̃[..., k]
fig, axes = plt.subplots(1, 3, figsize=(8, 2.2))
for ax, img, title in zip(
    axes,
    [raw[:, :, 0], raw[:, :, 1], pan],
    ["snapshot 1 (lenslet image)", "snapshot 2", "Σ_k: panchromatic"],
):
    ax.imshow(img, cmap="gray")
    ax.set_title(title)
    ax.set_axis_off()
fig.tight_layout()
plt.show()
