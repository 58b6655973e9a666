"""
Large captures in tiles
=======================

``tc.reconstruct_tiled`` cuts an SD-CASSI or DD-CASSI capture into
overlapping tiles, reconstructs each as its own small problem (one after the
other, or on a ``dask.distributed`` client with ``client=``) and blends
them.  It needs less memory than one large reconstruction and its cost per
pixel does not grow with the image.  The tiles are grown by ``overlap``
pixels, and across the shear by the shear itself: a tile's edge measurement
columns hold light dispersed in from its neighbours, which the overlap has
to absorb.  This example runs a 128×128×16 seeded scene whole and in tiles
of 64, with a small and a sufficient overlap.  (At 1024×1024×28 the default
``tile=256, overlap=128`` stays within 0.15 dB of the untiled OTD with half
its peak memory; see ``benchmarks/tiled.py``.)
"""

# %%
import matplotlib.pyplot as plt

import tensor_cosdi as tc

p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(128, 128), n_bands=16, snr_db=30)
whole = tc.reconstruct(p.system, p.measurement, "otd")
runs = {"untiled": whole}
for overlap in (8, 48):
    runs[f"tiles of 64, overlap {overlap}"] = tc.reconstruct_tiled(
        p.system, p.measurement, "otd", tile=64, overlap=overlap
    )
psnr = {name: tc.studies.score(p, r.cube)["psnr"] for name, r in runs.items()}
for name, r in runs.items():
    print(f"{name:24s} {psnr[name]:6.2f} dB  {r.seconds:5.1f} s")

# %%
fig = tc.plot.compare(p.cube, {name: r.cube for name, r in runs.items()}, p.wavelengths)
fig.suptitle("SD-CASSI 128×128×16, 30 dB: whole and tiled OTD", fontsize=9)
plt.show()
