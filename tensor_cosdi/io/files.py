"""Read and write cubes and arrays in the formats labs use, chosen by extension.

========================  =================================  ===============================
extension                 read (:func:`read_array`, cube)    write (:func:`write_cube`)
========================  =================================  ===============================
``.mat``                  MATLAB v5 (SciPy) and v7.3 (HDF5,  MATLAB v5 (SciPy)
                          h5py; transposed to NumPy order)
``.h5``, ``.hdf5``        h5py (any dataset, by path)        datasets ``cube``,
                                                             ``wavelengths``; gzip
``.npy``, ``.npz``        NumPy (no pickles)                 ``.npz`` (compressed);
                                                             ``.npy`` without wavelengths
``.nc`` (NetCDF-4)        h5py (NetCDF-4 is HDF5)            xarray + h5netcdf (extra
                                                             ``.[xarray]``): ``cube`` with
                                                             dims and a ``wavelength``
                                                             coordinate in nm
``.hdr`` (ENVI)           ``spectral`` (extra ``.[envi]``)   ``spectral``
``.tif``, ``.tiff``       tifffile (pages = bands)           tifffile (one page per band)
``.zarr`` (a folder)      zarr ≥ 3 (extra ``.[zarr]``; its   xarray + zarr: as NetCDF
                          own regular files only, numeric    (``cube``, ``wavelength``);
                          arrays, standard codecs only)      written to a temporary folder
                                                             and renamed
========================  =================================  ===============================

``key`` picks a variable (a MATLAB variable, an NPZ member, an HDF5 dataset
path); without it the one candidate array is taken, and several candidates
are an error listing each with its shape.  Cubes are ``(rows, columns,
bands)``; wavelengths are read from a variable named like
:data:`WAVELENGTH_KEYS` (or ENVI's ``wavelength`` with its units) and
checked to be nanometres in :data:`WAVELENGTH_RANGE_NM`.

Reads are bounded: declared shapes are checked against ``max_bytes``
(default :data:`MAX_ARRAY_BYTES`) before anything is allocated.  Writes
are atomic (temporary file, fsync, rename; :mod:`tensor_cosdi.io._atomic`)
and never replace an existing file without ``overwrite=True``.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from .._units import WAVELENGTH_RANGE_NM, check_wavelengths_nm
from ..validate import flag, integer, real_array
from ._atomic import atomic_write, atomic_write_folder
from ._readers import (  # noqa: F401 - frames/bundle/CLI use them
    MAX_ARRAY_BYTES,
    Refused,
    _load,
    _require_h5py,
    array_entries,
    parse_json,
    reason,
    require_file,
)

__all__ = [
    "read_array",
    "read_cube",
    "write_cube",
    "split_key",
    "CUBE_SUFFIXES",
    "MAX_ARRAY_BYTES",
    "WAVELENGTH_KEYS",
    "WAVELENGTH_RANGE_NM",
]

log = logging.getLogger(__name__)

#: Extensions :func:`read_array` / :func:`read_cube` / :func:`write_cube` know.
CUBE_SUFFIXES = (".mat", ".h5", ".hdf5", ".nc", ".npy", ".npz", ".hdr", ".tif", ".tiff", ".zarr")
#: Variable names taken as the band centres of a cube (case-insensitive).
WAVELENGTH_KEYS = ("wavelengths", "wavelengths_nm", "wavelength", "wl", "lambda", "bands_nm")


def split_key(spec: str) -> tuple[str, str | None]:
    """``"file.mat:mask"`` → ``("file.mat", "mask")``; a plain path → ``(path, None)``."""
    spec = str(spec)
    head, sep, tail = spec.rpartition(":")
    if sep and head and tail and "/" not in tail and "\\" not in tail:
        if Path(head).suffix.lower() in CUBE_SUFFIXES:
            return head, tail
    return spec, None


def cube_suffix(path: Path) -> str:
    """The lower-case suffix of ``path`` when it is a file type the readers know, else a
    one-line ``ValueError`` naming them (:data:`CUBE_SUFFIXES`)."""
    s = path.suffix.lower()
    if s not in CUBE_SUFFIXES:
        raise ValueError(
            f"{path}: unknown file type {path.suffix!r}; expected one of {', '.join(CUBE_SUFFIXES)}"
        )
    return s


def _size_text(n: int) -> str:
    """``n`` bytes in the largest binary unit that keeps it ≥ 1 (``"4.00 GiB"``, ``"1000 B"``).

    >>> _size_text(4 * 2**30), _size_text(1 << 20), _size_text(1000)
    ('4.00 GiB', '1.00 MiB', '1000 B')
    """
    for unit, shift in (("GiB", 30), ("MiB", 20), ("KiB", 10)):
        if n >= 1 << shift:
            return f"{n / (1 << shift):.2f} {unit}"
    return f"{int(n)} B"


def _check_size(path, name, shape, dtype, max_bytes):
    n = int(np.prod(shape, dtype=np.int64)) * np.dtype(dtype).itemsize
    if n > max_bytes:
        raise ValueError(
            f"{path}: {name!r} declares shape {tuple(shape)} of {np.dtype(dtype)} = "
            f"{_size_text(n)}, above the {_size_text(max_bytes)} limit "
            "(pass max_bytes= to allow it)"
        )


def _listing(entries) -> str:
    """The arrays of ``entries`` with their shapes, then what else the file holds and why it is
    not read (``"cube (256, 256, 28); not read: name (MATLAB text (char))"``)."""
    text = ", ".join(f"{k} {tuple(v[0])}" for k, v in entries.items()) or "no arrays"
    skipped = getattr(entries, "skipped", {})
    if skipped:
        text += "; not read: " + ", ".join(f"{k} ({why})" for k, (why, _) in skipped.items())
    return text


def _pick(path, entries, key, want_ndim=None):
    if key is not None:
        skipped = getattr(entries, "skipped", {})
        if key in skipped:
            why, refusal = skipped[key]
            raise refusal(
                f"{path}: {key!r} is {why}, not a numeric array stored in the file; only "
                "numeric arrays are read"
            )
        if key not in entries:
            raise KeyError(f"{path}: no array {key!r}; it holds {_listing(entries)}")
        return key
    wl = {k for k in entries if k.lower().rsplit("/", 1)[-1] in WAVELENGTH_KEYS}
    cands = [k for k, v in entries.items() if k not in wl and len(v[0]) >= 1]
    if want_ndim is not None:
        cands = [k for k in cands if len(entries[k][0]) >= want_ndim]
    if len(cands) == 1:
        return cands[0]
    listing = _listing(entries)
    what = "no candidate" if not cands else "several candidates"
    target = "the array to read" if want_ndim is None else f"a cube ({want_ndim} axes or more)"
    raise ValueError(f"{path}: {what} for {target} ({listing}); pass key=NAME (CLI: FILE:NAME)")


def read_array(path, key=None, *, max_bytes: int = MAX_ARRAY_BYTES) -> np.ndarray:
    """One array from ``path`` (see the module table); ``key`` picks a variable.

    The array is returned as stored (MATLAB v7.3 transposed back to the
    order MATLAB shows); nothing is converted or clipped.
    """
    max_bytes = integer("max_bytes", max_bytes, low=1)
    path = Path(path)
    suffix = cube_suffix(path)
    if suffix == ".hdr":
        cube, _ = _read_envi(path, max_bytes)
        if key is not None:
            raise ValueError(f"{path}: an ENVI file holds one cube; key must be None")
        return cube
    if suffix == ".npy" and key is not None:
        raise ValueError(f"{path}: a .npy file holds one array; key must be None, got {key!r}")
    entries = array_entries(path, suffix, max_bytes)
    name = _pick(path, entries, key)
    shape, dtype, load = entries[name]
    _check_size(path, name, shape, dtype, max_bytes)
    log.debug("reading %s:%s %s %s", path, name, tuple(shape), np.dtype(dtype))
    return _load(path, suffix, load)


def _check_wavelengths(path, wl, n_bands):
    wl = real_array(f"{path}: wavelengths", wl, finite=False).reshape(-1)
    if wl.size != n_bands:
        raise ValueError(f"{path}: {wl.size} wavelengths for a cube of {n_bands} bands")
    return check_wavelengths_nm(wl, f"{path}: wavelengths")


def _check_envi_header(path, img, shape, dtype) -> None:
    """Fields that spectral reads without complaint but that no cube of light can have: a
    complex data type, an unknown interleave or byte order, a negative offset, an empty axis."""
    meta = img.metadata
    interleave = str(meta.get("interleave", "bsq")).strip().lower()
    if interleave not in ("bsq", "bil", "bip"):
        raise ValueError(f"{path}: interleave {interleave!r}; ENVI knows bsq, bil and bip")
    order = str(meta.get("byte order", "0")).strip()
    if order not in ("0", "1"):
        raise ValueError(f"{path}: byte order {order!r}; ENVI knows 0 (little) and 1 (big endian)")
    if dtype.kind not in "biuf":
        raise ValueError(
            f"{path}: ENVI data type {meta.get('data type')} holds {dtype.name} values; a cube of "
            "light is real"
        )
    if int(img.offset) < 0:
        raise ValueError(f"{path}: header offset {int(img.offset)}; expected ≥ 0")
    if min(shape) < 1:
        raise ValueError(
            f"{path}: the header declares an empty cube (lines, samples, bands) {shape}"
        )


def _read_envi(path: Path, max_bytes):
    try:
        from spectral.io import envi
    except ImportError:
        raise ImportError(
            "reading ENVI files needs the spectral package: pip install 'tensor_cosdi[envi]'"
        ) from None
    require_file(path)
    try:
        img = envi.open(str(path))
        shape = (int(img.nrows), int(img.ncols), int(img.nbands))
        dtype = np.dtype(img.dtype)
    except Exception as e:  # spectral raises its own kinds on a bad header
        raise ValueError(f"{path}: not a readable ENVI header ({reason(e)})") from e
    _check_envi_header(path, img, shape, dtype)
    _check_size(path, "cube", shape, dtype, max_bytes)
    data = Path(img.filename)
    if data.is_symlink():  # the header's folder names the data; a link would read another file
        raise ValueError(
            f"{path}: its data file {data} is a symbolic link; copy the file there instead"
        )
    need = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize + int(img.offset)
    if not data.is_file() or data.stat().st_size < need:  # a device, a FIFO, a short file
        raise ValueError(
            f"{path}: its data file {data} is not a regular file of at least {need} bytes "
            f"(the header declares {shape} of {dtype})"
        )
    try:
        cube = np.asarray(img.load())
        wl = img.metadata.get("wavelength")
        wl = None if wl is None else np.asarray([float(v) for v in wl])
    except Exception as e:
        raise ValueError(f"{path}: cannot read the ENVI cube ({reason(e)})") from e
    if wl is not None:
        units = str(img.metadata.get("wavelength units", "nm")).strip().lower()
        scale = {"nm": 1.0, "nanometers": 1.0, "um": 1e3, "µm": 1e3, "micrometers": 1e3,
                 "microns": 1e3, "mm": 1e6}.get(units)  # fmt: skip
        if scale is None:
            raise ValueError(f"{path}: unknown wavelength units {units!r} (expected nm or µm)")
        wl = _check_wavelengths(path, wl * scale, cube.shape[2])
    return cube, wl


def read_cube(path, key=None, *, max_bytes: int = MAX_ARRAY_BYTES):
    """A cube ``(rows, columns, bands)`` and its wavelengths (nm, or ``None``) from ``path``.

    Multi-page TIFFs are read as one page per band.  Wavelengths come from a
    variable named like :data:`WAVELENGTH_KEYS` (or ENVI metadata), must
    match the band count and lie in :data:`WAVELENGTH_RANGE_NM`.
    """
    max_bytes = integer("max_bytes", max_bytes, low=1)
    path = Path(path)
    suffix = cube_suffix(path)
    if suffix == ".hdr":
        return _read_envi(path, max_bytes)
    if suffix == ".npy" and key is not None:
        raise ValueError(f"{path}: a .npy file holds one array; key must be None, got {key!r}")
    entries = array_entries(path, suffix, max_bytes)
    name = _pick(path, entries, key, want_ndim=3)
    shape, dtype, load = entries[name]
    _check_size(path, name, shape, dtype, max_bytes)
    if np.dtype(dtype).kind not in "biuf":
        raise ValueError(f"{path}: {name!r} holds {np.dtype(dtype)} values; a cube is real")
    log.debug("reading cube %s:%s %s %s", path, name, tuple(shape), np.dtype(dtype))
    cube = np.asarray(_load(path, suffix, load))
    if cube.dtype.kind not in "biuf":  # a format whose listing cannot tell (MATLAB v5 complex)
        raise Refused(f"{path}: {name!r} holds {cube.dtype} values; a cube is real")
    if suffix in (".tif", ".tiff") and cube.ndim == 3:
        axes = getattr(load, "axes", "")
        if axes.endswith("S") and cube.ndim == 3:
            pass  # one colour page (rows, columns, samples): already a cube
        elif axes.endswith("YX"):
            cube = np.moveaxis(cube, 0, -1)  # pages are bands
        else:
            raise ValueError(
                f"{path}: TIFF axes {axes!r}; expected pages of one band each or one colour page"
            )
    if cube.ndim < 3:
        raise ValueError(f"{path}: {name!r} has shape {cube.shape}; a cube needs 3 axes or more")
    wl = None
    for k, (_, _, wload) in entries.items():
        if k != name and k.lower().rsplit("/", 1)[-1] in WAVELENGTH_KEYS:
            wl = _check_wavelengths(path, wload(), cube.shape[2])
            break
    if wl is None and suffix in (".tif", ".tiff"):
        wl = _tiff_wavelengths(path, cube.shape[2])
    return cube, wl


def _tiff_wavelengths(path, n_bands):
    import tifffile

    with tifffile.TiffFile(path) as t:
        desc = t.pages[0].description
    try:
        meta = parse_json(desc, "the TIFF description")
    except (TypeError, ValueError):
        return None
    wl = meta.get("wavelengths_nm") if isinstance(meta, dict) else None
    return None if wl is None else _check_wavelengths(path, wl, n_bands)


def write_cube(path, cube, wavelengths=None, *, metadata=None, overwrite: bool = False):
    """Write ``cube (rows, columns, bands)`` and its wavelengths (nm) to ``path`` atomically.

    The format follows the extension (module table).  ``metadata``: a
    JSON-serialisable dict, stored as an attribute (HDF5), a variable
    (MATLAB, NPZ), the page description (TIFF) or header fields (ENVI).
    Never replaces an existing file without ``overwrite=True``.  Returns the path.
    """
    path = Path(path)
    suffix = cube_suffix(path)
    cube = np.asarray(cube)
    if cube.ndim != 3 or cube.dtype.kind not in "biuf":
        raise ValueError(
            f"cube must be a numeric (rows, columns, bands) array, got {cube.dtype} {cube.shape}"
        )
    if cube.size == 0:  # (a TIFF of no pages would not read back)
        raise ValueError(f"cube has no entries (shape {cube.shape}); nothing to write")
    wl = None if wavelengths is None else _check_wavelengths(path, wavelengths, cube.shape[2])
    if metadata is not None and not isinstance(metadata, dict):
        raise ValueError(f"metadata must be a dict (or None), got {type(metadata).__name__}")
    try:
        meta_json = json.dumps(metadata or {}, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise ValueError(f"metadata must be JSON-serialisable: {e}") from None
    except RecursionError:
        raise ValueError("metadata is nested too deeply to store as JSON") from None

    def write(tmp):
        if suffix in (".h5", ".hdf5"):
            h5py = _require_h5py()
            with h5py.File(tmp, "w") as f:
                ds = f.create_dataset("cube", data=cube, compression="gzip", shuffle=True)
                ds.attrs["dims"] = ["rows", "columns", "bands", *(
                    f"axis{i}" for i in range(3, cube.ndim)
                )]  # fmt: skip
                if wl is not None:
                    w = f.create_dataset("wavelengths", data=wl)
                    w.attrs["units"] = "nm"
                    w.make_scale("wavelength")
                    ds.dims[2].attach_scale(w)
                f.attrs["metadata"] = meta_json
        elif suffix == ".nc":
            _write_netcdf(tmp, cube, wl, meta_json)
        elif suffix == ".mat":
            import scipy.io

            d = {"cube": cube, "metadata": meta_json}
            if wl is not None:
                d["wavelengths"] = wl
            scipy.io.savemat(tmp, d, do_compression=True)
        elif suffix == ".npz":
            d = {"cube": cube, "metadata": np.array(meta_json)}
            if wl is not None:
                d["wavelengths"] = wl
            np.savez_compressed(tmp, **d)
        elif suffix == ".npy":
            np.save(tmp, cube, allow_pickle=False)
        elif suffix in (".tif", ".tiff"):
            import tifffile

            desc = {"metadata": metadata or {}}
            if wl is not None:
                desc["wavelengths_nm"] = wl.tolist()
            tifffile.imwrite(  # one grey page per band, also for 3 or 4 bands (not RGB)
                tmp, np.moveaxis(cube, -1, 0), photometric="minisblack",
                description=json.dumps(desc),
            )  # fmt: skip

    if suffix == ".nc":
        _netcdf_libraries()  # before anything is written
    if suffix == ".zarr":
        _zarr_libraries()
        return atomic_write_folder(
            path, lambda tmp: _write_zarr(tmp, cube, wl, meta_json), overwrite=overwrite
        )
    if suffix == ".npy" and (wl is not None or metadata):
        raise ValueError(f"{path}: .npy holds the cube only; use .npz or .h5 to keep wavelengths")
    if suffix == ".hdr":
        return _write_envi_atomic(path, cube, wl, metadata, overwrite)
    return atomic_write(path, write, overwrite=overwrite)


def _netcdf_libraries():
    try:
        import h5netcdf  # noqa: F401
        import xarray
    except ImportError:
        raise ImportError(
            "writing NetCDF needs xarray and h5netcdf: pip install 'tensor_cosdi[xarray]'"
        ) from None
    return xarray


def _labelled(xarray, cube, wl, meta_json):
    """The cube as an xarray Dataset: variable ``cube`` with dims ``rows, columns, wavelength``
    (extra axes ``axis3…``), the wavelengths in nm as the coordinate, the metadata as a JSON
    attribute."""
    dims = ["rows", "columns", "wavelength", *(f"axis{i}" for i in range(3, cube.ndim))]
    coords = {} if wl is None else {"wavelength": ("wavelength", wl, {"units": "nm"})}
    ds = xarray.DataArray(cube, dims=dims, coords=coords, name="cube").to_dataset()
    ds.attrs["metadata"] = meta_json
    return ds


def _write_netcdf(tmp, cube, wl, meta_json):
    ds = _labelled(_netcdf_libraries(), cube, wl, meta_json)
    encoding = {"cube": {"compression": "gzip", "shuffle": True}}
    ds.to_netcdf(tmp, engine="h5netcdf", encoding=encoding)


def _zarr_libraries():
    try:
        import xarray
        import zarr
    except ImportError:
        raise ImportError(
            "writing Zarr needs xarray and zarr ≥ 3 (Python ≥ 3.11): "
            "pip install 'tensor_cosdi[zarr]'"
        ) from None
    if int(zarr.__version__.split(".")[0]) < 3:
        raise ImportError(f"Zarr support needs zarr ≥ 3, found {zarr.__version__}")
    return xarray


def _write_zarr(folder, cube, wl, meta_json):
    """A Zarr v3 store in ``folder`` (empty, made by the caller): the dataset of
    :func:`_labelled`, without consolidated metadata (the reader ignores it)."""
    ds = _labelled(_zarr_libraries(), cube, wl, meta_json)
    ds.to_zarr(folder, mode="a", consolidated=False, zarr_format=3)


def _write_envi_atomic(path: Path, cube, wl, metadata, overwrite):
    """ENVI is a pair (``.hdr`` + raw ``.img``): each written atomically, the data first."""
    try:
        from spectral.io import envi
    except ImportError:
        raise ImportError(
            "writing ENVI files needs the spectral package: pip install 'tensor_cosdi[envi]'"
        ) from None
    import shutil
    import tempfile

    overwrite = flag("overwrite", overwrite)
    img_path = path.with_suffix(".img")
    for p in (path, img_path):
        if p.exists() and not overwrite:
            raise FileExistsError(f"{p} exists; pass overwrite=True (CLI: --force) to replace it")
    meta = {"description": json.dumps(metadata or {})}
    if wl is not None:
        meta.update({"wavelength": [f"{v:g}" for v in wl], "wavelength units": "nm"})
    with tempfile.TemporaryDirectory(dir=path.parent, prefix=f".{path.name}.") as tmpdir:
        hdr = Path(tmpdir) / path.name
        envi.save_image(str(hdr), cube, metadata=meta, ext=".img", force=True)
        atomic_write(img_path, lambda t: shutil.copyfile(Path(tmpdir) / img_path.name, t),
                     overwrite=overwrite)  # fmt: skip
        atomic_write(path, lambda t: shutil.copyfile(hdr, t), overwrite=overwrite)
    return path
