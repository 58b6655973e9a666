"""Listing and reading the arrays of a file without surprises: ``name → (shape, dtype, loader)``
per format (headers only, so sizes are checked before any allocation), and one clear error
for a file its format library cannot parse.  Used by :mod:`tensor_cosdi.io.files`."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

#: Largest array a reader allocates unless told otherwise (``max_bytes``): 4 GiB.
MAX_ARRAY_BYTES = 4 * 2**30
#: What a stored array may carry beyond its data (an ``.npy`` header, MATLAB tags and name).
HEADER_SLACK_BYTES = 1 << 16


class Refused(ValueError):
    """A file the readers parsed and refuse, with a message saying why (not a parse failure)."""


class UnsafeFile(Refused):
    """A file that would make a reader fetch data from elsewhere (another file, a device, a FIFO)
    or inflate beyond ``max_bytes``: refused before anything is read."""


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


def _entries_npy(path, max_bytes=MAX_ARRAY_BYTES):
    with open(path, "rb") as f:
        shape, dtype = _npy_header(f)
    return {"array": (shape, dtype, lambda: np.load(path, allow_pickle=False))}


def _entries_npz(path, max_bytes=MAX_ARRAY_BYTES):
    out = {}
    with np.load(path, allow_pickle=False) as z:
        names = list(z.files)
        for info in z.zip.infolist():  # the size it inflates to, before anything inflates
            if info.file_size > max_bytes + HEADER_SLACK_BYTES:
                raise UnsafeFile(
                    f"{path}: member {info.filename!r} inflates to {info.file_size} bytes, above "
                    f"the {max_bytes}-byte limit (pass max_bytes= to allow it)"
                )
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


def _check_mat_inflation(path, max_bytes):
    """Refuse a MATLAB v5 file with a compressed variable that inflates beyond ``max_bytes``:
    SciPy inflates a whole variable before it looks at its declared shape.  Streamed, so the
    check itself never holds more than a block."""
    limit = max_bytes + HEADER_SLACK_BYTES
    with open(path, "rb") as f:
        head = f.read(128)
        if len(head) < 128 or head[126:128] not in (b"IM", b"MI"):
            return  # not a version-5 file (version 4 has no compressed elements)
        order = "<" if head[126:128] == b"IM" else ">"
        while True:
            tag = f.read(8)
            if len(tag) < 8:
                return
            kind, nbytes = struct.unpack(order + "II", tag)
            if kind >> 16:  # a small data element: its data sits in the tag
                continue
            if kind != 15:  # miCOMPRESSED
                f.seek(nbytes + (-nbytes % 8), 1)
                continue
            inflater, total, left = zlib.decompressobj(), 0, nbytes
            while left > 0 and not inflater.eof:
                block = f.read(min(left, 1 << 16))
                if not block:
                    break
                left -= len(block)
                data = block
                while data and not inflater.eof:
                    total += len(inflater.decompress(data, 1 << 20))
                    data = inflater.unconsumed_tail
                    if total > limit:
                        raise UnsafeFile(
                            f"{path}: a compressed variable inflates to more than {max_bytes} "
                            "bytes, above the limit (pass max_bytes= to allow it)"
                        )
            f.seek(left, 1)


def _entries_mat(path, max_bytes=MAX_ARRAY_BYTES):
    if _is_v73(path):
        return _entries_h5(path, max_bytes, matlab=True)
    import scipy.io

    _check_mat_inflation(path, max_bytes)
    out = {}
    for name, shape, cls in scipy.io.whosmat(path):
        if cls == "sparse":
            raise Refused(
                f"{path}: {name!r} is a MATLAB sparse matrix; save it with full({name}) "
                "to read it as an array"
            )
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


def check_h5_dataset(path, name, ds, max_bytes=MAX_ARRAY_BYTES):
    """Refuse an HDF5 dataset whose data lives outside the file (external raw storage, a virtual
    dataset) or whose chunks inflate beyond ``max_bytes``; ``ds`` is an open ``h5py.Dataset``."""
    if ds.is_virtual:
        raise UnsafeFile(
            f"{path}: dataset {name!r} is a virtual dataset (its data comes from other files); "
            "only data stored in the file itself is read"
        )
    if ds.id.get_create_plist().get_external_count() > 0:
        raise UnsafeFile(
            f"{path}: dataset {name!r} keeps its data in external raw files; "
            "only data stored in the file itself is read"
        )
    if ds.chunks is not None:
        chunk = int(np.prod(ds.chunks, dtype=np.int64)) * ds.dtype.itemsize
        if chunk > max_bytes + HEADER_SLACK_BYTES:
            raise UnsafeFile(
                f"{path}: dataset {name!r} has {chunk}-byte chunks, above the {max_bytes}-byte "
                "limit (pass max_bytes= to allow it)"
            )


def hard_linked(f, name: str, path) -> None:
    """Refuse ``name`` in the open HDF5 file ``f`` unless every step of it is a hard link (a soft
    or external link can point into another file)."""
    h5py = _require_h5py()
    parts = [p for p in str(name).split("/") if p]
    node = f
    for i, part in enumerate(parts):
        link = node.get(part, getlink=True)
        if link is None:
            raise KeyError(f"{path}: no object {'/'.join(parts[: i + 1])!r}")
        if not isinstance(link, h5py.HardLink):
            raise UnsafeFile(
                f"{path}: {'/'.join(parts[: i + 1])!r} is a {type(link).__name__} (it can point "
                "into another file); only objects stored in the file itself are read"
            )
        node = node[part]


def _entries_h5(path, max_bytes=MAX_ARRAY_BYTES, *, matlab=False):
    h5py = _require_h5py()
    out = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                return
            if obj.dtype.kind not in "biuf":
                return
            check_h5_dataset(path, name, obj, max_bytes)
            if matlab and obj.attrs.get("MATLAB_class", b"") in (b"char", b"cell", b"struct"):
                return
            shape = tuple(reversed(obj.shape)) if matlab else tuple(obj.shape)

            def load(name=name):
                with h5py.File(path, "r") as g:
                    hard_linked(g, name, path)
                    check_h5_dataset(path, name, g[name], max_bytes)
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


def _entries_tiff(path, max_bytes=MAX_ARRAY_BYTES):
    import tifffile

    key = None
    with _TiffComplaints(), tifffile.TiffFile(path) as t:
        n_pages = len(t.pages)
        series = t.series[0]
        same = {(tuple(s.shape), s.dtype, len(s.pages)) for s in t.series}
        if len(t.series) > 1 and len(same) == 1 and series.ndim == 2 and len(series.pages) == 1:
            # one 2-D page per series (pages appended one by one): the pages are the stack
            shape, dtype = (len(t.series), *series.shape), series.dtype
            axes, key = "QYX", slice(None)
        elif len(t.series) != 1 or len(series.pages) != n_pages:
            shapes = ", ".join(str(tuple(s.shape)) for s in t.series)
            raise Refused(
                f"{path}: {n_pages} pages in {len(t.series)} image series of shapes {shapes}; "
                "expected one series (one page per band, all of one shape and type)"
            )
        else:
            shape, dtype, axes = tuple(series.shape), series.dtype, series.axes

    def load():
        with _TiffComplaints():
            return tifffile.imread(path) if key is None else tifffile.imread(path, key=key)

    load.axes = axes  # tifffile's axis codes: "YXS" is one RGB(A) page, "QYX"/"IYX" pages
    return {"array": (shape, dtype, load)}


_READERS = {
    ".npy": ("NumPy .npy", _entries_npy),
    ".npz": ("NumPy .npz", _entries_npz),
    ".mat": ("MATLAB", _entries_mat),
    ".h5": ("HDF5", _entries_h5),
    ".hdf5": ("HDF5", _entries_h5),
    ".nc": ("NetCDF-4 (HDF5)", _entries_h5),  # NetCDF-4 is HDF5: the same hardened reader
    ".tif": ("TIFF", _entries_tiff),
    ".tiff": ("TIFF", _entries_tiff),
}


def reason(exc: BaseException) -> str:
    """``"Kind: message"`` of a format library's exception for an error message — except that
    advice to unpickle (NumPy's ``allow_pickle``) is never passed on: pickled data can run code,
    and a reader refuses it."""
    text = str(exc)
    if "pickle" in text.lower():
        return "it holds pickled Python objects, which are never loaded (they can run code)"
    return f"{type(exc).__name__}: {text}"


def _unreadable(path, suffix, exc) -> ValueError:
    return ValueError(
        f"{path}: cannot read it as a {_READERS[suffix][0]} file — empty, truncated, corrupted "
        f"or another format ({reason(exc)})"
    )


def array_entries(path: Path, suffix: str, max_bytes: int = MAX_ARRAY_BYTES):
    """The arrays a file of type ``suffix`` holds, as ``{name: (shape, dtype, third)}`` (the
    third item is the format reader's own); any format library's failure becomes one clear
    error naming the file."""
    if not path.is_file():
        raise FileNotFoundError(f"file not found: {path}")
    try:
        return _READERS[suffix][1](path, max_bytes)
    except (ImportError, Refused):
        raise
    except Exception as exc:  # the format libraries raise a dozen kinds: one clear error
        raise _unreadable(path, suffix, exc) from exc


def _load(path, suffix, load):
    try:
        return load()
    except (ImportError, Refused):
        raise
    except Exception as exc:
        raise _unreadable(path, suffix, exc) from exc
