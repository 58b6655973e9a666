"""Measurement noise at a given SNR (SPEC §9)."""

from __future__ import annotations

import numbers

import numpy as np

from . import _backend as B
from .validate import number, real_array

__all__ = [
    "add_noise",
    "snr_db",
    "estimate_sigma",
    "frame_sigmas",
    "frame_rank_sigma",
    "frame_powers",
    "estimate_snr_db",
    "snr_db_from_sigma",
    "snr_schedule",
    "auto_weight",
]


def snr_db(clean, noisy) -> float:
    """``10 log10(Σ g² / Σ (noisy − g)²)`` in dB (``inf`` when equal)."""
    g = real_array("clean", B.to_numpy(clean), finite=False)
    n = real_array("noisy", B.to_numpy(noisy), finite=False)
    if g.shape != n.shape:
        raise ValueError(f"clean {g.shape} and noisy {n.shape} must have the same shape")
    if not (np.isfinite(g).all() and np.isfinite(n).all()):
        raise ValueError("snr_db: clean and noisy must hold finite values")
    e = n - g
    den = float(np.sum(e * e))
    return float("inf") if den == 0 else 10.0 * np.log10(float(np.sum(g * g)) / den)


def check_snr_db(snr_db) -> float:
    """``snr_db`` as a float, or a ``ValueError``: a finite real number of dB (negative is
    fine: noise stronger than the signal)."""
    if isinstance(snr_db, bool) or not isinstance(snr_db, numbers.Real) or not np.isfinite(snr_db):
        raise ValueError(f"snr_db must be a finite number of dB or None, got {snr_db!r}")
    return float(snr_db)


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
    snr_db = check_snr_db(snr_db)
    g = real_array("measurement", B.to_numpy(measurement), finite=False)
    if not np.isfinite(g).all():
        raise ValueError("the measurement holds NaN or inf; cannot set an SNR on it")
    power = float(np.mean(g * g))
    if power == 0.0:
        raise ValueError("cannot set an SNR on an all-zero measurement (signal power is 0)")
    lowest = 10.0 * np.log10(power) - 20.0 * np.log10(np.finfo(np.float64).max) + 40.0
    if snr_db < lowest:  # σ (times a normal draw) would overflow
        raise ValueError(
            f"snr_db {snr_db:g} dB asks for noise beyond the float range; expected ≥ "
            f"{lowest:.0f} dB"
        )
    sigma = float(np.sqrt(power) * 10.0 ** (-snr_db / 20.0))
    noise = B.default_rng(rng).standard_normal(g.shape) * sigma
    return measurement + B.tensor_like(noise, measurement)


def estimate_sigma(measurement) -> float:
    """Robust estimate of the white-noise standard deviation of a measurement.

    The median absolute deviation of the finest diagonal wavelet detail
    (``skimage.restoration.estimate_sigma``), averaged over the frames of a
    stack (axes after the first two).  Coded-aperture texture leaks into that
    subband too, so a noise-free CASSI measurement reads as ≈ 40-46 dB SNR,
    not infinity; at 30 and 20 dB the estimate was within 15 % of the true σ
    on real scenes (TSA mask).
    """
    from skimage.restoration import estimate_sigma as _mad_sigma

    frames = _frames(measurement, "estimate_sigma")
    return float(np.mean([_mad_sigma(frames[..., k]) for k in range(frames.shape[2])]))


def _frames(x, who: str) -> np.ndarray:
    """``x`` as float64 frames ``(rows, columns, K)`` (axes after the first two folded), checked:
    frames of at least 4×4 pixels, finite."""
    g = real_array(f"{who}: the input", B.to_numpy(x), finite=False)
    if g.ndim < 2 or min(g.shape[:2]) < 4:
        raise ValueError(f"{who} needs frames of at least 4×4 pixels, got shape {g.shape}")
    if not np.isfinite(g).all():
        raise ValueError(f"{who}: the input contains NaN or inf")
    return g.reshape(g.shape[:2] + (-1,))


def frame_sigmas(x, support=None) -> np.ndarray:
    """:func:`estimate_sigma` of each frame of a stack ``x`` (axes after the first two),
    each over the bounding box of its ``support`` (non-zero pixels of ``support``'s frame;
    default ``x``): a frame padded with columns no light reaches (the panchromatic frame of
    dual-camera CASSI, the views of Lytro-CASSI) is read where it holds data, without the
    step where the data ends.  Frames with no support, or a support under 4×4 pixels, read
    over the whole frame.  :func:`estimate_sigma` is the mean of such readings over the
    whole frames.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x = np.zeros((32, 40, 2)); x[:, :32, 1] = rng.normal(0, 0.1, (32, 32))
    >>> x[..., 0] = rng.normal(0, 0.1, (32, 40))
    >>> np.round(frame_sigmas(x), 2).tolist()
    [0.1, 0.1]
    """
    from skimage.restoration import estimate_sigma as _mad_sigma

    fx = _frames(x, "frame_sigmas")
    if support is None:
        fs = fx
    else:
        s = np.asarray(B.to_numpy(support))
        if s.shape != np.shape(x):
            raise ValueError(
                f"frame_sigmas: the support must have the input's shape {np.shape(x)}, "
                f"got {s.shape}"
            )
        fs = s.reshape(fx.shape)
    return np.asarray(
        [_mad_sigma(_in_box(fx[..., k], fs[..., k])) for k in range(fx.shape[2])], dtype=np.float64
    )


def _in_box(frame, support):
    """``frame`` cut to the bounding box of ``support``'s non-zero pixels (the whole frame when
    that box is under 4×4 pixels)."""
    nz = support != 0
    rows, cols = np.flatnonzero(nz.any(axis=1)), np.flatnonzero(nz.any(axis=0))
    if rows.size and rows[-1] - rows[0] >= 3 and cols[-1] - cols[0] >= 3:
        return frame[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    return frame


def frame_powers(x) -> np.ndarray:
    """The mean square of each frame of a stack ``x`` (axes after the first two), over the
    bounding box of its non-zero pixels as :func:`frame_sigmas` reads it: a frame padded with
    dark columns is measured where it holds data.

    Examples
    --------
    >>> x = np.zeros((8, 12, 2)); x[..., 0] = 2.0; x[:, :6, 1] = 1.0
    >>> frame_powers(x).tolist()
    [4.0, 1.0]
    """
    fx = _frames(x, "frame_powers")
    return np.asarray(
        [np.mean(np.square(_in_box(fx[..., k], fx[..., k]))) for k in range(fx.shape[2])],
        dtype=np.float64,
    )


def frame_rank_sigma(x) -> float:
    """The noise σ read from a stack of frames whose signal spans fewer dimensions than frames.

    Each pixel's values over the ``K`` frames (axes after the first two, folded) form one row
    of an ``n × K`` matrix.  Where the noiseless frames are combinations of fewer than ``K``
    images — CS2LI's phase steps are ``a + b cos(φ + 2πk/K)`` per pixel, three images for
    any ``K ≥ 4`` — the smallest singular value holds only noise, ``≈ σ √n`` for white noise
    of the same σ in every frame, whatever the code's texture; it is returned as
    ``s_min / √n``.  Where the frames span all ``K`` dimensions, signal adds to ``s_min`` and
    the noise reads high (never low, so an estimate may take the larger SNR of this and
    another reading).  Frames of different noise levels read as the cleanest one's, so a
    system declares whether this reading holds for it
    (:attr:`tensor_cosdi.systems.System.snr_frames_low_rank`).

    Parameters
    ----------
    x : tensor of shape ``(rows, columns, ...)``
        At least 2 frames of at least 4×4 pixels, with more than 4 times as many pixels
        a frame as frames.

    Returns
    -------
    float
        ``s_min / √n`` (0.0 for frames that are exactly low-rank).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.random((2, 64, 64, 1))
    >>> steps = np.cos(2 * np.pi * np.arange(4) / 4)
    >>> g = a * (1 + 0.5 * steps) + b + rng.normal(0, 0.01, (64, 64, 4))
    >>> round(frame_rank_sigma(g), 3)
    0.01
    """
    fx = _frames(x, "frame_rank_sigma")
    n, k = fx.shape[0] * fx.shape[1], fx.shape[2]
    if k < 2 or n <= 4 * k:
        raise ValueError(
            f"frame_rank_sigma needs at least 2 frames and more than 4 times as many pixels a "
            f"frame as frames, got {k} frame(s) of {n} pixels"
        )
    s = np.linalg.svd(fx.reshape(n, k), compute_uv=False)
    return float(s[-1] / np.sqrt(n))


def snr_db_from_sigma(power: float, sigma: float) -> float:
    """``10 log10(power / σ²)`` (``inf`` when ``σ = 0``); ``power`` finite and > 0, ``σ``
    finite and ≥ 0."""
    power = number("power", power, low=0, low_open=True)
    sigma = number("sigma", sigma, low=0)
    return float("inf") if sigma == 0 else float(10.0 * np.log10(power) - 20.0 * np.log10(sigma))


def estimate_snr_db(measurement) -> float:
    """``10 log10(mean g² / σ̂²)`` with :func:`estimate_sigma` (``inf`` when σ̂ = 0).

    From the measurement alone, so a code's fine texture reads as noise; with
    the system at hand, :func:`tensor_cosdi.solvers.snr.estimate_snr` also
    reads the residual of a fit through it.
    """
    g = real_array("measurement", B.to_numpy(measurement), finite=False)
    power = float(np.mean(g * g))
    if power == 0.0:
        raise ValueError("the measurement is all zero: there is no signal to reconstruct")
    return snr_db_from_sigma(power, estimate_sigma(g))


def snr_schedule(snr_db: float, anchors: dict) -> float:
    """A weight from ``anchors = {SNR dB: weight}``: log-linear between them, constant beyond.

    ``snr_schedule(35, {40: 0.3, 30: 1.0})`` is ``√(0.3 · 1.0)``; an
    infinite SNR takes the weight of the highest anchor.
    """
    if not isinstance(anchors, dict) or not anchors:
        raise ValueError(
            f"snr_schedule needs anchors {{SNR dB: weight}} with one entry or more, got {anchors!r}"
        )
    pts = sorted(
        (number("an anchor's SNR (dB)", k), number("an anchor's weight", v, low=0, low_open=True))
        for k, v in anchors.items()
    )
    if isinstance(snr_db, np.ndarray) and snr_db.ndim == 0:
        snr_db = snr_db[()]
    if isinstance(snr_db, (bool, np.bool_)) or not isinstance(snr_db, numbers.Real):
        raise ValueError(f"snr_db must be a number of dB (inf for noiseless), got {snr_db!r}")
    snr = float(snr_db)
    if np.isnan(snr):
        raise ValueError("snr_db is NaN")
    if snr <= pts[0][0]:
        return pts[0][1]
    if snr >= pts[-1][0]:
        return pts[-1][1]
    for (s0, w0), (s1, w1) in zip(pts, pts[1:]):
        if s0 <= snr <= s1:
            t = (snr - s0) / (s1 - s0)
            return float(w0 * (w1 / w0) ** t)
    raise AssertionError("unreachable")  # pragma: no cover


def auto_weight(
    measurement, *, at_30db: float, at_20db: float, floor: float | None = None
) -> float:
    """A regularisation weight that follows the measurement's estimated SNR.

    Log-linear through ``(30 dB, at_30db)`` and ``(20 dB, at_20db)``, never
    below ``floor`` (default ``at_30db``): noisier data get more
    regularisation; clean data keep the 30 dB value (on real scenes the best
    noise-free weight depends on the scene more than on the noise, so it is
    not extrapolated).
    """
    # weights beyond 1e100 would overflow once extrapolated to a noisy measurement
    at_30db = number("at_30db", at_30db, low=0, low_open=True, high=1e100)
    at_20db = number("at_20db", at_20db, low=0, low_open=True, high=1e100)
    floor = None if floor is None else number("floor", floor, low=0, low_open=True, high=1e100)
    snr = estimate_snr_db(measurement)
    lo = at_30db if floor is None else floor
    if not np.isfinite(snr):
        return float(lo)
    t = (30.0 - snr) / 10.0  # log-linear, in logs so that no ratio of weights overflows
    w = float(np.exp((1.0 - t) * np.log(at_30db) + t * np.log(at_20db)))
    return float(min(max(w, lo), 10 * at_20db))
