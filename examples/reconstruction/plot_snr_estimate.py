"""
How noisy is a measurement? The SNR estimate on every imager
============================================================

Every ``"auto"`` setting (OTD's sparsity weight, the learned path's last
denoiser level and iteration count, GAP's splitting) follows
:func:`tensor_cosdi.solvers.snr.estimate_snr`.  A coded aperture puts its
texture on the measurement at the finest scale, where a wavelet noise
estimate looks, so a reading from the measurement alone takes a clean,
coded measurement for a noisy one.  The estimate also reads the residual of
a fit through the system; CS2LI and Mu-CoSDI read their phase steps'
smallest singular value (four steps of one fringe are three images per
pixel); dual-camera and Lytro-CASSI are read camera by camera.

Each imager below sees the same scene (the ColorChecker, 64×64, 16 bands,
each system's seeded code) noiseless, at 30 dB and at 20 dB.  The verdict is
computed as in ``benchmarks/snr_estimate.py``: ``ok`` within 3 dB of a noisy
truth, above 32 dB for a noiseless one.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

import tensor_cosdi as tc
from tensor_cosdi.solvers.snr import estimate_snr

truths = {"noiseless": None, "30 dB": 30.0, "20 dB": 20.0}
readings = {}
for name in tc.studies.SYSTEMS:
    for label, snr in truths.items():
        p = tc.studies.make_problem(
            name, "colorchecker", shape=(64, 64), n_bands=16, snr_db=snr, rng=0
        )
        readings[name, label] = estimate_snr(p.system, p.measurement)
        e = readings[name, label]
        print(
            f"{name:18s} {label:9s} estimate {e.snr_db:6.1f} dB  (measurement only "
            f"{e.from_measurement_db:5.1f}, {e.fit} fit residual {e.from_residual_db:5.1f}, "
            f"frames' rank {e.from_frames_db:5.1f})"
        )


def verdict(snr, est):
    if snr is None:
        return "ok" if est > 32 else "reads noise"
    return "ok" if abs(est - snr) < 3 else f"off by {est - snr:+.1f} dB"


verdicts = {k: verdict(truths[k[1]], e.snr_db) for k, e in readings.items()}
print(f"{sum(v == 'ok' for v in verdicts.values())} of {len(verdicts)} estimates ok; others:")
for (name, label), v in verdicts.items():
    if v != "ok":
        print(f"  {name} {label}: {v}")

# %%
# The estimate (bars, capped at 50 dB for a noiseless measurement) against the truth (lines);
# the measurement-only reading (dots) is what a code's texture does to a plain noise estimate.
systems = list(tc.studies.SYSTEMS)
x = np.arange(len(systems))
fig, ax = plt.subplots(figsize=(8, 3))
for i, (label, snr) in enumerate(truths.items()):
    est = [min(readings[s, label].snr_db, 50.0) for s in systems]
    only = [min(readings[s, label].from_measurement_db, 50.0) for s in systems]
    bars = ax.bar(x + (i - 1) * 0.27, est, width=0.27, label=f"estimate, {label}")
    ax.plot(x + (i - 1) * 0.27, only, "k.", ms=4)
    if snr is not None:
        ax.axhline(snr, color=bars.patches[0].get_facecolor(), lw=0.8, ls="--")
ax.set_xticks(x, systems, rotation=30, ha="right", fontsize=7)
ax.set_ylabel("SNR dB")
ax.legend(fontsize=7, ncol=3)
fig.tight_layout()
