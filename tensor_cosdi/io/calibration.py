"""Calibration from captures (thesis Appendix A): measured code per band and the dispersion shifts.

Appendix A's protocol images the coded aperture through the system under a
monochromator, one wavelength per band: frame ``l`` is the code as band
``l`` sees it, displaced by that band's dispersion ``s_l``.  From such a
stack :func:`shifts_from_line_frames` measures ``s_l`` (sub-pixel phase
correlation against the first band) and :func:`code_from_monochromator`
undoes them to return the code per band and its mean — the calibrated code
of an :class:`~tensor_cosdi.systems.SDCASSI` with those shifts.  Line or
point targets (a slit, a pinhole) work the same way.

Without such frames, :func:`estimate_registration` finds how the mask sits
on the sensor from the capture itself: the measurement's fine texture is the
code's texture seen through the dispersion, so its correlation with the
sensing of a white scene ``A 1`` through a shifted mask peaks at the true
offset.  A shift by one band step ``s`` changes ``A 1`` only at the
measurement's ends, so the whole measurement is used, edges included.  The
same criterion decides the dispersion *direction* where the per-band shifts
are not evenly spaced (a prism's): the mirrored system then shears the code
into another texture.  With evenly spaced shifts it cannot, nor can any
criterion on the capture: the mirrored system measures the band-reversed
cube exactly as the other measures the cube.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..validate import number, real_array

__all__ = [
    "shifts_from_line_frames",
    "code_from_monochromator",
    "estimate_registration",
    "Registration",
    "shift_code",
    "mirror_symmetric",
]

#: ``estimate_registration``'s ``direction`` values.
DIRECTION_MODES = ("keep", "search")


def _stack(frames, what):
    a = real_array("frames", frames, finite=False)
    if a.ndim != 3 or a.shape[2] < 1:
        raise ValueError(
            f"{what} must be a (H, W, Nλ) stack, one frame per band, got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} contain NaN or inf")
    return a


def shifts_from_line_frames(frames, *, dark=None, upsample: int = 20, max_rows_shift: float = 0.5):
    """Per-band column shifts (px, first band 0) from calibration frames of one target under each
    band.

    Phase correlation (``skimage.registration.phase_cross_correlation``,
    ``1/upsample`` px precision) of every frame against the first.  The
    dispersion must run along the columns: a row shift above
    ``max_rows_shift`` px is an error (rotated prism or camera), as are
    shifts that are not non-decreasing (bands out of order).
    """
    from skimage.registration import phase_cross_correlation

    a = _stack(frames, "calibration frames")
    if dark is not None:
        a = a - real_array("dark", dark, finite=False)[..., None]
    ref = a[..., 0]
    out = np.zeros(a.shape[2])
    for l in range(1, a.shape[2]):
        shift, _, _ = phase_cross_correlation(ref, a[..., l], upsample_factor=upsample)
        # phase_cross_correlation returns the shift that registers a[..., l] onto ref: the negative
        # displacement
        dy, dx = -shift
        if abs(dy) > max_rows_shift:
            raise ValueError(
                f"band {l} is displaced {dy:.2f} px along the rows; dispersion must run along the "
                "columns (rotate the camera or the prism)"
            )
        out[l] = dx
    if np.any(np.diff(out) < -1.0 / upsample):
        bad = int(np.nonzero(np.diff(out) < -1.0 / upsample)[0][0]) + 1
        raise ValueError(
            f"measured shifts are not non-decreasing (band {bad}: {out[bad]:.2f} px after "
            f"{out[bad - 1]:.2f}); frames out of band order? shifts = {np.round(out, 2).tolist()}"
        )
    return np.maximum.accumulate(np.maximum(out, 0.0))


def code_from_monochromator(frames, *, shifts, ny: int | None = None, dark=None, open_frames=None):
    """The coded aperture per band and its mean, from monochromator frames and the per-band shifts.

    Parameters
    ----------
    frames : array (H, W, Nλ)
        Frame ``l``: the code seen through the system at band ``l`` (dark
        not yet subtracted unless ``dark`` is None).
    shifts : sequence of Nλ floats
        Column shift of each band (e.g. :func:`shifts_from_line_frames`).
    ny : int, optional
        Code width (default ``W − ⌈max shift⌉``).
    dark : array (H, W), optional
    open_frames : array (H, W, Nλ), optional
        The same captures with the aperture fully open (or a white
        reference): dividing by them turns counts into transmittance and
        removes the source spectrum and the sensor response.  Without them
        each band is divided by its 99th percentile.

    Returns
    -------
    code : ndarray (H, ny)
        The mean over bands — the code of an SDCASSI built with ``shifts``.
    per_band : ndarray (H, ny, Nλ)
        The code each band sees (for per-band models, e.g. CS2LI's 3-D code).
    """
    a = _stack(frames, "monochromator frames")
    s = real_array("shifts", shifts, finite=False).reshape(-1)
    if s.size != a.shape[2]:
        raise ValueError(f"{s.size} shifts for {a.shape[2]} frames: one shift per band")
    if dark is not None:
        d = real_array("dark", dark, finite=False)
        if d.shape != a.shape[:2]:
            raise ValueError(f"dark frame {d.shape} does not match the frames {a.shape[:2]}")
        a = a - d[..., None]
    if open_frames is not None:
        o = _stack(open_frames, "open frames")
        if o.shape != a.shape:
            raise ValueError(f"open frames {o.shape} do not match the frames {a.shape}")
        if dark is not None:
            o = o - d[..., None]
        if np.any(o <= 0):
            raise ValueError(
                "open (white) frames have pixels at or below the dark level; cannot normalise"
            )
        a = a / o
    else:
        scale = np.percentile(a, 99, axis=(0, 1))
        if np.any(scale <= 0):
            raise ValueError(
                "a band's frame is dark everywhere (99th percentile ≤ 0): wrong band or no light"
            )
        a = a / scale
    w = a.shape[1]
    ny = w - int(np.ceil(s.max())) if ny is None else int(ny)
    if ny < 1 or ny + np.ceil(s.max()) > w:
        raise ValueError(
            f"code width {ny} plus the largest shift {s.max():.2f} exceeds the frame width {w}"
        )
    per_band = np.empty((a.shape[0], ny, a.shape[2]))
    for l in range(a.shape[2]):
        back = ndimage.shift(a[..., l], (0.0, -s[l]), order=1, mode="constant")
        per_band[..., l] = back[:, :ny]
    return per_band.mean(axis=2), per_band


@dataclass(frozen=True)
class Registration:
    """Where the mask sits on the sensor, as :func:`estimate_registration` found it.

    Attributes
    ----------
    row_offset, col_offset : float
        Sub-pixel displacement of the code on the sensor relative to the mask
        file (rows down, columns towards the dispersion): the sensor sees
        ``mask`` shifted by ``(row_offset, col_offset)``.
    score : float
        Normalised correlation of the measurement's texture with the
        predicted one at the estimate (1: identical texture; about 0 for a
        measurement unrelated to the code).
    margin : float
        ``score`` minus the best score at an integer offset at least 1.5 px
        away.  The hardest competitor is one band step along the dispersion,
        which changes the predicted texture only at the measurement's ends,
        so margins are small even when the peak is right.
    grid : dict
        The score at every integer offset searched, ``{(row, col): score}``.
    direction : {1, -1}
        The dispersion relative to the system as filed: ``1`` as filed, ``-1``
        mirrored (:meth:`~tensor_cosdi.systems.SDCASSI.mirrored`).  Always
        ``1`` unless the direction was searched.
    direction_margin : float or None
        With a searched direction: the best score in that direction minus
        the best in the other (``None``: not searched).
    """

    row_offset: float
    col_offset: float
    score: float
    margin: float
    grid: dict = field(repr=False, default_factory=dict)
    direction: int = 1
    direction_margin: float | None = None

    #: ``reliable`` needs at least this score and this margin (and, with a searched direction,
    #: this direction margin).
    MIN_SCORE = 0.1
    MIN_MARGIN = 0.01
    MIN_DIRECTION_MARGIN = 0.01

    @property
    def reliable(self) -> bool:
        """Whether the peak stands out: ``score ≥ MIN_SCORE``, ``margin ≥ MIN_MARGIN`` and, when
        the direction was searched, ``direction_margin ≥ MIN_DIRECTION_MARGIN``."""
        ok = self.score >= self.MIN_SCORE and self.margin >= self.MIN_MARGIN
        if self.direction_margin is not None:
            ok = ok and self.direction_margin >= self.MIN_DIRECTION_MARGIN
        return ok

    def apply(self, system):
        """The system with its code moved by the estimated offsets (linear interpolation; the
        border row or column repeats where the shift uncovers one), its dispersion mirrored when
        ``direction`` is ``-1``."""
        code = np.asarray(system.code, dtype=np.float64)
        moved = system.with_code(shift_code(code, self.row_offset, self.col_offset))
        return moved.mirrored() if self.direction == -1 else moved


def shift_code(code: np.ndarray, rows: float, cols: float) -> np.ndarray:
    """``code`` moved by ``(rows, cols)`` pixels (linear interpolation, edges repeated)."""
    code = real_array("code", code)
    if code.ndim < 2:
        raise ValueError(f"code must have (rows, columns) axes, got shape {code.shape}")
    shift = (number("rows", rows), number("cols", cols)) + (0.0,) * (code.ndim - 2)
    return ndimage.shift(code, shift, order=1, mode="nearest")


def mirror_symmetric(shifts, tol: float = 0.05) -> bool:
    """Whether mirroring the dispersion (shifts ``s_l`` → ``max(s) − s_l``) gives the same set of
    shifts, within ``tol`` px: then the mirrored system measures the band-reversed cube exactly
    as the other measures the cube, and no capture can tell the directions apart (evenly
    spaced shifts are; a prism's are not).

    Parameters
    ----------
    shifts : sequence of float
        Per-band column shifts in pixels (``SDCASSI.shifts``).
    tol : float
        Pixels by which the two sorted shift sets may differ.

    Returns
    -------
    bool

    Examples
    --------
    >>> mirror_symmetric([0, 2, 4, 6]), mirror_symmetric([0, 2.4, 4.7, 6.8])
    (True, False)
    """
    try:
        s = real_array("shifts", shifts, finite=False).ravel()
    except (TypeError, ValueError):
        s = np.array([np.nan])
    if s.size == 0 or not np.all(np.isfinite(s)):
        raise ValueError(f"shifts must be finite numbers, got {shifts!r}")
    tol = number("tol", tol, low=0)
    return bool(np.allclose(np.sort(s.max() - s), np.sort(s), rtol=0.0, atol=tol))


def _texture(a: np.ndarray) -> np.ndarray:
    """The fine texture of a 2-D frame: the frame minus its Gaussian blur (σ 1 px)."""
    return a - ndimage.gaussian_filter(a, 1.0)


def _peak(positions, values, half_width: float = 0.5) -> float:
    """The vertex of a parabola fitted to the scores within ``half_width`` of the best one
    (the best position itself when the fit is not concave or leaves that window).  Along the
    dispersion the score is flat-topped and the argmax alone wanders; across it the peak is
    sharp and the argmax is kept (``benchmarks/registration.py`` measures both on tuning
    scenes)."""
    pos, val = (
        real_array("positions", positions, finite=False),
        real_array("values", values, finite=False),
    )
    best = float(pos[int(np.argmax(val))])
    near = np.abs(pos - best) <= half_width + 1e-9
    if near.sum() >= 3:
        a, b, _ = np.polyfit(pos[near] - best, val[near], 2)
        if a < 0 and abs(-b / (2 * a)) <= half_width:
            return round(best - b / (2 * a), 3)
    return best


def estimate_registration(
    system, measurement, *, max_offset: int = 3, direction: str = "keep"
) -> Registration:
    """Estimate the mask-to-sensor offset of a coded-aperture capture from the capture alone, and
    the dispersion direction where the shifts allow it.

    Parameters
    ----------
    system : SDCASSI
        The imager as calibrated (any system with ``code`` and ``with_code``,
        a single-shot 2-D code).
    measurement : array_like
        The capture, of the system's measurement shape.
    max_offset : int
        Integer offsets ``−max_offset … max_offset`` are searched in rows and
        columns, then refined to 0.05 px around the best.
    direction : {"keep", "search"}
        ``"keep"``: the dispersion runs as the system says.  ``"search"``:
        also try the mirrored dispersion and keep the better-scoring one
        (twice the time).  Only for shifts that are not mirror-symmetric
        (:func:`mirror_symmetric`; evenly spaced shifts are refused with the
        reason).

    Returns
    -------
    Registration
        The offsets, the score, the margin over the runner-up, whether that
        makes it ``reliable``, and the integer-offset grid;
        ``Registration.apply(system)`` gives the corrected system.

    Notes
    -----
    The criterion is the normalised correlation between the fine texture of
    the measurement and that of ``A' 1`` (a white scene seen through the
    code shifted by the candidate offset).  A data-fit residual hardly
    changes with the offset (a reconstruction absorbs the error); the
    texture correlation does.  The same score decides the dispersion
    direction when the per-band shifts are unevenly spaced (a prism
    disperses blue more than red): the mirrored system then shears the code
    into another texture (``benchmarks/results/registration_direction.md``).
    With evenly spaced shifts no criterion on the capture can: the mirrored
    system measures the band-reversed cube exactly as the other measures the
    cube (see :class:`~tensor_cosdi.systems.SDCASSI`'s ``shear_direction``);
    the direction then comes from the optics or a calibration frame
    (:func:`shifts_from_line_frames`).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi import codes, scenes, systems
    >>> from tensor_cosdi.io.calibration import estimate_registration, shift_code
    >>> mask = codes.random_binary((48, 48), rng=0)
    >>> true = systems.SDCASSI(shift_code(mask, 0.5, -1.0), n_bands=8, shifts=2)
    >>> g = true.simulate(scenes.colorchecker((48, 48), true.wavelengths), snr_db=30, rng=0)
    >>> reg = estimate_registration(systems.SDCASSI(mask, n_bands=8, shifts=2), g)
    >>> round(reg.row_offset, 1), round(reg.col_offset, 1)
    (0.5, -1.0)
    """
    if not callable(getattr(system, "with_code", None)):
        raise ValueError(
            f"estimate_registration needs an imager with a movable code (SDCASSI), got "
            f"{type(system).__name__}"
        )
    code = np.asarray(system.code, dtype=np.float64)
    if code.ndim != 2:
        raise ValueError(
            f"estimate_registration needs a single-shot 2-D code, got one of shape {code.shape}"
        )
    if isinstance(max_offset, bool) or not isinstance(max_offset, (int, np.integer)):
        raise ValueError(f"max_offset must be an integer number of pixels, got {max_offset!r}")
    if not 1 <= max_offset <= min(code.shape) // 4:
        raise ValueError(
            f"max_offset must be between 1 and a quarter of the code ({min(code.shape) // 4} "
            f"px), got {max_offset}"
        )
    g = np.asarray(measurement)
    if g.dtype.kind not in "biuf":
        raise ValueError(f"the measurement must be real numbers, got {g.dtype}")
    g = g.astype(np.float64)
    if g.shape != tuple(system.measurement_shape):
        raise ValueError(
            f"measurement of shape {g.shape}; the system measures {tuple(system.measurement_shape)}"
        )
    if not np.all(np.isfinite(g)):
        raise ValueError("the measurement holds NaN or infinite values")
    if not isinstance(direction, str) or direction not in DIRECTION_MODES:
        raise ValueError(f"direction must be one of {DIRECTION_MODES}, got {direction!r}")
    if direction == "search":
        if not callable(getattr(system, "mirrored", None)):
            raise ValueError(
                f"direction='search' needs an imager that can mirror its dispersion (SDCASSI), "
                f"got {type(system).__name__}"
            )
        if mirror_symmetric(system.shifts):
            raise ValueError(
                "direction='search' cannot decide with evenly spaced shifts (mirror-symmetric: "
                "the mirrored system measures the band-reversed cube exactly as this one "
                "measures the cube); take the direction from the optics or a calibration frame"
            )
    a = _texture(g)
    norm_a = float(np.linalg.norm(a))
    if norm_a == 0.0:
        raise ValueError("the measurement has no texture (a constant frame): nothing to register")
    a = a / norm_a
    found = _register(system, code, a, max_offset)
    if direction == "keep":
        return Registration(*found)
    other = _register(system.mirrored(), code, a, max_offset)
    if other[2] > found[2]:
        return Registration(*other, direction=-1, direction_margin=float(other[2] - found[2]))
    return Registration(*found, direction=1, direction_margin=float(found[2] - other[2]))


def _register(system, code, a, max_offset):
    """``(row, col, score, margin, grid)`` of the best code offset for the unit-norm texture
    ``a`` of a capture (see :func:`estimate_registration`)."""
    white = np.ones(system.cube_shape)
    cache: dict = {}

    def score(r: float, c: float) -> float:
        key = (round(r, 4), round(c, 4))
        if key not in cache:
            b = _texture(np.asarray(system.with_code(shift_code(code, r, c)).forward(white)))
            nb = float(np.linalg.norm(b))
            cache[key] = float(np.sum(a * b) / nb) if nb > 0 else -1.0
        return cache[key]

    span = range(-max_offset, max_offset + 1)
    grid = {(r, c): score(r, c) for r in span for c in span}
    r, c = max(grid, key=grid.get)
    x, y = float(r), float(c)
    fine = np.round(np.linspace(-1.0, 1.0, 41), 2)  # 0.05 px within a pixel of the best
    for _ in range(2):  # rows at the best column, then columns at the best row, twice
        x = float(max(r + fine, key=lambda v: score(v, y)))  # a sharp peak across the dispersion
        y = _peak(c + fine, [score(x, v) for v in c + fine])  # flat-topped along it
    best_score = score(x, y)
    far = [v for (gr, gc), v in grid.items() if max(abs(gr - x), abs(gc - y)) >= 1.5]
    margin = best_score - (max(far) if far else -1.0)
    return float(x), float(y), float(best_score), float(margin), grid
