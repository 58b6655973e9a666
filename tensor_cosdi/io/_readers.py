"""Listing and reading the arrays of a file without surprises: ``name → (shape, dtype, loader)``
per format (headers only, so sizes are checked before any allocation), and one clear error
for a file its format library cannot parse.  Used by :mod:`tensor_cosdi.io.files`."""

from __future__ import annotations

import json
import os
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


class Entries(dict):
    """``{name: (shape, dtype, load)}``: the numeric arrays a file holds.  ``skipped`` maps each
    other variable the listing met (text, a cell or struct, records, complex values, a soft or
    external link, which is never followed) to ``(what it is, the error class refusing it)``, so
    that an error can say what a name holds instead of that it is missing."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.skipped: dict[str, tuple[str, type]] = {}


def _matlab_text(cls: str) -> str:
    return "MATLAB text (char)" if cls == "char" else f"a MATLAB {cls}"


def _dtype_text(dtype) -> str:
    """What a non-numeric dtype holds, in words (``"text of dtype |S3"``)."""
    dtype = np.dtype(dtype)
    if dtype.fields is not None:
        return "compound records"
    kind = {"S": "text", "U": "text", "O": "objects", "c": "complex values"}
    return f"{kind.get(dtype.kind, 'values')} of dtype {dtype.str}"


def require_file(path, what: str = "file") -> None:
    """Return if ``path`` is a regular file (or a link to one); else ``FileNotFoundError`` when
    nothing is there, :class:`UnsafeFile` when something else is (a folder, a FIFO, a device,
    a dangling link) — never opened."""
    if path.is_file():
        return
    if os.path.lexists(path):
        raise UnsafeFile(
            f"{path}: not a regular file (a folder, FIFO, device or dangling link); only "
            "regular files are read"
        )
    raise FileNotFoundError(f"{what} not found: {path}")


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
    out = Entries()
    for name, shape, cls in scipy.io.whosmat(path):
        if cls == "sparse":
            raise Refused(
                f"{path}: {name!r} is a MATLAB sparse matrix; save it with full({name}) "
                "to read it as an array"
            )
        if cls in ("cell", "struct", "object", "function_handle", "opaque", "char"):
            out.skipped[name] = (_matlab_text(cls), Refused)
            continue
        dtype = {
            "logical": np.bool_, "int8": np.int8, "uint8": np.uint8,
            "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
            "int64": np.int64, "uint64": np.uint64, "single": np.float32,
        }.get(cls, np.float64)  # fmt: skip

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
    out = Entries()
    with h5py.File(path, "r") as f:

        def link(name, obj):  # visits links without following them (h5py ≥ 3.11)
            if isinstance(obj, h5py.HardLink) or name.startswith("#"):
                return
            if isinstance(obj, h5py.SoftLink):  # an alias: name what it stands for
                target = str(obj.path).lstrip("/")
                hint = f"; pass key={target!r}" if target in out else ""  # datasets come first
                why = f"a soft link to {target!r} (links are not followed{hint})"
                out.skipped[name] = (why, Refused)
            elif isinstance(obj, h5py.ExternalLink):
                out.skipped[name] = ("an external link, which points into another file", UnsafeFile)
            else:  # a link class of the HDF5 library's own that h5py cannot resolve
                out.skipped[name] = (f"a link ({type(obj).__name__}), never followed", UnsafeFile)

        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                return
            cls = obj.attrs.get("MATLAB_class", b"") if matlab else b""
            if matlab and cls in (b"char", b"cell", b"struct"):
                out.skipped[name] = (_matlab_text(cls.decode()), Refused)
                return
            if obj.dtype.kind not in "biuf":
                out.skipped[name] = (_dtype_text(obj.dtype), Refused)
                return
            check_h5_dataset(path, name, obj, max_bytes)
            shape = tuple(reversed(obj.shape)) if matlab else tuple(obj.shape)

            def load(name=name):
                with h5py.File(path, "r") as g:
                    hard_linked(g, name, path)
                    check_h5_dataset(path, name, g[name], max_bytes)
                    a = g[name][()]
                return np.ascontiguousarray(a.T) if matlab else a

            out[name] = (shape, obj.dtype, load)

        f.visititems(visit)
        if hasattr(f, "visititems_links"):
            f.visititems_links(link)
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


#: Codecs a Zarr array may use (serialiser, filters, compressors, checksums).  Anything else —
#: a pickle or JSON object codec, a plug-in — is refused before a byte is decoded.
ZARR_CODECS = frozenset(
    {"bytes", "zstd", "gzip", "zlib", "blosc", "lz4", "bz2", "lzma", "crc32c", "transpose",
     "shuffle", "delta", "fletcher32", "adler32"}
)  # fmt: skip
#: At most this many files and folders in a Zarr store, and metadata documents of at most this
#: many bytes each.
ZARR_MAX_ENTRIES = 100_000
ZARR_MAX_METADATA_BYTES = 1 << 24
_ZARR_METADATA = {"zarr.json", ".zarray", ".zgroup", ".zattrs", ".zmetadata"}


def _zarr_codec_name(codec) -> str:
    name = getattr(codec, "codec_id", None) or getattr(codec, "codec_name", None)
    if not name:
        name = type(codec).__name__.removesuffix("Codec")
    return str(name).lower().rsplit(".", 1)[-1]


def _zarr_tree(path: Path) -> None:
    """Every entry of the store is a regular file or a folder inside it (no link to elsewhere,
    no device or FIFO), there are at most :data:`ZARR_MAX_ENTRIES`, and no metadata document
    is larger than :data:`ZARR_MAX_METADATA_BYTES`."""
    count, stack = 0, [path]
    while stack:
        with os.scandir(stack.pop()) as entries:
            for e in entries:
                count += 1
                if count > ZARR_MAX_ENTRIES:
                    raise Refused(f"{path}: more than {ZARR_MAX_ENTRIES} entries in the store")
                if e.is_symlink():
                    raise UnsafeFile(
                        f"{path}: {e.path} is a symbolic link; a Zarr store is read from its own "
                        "files only"
                    )
                if e.is_dir(follow_symlinks=False):
                    stack.append(e.path)
                elif not e.is_file(follow_symlinks=False):
                    raise UnsafeFile(f"{path}: {e.path} is not a regular file (a device or FIFO)")
                elif e.name in _ZARR_METADATA and e.stat().st_size > ZARR_MAX_METADATA_BYTES:
                    raise Refused(
                        f"{path}: metadata {e.path} is {e.stat().st_size} bytes, above "
                        f"{ZARR_MAX_METADATA_BYTES}"
                    )


def _zstd_bound(data: bytes) -> int | None:
    """An upper bound of what Zstandard frames ``data`` decode to, without decoding: each
    frame's declared content size (which the decoder enforces), else the sum over its blocks
    (raw and RLE blocks give their size, a compressed block at most 128 KiB); ``None`` for
    anything that is not a sequence of plain Zstandard frames."""
    total, i, n = 0, 0, len(data)
    while i < n:
        if data[i : i + 4] != b"\x28\xb5\x2f\xfd" or i + 6 > n:
            return None
        fhd = data[i + 4]
        single = bool(fhd & 0x20)
        fcs_size = {0: 1 if single else 0, 1: 2, 2: 4, 3: 8}[fhd >> 6]
        i += 5 + (0 if single else 1) + (0, 1, 2, 4)[fhd & 3]
        fcs = int.from_bytes(data[i : i + fcs_size], "little") if fcs_size else None
        if fcs_size == 2:
            fcs += 256
        i += fcs_size
        blocks = 0
        while True:
            if i + 3 > n:
                return None
            header = int.from_bytes(data[i : i + 3], "little")
            last, kind, size = header & 1, (header >> 1) & 3, header >> 3
            if kind == 3:
                return None
            blocks += size if kind in (0, 1) else 1 << 17
            i += 3 + (1 if kind == 1 else size)
            if last:
                break
        total += blocks if fcs is None else min(fcs, blocks)
        i += 4 if fhd & 0x04 else 0  # content checksum
    return total if i == n else None


def _stream_bound(decompressor, data: bytes, limit: int) -> int | None:
    """Decoded size of ``data`` through a stdlib streaming ``decompressor`` (``decompress(d,
    max_length)``), counted without keeping it and stopped past ``limit``."""
    total, chunk = 0, data
    while True:
        out = decompressor.decompress(chunk, 1 << 20)
        total += len(out)
        if total > limit:
            return total
        if decompressor.eof or (not out and not getattr(decompressor, "unconsumed_tail", b"")
                                and getattr(decompressor, "needs_input", True)):  # fmt: skip
            return total
        chunk = getattr(decompressor, "unconsumed_tail", b"")


def _decoded_bound(codec: str, data: bytes, limit: int) -> int | None:
    """At most how many bytes ``data`` decodes to through ``codec`` (``None``: cannot tell)."""
    import bz2
    import lzma

    if codec == "zstd":
        return _zstd_bound(data)
    if codec == "blosc":  # the header's uncompressed size, which Blosc allocates
        return int.from_bytes(data[4:8], "little") if len(data) >= 16 else None
    if codec == "lz4":  # numcodecs' LZ4 prefixes the uncompressed size
        return int.from_bytes(data[:4], "little") if len(data) >= 4 else None
    maker = {
        "gzip": lambda: zlib.decompressobj(16 + zlib.MAX_WBITS),
        "zlib": lambda: zlib.decompressobj(),
        "bz2": bz2.BZ2Decompressor,
        "lzma": lzma.LZMADecompressor,
    }[codec]
    return _stream_bound(maker(), data, limit)


#: Checksums appended to a chunk: bytes they add at the end.
_ZARR_CHECKSUMS = {"crc32c": 4, "fletcher32": 4, "adler32": 4}
_ZARR_COMPRESSORS = ("zstd", "gzip", "zlib", "blosc", "lz4", "bz2", "lzma")


def _zarr_chunks_bounded(path: Path, name: str, folder: Path, bytes_codecs, chunk_bytes: int):
    """Refuse before decoding when a chunk file of the array in ``folder`` would decode to more
    than a chunk's ``chunk_bytes`` (a compression bomb): each bytes-to-bytes codec, last one
    first, is bounded without inflating."""
    for root, dirs, files in os.walk(folder):
        # a sub-folder with its own metadata is another array, not this one's chunks
        dirs[:] = [
            d
            for d in dirs
            if not (Path(root, d) / "zarr.json").exists()
            and not (Path(root, d) / ".zarray").exists()
        ]
        for f in files:
            if f in _ZARR_METADATA:
                continue
            stored = Path(root, f).stat().st_size
            if stored > chunk_bytes + chunk_bytes // 64 + 4096:  # more than any codec adds
                raise Refused(
                    f"{path}: chunk {Path(root, f)} of {name!r} is {stored} bytes on disk for "
                    f"a chunk of {chunk_bytes}; not read"
                )
            if not any(c in _ZARR_COMPRESSORS for c in bytes_codecs):
                continue  # stored as is (and checksums): the size on disk is the bound
            data = Path(root, f).read_bytes()
            size = len(data)
            for codec in reversed(bytes_codecs):
                if codec in _ZARR_CHECKSUMS:
                    size -= _ZARR_CHECKSUMS[codec]
                    data = data[: max(size, 0)]
                    continue
                if codec not in _ZARR_COMPRESSORS:  # shuffle, delta: the same number of bytes
                    continue
                bound = _decoded_bound(codec, data, chunk_bytes)
                if bound is None:
                    raise Refused(f"{path}: chunk {Path(root, f)} of {name!r} is not valid {codec}")
                size = bound
            if size > chunk_bytes + 64:  # a checksum filter may add a few bytes
                raise Refused(
                    f"{path}: chunk {Path(root, f)} of {name!r} decodes to more than its "
                    f"{chunk_bytes} bytes (a compression bomb?); not read"
                )


def _entries_zarr(path, max_bytes):
    try:
        import zarr
    except ImportError:
        raise ImportError(
            "reading Zarr needs zarr ≥ 3 (Python ≥ 3.11): pip install 'tensor_cosdi[zarr]'"
        ) from None
    _zarr_tree(path)
    try:  # the arrays' own metadata, never a consolidated copy that may disagree with it
        node = zarr.open_group(str(path), mode="r", use_consolidated=False)
        arrays = [(k, v, path / k) for k, v in node.members(max_depth=None)
                  if isinstance(v, zarr.Array)]  # fmt: skip
    except (zarr.errors.GroupNotFoundError, zarr.errors.ContainsArrayError):  # one array
        arrays = [("array", zarr.open_array(str(path), mode="r"), path)]
    out = {}
    for name, arr, folder in arrays:
        codecs = [*arr.filters, *([arr.serializer] if arr.serializer is not None else [])]
        for codec in codecs + list(arr.compressors):
            cname = _zarr_codec_name(codec)
            if cname not in ZARR_CODECS:
                raise Refused(
                    f"{path}: array {name!r} uses the codec {cname!r}, which is not decoded "
                    f"(allowed: {', '.join(sorted(ZARR_CODECS))})"
                )
        squeezers = [_zarr_codec_name(c) for c in arr.compressors]
        if sum(c in _ZARR_COMPRESSORS for c in squeezers) > 1:
            raise Refused(f"{path}: array {name!r} chains compressors {squeezers}; not read")
        dtype = np.dtype(arr.dtype)
        if dtype.kind not in "biufc":
            raise Refused(f"{path}: array {name!r} holds {dtype} values; only numbers are read")
        chunk = int(np.prod(arr.chunks, dtype=np.int64)) * dtype.itemsize
        if chunk > max_bytes:
            raise Refused(
                f"{path}: array {name!r} declares chunks {tuple(arr.chunks)} of {chunk} bytes, "
                f"above the {max_bytes}-byte limit (pass max_bytes= to allow it)"
            )
        _zarr_chunks_bounded(path, name, folder, squeezers, chunk)
        out[name] = (tuple(arr.shape), dtype, (lambda a=arr: np.asarray(a[...])))
    return out


_READERS = {
    ".npy": ("NumPy .npy", _entries_npy),
    ".npz": ("NumPy .npz", _entries_npz),
    ".mat": ("MATLAB", _entries_mat),
    ".h5": ("HDF5", _entries_h5),
    ".hdf5": ("HDF5", _entries_h5),
    ".nc": ("NetCDF-4 (HDF5)", _entries_h5),  # NetCDF-4 is HDF5: the same hardened reader
    ".tif": ("TIFF", _entries_tiff),
    ".tiff": ("TIFF", _entries_tiff),
    ".zarr": ("Zarr", _entries_zarr),
}


def parse_json(text, where: str):
    """``text`` parsed as JSON; a ``ValueError`` naming ``where`` for JSON nested past what the
    parser's stack holds (a ``RecursionError`` otherwise; malformed JSON is already a
    ``ValueError``, :class:`json.JSONDecodeError`)."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError(f"{where}: the JSON is nested too deeply to be read") from None


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
    if suffix == ".zarr":
        if not path.is_dir():
            raise FileNotFoundError(f"Zarr store (a folder) not found: {path}")
    else:
        require_file(path)
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
