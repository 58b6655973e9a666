"""
D-CoSNet with a learned coded aperture
======================================

The thesis trains D-CoSNet's coded aperture together with the network
(Sec. 7.3).  ``tensor-cosdi train-dcosnet --mask seeded --learn-code``
does the same for SD-CASSI: a binary 64×64 code starts from a seeded
Bernoulli(½) draw, changes during the first half of training through a
straight-through estimator (every code the network sees is binary), and is
then held while the network adapts to it.  The package ships one such
network and its twin trained identically on the fixed seeded code
(:data:`tensor_cosdi.studies.learned.CODE_STUDY_WEIGHTS`; 3 stages,
28 bands, 2 px per band).  :func:`tensor_cosdi.studies.learned_code`
images a scene through each network's own code, tiled over the scene, and
scores the reconstruction.

Learning flips a few per cent of the code's pixels (printed below); whether
that pays off depends on the shear
(``benchmarks/results/dcosnet_code.md``: at 2 px within the networks'
training noise, at 1 px the fixed code is better, at 3 px the learned one).

It runs on a real CAVE scene (``"cave.face"``; from ``$TENSOR_COSDI_DATA``
or ``../shared/data`` next to a source checkout) and, without the data
folder, says so and uses the measured ColorChecker reflectances.  It needs
PyTorch (``pip install 'tensor_cosdi[torch]'``).
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies
from tensor_cosdi.learn.dcosnet import training_code
from tensor_cosdi.studies.learned import CODE_STUDY_WEIGHTS

scene, note = datasets.scene_or("cave.face", "colorchecker")  # real spectra where present
if note:
    print(note)
codes = {k: training_code(w) for k, w in CODE_STUDY_WEIGHTS.items()}
flipped = codes["learned"] != codes["seeded"]
print(f"learning flipped {flipped.mean():.1%} of the code's pixels; open fraction "
      f"{codes['seeded'].mean():.3f} → {codes['learned'].mean():.3f}")  # fmt: skip

rows = studies.learned_code(scenes=(scene,), shape=(128, 128), snrs=(None, 30.0),
                            progress=False)  # fmt: skip
psnr = {(r["code"], r["snr_db"]): r["psnr"] for r in rows}
for (code, snr), value in psnr.items():
    print(f"{code:8s} code, {'noiseless' if snr is None else f'{snr:g} dB':9s}: "
          f"PSNR {value:.2f} dB")  # fmt: skip

# %%
fig, axes = plt.subplots(1, 4, figsize=(12, 3.2))
axes[0].imshow(codes["seeded"], cmap="gray", interpolation="nearest")
axes[0].set_title("fixed seeded code")
axes[1].imshow(codes["learned"], cmap="gray", interpolation="nearest")
axes[1].set_title("learned code")
axes[2].imshow(flipped, cmap="magma", interpolation="nearest")
axes[2].set_title(f"pixels learning flipped ({flipped.mean():.1%})")
for ax in axes[:3]:
    ax.set_axis_off()
x = np.arange(2)
for i, code in enumerate(("seeded", "learned")):
    axes[3].bar(x + 0.38 * i, [psnr[(code, None)], psnr[(code, 30.0)]], 0.38, label=code)
axes[3].set_xticks(x + 0.19, ["noiseless", "30 dB"])
axes[3].set_ylim(min(psnr.values()) - 2, None)
axes[3].set_ylabel("PSNR dB")
axes[3].set_title(f"{scene}, 128×128")
axes[3].legend(fontsize=8)
fig.tight_layout()
plt.show()
