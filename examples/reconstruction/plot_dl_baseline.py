"""
Learned patch dictionaries: the thesis' DL-3D and Lytro-CASSI baselines
=======================================================================

The thesis compares its online Tucker dictionary (OTD) with "DL": an
over-complete dictionary of ``patch × patch × bands`` patches learned by
K-SVD on *other* scenes.  :func:`tensor_cosdi.solvers.train_dictionary`
learns one, and ``method="dl"`` reconstructs with it as the prior of GAP.
Here: C3SLFI light fields (the 3-D lenslet form), a dictionary learned on
four tuning scenes, scored on a held-back real scene (32×32, 8 bands,
20 dB: DL 28.0 dB against WDCT 25.9 and OTD 26.5).  Without the research
data it learns on photos and scores the colour checker, where it trails
(20.7 dB against 22.0 and 22.2): a dictionary is only as good as its
training scenes are like the scene.

The thesis' other baseline, Lytro-CASSI, is another *architecture*: a
plenoptic RGB camera beside a CASSI that takes ``K`` coded snapshots of the
same lenslet image (:class:`tensor_cosdi.systems.LytroCASSI`).
``method="lytro"`` learns 8×8 spatial atoms from its own RGB frames and
takes a DCT across the bands (no training scenes at all).
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets, studies

opts = {"shape": (32, 32), "n_bands": 8, "rng": 0, "n_snapshots": 2, "views": (2, 2)}
test, why = datasets.scene_or("cave.face", "colorchecker")
if why:
    print(why)
    train = ["chelsea", "coffee", "astronaut", "rocket"]
else:
    train = [f"cave.{s}" for s in datasets.TUNE_SCENES[:4]]
cubes = [studies.make_problem("c3slfi", s, **opts).cube for s in train]
dictionary = tc.solvers.train_dictionary(cubes, patch=6, n_patches=1500, n_iter=3)
print(dictionary)

# %%
p = studies.make_problem("c3slfi", test, snr_db=20.0, **opts)
psnr, cubes_out = {}, {}
for method, options in (("wdct", {}), ("otd", {}), ("dl", {"dictionary": dictionary})):
    res = tc.reconstruct(p.system, p.measurement, method, **options)
    psnr[method], cubes_out[method] = studies.score(p, res.cube)["psnr"], res.cube
    print(f"{method:5s} {psnr[method]:.2f} dB in {res.seconds:.2f} s")

# %%
band = p.system.cube_shape[2] // 2
fig, axes = plt.subplots(1, 4, figsize=(10, 2.8))
for ax, (title, cube) in zip(axes, [("truth", p.cube), *cubes_out.items()]):
    ax.imshow(np.asarray(cube)[:, :, band], cmap="gray", vmin=0, vmax=float(np.max(p.cube)))
    ax.set_title(title if title == "truth" else f"{title} {psnr[title]:.1f} dB")
    ax.axis("off")
fig.tight_layout()
plt.show()

# %%
# Lytro-CASSI on the same light field: its RGB arm adds three frames to the
# ``K = 2`` CASSI snapshots.
lytro = studies.make_problem("lytro_cassi", test, snr_db=20.0, **opts)
res = tc.reconstruct(lytro.system, lytro.measurement, "lytro")
psnr["lytro"] = studies.score(lytro, res.cube)["psnr"]
psnr["lytro_lsq"] = studies.score(
    lytro, tc.reconstruct(lytro.system, lytro.measurement, "lsq").cube
)["psnr"]
print(f"lytro {psnr['lytro']:.2f} dB in {res.seconds:.2f} s (LSQ {psnr['lytro_lsq']:.2f})")
