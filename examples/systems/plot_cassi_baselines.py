"""
Baselines: SD-CASSI (one and two shots), DD-CASSI and dual-camera CASSI
=======================================================================

The systems the thesis compares against (SPEC §3.0), on the measured
ColorChecker reflectances (28 bands, 450–650 nm) at 30 dB SNR.  The
single disperser smears the bands along ``y``; the dual disperser keeps the
image aligned and moves the code instead; the dual-camera system adds a
noise-free panchromatic frame.
"""

# %%
import matplotlib.pyplot as plt

from tensor_cosdi.codes import random_binary
from tensor_cosdi.scenes import colorchecker
from tensor_cosdi.systems import DDCASSI, SDCASSI, DualCameraCASSI

nx, ny, nl = 64, 96, 28
sd = SDCASSI(random_binary((nx, ny), rng=0), n_bands=nl, shifts=2)
cube = colorchecker((nx, ny), sd.wavelengths)
two_shots = SDCASSI(random_binary((nx, ny, 2), rng=1), n_bands=nl, shifts=2)
dd = DDCASSI(random_binary((nx, ny + 2 * (nl - 1)), rng=2), n_bands=nl, shifts=2)
dual = DualCameraCASSI(sd.code, n_bands=nl, shifts=2)
for system in (sd, two_shots, dd, dual):
    print(system, "A Aᵀ:", type(system.gram_dual()).__name__)

# %%
# Simulated measurements
frames = {
    "SD-CASSI": sd.simulate(cube, 30.0, rng=0),
    "SD-CASSI, shot 2 of 2": two_shots.simulate(cube, 30.0, rng=0)[:, :, 1],
    "DD-CASSI": dd.simulate(cube, 30.0, rng=0),
    "dual camera: panchromatic": dual.simulate(cube, 30.0, rng=0)[:, :ny, 1],
}
fig, axes = plt.subplots(2, 2, figsize=(8, 4.6))
for ax, (title, g) in zip(axes.ravel(), frames.items()):
    ax.imshow(g, cmap="gray")
    ax.set_title(title)
    ax.set_axis_off()
fig.tight_layout()
plt.show()
