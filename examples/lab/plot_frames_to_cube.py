"""
From raw frames and a calibration to a reconstructed cube
=========================================================

What a lab does with its own prototype, end to end, on simulated captures
(the real coded aperture ``tsa_mask256.mat`` and the real lenslet capture of
``$TENSOR_COSDI_DATA`` or ``../shared/data`` are used where present, seeded
stand-ins where not):

1. **calibrate** (thesis Appendix A): frames of the coded aperture under a
   monochromator, one per band → the dispersion shifts and the code;
2. **save** the calibrated system, with its dark frame, as one bundle;
3. **capture**: raw TIFF frames (scene and white reference under a coloured
   lamp) with a dark offset and a pixel gain;
4. **reconstruct**: dark/flat correction → the system's measurement → OTD
   of the scene and of a white reference → reflectance (scene ÷ white
   spectrum), saved with provenance;
5. **lenslet cameras**: fit the lenslet grid of a microscope light-field
   capture from its flat ("radiometry") frame and cut the views.
"""

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import tifffile

import tensor_cosdi as tc
from tensor_cosdi import datasets, io


def research_data(relative):
    """The project's research-use data (not shipped): under $TENSOR_COSDI_DATA, else ../shared/data
    next to a source checkout.  Where it is absent the example stops, unless
    TENSOR_COSDI_ALLOW_FALLBACK=1 lets it go on with a seeded stand-in (None)."""
    try:
        return datasets.data_file(relative)
    except FileNotFoundError as err:
        print(datasets.stand_in(err, "a seeded stand-in"))
        return None


work = Path(tempfile.mkdtemp())
n, nl = 64, 16
wl = tc.scenes.default_wavelengths(nl)
mask_file = research_data("masks/tsa_mask256.mat")
true_code = (
    io.read_frame(mask_file, key="mask")[96:160, 96:160]
    if mask_file is not None
    else tc.codes.random_binary((n, n), rng=0)
)
true_system = tc.systems.SDCASSI(true_code, n_bands=nl, shifts=2, wavelengths=wl)

# %%
# 1. Monochromator frames: band l lights the code alone; camera dark level 100 counts
rng = np.random.default_rng(0)
dark = 100 + rng.normal(0, 1, true_system.measurement_shape)
mono = np.stack(
    [
        np.asarray(true_system.forward(np.ones((n, n, nl)) * np.eye(nl)[l])) * 2000
        for l in range(nl)
    ],
    -1,
)
mono = mono + dark[..., None]
shifts = io.shifts_from_line_frames(mono, dark=dark)
code, per_band = io.code_from_monochromator(mono, shifts=shifts, dark=dark, ny=n)
print("measured shifts (px):", np.round(shifts, 2))
print(f"code error vs the true mask: {np.abs(code - true_code).mean():.4f} (mean absolute)")

# %%
# 2. The calibrated system in a bundle (never overwritten without overwrite=True)
system = tc.systems.SDCASSI(code, n_bands=nl, shifts=shifts, wavelengths=wl)
cal = io.save_bundle(
    work / "calibration.npz",
    system=system,
    calibration={"dark": dark},
    metadata={"camera": "simulated", "prism_to_sensor_mm": 30},
)

# %%
# 3. Raw captures under a reddish lamp (radiance = reflectance × illuminant): the scene, a white
# reference (a spectralon, reflectance 1), a flat field and the dark frame.  2000 counts full
# scale, a ±10 % pixel gain, the dark level, read noise.
scene = tc.scenes.photo("chelsea", (n, n), wl)
lamp = np.linspace(0.4, 1.0, nl)  # relative power per band, rising towards the red
gain = 1 + 0.1 * rng.standard_normal(true_system.measurement_shape)
flat_raw = 3000 * gain + dark


def capture(reflectance_cube):
    radiance = np.asarray(true_system.forward(reflectance_cube * lamp)) * 2000
    return radiance * gain + dark + rng.normal(0, 3, dark.shape)


raw, white_raw = capture(scene), capture(np.ones((n, n, nl)))
for name, frame in [("capture_000", raw), ("white", white_raw), ("flat", flat_raw), ("dark", dark)]:
    tifffile.imwrite(work / f"{name}.tif", frame.astype(np.float32))

# %%
# 4. Load, correct (dark, flat), map onto the measurement, reconstruct scene and white, divide
# by the white's spectrum (colour.reflectance, thesis Eq. 171), save with provenance
bundle = io.load_bundle(cal)
cubes = {}
for name in ("capture_000", "white"):
    frames = io.load_frames([work / f"{name}.tif"], dark=work / "dark.tif", flat=work / "flat.tif")
    g = io.frames_to_measurement(bundle.system, frames)
    cubes[name] = tc.reconstruct(bundle.system, g, "otd").cube
white_spectrum = np.median(np.asarray(cubes["white"]).reshape(-1, nl), axis=0)
cube = tc.colour.reflectance(cubes["capture_000"], white_spectrum)
out = io.save_bundle(
    work / "result.npz",
    system=bundle.system,
    measurement=g,
    cube=cube,
    sources=[work / f"{f}.tif" for f in ("capture_000", "white", "dark", "flat")] + [cal],
)
radiance_psnr = tc.metrics.psnr(scene, np.asarray(cubes["capture_000"]) / 2000)
reflectance_psnr, sam = tc.metrics.psnr(scene, cube), tc.metrics.sam(scene, cube)
print(
    f"reflectance PSNR {reflectance_psnr:.2f} dB, SAM {sam:.1f}° "
    f"(without the white: {radiance_psnr:.2f} dB, the lamp tints it); saved {out.name} with "
    f"{len(io.load_bundle(out).provenance)} source hashes"
)

fig, axes = plt.subplots(1, 3, figsize=(7, 2.4))
axes[0].imshow(raw, cmap="gray")
axes[0].set_title("raw capture", fontsize=8)
axes[1].imshow(tc.colour.to_srgb(scene, wl))
axes[1].set_title("scene", fontsize=8)
axes[2].imshow(tc.colour.to_srgb(np.clip(cube, 0, None), wl))
axes[2].set_title("reflectance: OTD ÷ white", fontsize=8)
for ax in axes:
    ax.axis("off")
fig.tight_layout()

# %%
# 5. A lenslet (light-field) camera: fit the grid on the flat frame, cut the views of the capture
lf_dir = research_data("lenslet_raw_guv")
if lf_dir is not None:
    white = io.read_frame(lf_dir / "Radiometry_GUVExperim1.tif")
    dark_lf = io.read_frame(lf_dir / "DarkFrame_GUVExperim1.tif")
    raw_lf = io.read_frame(lf_dir / "Lightfield_GUVExperim1.tif").astype(float) - dark_lf
    grid = io.calibrate_lenslet_grid(white, dark=dark_lf)
    print(
        f"lenslet pitch {grid.pitch:.3f} px (100 µm / 6.5 µm = 15.385), rotation "
        f"{np.rad2deg(grid.rotation):.3f}°, {len(grid.residuals)} discs, residual RMS "
        f"{np.sqrt(np.mean(grid.residuals**2)):.2f} px"
    )
    views = grid.views(raw_lf)
    fig, axes = plt.subplots(1, 3, figsize=(7, 2.4))
    axes[0].imshow(white, cmap="gray")
    axes[0].plot(grid.centres[:, 1], grid.centres[:, 0], "r.", ms=1)
    axes[0].set_title("flat frame + fitted centres", fontsize=8)
    axes[1].imshow(views[views.shape[0] // 2, views.shape[1] // 2], cmap="gray")
    axes[1].set_title("centre view", fontsize=8)
    axes[2].imshow(views[2, views.shape[1] // 2], cmap="gray")
    axes[2].set_title("view u = 2", fontsize=8)
    for ax in axes:
        ax.axis("off")
    fig.tight_layout()
else:
    print(
        "step 5 skipped: the real lenslet capture is not here — it is research-use "
        "data and not shipped; point TENSOR_COSDI_DATA at a folder holding lenslet_raw_guv/ to "
        "run it"
    )
