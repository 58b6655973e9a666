"""Lenslet-grid calibration from a flat ("radiometry") frame, and cutting views (issue: lab
adapter).

Behind a microlens array every lenslet draws a bright disc on the sensor; on a
uniformly lit (flat) frame the disc centres form a lattice
``c(i, j) = offset + i·a + j·b`` with ``a = p (cos θ, sin θ)`` and
``b = p (−sin θ, cos θ)`` (row, column coordinates): pitch ``p`` in pixels
(not an integer: 100 µm lenslets over 6.5 µm pixels give 15.38 px), a small
rotation ``θ`` and an offset.

:func:`calibrate_lenslet_grid` estimates them in three steps: the lattice's
fundamental frequency from the 2-D FFT of the flat frame (coarse pitch and
rotation), sub-pixel centroids of every disc inside the frame, and a
least-squares fit of the lattice to those centroids.  ``residuals`` reports
how far each centroid lies from the fitted lattice.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..validate import integer, number, real_array

__all__ = ["LensletGrid", "calibrate_lenslet_grid"]


@dataclass(frozen=True)
class LensletGrid:
    """A fitted lenslet lattice.

    Attributes
    ----------
    pitch : float
        Lenslet pitch in pixels.
    offset : (float, float)
        (row, column) of the centre of lenslet ``(0, 0)``, the one nearest the
        frame centre.
    rotation : float
        Lattice rotation in radians (row axis towards column axis).
    shape : (int, int)
        Frame shape the grid was fitted on.
    centres : ndarray (n, 2)
        Measured disc centroids used in the fit.
    indices : ndarray (n, 2)
        Their lattice indices ``(i, j)``.
    residuals : ndarray (n,)
        Distance (px) of each centroid from its fitted lattice point.
    """

    pitch: float
    offset: tuple
    rotation: float
    shape: tuple
    centres: np.ndarray = field(repr=False)
    indices: np.ndarray = field(repr=False)
    residuals: np.ndarray = field(repr=False)

    def __post_init__(self):
        number("pitch", self.pitch, low=1, low_open=False)
        number("rotation", self.rotation)
        try:
            r, c = self.offset
            rows, cols = self.shape
        except (TypeError, ValueError):
            raise ValueError(
                f"offset and shape must be (row, column) pairs, got {self.offset!r}, {self.shape!r}"
            ) from None
        number("offset row", r), number("offset column", c)
        integer("shape rows", rows, low=1), integer("shape columns", cols, low=1)

    @property
    def basis(self) -> np.ndarray:
        """``[a, b]`` as rows: the lattice vectors in (row, column) pixels."""
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        return self.pitch * np.array([[c, s], [-s, c]])

    def centre(self, i, j) -> np.ndarray:
        """(row, column) of lenslet ``(i, j)`` (broadcasts)."""
        a, b = self.basis
        i = real_array("lenslet row i", i, finite=False)[..., None]
        j = real_array("lenslet column j", j, finite=False)[..., None]
        return np.asarray(self.offset) + i * a + j * b

    def lenslet_range(self, margin: float | None = None):
        """Index ranges ``(i0, i1), (j0, j1)`` of the lenslets fully inside the frame (``margin``
        px, default pitch/2)."""
        m = self.pitch / 2 if margin is None else margin
        h, w = self.shape
        ii = np.arange(-int(h / self.pitch) - 2, int(h / self.pitch) + 3)
        jj = np.arange(-int(w / self.pitch) - 2, int(w / self.pitch) + 3)
        I, J = np.meshgrid(ii, jj, indexing="ij")
        c = self.centre(I, J)
        inside = (
            (c[..., 0] >= m)
            & (c[..., 0] <= h - 1 - m)
            & (c[..., 1] >= m)
            & (c[..., 1] <= w - 1 - m)
        )
        rows = np.nonzero(inside.any(axis=1))[0]
        cols = np.nonzero(inside.any(axis=0))[0]
        if rows.size == 0 or cols.size == 0:
            raise ValueError("no lenslet lies fully inside the frame with this margin")
        r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        # shrink the index box, dropping the border row/column with most lenslets outside, until all
        # are inside
        while r1 > r0 and c1 > c0 and not inside[r0:r1, c0:c1].all():
            box = inside[r0:r1, c0:c1]
            losses = [(~box[0]).sum(), (~box[-1]).sum(), (~box[:, 0]).sum(), (~box[:, -1]).sum()]
            k = int(np.argmax(losses))
            if k == 0:
                r0 += 1
            elif k == 1:
                r1 -= 1
            elif k == 2:
                c0 += 1
            else:
                c1 -= 1
        if r1 <= r0 or c1 <= c0:
            raise ValueError("no rectangle of lenslets lies fully inside the frame")
        return (int(ii[r0]), int(ii[r1 - 1]) + 1), (int(jj[c0]), int(jj[c1 - 1]) + 1)

    def views(self, raw, n_views: int | None = None, *, order: int = 1) -> np.ndarray:
        """Cut a raw lenslet frame into sub-aperture views ``(U, V, Ni, Nj)``.

        View ``(u, v)`` samples every lenslet at ``centre + (u − U//2)·â + (v − V//2)·b̂``
        (unit lattice vectors, one pixel apart) by spline interpolation of
        ``order``; ``n_views`` (default ``floor(pitch)``, odd) views per axis.
        Lenslets whose disc is not fully inside the frame are left out.
        """
        x = real_array("raw", raw, finite=False)
        if x.shape != tuple(self.shape):
            raise ValueError(
                f"raw frame shape {x.shape} differs from the calibration frame's "
                f"{tuple(self.shape)}"
            )
        if not np.isfinite(x).all():
            raise ValueError("the raw frame holds NaN or infinite pixels")
        integer("order", order, low=0, high=5)  # scipy's spline orders
        if n_views is None:  # the most whole pixels a pitch holds, made odd
            n = int(np.floor(self.pitch))
            n -= 1 - n % 2
        else:
            n = integer("n_views", n_views, low=1)
            if n % 2 == 0:
                raise ValueError(f"n_views must be odd (a centre view), got {n}")
        if n < 1 or n > self.pitch + 1e-9:
            raise ValueError(
                f"n_views must be between 1 and the pitch ({self.pitch:.2f} px), got {n_views!r}"
            )
        (i0, i1), (j0, j1) = self.lenslet_range(margin=(n // 2) + 1)
        I, J = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1), indexing="ij")
        c = self.centre(I, J)
        ua, ub = self.basis / self.pitch
        out = np.empty((n, n) + I.shape)
        for u in range(n):
            for v in range(n):
                p = c + (u - n // 2) * ua + (v - n // 2) * ub
                out[u, v] = ndimage.map_coordinates(
                    x, [p[..., 0], p[..., 1]], order=order, mode="nearest"
                )
        return out

    def rectified(
        self, raw, n_views: int | None = None, *, layout: str = "interleaved", order: int = 1
    ) -> np.ndarray:
        """A raw lenslet frame resampled onto an integer grid: ``(Ni·U, Nj·V)`` for C3SLFI /
        Mu-CoSDI ``"lf"``.

        ``"interleaved"`` (Eq. 85): pixel ``(i·U + u, j·V + v)`` is view
        ``(u, v)`` of lenslet ``(i, j)``; ``"tiled"`` (Eq. 78): pixel
        ``(u·Ni + i, v·Nj + j)``.  Feed the result (one per snapshot) to
        :func:`~tensor_cosdi.io.frames_to_measurement` of a system with that
        ``raw_layout``.
        """
        v = self.views(raw, n_views, order=order)  # (U, V, Ni, Nj)
        U, V, Ni, Nj = v.shape
        if layout == "interleaved":
            return v.transpose(2, 0, 3, 1).reshape(Ni * U, Nj * V)
        if layout == "tiled":
            return v.transpose(0, 2, 1, 3).reshape(U * Ni, V * Nj)
        raise ValueError(f"layout must be 'interleaved' or 'tiled', got {layout!r}")


def _pitch_range(pitch_range) -> tuple[float, float]:
    """``(low, high)`` lenslet pitches in pixels with ``2 ≤ low < high``, or a ``ValueError``."""
    try:
        lo, hi = pitch_range
    except (TypeError, ValueError):
        raise ValueError(
            f"pitch_range must be (low, high) pitches in pixels, got {pitch_range!r}"
        ) from None
    lo = number("pitch_range's low end", lo, low=2)
    hi = number("pitch_range's high end", hi, low=2)
    if not lo < hi:
        raise ValueError(f"pitch_range must have low < high, got {pitch_range!r}")
    return lo, hi


def _coarse_lattice(img, pitch_range):
    """Pitch and rotation from the strongest FFT peak inside the expected frequency band."""
    h, w = img.shape
    win = np.outer(np.hanning(h), np.hanning(w))
    F = np.abs(np.fft.fftshift(np.fft.fft2((img - img.mean()) * win)))
    fy = np.fft.fftshift(np.fft.fftfreq(h))
    fx = np.fft.fftshift(np.fft.fftfreq(w))
    FY, FX = np.meshgrid(fy, fx, indexing="ij")
    rad = np.hypot(FY, FX)
    lo, hi = 1.0 / pitch_range[1], 1.0 / pitch_range[0]
    band = (
        (rad >= lo) & (rad <= hi) & (FX > 0) & (np.abs(FY) <= FX)
    )  # one of the two lattice directions
    if not band.any():
        raise ValueError(f"pitch_range {pitch_range} px has no frequencies on a {h}×{w} frame")
    k = np.argmax(np.where(band, F, -1))
    r, c = np.unravel_index(k, F.shape)

    # parabolic refinement along both axes
    def refine(v0, vm, vp):
        d = vm - 2 * v0 + vp
        return 0.5 * (vm - vp) / d if d < 0 else 0.0

    dy = refine(F[r, c], F[r - 1, c], F[r + 1, c]) if 0 < r < h - 1 else 0.0
    dx = refine(F[r, c], F[r, c - 1], F[r, c + 1]) if 0 < c < w - 1 else 0.0
    f_y = fy[r] + dy / h
    f_x = fx[c] + dx / w
    pitch = 1.0 / np.hypot(f_y, f_x)
    # the column-direction lattice vector b = p(−sin θ, cos θ) gives the wave vector (f_y, f_x) ∝
    # (−sin θ, cos θ)
    rotation = np.arctan2(-f_y, f_x)
    return pitch, rotation


def calibrate_lenslet_grid(
    white_frame, *, dark=None, pitch_range=(4.0, 64.0), min_peak: float = 0.2
) -> LensletGrid:
    """Fit the lenslet lattice (pitch, offset, rotation) to a flat/white ("radiometry") frame.

    Parameters
    ----------
    white_frame : array_like (H, W)
        Uniformly lit capture through the lenslet array.
    dark : array_like (H, W), optional
        Dark frame, subtracted first.
    pitch_range : (float, float)
        Pitches (px) to search.
    min_peak : float
        Discs dimmer than this fraction of the 90th-percentile disc are
        ignored (vignetted edges).

    Returns
    -------
    LensletGrid

    Examples
    --------
    >>> import numpy as np
    >>> yy, xx = np.mgrid[0:120, 0:120].astype(float)
    >>> p, th = 9.7, 0.01
    >>> u = np.cos(th) * yy + np.sin(th) * xx   # lattice coordinates of every pixel
    >>> v = -np.sin(th) * yy + np.cos(th) * xx
    >>> flat = np.cos(np.pi * (u - 3.2) / p) ** 2 * np.cos(np.pi * (v - 5.1) / p) ** 2
    >>> grid = calibrate_lenslet_grid(flat)
    >>> round(grid.pitch, 2), round(grid.rotation, 3)
    (9.7, 0.01)
    """
    img = real_array("white_frame", white_frame, finite=False)
    if img.ndim != 2:
        raise ValueError(f"white_frame must be a 2-D frame, got shape {img.shape}")
    pitch_range = _pitch_range(pitch_range)
    min_peak = number("min_peak", min_peak, low=0)
    if not np.all(np.isfinite(img)):
        raise ValueError("white_frame contains NaN or inf")
    if dark is not None:
        d = real_array("dark", dark, finite=False)
        if d.shape != img.shape:
            raise ValueError(
                f"dark frame shape {d.shape} differs from the white frame's {img.shape}"
            )
        if d.mean() >= img.mean():
            raise ValueError("the dark frame is as bright as the white frame: swapped files?")
        img = img - d
    pitch0, rot0 = _coarse_lattice(img, pitch_range)
    if not pitch_range[0] <= pitch0 <= pitch_range[1]:
        raise ValueError(f"no lenslet lattice found in pitch_range {pitch_range}")
    # disc centroids: local maxima of the smoothed frame, one per lenslet, refined by weighted
    # centroids
    smooth = ndimage.gaussian_filter(img, pitch0 / 6)
    size = max(3, int(round(pitch0 * 0.7)))
    peaks = (smooth == ndimage.maximum_filter(smooth, size=size)) & (smooth > 0)
    pr, pc = np.nonzero(peaks)
    if pr.size == 0:
        raise ValueError(
            "white_frame has no bright lenslet discs (no positive maxima): is it inverted, or a "
            "dark frame?"
        )
    vals = smooth[pr, pc]
    keep = vals >= min_peak * np.percentile(vals, 90)
    pr, pc = pr[keep], pc[keep]
    half = int(np.floor(pitch0 / 2))
    h, w = img.shape
    inside = (pr >= half) & (pr < h - half) & (pc >= half) & (pc < w - half)
    pr, pc = pr[inside], pc[inside]
    if pr.size < 4:
        raise ValueError(
            f"found only {pr.size} lenslet discs inside the frame; need ≥ 4 to fit a lattice"
        )
    yy, xx = np.mgrid[-half : half + 1, -half : half + 1]
    cent = np.empty((pr.size, 2))
    for n, (r, c) in enumerate(zip(pr, pc)):
        patch = img[r - half : r + half + 1, c - half : c + half + 1]
        wgt = np.clip(patch - patch.min(), 0, None)
        s = wgt.sum()
        cent[n] = (r + (wgt * yy).sum() / s, c + (wgt * xx).sum() / s) if s > 0 else (r, c)
    # lattice indices from the coarse lattice around the disc nearest the frame centre
    ref = cent[np.argmin(np.hypot(cent[:, 0] - h / 2, cent[:, 1] - w / 2))]
    cs, sn = np.cos(rot0), np.sin(rot0)
    basis0 = pitch0 * np.array([[cs, sn], [-sn, cs]])
    ij = np.rint(np.linalg.solve(basis0.T, (cent - ref).T).T)
    # least squares: cent = offset + i a + j b  (6 unknowns)
    A = np.column_stack([np.ones(len(ij)), ij[:, 0], ij[:, 1]])
    coef, *_ = np.linalg.lstsq(A, cent, rcond=None)
    offset, a, b = coef[0], coef[1], coef[2]
    pitch = float((np.linalg.norm(a) + np.linalg.norm(b)) / 2)
    rotation = float((np.arctan2(a[1], a[0]) + np.arctan2(-b[0], b[1])) / 2)
    grid = LensletGrid(
        pitch,
        (float(offset[0]), float(offset[1])),
        rotation,
        img.shape,
        cent,
        ij.astype(int),
        np.zeros(len(ij)),
    )
    res = np.hypot(*(cent - grid.centre(ij[:, 0], ij[:, 1])).T)
    return LensletGrid(pitch, grid.offset, rotation, img.shape, cent, ij.astype(int), res)
