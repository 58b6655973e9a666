"""Listing and reading the arrays of a file without surprises: ``name → (shape, dtype, loader)``
per format (headers only, so sizes are checked before any allocation), and one clear error
for a file its format library cannot parse.  Used by :mod:`tensor_cosdi.io.files`."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _require_h5py():
    try:
        import h5py
    except ImportError:  # pragma: no cover - a core dependency
        raise ImportError("HDF5 and MATLAB v7.3 files need h5py: pip install h5py") from None
    return h5py


# ---- listing: name → (shape, dtype, loader) without reading the data -----------------------------
def _npy_header(f):
    version = np.lib.format.read_magic(f)
    read = (
        np.lib.format.read_array_header_1_0
        if version == (1, 0)
        else np.lib.format.read_array_header_2_0
    )
    shape, _, dtype = read(f)
    return shape, dtype


def _entries_npy(path):
    with open(path, "rb") as f:
        shape, dtype = _npy_header(f)
    return {"array": (shape, dtype, lambda: np.load(path, allow_pickle=False))}


def _entries_npz(path):
    out = {}
    with np.load(path, allow_pickle=False) as z:
        names = list(z.files)
    for name in names:
        with np.load(path, allow_pickle=False) as z, z.zip.open(name + ".npy") as f:
            shape, dtype = _npy_header(f)

        def load(name=name):
            with np.load(path, allow_pickle=False) as z:
                return z[name]

        out[name] = (shape, dtype, load)
    return out


def _is_v73(path) -> bool:
    with open(path, "rb") as f:
        head = f.read(128)
    return b"MATLAB 7.3" in head


def _entries_mat(path):
    if _is_v73(path):
        return _entries_h5(path, matlab=True)
    import scipy.io

    out = {}
    for name, shape, cls in scipy.io.whosmat(path):
        if cls in ("cell", "struct", "object", "function_handle", "opaque"):
            continue
        dtype = {
            "logical": np.bool_, "char": np.str_, "int8": np.int8, "uint8": np.uint8,
            "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
            "int64": np.int64, "uint64": np.uint64, "single": np.float32,
        }.get(cls, np.float64)  # fmt: skip
        if dtype is np.str_:
            continue

        def load(name=name):
            return np.asarray(scipy.io.loadmat(path, variable_names=[name])[name])

        out[name] = (tuple(shape), np.dtype(dtype), load)
    return out


def _entries_h5(path, *, matlab=False):
    h5py = _require_h5py()
    out = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                return
            if obj.dtype.kind not in "biuf":
                return
            if matlab and obj.attrs.get("MATLAB_class", b"") in (b"char", b"cell", b"struct"):
                return
            shape = tuple(reversed(obj.shape)) if matlab else tuple(obj.shape)

            def load(name=name):
                with h5py.File(path, "r") as g:
                    a = g[name][()]
                return np.ascontiguousarray(a.T) if matlab else a

            out[name] = (shape, obj.dtype, load)

        f.visititems(visit)
    return out


class _TiffComplaints:
    """tifffile logs (instead of raising) what it skips in a damaged file — a truncated page
    chain reads as fewer pages.  Inside this context an ERROR record of its logger is an error
    (its warnings, e.g. about odd vendor tags, are left alone)."""

    def __enter__(self):
        import logging

        self.records = []
        handler = logging.Handler(logging.ERROR)  # its warnings (odd vendor tags) are benign
        handler.emit = self.records.append
        self.logger, self.handler = logging.getLogger("tifffile"), handler
        self.logger.addHandler(handler)
        return self

    def __exit__(self, *exc):
        self.logger.removeHandler(self.handler)
        if exc[0] is None and self.records:
            raise ValueError(f"tifffile: {self.records[0].getMessage()}")


def _entries_tiff(path):
    import tifffile

    with _TiffComplaints(), tifffile.TiffFile(path) as t:
        series = t.series[0]
        shape, dtype = tuple(series.shape), series.dtype

    def load():
        with _TiffComplaints():
            return tifffile.imread(path)

    return {"array": (shape, dtype, load)}


_READERS = {
    ".npy": ("NumPy .npy", _entries_npy),
    ".npz": ("NumPy .npz", _entries_npz),
    ".mat": ("MATLAB", _entries_mat),
    ".h5": ("HDF5", _entries_h5),
    ".hdf5": ("HDF5", _entries_h5),
    ".tif": ("TIFF", _entries_tiff),
    ".tiff": ("TIFF", _entries_tiff),
}


def _unreadable(path, suffix, exc) -> ValueError:
    return ValueError(
        f"{path}: cannot read it as a {_READERS[suffix][0]} file — empty, truncated, corrupted "
        f"or another format ({type(exc).__name__}: {exc})"
    )


def _entries(path: Path, suffix: str):
    if not path.is_file():
        raise FileNotFoundError(f"file not found: {path}")
    try:
        return _READERS[suffix][1](path)
    except ImportError:
        raise
    except Exception as exc:  # the format libraries raise a dozen kinds: one clear error
        raise _unreadable(path, suffix, exc) from exc


def _load(path, suffix, load):
    try:
        return load()
    except ImportError:
        raise
    except Exception as exc:
        raise _unreadable(path, suffix, exc) from exc
