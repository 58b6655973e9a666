"""
Mu-CoSDI: one dual-disperser core, three depth modalities
=========================================================

The multimodal imager (SPEC §3.5, thesis Ch. 7).  A binary code sheared by
``Γ(l) = γ·l`` (here ``γ = 1``) modulates the cube; a lenslet array (LF),
a projector (SL) or nothing (monocular) supplies the depth cue.  All three
share ``A Aᵀ = diag(Σ_l Ceff_l²)``.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi.codes import random_binary
from tensor_cosdi.scenes import colorchecker
from tensor_cosdi.systems import MuCoSDI, fringe_cube

nl = 16
wl = np.linspace(450, 650, nl)

# light field: 2 × 2 views of a 32 × 48 scene, one pixel of disparity per view
scene = colorchecker((34, 50), wl)
views = np.stack(
    [np.stack([scene[u : u + 32, v : v + 48] for v in range(2)], -1) for u in range(2)], -2
)
lf = MuCoSDI(random_binary((64, 96 + nl - 1), rng=0), n_bands=nl, modality="lf", views=(2, 2))
g_lf = lf.simulate(lf.from_views(views), 30.0, rng=1)

# structured light: 4 phase steps of one fringe frequency
refl = colorchecker((64, 96), wl)
phase = 2 * np.pi * 6 * np.arange(96)[None, :].repeat(64, 0) / 96
sl = MuCoSDI(random_binary((64, 96 + nl - 1), rng=2), n_bands=nl, modality="sl", n_patterns=4)
g_sl = sl.simulate(fringe_cube(refl, phase, n_steps=4), 30.0, rng=3)

mono = MuCoSDI(random_binary((64, 96 + nl - 1), rng=4), n_bands=nl, modality="monocular")
g_mono = mono.simulate(refl, 30.0, rng=5)
for s in (lf, sl, mono):
    print(s, "A Aᵀ:", type(s.gram_dual()).__name__)

# %%
fig, axes = plt.subplots(1, 3, figsize=(8, 2.3))
for ax, img, title in zip(
    axes, [g_lf, g_sl[:, :, 0], g_mono], ["LF (lenslet image)", "SL, pattern 0", "monocular"]
):
    ax.imshow(img, cmap="gray")
    ax.set_title(title)
    ax.set_axis_off()
fig.tight_layout()
plt.show()
