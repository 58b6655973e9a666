"""Calibration from captures (thesis Appendix A): measured code per band and the dispersion shifts.

Appendix A's protocol images the coded aperture through the system under a
monochromator, one wavelength per band: frame ``l`` is the code as band
``l`` sees it, displaced by that band's dispersion ``s_l``.  From such a
stack :func:`shifts_from_line_frames` measures ``s_l`` (sub-pixel phase
correlation against the first band) and :func:`code_from_monochromator`
undoes them to return the code per band and its mean — the calibrated code
of an :class:`~tensor_cosdi.systems.SDCASSI` with those shifts.  Line or
point targets (a slit, a pinhole) work the same way.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["shifts_from_line_frames", "code_from_monochromator"]


def _stack(frames, what):
    a = np.asarray(frames, dtype=np.float64)
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
        a = a - np.asarray(dark, dtype=np.float64)[..., None]
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
    s = np.asarray(shifts, dtype=np.float64).reshape(-1)
    if s.size != a.shape[2]:
        raise ValueError(f"{s.size} shifts for {a.shape[2]} frames: one shift per band")
    if dark is not None:
        d = np.asarray(dark, dtype=np.float64)
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
