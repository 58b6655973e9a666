"""
Conditioning against design parameters, and the CASSI-VSI beam splitter
=======================================================================

Every ADMM x-step of the library inverts ``μI + A Aᵀ``; how far apart the
extreme eigenvalues of ``A Aᵀ`` lie (its condition number κ on the measured
range) says how much a design amplifies noise there.
:func:`tensor_cosdi.studies.conditioning_design` sweeps one design parameter
of any imager and computes κ exactly from the structure the library derives
(diagonal, per-pixel ``K × K`` blocks, banded rows).  Here: the CASSI-VSI
splitting ratio ``αT`` and grayscale offset ``β``, SD-CASSI snapshots ``K``
and CASSDI-DFA depth planes.

:func:`tensor_cosdi.studies.vsi_arms` is the thesis' beam-splitter study
(Sec. 3.3.1, Fig. 19-20) on a real scene: κ of the cube's sensing ``H``
falls with ``αT`` while κ of the panchromatic image's sensing ``H Dᵀ``
rises (they cross near 0.75 in the thesis), the two arms' SNRs cross and
their mean peaks (thesis: ≈ 0.6), and the arms' dynamic ranges balance
(thesis: ≈ 0.7).
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from tensor_cosdi import datasets, studies

alphas = np.round(np.arange(0.1, 1.0, 0.1), 2)
vsi = studies.conditioning_design("cassi_vsi", "alpha_t", alphas)
beta = studies.conditioning_design("cassi_vsi", "beta", [0, 2, 4, 7])
shots = studies.conditioning_design("sd_cassi", "shots", [1, 2, 3, 4])
planes = studies.conditioning_design("cassdi_dfa", "n_depths", [1, 2, 3, 4, 6])
for name, recs in (("αT", vsi), ("β", beta), ("K", shots), ("DFA planes", planes)):
    key = {"αT": "alpha_t", "β": "beta", "K": "shots", "DFA planes": "n_depths"}[name]
    print(name + ": " + ", ".join(f"{r[key]}: κ {r['cond_nonzero']:.1f}" for r in recs))

# %%
# The beam-splitter study on a real CAVE scene (a photo-derived one without the research data).
scene, why = datasets.scene_or("cave.face", "chelsea")
if why:
    print(why)
arms = studies.vsi_arms((scene,), np.round(np.arange(0.0, 1.01, 0.1), 2), shape=(64, 64))
a = np.array([r["alpha_t"] for r in arms])
best_snr = a[int(np.nanargmax([r["snr_mean"] for r in arms]))]
best_range = a[int(np.nanargmin([r["range_error"] for r in arms]))]
print(f"mean arm SNR peaks at αT = {best_snr}; dynamic range balances at αT = {best_range}")
assert 0.5 <= best_snr <= 0.8 and 0.5 <= best_range <= 0.8

# %%
fig, axes = plt.subplots(1, 3, figsize=(11, 3))
axes[0].semilogy(alphas, [r["cond_nonzero"] for r in vsi], "o-", label="αT (CASSI-VSI)")
axes[0].semilogy([r["shots"] for r in shots], [r["cond_nonzero"] for r in shots], "s-",
                 label="K (SD-CASSI)")  # fmt: skip
axes[0].semilogy([r["n_depths"] for r in planes], [r["cond_nonzero"] for r in planes], "^-",
                 label="planes (CASSDI-DFA)")  # fmt: skip
axes[0].set_ylabel("κ(A Aᵀ) on its range")
axes[0].legend(fontsize=7)
inner = a[1:-1]  # αT = 0 and 1 switch an arm off
axes[1].semilogy(inner, [r["cond_H"] for r in arms[1:-1]], "o-", label="H")
axes[1].semilogy(inner, [r["cond_HDt"] for r in arms[1:-1]], "s-", label="H Dᵀ")
axes[1].set_xlabel("αT")
axes[1].legend(fontsize=7)
axes[2].plot(inner, [r["snr_t"] for r in arms[1:-1]], label="dispersed arm")
axes[2].plot(inner, [r["snr_r"] for r in arms[1:-1]], label="grayscale arm")
axes[2].plot(inner, [r["snr_mean"] for r in arms[1:-1]], "k", label="mean")
axes[2].set_xlabel("αT")
axes[2].set_ylabel("SNR dB (20 dB in all)")
axes[2].legend(fontsize=7)
fig.tight_layout()
plt.show()
