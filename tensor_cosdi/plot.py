"""Figures of cubes, spectra, comparisons, depth maps and convergence (matplotlib, ``.[plot]``).

matplotlib is imported when a function is called, not with this module.
Every function draws into the axes or figure it is given (or a new one) and
returns it, so figures compose and tests can read back what was drawn.

Exposure: reconstructions of dark scenes are far below reflectance 1, and a
plain sRGB conversion shows them black.  :func:`preview` divides the cube by
a white point, the ``percentile`` (default 99.5) of its band-mean image, so
the brightest ~0.5 % of pixels saturate and the rest is visible; the factor
is reported in the title when it is not 1.
"""

from __future__ import annotations

import numpy as np

from . import _backend as B

__all__ = [
    "preview", "bands", "spectra", "compare", "depth", "convergence", "study", "white_point",
]  # fmt: skip


def _plt():
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError(
            "plots need matplotlib: pip install 'tensor_cosdi[plot]' (or pip install matplotlib)"
        ) from None
    return plt


def _cube(cube, wavelengths=None):
    c = np.asarray(B.to_numpy(cube), dtype=np.float64)
    if c.ndim != 3:
        raise ValueError(f"expected a cube (rows, columns, bands), got shape {c.shape}")
    if wavelengths is not None:
        wl = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
        if wl.size != c.shape[2]:
            raise ValueError(f"{wl.size} wavelengths for a cube of {c.shape[2]} bands")
        return c, wl
    return c, None


def white_point(cube, percentile: float = 99.5) -> float:
    """The ``percentile`` of the cube's band-mean image (``1.0`` when that is not positive)."""
    if not 0 < percentile <= 100:
        raise ValueError(f"percentile must lie in (0, 100], got {percentile}")
    c, _ = _cube(cube)
    w = float(np.percentile(c.mean(axis=2), percentile))
    return w if np.isfinite(w) and w > 0 else 1.0


def preview(cube, wavelengths, *, ax=None, percentile: float | None = 99.5, title=None):
    """sRGB preview (:func:`tensor_cosdi.colour.to_srgb`) exposed to a :func:`white_point`.

    ``percentile=None`` shows the cube as reflectance (no exposure).  Returns the axes.
    """
    from .colour import to_srgb

    plt = _plt()
    c, wl = _cube(cube, wavelengths)
    white = 1.0 if percentile is None else white_point(c, percentile)
    if ax is None:
        _, ax = plt.subplots(figsize=(4, 4))
    ax.imshow(to_srgb(np.clip(c / white, 0, None), wl))
    label = title if title is not None else "sRGB preview"
    if white != 1.0:
        label += f" (÷{white:.3g})"
    ax.set_title(label, fontsize=9)
    ax.set_axis_off()
    return ax


def bands(cube, wavelengths, *, columns: int | None = None, max_bands: int = 32, fig=None):
    """A montage of the bands, each titled with its wavelength (nm), on one grey scale with a
    colour bar (0 to the cube's 99.5th percentile).  At most ``max_bands`` evenly spaced bands.
    Returns the figure."""
    plt = _plt()
    c, wl = _cube(cube, wavelengths)
    idx = np.unique(np.linspace(0, c.shape[2] - 1, min(max_bands, c.shape[2])).round().astype(int))
    cols = columns or int(np.ceil(np.sqrt(idx.size)))
    rows = int(np.ceil(idx.size / cols))
    if fig is None:
        fig = plt.figure(figsize=(1.6 * cols + 0.8, 1.6 * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    vmax = float(np.percentile(c, 99.5)) or 1.0
    im = None
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, i in zip(axes.ravel(), idx):
        im = ax.imshow(c[:, :, i], cmap="gray", vmin=0, vmax=vmax)
        ax.set_title(f"{wl[i]:.0f} nm", fontsize=8)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8, label="intensity")
    return fig


def spectra(cube, wavelengths, points, *, reference=None, ax=None):
    """Spectra at ``points`` (``(row, column)`` pairs), with ``reference`` (a cube, e.g. the
    truth) dashed in the same colour.  Returns the axes."""
    plt = _plt()
    c, wl = _cube(cube, wavelengths)
    ref = None if reference is None else _cube(reference, wavelengths)[0]
    if ref is not None and ref.shape != c.shape:
        raise ValueError(f"reference {ref.shape} does not match the cube {c.shape}")
    pts = [tuple(int(v) for v in p) for p in points]
    for p in pts:
        if len(p) != 2 or not (0 <= p[0] < c.shape[0] and 0 <= p[1] < c.shape[1]):
            raise ValueError(f"point {p} is not a (row, column) inside {c.shape[:2]}")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    for k, (r, col) in enumerate(pts):
        colour = f"C{k % 10}"
        ax.plot(wl, c[r, col], color=colour, label=f"({r}, {col})")
        if ref is not None:
            ax.plot(wl, ref[r, col], "--", color=colour, label=f"({r}, {col}) reference")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("intensity")
    ax.legend(fontsize=7)
    return ax


def compare(truth, cubes: dict, wavelengths, *, percentile: float = 99.5, fig=None):
    """sRGB panels of the truth and each reconstruction (one exposure for all), and maps of the
    mean absolute error over bands; PSNR / SSIM (data range: the truth's maximum) in the titles.
    Returns the figure."""
    from .colour import to_srgb
    from .metrics import psnr, ssim

    plt = _plt()
    t, wl = _cube(truth, wavelengths)
    if not cubes:
        raise ValueError("compare needs at least one reconstruction")
    est = {}
    for name, cube in cubes.items():
        c, _ = _cube(cube, wavelengths)
        if c.shape != t.shape:
            raise ValueError(f"{name}: shape {c.shape} does not match the truth {t.shape}")
        est[name] = c
    n = len(est) + 1
    if fig is None:
        fig = plt.figure(figsize=(2.6 * n, 5.4))
    axes = fig.subplots(2, n, squeeze=False)
    white = white_point(t, percentile)
    preview(t, wl, ax=axes[0, 0], percentile=None if white == 1.0 else percentile, title="truth")
    axes[1, 0].set_axis_off()
    rng = float(t.max()) or 1.0
    errs = {k: np.abs(c - t).mean(axis=2) for k, c in est.items()}
    vmax = max(float(np.percentile(e, 99)) for e in errs.values()) or 1.0
    for j, (name, c) in enumerate(est.items(), start=1):
        ax = axes[0, j]
        ax.imshow(to_srgb(np.clip(c / white, 0, None), wl))
        ax.set_title(
            f"{name}\n{psnr(t, c, data_range=rng):.2f} dB, SSIM {ssim(t, c, data_range=rng):.3f}",
            fontsize=8,
        )
        ax.set_axis_off()
        im = axes[1, j].imshow(errs[name], cmap="magma", vmin=0, vmax=vmax)
        axes[1, j].set_title(f"{name}: |error|", fontsize=8)
        axes[1, j].set_axis_off()
    fig.colorbar(im, ax=axes[1, 1:].tolist(), shrink=0.8, label="mean |error| over bands")
    return fig


def depth(depth_map, *, ax=None, label: str = "depth", cmap: str = "viridis"):
    """A depth (or phase, disparity, plane index) map with a labelled colour bar; NaN shown as
    blank.  Returns the axes."""
    plt = _plt()
    d = np.asarray(B.to_numpy(depth_map), dtype=np.float64)
    if d.ndim == 3 and d.shape[2] == 1:
        d = d[:, :, 0]
    if d.ndim != 2:
        raise ValueError(f"expected a 2-D map (or one channel), got shape {d.shape}")
    if ax is None:
        _, ax = plt.subplots(figsize=(4, 3.5))
    im = ax.imshow(np.ma.masked_invalid(d), cmap=cmap)
    ax.figure.colorbar(im, ax=ax, label=label)
    ax.set_title(label, fontsize=9)
    ax.set_axis_off()
    return ax


def convergence(result, *, ax=None):
    """Relative residual (log scale) and relative change per iteration of a
    :class:`~tensor_cosdi.solvers.Result` (or its history dict).  Returns the axes."""
    plt = _plt()
    hist = getattr(result, "history", result)
    if not isinstance(hist, dict) or "residual" not in hist:
        raise ValueError("expected a reconstruct() Result or its history dict")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    it = np.arange(1, len(hist["residual"]) + 1)
    ax.semilogy(it, hist["residual"], label="relative residual ‖Ax − g‖/‖g‖")
    if "change" in hist and len(hist["change"]) == it.size:
        ax.semilogy(it, np.maximum(hist["change"], 1e-16), label="relative change")
    ax.set_xlabel("iteration")
    ax.legend(fontsize=7)
    ax.set_title(getattr(result, "method", "") or "convergence", fontsize=9)
    return ax


def study(records, x: str, y: str, *, by: str | None = None, ax=None, logy: bool = False):
    """One line of ``y`` against ``x`` per value of ``by`` from a design study's records
    (:func:`tensor_cosdi.studies.sweep` and the studies built on it); records that share
    ``(by, x)`` (seeds, say) are averaged.  Returns the axes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> recs = [{"f": 1, "k": 0.5, "psnr": 28.0}, {"f": 2, "k": 0.5, "psnr": 30.0}]
    >>> ax = study(recs, "f", "psnr", by="k")
    >>> ax.get_lines()[0].get_ydata().tolist(), ax.get_legend().get_texts()[0].get_text()
    ([28.0, 30.0], 'k = 0.5')
    """
    plt = _plt()
    recs = list(records)
    if not recs:
        raise ValueError("study needs at least one record")
    for key in (x, y) + (() if by is None else (by,)):
        missing = [i for i, r in enumerate(recs) if key not in r]
        if missing:
            raise ValueError(f"record {missing[0]} has no {key!r}; it has {sorted(recs[0])}")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    groups = {}
    for r in recs:
        groups.setdefault(None if by is None else r[by], {}).setdefault(r[x], []).append(r[y])
    for value, cells in groups.items():
        xs = sorted(cells)
        ys = [float(np.mean(cells[v])) for v in xs]
        label = None if by is None else f"{by} = {value}"
        (ax.semilogy if logy else ax.plot)(xs, ys, "o-", label=label)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if by is not None:
        ax.legend(fontsize=7)
    return ax
