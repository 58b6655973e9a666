"""
CS2LI colour-coded aperture: spectra against depth
==================================================

CS2LI's mirror carries a colour-coded aperture: ``#f`` contiguous band-pass
filters, each pixel open with probability ``κ``.  The thesis (Sec. 6.3.2,
Fig. 58) finds that the code that serves the spectra is not the one that
serves the depth: the least SAM at one narrow filter per band (``#f = Nλ``)
and ``κ = 25 %``, the best height map with a binary code (``#f = 1``) at
``κ = 75 %``, and picks ``#f = 6, κ = 50 %`` as the trade-off.
:func:`tensor_cosdi.studies.cs2li_code_design` sweeps both and scores the
reflectance and the height map of each OTD reconstruction;
``benchmarks/results/thesis_findings.md`` holds the verdicts over three seeds
and the report scenes.

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
filters, kappas = (1, 2, 6, 8), (0.25, 0.5, 0.75)
recs = studies.cs2li_code_design(
    filters, kappas, scene=scene, shape=(32, 32), n_bands=8, snr_db=30, progress=False
)


def grid(key):
    return np.array([[r[key] for r in recs if r["n_filters"] == f] for f in filters])


sam, depth_psnr = grid("sam"), grid("depth_psnr")
for name, g, pick in (("SAM °", sam, np.argmin), ("depth PSNR dB", depth_psnr, np.argmax)):
    i, j = np.unravel_index(pick(g), g.shape)
    print(f"best {name}: #f = {filters[i]}, κ = {kappas[j]} ({g[i, j]:.2f})")

# %%
fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
for ax, g, title, cmap in (
    (axes[0], sam, "reflectance SAM ° (lower is better)", "viridis_r"),
    (axes[1], depth_psnr, "height map PSNR dB (higher is better)", "viridis"),
):
    im = ax.imshow(g, cmap=cmap)
    ax.set_xticks(range(len(kappas)), [f"κ {k:.2f}" for k in kappas])
    ax.set_yticks(range(len(filters)), [f"#f {f}" for f in filters])
    for (i, j), v in np.ndenumerate(g):
        ax.text(j, i, f"{v:.1f}", ha="center", va="center", color="w", fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, shrink=0.8)
fig.suptitle(f"CS2LI on {scene}, 32×32×8, 30 dB, OTD")
fig.tight_layout()
plt.show()
