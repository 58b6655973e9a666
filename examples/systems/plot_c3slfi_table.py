"""
C3SLFI: the thesis' Table 1 over snapshots and noise
====================================================

The thesis' Table 1 compares learned (OTD) and fixed (WDCT: Symlet-8 ⊗ DCT)
bases for C3SLFI over the compression ratio ``C = K / Nλ`` and the SNR.
``studies.c3slfi_table`` runs that grid; ``plot.study`` draws it.  The
answer depends on the spectra: run it on a real CAVE scene where the
research data are (``$TENSOR_COSDI_DATA`` or ``../shared/data``), not only
on photo-derived cubes, whose spectra live in a 3-D subspace.
"""

# %%
import matplotlib.pyplot as plt

from tensor_cosdi import datasets, plot, studies

scene, note = datasets.scene_or("cave.face", "chelsea")  # real spectra where present
if note:
    print(note)
recs = studies.c3slfi_table(
    (scene,), snapshots=(2, 3), snrs=(20.0, 40.0), methods=("otd", "wdct"), forms=("3d",),
    shape=(64, 64), views=(4, 4), n_bands=31, progress=False,
)  # fmt: skip
for r in recs:
    print(
        f"K = {r['n_snapshots']} (C = {r['ratio']:.1%}), {r['snr_db']:g} dB, {r['method']}: "
        f"PSNR {r['psnr']:.2f} dB, SAM {r['sam']:.1f}°"
    )

# %%
fig, axes = plt.subplots(1, 2, figsize=(9, 3.2))
for r in recs:
    r["method at SNR"] = f"{r['method'].upper()}, {r['snr_db']:g} dB"
plot.study(recs, "n_snapshots", "psnr", by="method at SNR", ax=axes[0])
plot.study(recs, "n_snapshots", "sam", by="method at SNR", ax=axes[1])
axes[0].set_xlabel("snapshots K")
axes[0].set_ylabel("PSNR dB")
axes[0].set_title(f"{scene}, 31 bands", fontsize=9)
axes[1].set_xlabel("snapshots K")
axes[1].set_ylabel("SAM °")
fig.tight_layout()
plt.show()
