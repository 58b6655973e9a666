"""
The thesis' own algorithms next to OTD
======================================

Each imager of the thesis came with its own reconstruction: A-VSI (Alg. 1)
for CASSI-VSI, the multiresolution method (Alg. 2-4) for CASSDI-DFA and the
hierarchical PnP-ADMM (Alg. 6) for CS2LI.  All three run matrix-free in the
same harness as the online Tucker dictionary ADMM that generalises the
C3SLFI algorithm; here they are compared on seeded 64×64×16 scenes at 30 dB
(fixed-basis ADMMs such as A-VSI need that size; at 48×48×12 A-VSI and
WDCT-ADMM barely beat least squares).
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import depth
from tensor_cosdi.studies import compare, make_problem, spectral_view

cases = [
    ("cassi_vsi", "chelsea", "avsi"),
    ("cassdi_dfa", "chelsea", "dfa"),
    ("cs2li", "coffee", "pnp_admm"),
]
fig, axes = plt.subplots(len(cases), 3, figsize=(6, 6))
for row, (system, scene, own) in enumerate(cases):
    p = make_problem(system, scene, shape=(64, 64), n_bands=16, snr_db=30, rng=0)
    rows = compare(p, [own, "otd"])
    for r in rows:
        line = (
            f"{system:10s} {r['method']:8s} PSNR {r['psnr']:5.2f} dB  SAM {r['sam']:5.2f}°  "
            f"{r['seconds']:.2f} s"
        )
        d = r["result"].depth
        if system == "cassdi_dfa":
            line += f"  depth planes right {np.mean(np.asarray(d) == p.depth):.0%}"
        if system == "cs2li":
            err = depth.wrap(np.asarray(d)[..., 0] - p.extras["phase"][..., 0])
            line += f"  phase error {np.abs(err).mean():.2f} rad"
        print(line)
    panels = [("truth", p.cube)] + [(r["method"], r["result"].cube) for r in rows]
    for ax, (name, cube) in zip(axes[row], panels):
        ax.imshow(tc.colour.to_srgb(np.clip(spectral_view(p, cube), 0, None), p.wavelengths))
        ax.set_title(f"{system}: {name}", fontsize=7)
        ax.axis("off")
fig.tight_layout()
