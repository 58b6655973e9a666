"""Capture files → float frames: read, dark/flat correction, region of interest, binning (issue: lab
adapter).

Readers by extension: ``.tif``/``.tiff`` (tifffile), ``.png``/``.jpg``/``.jpeg``/``.bmp``
(imageio), ``.npy``/``.npz`` (NumPy) and ``.mat`` (SciPy).  A frame is one 2-D
image; a colour PNG/JPEG is refused (a spectral imager's sensor is
monochrome) unless ``channel=`` picks one.  Every error names the file.
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import numpy as np

from ..validate import integer, real_array
from ._atomic import atomic_write_many

__all__ = [
    "read_frame",
    "write_frames",
    "load_frames",
    "bin_frame",
    "crop",
    "frame_paths",
    "FRAME_SUFFIXES",
]

FRAME_SUFFIXES = (".tif", ".tiff", ".png", ".jpg", ".jpeg", ".bmp", ".npy", ".npz", ".mat")


def _single_array(mapping: dict, path, key):
    if key is not None:
        if key not in mapping:
            raise ValueError(f"{path}: no array named {key!r}; it holds {sorted(mapping)}")
        return mapping[key]
    names = [k for k in mapping if not k.startswith("__")]
    if len(names) != 1:
        raise ValueError(
            f"{path}: holds {len(names)} arrays {sorted(names)}; pass key= to pick one"
        )
    return mapping[names[0]]


def _check_declared(p: Path, suffix: str, max_bytes: int) -> None:
    """Refuse a file whose header declares more than ``max_bytes`` before reading its data."""
    from ._readers import reason
    from .files import _check_size, array_entries

    try:
        if suffix in (".png", ".jpg", ".jpeg", ".bmp"):
            import imageio.v3 as iio

            props = iio.improps(p)
            entries = {"frame": (props.shape, props.dtype)}
        else:
            found = array_entries(p, ".tif" if suffix == ".tiff" else suffix, max_bytes)
            entries = {k: (v[0], v[1]) for k, v in found.items()}
    except (ValueError, KeyError):
        raise
    except Exception as e:  # corrupt headers raise many different errors in the readers
        raise ValueError(f"{p}: cannot read the file ({reason(e)})") from e
    for name, (shape, dtype) in entries.items():
        _check_size(p, name, shape, dtype, max_bytes)


def read_frame(
    path, *, key: str | None = None, channel: int | None = None, max_bytes: int | None = None
) -> np.ndarray:
    """Read one 2-D frame from ``path`` in its stored dtype.

    Parameters
    ----------
    path : str or Path
    key : str, optional
        Array name inside ``.npz`` / ``.mat`` files holding several arrays.
    channel : int, optional
        Channel of an RGB(A) image to use.
    max_bytes : int, optional
        Largest array the file may declare (default
        :data:`tensor_cosdi.io.files.MAX_ARRAY_BYTES`); checked from the
        header before anything is allocated.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        Unknown format, unreadable or truncated file, not a 2-D numeric
        image, not a regular file (a folder, FIFO or device: never opened) —
        the message names the file.
    """
    from ._readers import reason, require_file
    from .files import MAX_ARRAY_BYTES

    max_bytes = MAX_ARRAY_BYTES if max_bytes is None else integer("max_bytes", max_bytes, low=1)
    if channel is not None:
        channel = integer("channel", channel, low=0, high=3)
    if key is not None and not isinstance(key, str):
        raise ValueError(f"key must be the name of an array (a string), got {key!r}")
    p = Path(path)
    require_file(p, "frame file")
    suffix = p.suffix.lower()
    if suffix not in FRAME_SUFFIXES:
        raise ValueError(
            f"{p}: unknown frame format {suffix!r}; readable: {', '.join(FRAME_SUFFIXES)}"
        )
    if key is not None and suffix not in (".npz", ".mat"):
        raise ValueError(f"{p}: key= names an array of an .npz or .mat file; a {suffix} frame "
                         f"holds one (got key={key!r})")  # fmt: skip
    _check_declared(p, suffix, max_bytes)
    try:
        if suffix in (".tif", ".tiff"):
            import tifffile

            a = tifffile.imread(p)
        elif suffix in (".png", ".jpg", ".jpeg", ".bmp"):
            import imageio.v3 as iio

            a = iio.imread(p)
        elif suffix == ".npy":
            a = np.load(p, allow_pickle=False)
        elif suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                a = {k: z[k] for k in z.files}
        else:
            import scipy.io

            a = scipy.io.loadmat(p)
    except Exception as e:  # truncated or corrupt files raise many different errors in the readers
        raise ValueError(f"{p}: cannot read the file ({reason(e)})") from e
    if isinstance(a, dict):
        a = _single_array(a, p, key)
    a = np.asarray(a)
    if (
        a.ndim == 3
        and a.shape[-1] in (3, 4)
        and suffix in (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
    ):
        if channel is None:
            raise ValueError(
                f"{p}: colour image {a.shape}; a frame must be monochrome — pass channel= to pick "
                f"one"
            )
        if channel >= a.shape[-1]:
            raise ValueError(f"{p}: channel {channel} of an image of {a.shape[-1]} channels")
        a = a[..., channel]
    elif channel is not None:
        raise ValueError(f"{p}: channel={channel} picks a colour channel; this frame is monochrome")
    if a.ndim != 2:
        raise ValueError(f"{p}: expected a 2-D frame, got an array of shape {a.shape}")
    if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
        raise ValueError(f"{p}: expected integer or float pixels, got dtype {a.dtype}")
    if np.issubdtype(a.dtype, np.floating) and not np.all(np.isfinite(a)):
        raise ValueError(f"{p}: the frame contains NaN or inf")
    return a


def crop(frame, roi):
    """``frame[r0:r1, c0:c1]`` for ``roi = (r0, r1, c0, c1)``; out-of-frame ROIs are errors, not
    clipped."""
    a = np.asarray(frame)
    try:
        r0, r1, c0, c1 = (integer("roi", v) for v in roi)  # 2.5 is no pixel index
    except (TypeError, ValueError):
        raise ValueError(f"roi must be (row0, row1, col0, col1) in pixels, got {roi!r}") from None
    h, w = a.shape[:2]
    if not (0 <= r0 < r1 <= h and 0 <= c0 < c1 <= w):
        raise ValueError(f"roi {(r0, r1, c0, c1)} does not lie inside the {h}×{w} frame")
    return a[r0:r1, c0:c1]


def bin_frame(frame, binning: int):
    """Sum ``binning × binning`` blocks (sensor binning: 6×6 for a 2×2-binned DMD, Section 3.4).

    The frame's size must be a multiple of ``binning`` (crop with ``roi``
    first): nothing is silently dropped.
    """
    a = real_array("frame", frame, finite=False)
    if isinstance(binning, bool) or not isinstance(binning, (int, np.integer)) or binning < 1:
        raise ValueError(f"binning must be a positive integer, got {binning!r}")
    if binning == 1:
        return a
    h, w = a.shape[:2]
    if h % binning or w % binning:
        raise ValueError(
            f"a {h}×{w} frame cannot be binned {binning}×{binning}: crop it to a multiple first "
            f"(roi=)"
        )
    return a.reshape(h // binning, binning, w // binning, binning, *a.shape[2:]).sum(axis=(1, 3))


def _natural_key(p: Path):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


def frame_paths(source, *, pattern: str = "*", exclude=()) -> list[Path]:
    """Frame files from a folder (natural sort order: ``f2`` before ``f10``) or a list of paths.

    A folder's frames must be one numbered sequence (``frame_000, frame_001,
    …``): a file outside it (another prefix, no number), two files with the
    same number, or a gap is an error listing them — a stray file must not
    shift the frame order silently.  ``exclude``: paths to ignore (the dark
    and flat frames kept beside the frames).  A folder of unnumbered files
    is taken in natural order.
    """
    if isinstance(source, (str, Path)) and Path(source).is_dir():
        folder = Path(source)
        skip = {Path(x).resolve() for x in exclude if x is not None and not hasattr(x, "shape")}
        paths = sorted(
            (
                p
                for p in folder.glob(pattern)
                if p.is_file() and p.suffix.lower() in FRAME_SUFFIXES and p.resolve() not in skip
            ),
            key=_natural_key,
        )
        if not paths:
            raise ValueError(
                f"{folder}: no frame files ({', '.join(FRAME_SUFFIXES)}) matching {pattern!r}"
            )
        numbered = {p: re.fullmatch(r"(.*?)(\d+)", p.stem) for p in paths}
        if any(numbered.values()):
            prefixes = Counter(m.group(1) for m in numbered.values() if m)
            main = prefixes.most_common(1)[0][0]
            stray = [p.name for p, m in numbered.items() if not m or m.group(1) != main]
            if stray:
                raise ValueError(
                    f"{folder}: files outside the {main}<number> frame sequence: {stray[:10]}"
                    + (f" and {len(stray) - 10} more" if len(stray) > 10 else "")
                    + "; move them, or pick the frames with pattern="
                )
            idx = {p: int(m.group(2)) for p, m in numbered.items()}
            counts = Counter(idx.values())
            dup = sorted(p.name for p, i in idx.items() if counts[i] > 1)
            if dup:
                raise ValueError(f"{folder}: several files share a frame number: {dup[:10]}")
            missing = sorted(set(range(min(counts), max(counts) + 1)) - set(counts))
            if missing:
                width = len(next(iter(numbered.values())).group(2))
                names = [f"{main}{i:0{width}d}" for i in missing[:10]]
                raise ValueError(
                    f"{folder}: frame sequence has gaps — missing {names}"
                    + (f" and {len(missing) - 10} more" if len(missing) > 10 else "")
                )
        return paths
    if isinstance(source, (str, Path)):
        return [Path(source)]
    paths = [Path(p) for p in source]
    if not paths:
        raise ValueError("no frame files given")
    return paths


def load_frames(
    paths_or_folder,
    *,
    dark=None,
    flat=None,
    roi=None,
    binning: int = 1,
    expected: int | None = None,
    key: str | None = None,
    pattern: str = "*",
) -> np.ndarray:
    """Load, correct and stack frames: ``(H, W, N)`` float64, in file order.

    ``F = (raw − dark) / gain`` with ``gain = (flat − dark) / mean(flat − dark)``
    (a flat of mean gain 1, so counts keep their scale), then the region of
    interest, then binning.

    Parameters
    ----------
    paths_or_folder : folder, file, or sequence of files
        A folder is read in natural order and checked for gaps in numbered
        names (:func:`frame_paths`).
    dark, flat : path or array, optional
        Dark frame (no light) and flat/white frame (uniform illumination).
    roi : (row0, row1, col0, col1), optional
    binning : int
    expected : int, optional
        Number of frames the acquisition should have produced.
    key, pattern
        Array name in ``.npz``/``.mat`` files; glob pattern inside a folder.

    Raises
    ------
    ValueError
        Frames of different shapes, a dark frame as bright as the signal,
        a flat with non-positive pixels after dark subtraction, missing
        frames — naming the file.
    """
    paths = frame_paths(paths_or_folder, pattern=pattern, exclude=(dark, flat))
    if expected is not None and len(paths) != expected:
        raise ValueError(f"expected {expected} frames, found {len(paths)} ({paths[0].parent})")

    def load(x, what):
        if x is None:
            return None, None
        if isinstance(x, (str, Path)):
            return read_frame(x, key=key).astype(np.float64), str(x)
        a = real_array(f"the {what} frame", x, finite=False)
        if a.ndim != 2 or not np.all(np.isfinite(a)):
            raise ValueError(f"{what} must be a finite 2-D frame, got shape {a.shape}")
        return a, what

    dark_a, dark_name = load(dark, "dark frame")
    flat_a, flat_name = load(flat, "flat frame")
    frames = []
    shape = None
    for p in paths:
        a = read_frame(p, key=key).astype(np.float64)
        if shape is None:
            shape = a.shape
        elif a.shape != shape:
            raise ValueError(f"{p}: frame shape {a.shape} differs from {shape} of {paths[0].name}")
        if dark_a is not None:
            if dark_a.shape != a.shape:
                raise ValueError(
                    f"dark frame {dark_name}: shape {dark_a.shape} does not match {p} {a.shape}"
                )
            if dark_a.mean() >= a.mean():
                raise ValueError(
                    f"{p}: its mean {a.mean():.4g} is not above the dark frame's "
                    f"{dark_a.mean():.4g} "
                    f"({dark_name}) — swapped files, or a frame without light?"
                )
            a = a - dark_a
        frames.append(a)
    if flat_a is not None:
        if flat_a.shape != shape:
            raise ValueError(
                f"flat frame {flat_name}: shape {flat_a.shape} does not match the frames' {shape}"
            )
        gain = flat_a - (dark_a if dark_a is not None else 0.0)
        if np.any(gain <= 0):
            bad = np.argwhere(gain <= 0)[0]
            raise ValueError(
                f"flat frame {flat_name}: {int((gain <= 0).sum())} pixel(s) ≤ the dark level "
                f"(first at row {bad[0]}, column {bad[1]}); cannot divide by it"
            )
        gain = gain / gain.mean()
        frames = [f / gain for f in frames]
    out = []
    for f in frames:
        if roi is not None:
            f = crop(f, roi)
        out.append(bin_frame(f, binning))
    return np.stack(out, axis=-1)


def write_frames(
    frames, folder, *, prefix: str = "frame_", suffix: str = ".tif", overwrite: bool = False
) -> list[Path]:
    """Write a ``(H, W, N)`` stack, or a list / tuple of ``(H, W)`` frames, as numbered files
    ``prefix000suffix …`` (the reverse of :func:`load_frames`).

    ``.tif`` keeps the array's dtype (float32/64, uint16 …) exactly; ``.npy``
    likewise; ``.png`` needs integer pixels.  Existing files are an error
    unless ``overwrite=True`` — checked for every file before any is written.
    Atomic as a set: every frame is written and fsynced under a temporary name
    before any is renamed into place.
    """
    if isinstance(frames, (list, tuple)):  # a sequence of frames, not an (N, H, W) array
        if not frames:
            raise ValueError("no frames given")
        shapes = {np.shape(f) for f in frames}
        if len(shapes) != 1 or len(next(iter(shapes))) != 2:
            raise ValueError(f"a list of frames must hold 2-D frames of one shape, got {shapes}")
        a = np.stack([np.asarray(f) for f in frames], axis=-1)
    else:
        a = np.asarray(frames)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"frames must be a (H, W, N) stack, got shape {a.shape}")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    width = max(3, len(str(a.shape[2] - 1)))
    paths = [folder / f"{prefix}{i:0{width}d}{suffix}" for i in range(a.shape[2])]
    clash = [p.name for p in paths if p.exists()]
    if clash and not overwrite:
        raise FileExistsError(
            f"{folder}: {clash[:5]} exist; pass overwrite=True (CLI: --force) to replace them"
        )
    if suffix.lower() in (".tif", ".tiff"):
        import tifffile

        def writer(i):
            return lambda tmp: tifffile.imwrite(tmp, a[..., i])
    elif suffix.lower() == ".npy":

        def writer(i):
            return lambda tmp: np.save(tmp, a[..., i])
    elif suffix.lower() == ".png":
        if not np.issubdtype(a.dtype, np.integer):
            raise ValueError(
                f"PNG frames need integer pixels (uint8/uint16), got {a.dtype}; use .tif for floats"
            )
        import imageio.v3 as iio

        def writer(i):
            return lambda tmp: iio.imwrite(tmp, a[..., i], extension=".png")
    else:
        raise ValueError(f"write_frames writes .tif, .npy or .png, not {suffix!r}")
    # all frames complete on disk before any existing one is replaced (a full disk mid-way
    # leaves the previous capture intact and no partial frame)
    return atomic_write_many([(p, writer(i)) for i, p in enumerate(paths)], overwrite=overwrite)
