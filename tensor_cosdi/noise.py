"""Measurement noise at a given SNR (SPEC §9)."""

from __future__ import annotations

import numpy as np

from . import _backend as B

__all__ = ["add_noise", "snr_db"]


def snr_db(clean, noisy) -> float:
    """``10 log10(Σ g² / Σ (noisy − g)²)`` in dB (``inf`` when equal)."""
    g = np.asarray(B.to_numpy(clean), dtype=np.float64)
    e = np.asarray(B.to_numpy(noisy), dtype=np.float64) - g
    den = float(np.sum(e * e))
    return float("inf") if den == 0 else 10.0 * np.log10(float(np.sum(g * g)) / den)


def add_noise(measurement, snr_db: float | None, *, rng=None):
    """Add white Gaussian noise so that ``10 log10(Σ g² / Σ ε²) = snr_db`` in expectation.

    Parameters
    ----------
    measurement : tensor
        Noise-free measurement ``g``.
    snr_db : float or None
        Target SNR in dB; ``None`` returns ``measurement`` unchanged.
    rng : int or numpy.random.Generator, optional
        Seed or generator (the noise is drawn with NumPy, then moved to the
        tensor's backend, dtype and device).

    Examples
    --------
    >>> import numpy as np
    >>> g = np.ones((100, 100))
    >>> round(snr_db(g, add_noise(g, 20.0, rng=0)))
    20
    """
    if snr_db is None:
        return measurement
    if not np.isfinite(snr_db):
        raise ValueError(f"snr_db must be a finite number of dB or None, got {snr_db!r}")
    g = np.asarray(B.to_numpy(measurement), dtype=np.float64)
    power = float(np.mean(g * g))
    if power == 0.0:
        raise ValueError("cannot set an SNR on an all-zero measurement (signal power is 0)")
    sigma = np.sqrt(power / 10.0 ** (snr_db / 10.0))
    noise = B.default_rng(rng).standard_normal(g.shape) * sigma
    return measurement + B.tensor_like(noise, measurement)
