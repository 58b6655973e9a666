"""
Reconstruction on a real hyperspectral scene
============================================

Cubes made from RGB photographs live in a 3-D spectral subspace and flatter
spectral-subspace methods; judge reconstruction on measured spectra.  This
example reads a CAVE scene (``tensor_cosdi.datasets``, from
``$TENSOR_COSDI_DATA`` or ``../shared/data/hsi_train`` next to a source
checkout; research-use data, not shipped), resamples it onto the 28 KAIST
bands, measures a 96×96 crop with SD-CASSI at 30 dB, and compares GAP-TV,
OTD at its default (``lam="auto"``: the weight follows the measurement's
estimated SNR, :func:`tensor_cosdi.solvers.snr.estimate_snr`, which reads
the residual of a fit in the spectral subspace so that the code's texture is
not taken for noise) and at a fixed ``lam=0.3``, the experimental non-local Tucker prior
``"otd_nl"`` and, where PyTorch is installed, plug-and-play GAP with the
learned spectral denoiser (``"pnp_gap"``, and its quicker form ``"pnp_fast"``)
and the unfolded network
D-CoSNet (``"dcosnet"``, thesis §7; one forward pass).

Without the data folder it stops and says how to point to it; with
``TENSOR_COSDI_ALLOW_FALLBACK=1`` it runs on the measured ColorChecker
reflectances instead (still real spectra, but a flat, patchy scene) and a
seeded binary code, and says so.  On a small crop like this one GAP-TV is
competitive; the full-size comparison is on the benchmarks page.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets
from tensor_cosdi.solvers.snr import estimate_snr

n = 96
try:
    cube, wl = datasets.load_hsi("flowers", "kaist", shape=(n, n))  # a tune-split scene
    source = "CAVE 'flowers' (real reflectance spectra)"
except FileNotFoundError as err:  # stops unless TENSOR_COSDI_ALLOW_FALLBACK=1
    source = datasets.stand_in(err, "ColorChecker reflectances")
    wl = datasets.KAIST_WAVELENGTHS
    cube = tc.scenes.colorchecker((n, n), wl)
try:  # the measured TSA mask where the research data are
    code = tc.io.read_frame(datasets.data_file("masks/tsa_mask256.mat"), key="mask")[:n, :n]
except FileNotFoundError as err:
    print(datasets.stand_in(err, "a seeded random code"))
    code = tc.codes.random_binary((n, n), rng=0)
print(source)
system = tc.systems.SDCASSI(code, n_bands=len(wl), shifts=2, wavelengths=wl)
g = system.simulate(cube, snr_db=30, rng=0)
snr = estimate_snr(system, g)
print(f"estimated SNR: {snr.snr_db:.1f} dB (simulated at 30 dB; {snr.fit} fit)")

# %%
runs = {
    "gap_tv": tc.reconstruct(system, g, "gap_tv"),
    "lsq": tc.reconstruct(system, g, "lsq"),
    "otd": tc.reconstruct(system, g, "otd"),
    "otd, lam=0.3": tc.reconstruct(system, g, "otd", lam=0.3),
    "otd_nl": tc.reconstruct(system, g, "otd_nl"),
}
if tc.solvers.METHODS["pnp_gap"].available:  # the learned methods need torch
    runs["pnp_gap"] = tc.reconstruct(system, g, "pnp_gap")
    # fewer denoiser calls (solvers.pnp_gap.fast_budget), bfloat16 where the CPU runs it natively
    runs["pnp_fast"] = tc.reconstruct(system, g, "pnp_fast")
    # weights for SD-CASSI, 28 bands, 2 px; by default from pnp_fast's start, told the SNR
    runs["dcosnet"] = tc.reconstruct(system, g, "dcosnet")
else:
    print("PyTorch is not installed: no learned methods (pip install 'tensor_cosdi[torch]')")
psnr = {k: tc.metrics.psnr(cube, r.cube, data_range=1.0) for k, r in runs.items()}
for k, r in runs.items():
    sam = tc.metrics.sam(cube, r.cube)
    print(f"{k:14s} PSNR {psnr[k]:5.2f} dB  SAM {sam:5.2f}°  {r.seconds:5.2f} s")

# %%
# sRGB previews and the spectrum of one pixel
fig, axes = plt.subplots(1, 4, figsize=(8, 2.4))
for ax, (name, img) in zip(
    axes[:3], [("truth", cube), ("gap_tv", runs["gap_tv"].cube), ("otd", runs["otd"].cube)]
):
    ax.imshow(tc.colour.to_srgb(np.clip(img, 0, None), wl))
    ax.set_title(name, fontsize=8)
    ax.axis("off")
y, x = n // 2, n // 3
axes[3].plot(wl, cube[y, x], "k", label="truth")
for name in ("gap_tv", "otd", "otd_nl"):
    axes[3].plot(wl, np.asarray(runs[name].cube)[y, x], label=name)
axes[3].set_xlabel("nm", fontsize=8)
axes[3].legend(fontsize=6)
fig.tight_layout()
plt.show()
