"""Projected patterns for structured light: phase-shifted fringes and Gray codes (SPEC §7, Eq.
21/25/136).

Phase convention (the one :func:`tensor_cosdi.depth.wrapped_phase` inverts):
frame ``k`` of a ``K``-step sequence is ``I_k = a + b·cos(Φ + 2πk/K)``, with
``Φ`` the absolute projector phase seen at a pixel.  On the flat reference
plane ``Φ = 2πν·y/L`` (:func:`projector_phase`), ``ν`` periods across the
``L`` projector columns.  Several frequencies are stacked frequency-major:
pattern ``f·K + k`` — the order :func:`tensor_cosdi.systems.fringe_cube`
uses.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..validate import number, real_array

__all__ = [
    "projector_phase",
    "phase_shift_patterns",
    "gray_code_patterns",
    "gray_code_bits",
    "gray_to_binary",
]


#: The most Gray-code bits :func:`gray_code_patterns` and :func:`gray_to_binary` take: the
#: labels are int64.
MAX_GRAY_BITS = 62
#: The most phase steps :func:`phase_shift_patterns` makes (one full frame each).
MAX_STEPS = 1024


def _steps(n_steps):
    if (
        isinstance(n_steps, bool)
        or not isinstance(n_steps, numbers.Integral)
        or not 3 <= n_steps <= MAX_STEPS
    ):
        raise ValueError(
            f"n_steps must be an integer in 3…{MAX_STEPS} (phase shifting needs 3 steps), got "
            f"{n_steps!r}"
        )
    return int(n_steps)


def projector_phase(shape, frequencies, *, axis: int = 1) -> np.ndarray:
    """Absolute phase ``2πν·i/L`` of the reference plane along ``axis`` for each frequency.

    Parameters
    ----------
    shape : (H, W)
    frequencies : float or sequence of float
        Fringe periods across the pattern (thesis: ``ν = {14, 2}`` over
        ``L = 1388`` columns).
    axis : {0, 1}
        The direction the phase grows along (thesis Eq. 25 uses a diagonal;
        pass a phase of your own to :func:`phase_shift_patterns` for that).

    Returns
    -------
    ndarray (H, W, n_freq)

    Examples
    --------
    >>> projector_phase((1, 4), 1.0)[0, :, 0].round(4).tolist()
    [0.0, 1.5708, 3.1416, 4.7124]
    """
    try:
        dims = tuple(shape)
    except TypeError:
        dims = ()
    if len(dims) != 2 or not all(
        isinstance(s, numbers.Integral) and not isinstance(s, (bool, np.bool_)) and s >= 1
        for s in dims
    ):
        raise ValueError(f"shape must be (H, W) with positive integer sizes, got {shape!r}")
    if isinstance(axis, (bool, np.bool_)) or axis not in (0, 1):
        raise ValueError(f"axis must be 0 or 1, got {axis!r}")
    f = np.atleast_1d(real_array("frequencies", frequencies, finite=False))
    if f.ndim != 1 or not f.size or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError(f"frequencies must be positive numbers, got {frequencies!r}")
    h, w = (int(s) for s in shape)
    L = (h, w)[axis]
    ramp = 2 * np.pi * np.arange(L) / L
    ramp = ramp[:, None] if axis == 0 else ramp[None, :]
    return np.broadcast_to(ramp, (h, w))[..., None] * f


def phase_shift_patterns(
    phase, n_steps: int = 4, *, offset: float = 0.5, amplitude: float = 0.5
) -> np.ndarray:
    """``K``-step phase-shifted fringes ``a + b·cos(Φ + 2πk/K)`` for each phase map.

    Parameters
    ----------
    phase : array_like (H, W) or (H, W, n_freq)
        Absolute phase per pixel (e.g. :func:`projector_phase`, or a
        height-deformed phase as a camera sees it).
    n_steps : int ≥ 3
    offset, amplitude : float
        ``a`` and ``b`` with ``0 ≤ b ≤ a`` (Eq. 21: ``a = b = 1/2``).

    Returns
    -------
    ndarray (H, W, n_freq · K), frequency-major.

    Examples
    --------
    >>> phase_shift_patterns(np.zeros((1, 1)), 4)[0, 0].round(12).tolist()
    [1.0, 0.5, 0.0, 0.5]
    """
    K = _steps(n_steps)
    offset, amplitude = number("offset", offset), number("amplitude", amplitude)
    if not 0 <= amplitude <= offset:
        raise ValueError(
            f"need 0 ≤ amplitude ≤ offset (light is ≥ 0), got offset={offset!r}, "
            f"amplitude={amplitude!r}"
        )
    p = real_array("phase", phase, finite=False)
    if p.ndim == 2:
        p = p[..., None]
    if p.ndim != 3:
        raise ValueError(f"phase must have shape (H, W) or (H, W, n_freq), got {np.shape(phase)}")
    if not np.all(np.isfinite(p)):
        raise ValueError("phase contains NaN or inf")
    steps = 2 * np.pi * np.arange(K) / K
    out = offset + amplitude * np.cos(p[..., None] + steps)  # (H, W, F, K)
    return out.reshape(p.shape[0], p.shape[1], -1)


def gray_code_bits(n_periods: float) -> int:
    """Number of Gray-code patterns that label every half period of ``n_periods`` fringes."""
    n = number("n_periods", n_periods, low=0, low_open=True, high=2.0 ** (MAX_GRAY_BITS - 1))
    return max(1, int(np.ceil(np.log2(2 * n))))


def gray_code_patterns(
    phase, n_bits: int | None = None, *, n_periods: float | None = None
) -> np.ndarray:
    """Binary Gray-code frames that label each half fringe period: ``h = ⌊Φ/π⌋``.

    Real rigs pair phase shifting with Gray codes to find the fringe order.
    Labelling *half* periods makes the decoding robust
    (:func:`tensor_cosdi.depth.unwrap_gray_code`): away from a wrap of the
    phase the code's whole-period boundaries are used, near one the
    half-shifted ones, so code errors at stripe edges never change the order.

    Parameters
    ----------
    phase : array_like (H, W)
        Absolute phase ``Φ ≥ 0`` of the fringe frequency to unwrap (one
        frequency, e.g. ``projector_phase(...)[..., 0]``).
    n_bits : int, optional
        Patterns to use; default :func:`gray_code_bits` of ``n_periods``.
    n_periods : float, optional
        Fringe periods across the field (default ``max Φ / 2π``).

    Returns
    -------
    ndarray (H, W, n_bits) of 0.0 / 1.0, most significant bit first.

    Examples
    --------
    >>> from tensor_cosdi.optics import projector_phase
    >>> G = gray_code_patterns(projector_phase((1, 8), 2.0)[..., 0])
    >>> G.shape, G[0, :, 0].tolist()
    ((1, 8, 2), [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0])
    """
    p = real_array("phase", phase, finite=False)
    if p.ndim != 2:
        raise ValueError(f"phase must be one (H, W) map, got shape {p.shape}")
    if not np.all(np.isfinite(p)) or np.any(p < 0):
        raise ValueError("phase must be finite and ≥ 0 (an absolute projector phase)")
    h = np.floor(p / np.pi).astype(np.int64)
    if n_bits is None:
        n_bits = gray_code_bits(
            n_periods if n_periods is not None else max(p.max() / (2 * np.pi), 0.5)
        )
    if isinstance(n_bits, bool) or not isinstance(n_bits, numbers.Integral) or n_bits < 1:
        raise ValueError(f"n_bits must be a positive integer, got {n_bits!r}")
    if n_bits > MAX_GRAY_BITS:  # labels are int64: wider codes would shift past their bits
        raise ValueError(f"n_bits must be at most {MAX_GRAY_BITS}, got {n_bits}")
    if h.max() >= 2**n_bits:
        raise ValueError(
            f"{n_bits} Gray-code bits label {2**n_bits} half periods, the phase needs "
            f"{int(h.max()) + 1}"
        )
    g = h ^ (h >> 1)
    bits = [(g >> (n_bits - 1 - b)) & 1 for b in range(n_bits)]
    return np.stack(bits, axis=-1).astype(np.float64)


def gray_to_binary(bits) -> np.ndarray:
    """Integer labels from Gray-code bits ``(…, n_bits)`` (0/1, most significant first)."""
    b = np.asarray(bits)
    if b.ndim < 1 or b.shape[-1] < 1:
        raise ValueError("bits need a trailing axis of Gray-code bits")
    if not np.all((b == 0) | (b == 1)):
        raise ValueError("Gray-code bits must be 0 or 1 (threshold the frames first)")
    if b.shape[-1] > MAX_GRAY_BITS:
        raise ValueError(
            f"at most {MAX_GRAY_BITS} Gray-code bits (int64 labels), got {b.shape[-1]}"
        )
    b = b.astype(np.int64)
    out = b[..., 0].copy()
    acc = b[..., 0].copy()
    for i in range(1, b.shape[-1]):
        acc = acc ^ b[..., i]
        out = (out << 1) | acc
    return out
