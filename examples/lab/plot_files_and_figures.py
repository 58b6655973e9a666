"""
From measurement files to figures
=================================

What a lab does with a capture, in Python (the command line does the same
with ``tensor-cosdi reconstruct --system … --mask FILE:KEY --measurement
FILE:KEY --out cube.h5`` and ``tensor-cosdi preview cube.h5``): read a
measurement and a mask from MATLAB files, reconstruct, write the cube with
its wavelengths to HDF5, read it back, and draw every figure of
:mod:`tensor_cosdi.plot` — an exposed sRGB preview, the band montage, spectra
against the truth, a comparison with PSNR / SSIM and error maps, a depth map
and the convergence of the solver.
"""

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import scipy.io

import tensor_cosdi as tc
from tensor_cosdi import plot
from tensor_cosdi.io import read_array, read_cube, write_cube

folder = Path(tempfile.mkdtemp())
p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(48, 48), n_bands=12, snr_db=30, rng=0)
wl = p.system.wavelengths
scipy.io.savemat(folder / "capture.mat", {"meas": np.asarray(p.measurement), "exposure_ms": 20})
scipy.io.savemat(folder / "mask.mat", {"mask": p.system.code})

# %%
# Read the files (a variable is picked by name; one candidate would be found alone)
g = read_array(folder / "capture.mat", "meas")
code = read_array(folder / "mask.mat")
system = tc.systems.SDCASSI(code, n_bands=12, shifts=1, wavelengths=wl)
runs = {m: tc.reconstruct(system, g, m) for m in ("lsq", "gap_tv", "otd")}
write_cube(folder / "otd.h5", runs["otd"].cube, wl, metadata={"method": "otd"})
cube, wl_back = read_cube(folder / "otd.h5")
print(f"read back {cube.shape} {cube.dtype}, {wl_back[0]:.0f}–{wl_back[-1]:.0f} nm")

# %%
# An exposed preview and the band montage
plot.preview(cube, wl_back, title="OTD reconstruction")
plot.bands(cube, wl_back)

# %%
# Spectra at two pixels against the truth, and the comparison figure
plot.spectra(cube, wl, [(10, 12), (30, 34)], reference=p.cube)
plot.compare(p.cube, {m: r.cube for m, r in runs.items()}, wl)
psnr = {
    m: tc.metrics.psnr(p.cube, r.cube, data_range=float(np.max(p.cube))) for m, r in runs.items()
}
print({m: round(v, 2) for m, v in psnr.items()})

# %%
# A depth map (CASSDI-DFA's depth planes) and the convergence of GAP-TV
dfa = tc.studies.make_problem("cassdi_dfa", "chelsea", shape=(32, 32), n_bands=8, rng=0)
res = tc.reconstruct(dfa.system, dfa.measurement, "gap_tv")
plot.depth(res.depth, label="depth plane")
plot.convergence(runs["gap_tv"])
plt.show()
