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

import numbers

import numpy as np

from . import _backend as B
from . import validate

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


def _cube(cube, wavelengths=None, name: str = "cube"):
    c = validate.real_array(name, B.to_numpy(cube))
    if c.ndim != 3:
        raise ValueError(f"expected a {name} (rows, columns, bands), got shape {c.shape}")
    if c.size == 0:
        raise ValueError(f"the {name} is empty (shape {c.shape}): there is nothing to draw")
    if wavelengths is not None:
        return c, validate.increasing("wavelengths", wavelengths, size=c.shape[2])
    return c, None


def _target(kind: str, value):
    """``value`` when it is a matplotlib Axes (``kind="ax"``) or figure / sub-figure
    (``kind="fig"``); ``None`` passes (a new one is made)."""
    if value is None:
        return None
    from matplotlib.axes import Axes
    from matplotlib.figure import FigureBase

    want = Axes if kind == "ax" else FigureBase
    if not isinstance(value, want):
        what = "a matplotlib Axes" if kind == "ax" else "a matplotlib Figure or SubFigure"
        raise ValueError(f"{kind} must be {what} (or None for a new one), got {value!r}")
    return value


def white_point(cube, percentile: float = 99.5) -> float:
    """The ``percentile`` of the cube's band-mean image (``1.0`` when that is not positive)."""
    percentile = validate.number("percentile", percentile, low=0, high=100, low_open=True)
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
    if _target("ax", ax) is None:
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
    max_bands = validate.integer("max_bands", max_bands, low=1)
    idx = np.unique(np.linspace(0, c.shape[2] - 1, min(max_bands, c.shape[2])).round().astype(int))
    if columns is None:
        cols = int(np.ceil(np.sqrt(idx.size)))
    else:
        cols = validate.integer("columns", columns, low=1)
    rows = int(np.ceil(idx.size / cols))
    if _target("fig", fig) is None:
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
    ref = None if reference is None else _cube(reference, wavelengths, "reference")[0]
    if ref is not None and ref.shape != c.shape:
        raise ValueError(f"reference {ref.shape} does not match the cube {c.shape}")
    pts = _points(points, c.shape[:2])
    if _target("ax", ax) is None:
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


def _points(points, shape) -> list[tuple[int, int]]:
    """``points`` as a non-empty list of integer ``(row, column)`` pairs inside ``shape``."""
    want = f"a non-empty sequence of (row, column) pairs inside {tuple(shape)}"
    if isinstance(points, (str, bytes)) or not hasattr(points, "__iter__"):
        raise ValueError(f"points must be {want}, got {points!r}")
    pts = []
    for p in points:
        if isinstance(p, (str, bytes)) or not hasattr(p, "__len__") or len(p) != 2:
            raise ValueError(f"points must be {want}; point {p!r} is not a (row, column) pair")
        r = validate.integer("point row", p[0], low=0, high=shape[0] - 1)
        col = validate.integer("point column", p[1], low=0, high=shape[1] - 1)
        pts.append((r, col))
    if not pts:
        raise ValueError(f"points must be {want}, got none")
    return pts


def compare(truth, cubes: dict, wavelengths, *, percentile: float = 99.5, fig=None):
    """sRGB panels of the truth and each reconstruction (one exposure for all), and maps of the
    mean absolute error over bands; PSNR / SSIM (data range: the truth's maximum) in the titles.
    Returns the figure."""
    from collections.abc import Mapping

    from .colour import to_srgb
    from .metrics import psnr, ssim

    plt = _plt()
    t, wl = _cube(truth, wavelengths, "truth")
    if not isinstance(cubes, Mapping):
        kind = type(cubes).__name__
        raise ValueError(f"cubes must be a dict of name → reconstruction, got {kind}")
    if not cubes:
        raise ValueError("compare needs at least one reconstruction")
    est = {}
    for name, cube in cubes.items():
        c, _ = _cube(cube, wavelengths, f"reconstruction {name!r}")
        if c.shape != t.shape:
            raise ValueError(f"{name}: shape {c.shape} does not match the truth {t.shape}")
        est[name] = c
    n = len(est) + 1
    if _target("fig", fig) is None:
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
    d = validate.real_array("depth_map", B.to_numpy(depth_map), finite=False)
    if d.ndim == 3 and d.shape[2] == 1:
        d = d[:, :, 0]
    if d.ndim != 2 or d.size == 0:
        raise ValueError(
            f"depth_map must be a non-empty 2-D map (or one channel), got shape {d.shape}"
        )
    import matplotlib

    if not isinstance(cmap, str) or cmap not in matplotlib.colormaps:
        raise ValueError(f"cmap must be a matplotlib colour map name such as 'viridis', "
                         f"got {cmap!r}")  # fmt: skip
    if _target("ax", ax) is None:
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
    res = _trace("history['residual']", hist["residual"])
    change = None if "change" not in hist else _trace("history['change']", hist["change"])
    if change is not None and change.size != res.size:
        raise ValueError(
            f"history['change'] has {change.size} entries for {res.size} residuals; "
            "expected one per iteration"
        )
    if _target("ax", ax) is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    it = np.arange(1, res.size + 1)
    ax.semilogy(it, res, label="relative residual ‖Ax − g‖/‖g‖")
    if change is not None:
        ax.semilogy(it, np.maximum(change, 1e-16), label="relative change")
    ax.set_xlabel("iteration")
    ax.legend(fontsize=7)
    ax.set_title(getattr(result, "method", "") or "convergence", fontsize=9)
    return ax


def _trace(name: str, values) -> np.ndarray:
    """A per-iteration trace: a non-empty 1-D array of numbers ≥ 0 (NaN and inf are kept, a
    diverged run is drawn as it went)."""
    v = validate.real_array(name, values, finite=False)
    if v.ndim != 1 or v.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence, got shape {v.shape}")
    if (v < 0).any():
        raise ValueError(f"{name} must be ≥ 0 (a relative norm), got {v[v < 0][0]:g}")
    return v


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
    logy = validate.flag("logy", logy)
    plt = _plt()
    if isinstance(records, (str, bytes, dict)) or not hasattr(records, "__iter__"):
        raise ValueError(f"records must be a sequence of dicts, got {type(records).__name__}")
    recs = list(records)
    if not recs:
        raise ValueError("study needs at least one record")
    for i, r in enumerate(recs):
        if not isinstance(r, dict):
            raise ValueError(f"record {i} must be a dict, got {type(r).__name__}")
    for key in (x, y) + (() if by is None else (by,)):
        missing = [i for i, r in enumerate(recs) if key not in r]
        if missing:
            raise ValueError(f"record {missing[0]} has no {key!r}; it has {sorted(recs[0])}")
    for i, r in enumerate(recs):
        v = r[y]
        real = isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
        if not real or (logy and not v > 0):
            want = "a number > 0 (logy)" if logy else "a number"
            raise ValueError(f"record {i}: {y!r} must be {want}, got {v!r}")
    if _target("ax", ax) is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    groups = {}
    for r in recs:
        groups.setdefault(None if by is None else r[by], {}).setdefault(r[x], []).append(r[y])
    for cells in groups.values():
        try:
            sorted(cells)
        except TypeError:
            kinds = sorted({type(v).__name__ for v in cells})
            raise ValueError(f"the {x!r} values cannot be ordered: they mix {kinds}") from None
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
