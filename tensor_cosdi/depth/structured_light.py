"""Depth from projected fringes: phase-shifting analysis, unwrapping, phase → height (SPEC §7, Eq.
19-25).

Conventions (those of :mod:`tensor_cosdi.optics.fringes`): frame ``k`` of a
``K``-step sequence is ``I_k = a + b·cos(Φ + 2πk/K)``; a frequency ``ν`` has
``ν`` periods across the projector, so on the reference plane
``Φ = 2πν·y/L ≥ 0``.  Wrapped phases are in ``(−π, π]``, absolute ones are
``Φ`` itself.
"""

from __future__ import annotations

import numpy as np

from ..validate import axis_index, number, real_array

__all__ = [
    "wrapped_phase",
    "fringe_modulation",
    "temporal_unwrap",
    "heterodyne_unwrap",
    "unwrap_gray_code",
    "decode_gray_code",
    "spatial_unwrap",
    "phase_to_height",
    "calibrate_phase_to_height",
    "wrap",
]


def _phase(name, value):
    """A phase map: real numbers, NaN allowed (an invalid pixel stays NaN), ±inf refused."""
    p = real_array(name, value, finite=False)
    n_inf = int(np.isinf(p).sum())
    if n_inf:
        raise ValueError(
            f"{name} holds {n_inf} infinite values; expected radians (NaN marks an invalid pixel)"
        )
    return p


def wrap(phase):
    """Wrap to ``(−π, π]`` (a NaN, an invalid pixel, stays NaN)."""
    p = _phase("phase", phase)
    w = np.mod(p + np.pi, 2 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def _frames(frames, axis, what="frames"):
    x = real_array("frames", frames, finite=False)
    if x.ndim < 1:
        raise ValueError(f"{what} must be an array with a step axis, got a scalar")
    x = np.moveaxis(x, axis_index("axis", axis, x.ndim), -1)
    if x.shape[-1] < 3:
        raise ValueError(f"phase shifting needs K ≥ 3 frames along axis {axis}, got {x.shape[-1]}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{what} contain NaN or inf")
    return x


def _sums(x):
    K = x.shape[-1]
    d = 2 * np.pi * np.arange(K) / K
    return x @ np.sin(d), x @ np.cos(d), K


def wrapped_phase(frames, *, axis: int = -1):
    """N-step least-squares phase (Equation 19) of ``K ≥ 3`` frames ``I_k = a + b·cos(φ + 2πk/K)``.

    ``φ = atan2(−Σ_k I_k sin(2πk/K), Σ_k I_k cos(2πk/K))`` in ``(−π, π]``
    — the sign makes it invert :func:`~tensor_cosdi.optics.phase_shift_patterns`
    exactly.

    Parameters
    ----------
    frames : array_like (…, K, …)
    axis : int
        The step axis ``k``.

    Returns
    -------
    ndarray, ``frames`` without ``axis``.

    Examples
    --------
    >>> import numpy as np
    >>> k = np.arange(4)
    >>> round(float(wrapped_phase(0.5 + 0.5 * np.cos(1.0 + 2 * np.pi * k / 4))), 12)
    1.0
    """
    s, c, _ = _sums(_frames(frames, axis))
    return wrap(np.arctan2(-s, c))


def fringe_modulation(frames, *, axis: int = -1):
    """Offset ``a``, amplitude ``b`` and confidence ``b / a`` per pixel of a ``K``-step sequence.

    ``a = mean_k I_k``, ``b = (2/K)·sqrt((Σ I_k sin)² + (Σ I_k cos)²)``.  A low
    ``b`` (shadow, dark or saturated surface) means an unreliable phase; mask
    pixels whose confidence is below e.g. 0.1.

    Returns
    -------
    offset, amplitude, confidence : ndarrays
    """
    x = _frames(frames, axis)
    s, c, K = _sums(x)
    a = x.mean(axis=-1)
    b = 2.0 / K * np.hypot(s, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        conf = np.where(a > 0, b / np.where(a > 0, a, 1), 0.0)
    return a, b, conf


def temporal_unwrap(wrapped, reference, ratio):
    """Unwrap ``wrapped`` with an absolute ``reference`` phase of a frequency ``ratio`` times lower.

    ``Φ = φ + 2π·round((ratio·Φ_ref − φ) / 2π)`` — the fringe order of Eq. 20/24
    (``ratio = ν_h / ν_l``).  Correct where ``|ratio·(Φ_ref error)| < π``.
    """
    w = _phase("wrapped", wrapped)
    r = _phase("reference", reference)
    if w.shape != r.shape:
        raise ValueError(
            f"wrapped phase {w.shape} and reference {r.shape} must have the same shape"
        )
    ratio = number("ratio", ratio, low=0, low_open=True)
    order = np.round((ratio * r - w) / (2 * np.pi))
    return w + 2 * np.pi * order


def heterodyne_unwrap(wrapped, frequencies):
    """Absolute phase of the highest frequency from wrapped phases at several frequencies
    (Equations 22-24).

    Multi-frequency temporal unwrapping.  Where the lowest frequency has at
    most one period across the field (``ν ≤ 1``) its phase is already
    absolute and the others are unwrapped up the chain (hierarchical).
    Otherwise the heterodyne principle is applied recursively: two phases
    ``ν_1 > ν_2`` beat into ``wrap(φ_1 − φ_2)`` of frequency ``ν_1 − ν_2``,
    until a beat has ``ν ≤ 1`` (e.g. 70/64/59 → 6/5 → 1).

    Parameters
    ----------
    wrapped : array_like (…, P)
        Wrapped phases (``(−π, π]``), one per frequency on the last axis.
    frequencies : sequence of P floats
        Periods across the field, all different.

    Returns
    -------
    ndarray (…)
        Absolute phase of the highest frequency.

    Raises
    ------
    ValueError
        If no chain reaches ``ν ≤ 1``: the absolute phase is then ambiguous
        (thesis ``ν = {14, 2}``: use :func:`spatial_unwrap` on the low
        frequency first, then :func:`temporal_unwrap`, or a Gray code).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.optics import projector_phase
    >>> Phi = projector_phase((1, 64), [8.0, 7.2])  # beat: 0.8 period
    >>> bool(np.allclose(heterodyne_unwrap(wrap(Phi), [8.0, 7.2]), Phi[..., 0]))
    True
    """
    w = _phase("wrapped", wrapped)
    f = real_array("frequencies", frequencies, finite=False).reshape(-1)
    if w.shape[-1:] != f.shape:
        raise ValueError(
            f"wrapped has {w.shape[-1] if w.ndim else 0} phases on its last axis but {f.size} "
            f"frequencies"
        )
    if not np.all(np.isfinite(f)) or np.any(f <= 0) or len(set(f.tolist())) != f.size:
        raise ValueError(f"frequencies must be distinct positive numbers, got {f.tolist()}")
    order = np.argsort(-f)
    return _absolute([w[..., i] for i in order], [float(f[i]) for i in order])


def _absolute(phases, freqs):
    """Absolute phase of freqs[0] (descending list)."""
    if freqs[-1] <= 1.0:
        # one period or less: already absolute.  Its values fill [0, 2πν) of the circle; the unused
        # 2π(1 − ν) is split on both sides so noise at the field's edges (Φ ≈ 0) does not wrap to
        # 2π.
        lo = -np.pi * (1.0 - freqs[-1])
        phi = np.mod(phases[-1] - lo, 2 * np.pi) + lo
        for i in range(len(freqs) - 2, -1, -1):
            phi = temporal_unwrap(phases[i], phi, freqs[i] / freqs[i + 1])
        return phi
    if len(freqs) == 1:
        raise ValueError(
            "cannot find the absolute phase: no frequency or heterodyne beat has ≤ 1 period "
            f"(lowest: {freqs[0]:g}); "
            "add a frequency, use a Gray code (unwrap_gray_code) or spatial_unwrap"
        )
    beats = [wrap(phases[i] - phases[i + 1]) for i in range(len(freqs) - 1)]
    bf = [freqs[i] - freqs[i + 1] for i in range(len(freqs) - 1)]
    if len(set(bf)) != len(bf):  # equal beats carry no new information: keep one
        keep = sorted({b: i for i, b in reversed(list(enumerate(bf)))}.values())
        beats, bf = [beats[i] for i in keep], [bf[i] for i in keep]
    order = np.argsort(-np.asarray(bf))
    top = _absolute([beats[i] for i in order], [bf[i] for i in order])
    return temporal_unwrap(phases[0], top, freqs[0] / bf[order[0]])


def decode_gray_code(frames, threshold=0.5, *, axis: int = -1):
    """Half-period labels ``h`` from captured Gray-code frames (most significant first along
    ``axis``).

    ``threshold`` is a number or a per-pixel map (e.g. the fringe offset
    ``a`` from :func:`fringe_modulation`, which adapts to reflectance).
    """
    from ..optics.fringes import gray_to_binary

    x = real_array("frames", frames, finite=False)
    if x.ndim < 1:
        raise ValueError("Gray-code frames must be an array with a bit axis, got a scalar")
    x = np.moveaxis(x, axis_index("axis", axis, x.ndim), -1)
    if not np.all(np.isfinite(x)):
        raise ValueError("Gray-code frames contain NaN or inf")
    if isinstance(threshold, (bool, np.bool_)):
        raise ValueError(f"threshold must be a number or a per-pixel map, got {threshold!r}")
    t = real_array("threshold", threshold, finite=False)
    if not np.all(np.isfinite(t)):
        raise ValueError("threshold must be finite (a number or a per-pixel map)")
    if t.ndim:
        if t.shape != x.shape[:-1]:
            raise ValueError(f"threshold map {t.shape} must match the frame shape {x.shape[:-1]}")
        t = t[..., None]
    return gray_to_binary((x > t).astype(np.int64))


def unwrap_gray_code(wrapped, labels):
    """Absolute phase from a wrapped phase and half-period Gray-code labels ``h = ⌊Φ/π⌋``.

    Where ``|φ| ≤ π/2`` (far from a wrap) the whole-period order
    ``⌈h/2⌉`` is used; near a wrap the period centred on it, ``⌊h/2⌋``
    — so a label that is off by one at a stripe edge never changes the
    result (see :func:`~tensor_cosdi.optics.gray_code_patterns`).
    """
    w = _phase("wrapped", wrapped)
    h = np.asarray(labels)
    if w.shape != h.shape:
        raise ValueError(f"wrapped phase {w.shape} and labels {h.shape} must have the same shape")
    if not np.issubdtype(h.dtype, np.integer):
        raise ValueError(f"labels must be integers (from decode_gray_code), got dtype {h.dtype}")
    if h.size and h.min() < 0:
        raise ValueError(f"labels count half periods from 0, got a label {int(h.min())}")
    near = w + 2 * np.pi * ((h + 1) // 2)
    centre = 2 * np.pi * (h // 2) + np.pi
    far = w + 2 * np.pi * np.round((centre - w) / (2 * np.pi))
    return np.where(np.abs(w) <= np.pi / 2, near, far)


def spatial_unwrap(wrapped, *, mask=None, reference=None):
    """Spatial unwrapping (scikit-image ``unwrap_phase``), the fallback when no temporal data exist.

    The result is defined up to ``2πm``; ``reference=(index, absolute_phase)``
    fixes ``m`` so that the pixel ``index`` gets the nearest value to
    ``absolute_phase``.  ``mask`` (True = invalid) excludes unreliable pixels
    (their output is NaN); so are NaN or infinite phase values.
    """
    from skimage.restoration import unwrap_phase

    w = real_array("wrapped", wrapped, finite=False)
    if w.ndim not in (1, 2, 3):
        raise ValueError(f"spatial_unwrap handles 1-D to 3-D phase maps, got shape {w.shape}")
    bad = ~np.isfinite(w)  # scikit-image's unwrapper never returns on NaN: mask them
    if mask is not None or bad.any():
        m = bad if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != w.shape:
            raise ValueError(f"mask {m.shape} must match the phase {w.shape}")
        m = m | bad
        if m.all():
            raise ValueError("spatial_unwrap: every pixel is masked or non-finite")
        out = unwrap_phase(np.ma.masked_array(np.where(bad, 0.0, w), m))
        out = np.ma.filled(out.astype(np.float64), np.nan)
    else:
        out = np.asarray(unwrap_phase(w), dtype=np.float64)
    if reference is not None:
        idx, value = reference
        out = out + 2 * np.pi * np.round(
            (float(value) - out[tuple(np.atleast_1d(idx))]) / (2 * np.pi)
        )
    return out


def phase_to_height(phase, reference_phase, *, phase_per_height: float):
    """Height from the absolute phase: ``h = (Φ − Φ_ref) / k`` (reference-plane calibration).

    ``Φ_ref`` is the absolute phase measured on the flat reference plane
    (height 0) with the same frequency; ``k = phase_per_height`` is the phase
    change per unit height, from :func:`calibrate_phase_to_height` with
    planes of known height.  The linear model holds when the height is small
    next to the camera/projector distance (the thesis' ~1 cm objects).
    """
    k = number("phase_per_height", phase_per_height)
    if k == 0:
        raise ValueError("phase_per_height must be a finite non-zero number, got 0")
    p = _phase("phase", phase)
    r = _phase("reference_phase", reference_phase)
    try:
        return (p - r) / k
    except ValueError:
        raise ValueError(
            f"phase {p.shape} and reference_phase {r.shape} do not broadcast"
        ) from None


def calibrate_phase_to_height(phases, reference_phase, heights, *, mask=None) -> float:
    """Least-squares phase-per-height ``k`` from absolute phases of planes at known ``heights``.

    ``phases`` (n, H, W) measured on ``n`` flat targets at ``heights`` (n,);
    fits ``Φ_i − Φ_ref = k·h_i`` over all (unmasked) pixels.
    """
    P = real_array("phases", phases, finite=False)
    h = real_array("heights", heights, finite=False).reshape(-1)
    if P.ndim < 2 or P.shape[0] != h.size:
        raise ValueError(
            f"phases must stack one map per height: got {P.shape} for {h.size} heights"
        )
    if not np.all(np.isfinite(h)):
        raise ValueError(f"calibration heights must be finite, got {h.tolist()}")
    if not np.any(h != 0):
        raise ValueError("at least one calibration height must be non-zero")
    d = P - real_array("reference_phase", reference_phase, finite=False)
    H = np.broadcast_to(h.reshape((-1,) + (1,) * (P.ndim - 1)), P.shape)
    if mask is not None:
        keep = ~np.broadcast_to(np.asarray(mask, dtype=bool), P.shape)
        d, H = d[keep], H[keep]
    if not np.all(np.isfinite(d)):
        raise ValueError(
            "phases or reference_phase hold NaN or inf where they are used; mask those pixels"
        )
    return float(np.sum(d * H) / np.sum(H * H))
