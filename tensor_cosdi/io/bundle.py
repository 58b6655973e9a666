"""Bundles: one file holding a measurement or reconstruction with everything needed to use it later.

Two containers with the same content.  HDF5 (``.h5``/``.hdf5``): datasets
``measurement``, ``cube``, ``depth``, ``wavelengths`` at the root, groups
``system``, ``calibration`` and ``extra``, gzip-compressed, the JSON
document below as the root attribute ``tensor_cosdi_bundle`` (with
``metadata`` and ``provenance`` also as their own attributes) — readable
from MATLAB (``h5read``), Julia or ``h5py`` without this library.  NumPy
``.npz`` (the default for any other name):

Format (documented, stable): a NumPy ``.npz`` archive (``numpy.savez``, no
pickles) whose arrays keep their exact dtype and bits, plus one JSON document
stored as the string array ``__bundle__``:

.. code-block:: json

    {"format": "tensor_cosdi-bundle", "format_version": 1,
     "software": {"tensor_cosdi": "…", "numpy": "…", "python": "…"},
     "created": "2026-11-22T10:00:00+00:00", "kind": "measurement",
     "system": {"system": "sd_cassi", "class": "SDCASSI", "params": {"n_bands": 28, …},
                "arrays": ["code", "shifts", "wavelengths"]},
     "arrays": ["measurement", "calibration.white", …],
     "provenance": [{"path": "…", "sha256": "…", "bytes": 123}],
     "metadata": {…}}

Arrays are stored under ``system.*`` (the system's codes, shifts,
wavelengths, PSFs), ``measurement``, ``cube``, ``depth``,
``calibration.*`` and ``extra.*``.  Files are written to a temporary name and
linked into place, so an existing bundle is never overwritten unless
``overwrite=True`` and a crash never leaves half a file.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import logging
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _backend as B
from ..validate import flag, integer, output_folder
from ._atomic import atomic_write

#: Extensions written and read as HDF5 bundles (everything else: ``.npz``).
H5_SUFFIXES = (".h5", ".hdf5")

__all__ = [
    "save_bundle",
    "load_bundle",
    "Bundle",
    "system_state",
    "system_from_state",
    "file_digest",
]

FORMAT = "tensor_cosdi-bundle"
#: 2: the document carries ``document_sha256`` over itself (version 1 bundles still load).
FORMAT_VERSION = 2


def file_digest(path) -> dict:
    """``{"path", "sha256", "bytes"}`` of a source file (provenance)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"provenance: source file not found: {p}")
    h = hashlib.sha256()
    with open(p, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return {"path": str(p.resolve()), "sha256": h.hexdigest(), "bytes": p.stat().st_size}


def _np(x):
    return np.asarray(B.to_numpy(x))


def system_state(system) -> tuple[dict, dict]:
    """``(description, arrays)`` that rebuild ``system`` with :func:`system_from_state`.

    The system describes itself (:meth:`~tensor_cosdi.systems.System.to_state`);
    the description stores its registry name, class, parameters and array names.
    """
    to_state = getattr(system, "to_state", None)
    if to_state is None or not getattr(system, "name", ""):
        raise ValueError(
            f"cannot save a {type(system).__name__}: bundles know the systems of "
            "tensor_cosdi.systems.REGISTRY"
        )
    state = to_state()
    arrays = state["arrays"]
    return {
        "system": state["system"],
        "class": state["class"],
        "params": state["params"],
        "arrays": sorted(arrays),
    }, arrays


def system_from_state(desc: dict, arrays: dict):
    """Rebuild a system saved by :func:`system_state` (bundles that name only the class
    included)."""
    from ..systems import System

    return System.from_state({**desc, "arrays": arrays})


@dataclass(frozen=True)
class Bundle:
    """What :func:`load_bundle` returns.

    Attributes
    ----------
    system : System or None
        Rebuilt from the stored parameters (bit-identical codes, shifts, …).
    measurement, cube, depth : ndarray or None
    calibration : dict of ndarray
        E.g. ``white``, ``dark`` and anything else saved under it.
    arrays : dict of ndarray
        The ``extra`` arrays.
    metadata : dict
        The user's metadata.
    provenance : list of dict
        Source files with their SHA-256 and size.
    info : dict
        The whole JSON document (software versions, creation time, kind).
    """

    system: object
    measurement: object
    cube: object
    depth: object
    calibration: dict = field(default_factory=dict)
    arrays: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    provenance: list = field(default_factory=list)
    info: dict = field(default_factory=dict, repr=False)


def _check_name(name: str, what: str):
    if not isinstance(name, str) or not name or "/" in name or name.startswith("__"):
        raise ValueError(
            f"{what} names must be non-empty strings without '/' or a leading '__', got {name!r}"
        )


def save_bundle(
    path,
    *,
    system=None,
    measurement=None,
    cube=None,
    depth=None,
    calibration=None,
    arrays=None,
    metadata=None,
    sources=(),
    kind: str | None = None,
    overwrite: bool = False,
) -> Path:
    """Save a measurement / reconstruction / calibration with its system and provenance as one
    ``.npz`` file.

    Parameters
    ----------
    path : str or Path
        Target file: ``.h5``/``.hdf5`` for HDF5, ``.npz`` for NumPy's zip; any other
        suffix (or none) is a ``ValueError``, not a renamed file.
    system : System, optional
        Saved by parameters and arrays (rebuilt on load).
    measurement, cube, depth : array or tensor, optional
    calibration : dict of arrays, optional
        E.g. ``{"white": W, "dark": D}`` (reflectance, Eq. 171).
    arrays : dict of arrays, optional
        Anything else to keep.
    metadata : dict, optional
        JSON-serialisable notes (exposure, operator, sample …).
    sources : sequence of paths
        Capture files this bundle was made from; their SHA-256 is recorded.
    kind : str, optional
        Default: ``"reconstruction"`` with a cube, ``"measurement"`` with a
        measurement, else ``"calibration"``.
    overwrite : bool
        Replace an existing file (default: refuse with ``FileExistsError``).

    Returns
    -------
    Path of the written file.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from tensor_cosdi.systems import SDCASSI
    >>> sd = SDCASSI(np.eye(4), n_bands=3)
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "capture.npz"
    >>> _ = save_bundle(f, system=sd, measurement=np.ones((4, 6)), metadata={"exposure_ms": 20})
    >>> b = load_bundle(f)
    >>> b.system.measurement_shape, b.metadata, b.info["kind"]
    ((4, 6), {'exposure_ms': 20}, 'measurement')
    """
    from .._version import __version__

    overwrite = flag("overwrite", overwrite)
    p = Path(path)
    if p.suffix.lower() not in (".npz",) + H5_SUFFIXES:  # never a name other than the one given
        raise ValueError(
            f"{p}: a bundle is an .npz or .h5/.hdf5 file (e.g. {p.with_suffix('.npz').name}); "
            f"got suffix {p.suffix or '(none)'!r}"
        )
    if p.exists() and not overwrite:
        raise FileExistsError(f"{p} exists; pass overwrite=True (CLI: --force) to replace it")
    output_folder(p)
    store: dict[str, np.ndarray] = {}
    doc = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "software": {
            "tensor_cosdi": __version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
        },
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }
    if system is not None:
        desc, sys_arrays = system_state(system)
        doc["system"] = desc
        store.update({f"system.{k}": v for k, v in sys_arrays.items()})
    for name, value in (("measurement", measurement), ("cube", cube), ("depth", depth)):
        if value is not None:
            store[name] = _np(value)
    for group, mapping in (("calibration", calibration), ("extra", arrays)):
        for k, v in (mapping or {}).items():
            _check_name(k, group)
            store[f"{group}.{k}"] = _np(v)
    if (
        system is not None
        and measurement is not None
        and store["measurement"].shape != tuple(system.measurement_shape)
    ):
        raise ValueError(
            f"measurement shape {store['measurement'].shape} does not match the system's "
            f"{tuple(system.measurement_shape)}"
        )
    if system is not None and cube is not None and store["cube"].shape != tuple(system.cube_shape):
        raise ValueError(
            f"cube shape {store['cube'].shape} does not match the system's "
            f"{tuple(system.cube_shape)}"
        )
    for k, v in store.items():
        if v.dtype == object:
            raise ValueError(f"array {k!r} has dtype object; bundles store numeric arrays only")
    for name in ("measurement", "cube"):  # what load_bundle refuses is never written
        a = store.get(name)
        if a is not None and a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            raise ValueError(f"the {name} holds NaN or infinite values; bundles store finite ones")
    if metadata is not None and not isinstance(metadata, dict):
        raise ValueError(f"metadata must be a dict (or None), got {type(metadata).__name__}")
    try:
        doc["metadata"] = json.loads(json.dumps(metadata or {}, allow_nan=False))
    except (TypeError, ValueError) as e:
        raise ValueError(
            f"metadata must be JSON-serialisable (numbers, strings, lists, dicts): {e}"
        ) from None
    except RecursionError:
        raise ValueError("metadata is nested too deeply to store as JSON") from None
    doc["provenance"] = [file_digest(s) for s in sources]
    doc["kind"] = kind or (
        "reconstruction"
        if cube is not None
        else "measurement"
        if measurement is not None
        else "calibration"
    )
    doc["arrays"] = sorted(store)
    doc["sha256"] = _arrays_digest(store)
    doc["document_sha256"] = _document_digest(doc)
    store["__bundle__"] = np.array(json.dumps(doc))
    if p.suffix.lower() in H5_SUFFIXES:
        store.pop("__bundle__")
        atomic_write(p, lambda tmp: _write_h5(tmp, store, doc), overwrite=overwrite)
    else:
        atomic_write(p, lambda tmp: np.savez(tmp, **store), overwrite=overwrite, suffix=".npz")
    logging.getLogger(__name__).info("bundle %s written (%s)", p, doc["kind"])
    return p


def _arrays_digest(arrays: dict) -> str:
    """SHA-256 over the arrays' names, dtypes, shapes and bytes, in name order."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _document_digest(doc: dict) -> str:
    """SHA-256 over the document (keys sorted, ``document_sha256`` itself left out): an edited
    system description or metadata is noticed, as edited arrays are by ``sha256``."""
    body = {k: v for k, v in doc.items() if k != "document_sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _h5_name(key: str) -> str:
    """``system.code`` → ``system/code`` (groups in HDF5), ``cube`` → ``cube``."""
    head, sep, tail = key.partition(".")
    return f"{head}/{tail}" if sep and head in ("system", "calibration", "extra") else key


def _write_h5(tmp, store, doc):
    from .files import _require_h5py

    h5py = _require_h5py()
    with h5py.File(tmp, "w") as f:
        for k, v in store.items():
            big = v.ndim > 0 and v.size > 64
            kw = {"compression": "gzip", "shuffle": True} if big else {}
            f.create_dataset(_h5_name(k), data=v, **kw)
        if "system.wavelengths" in store and "wavelengths" not in store:
            f["wavelengths"] = f["system/wavelengths"]  # a hard link: readable without the group
        f.attrs["tensor_cosdi_bundle"] = json.dumps(doc)
        f.attrs["metadata"] = json.dumps(doc.get("metadata", {}))
        f.attrs["provenance"] = json.dumps(doc.get("provenance", []))


def _read_h5(p: Path, max_bytes: int):
    from ._readers import check_h5_dataset, hard_linked, parse_json
    from .files import _check_size, _require_h5py

    h5py = _require_h5py()
    try:
        f = h5py.File(p, "r")
    except OSError as e:
        raise ValueError(f"{p}: not a readable HDF5 bundle ({e})") from e
    with f:
        if "tensor_cosdi_bundle" not in f.attrs:
            raise ValueError(f"{p}: an HDF5 file without the tensor_cosdi_bundle attribute")
        doc = parse_json(f.attrs["tensor_cosdi_bundle"], f"{p}: the bundle's document")
        data = {}
        for k in doc.get("arrays", []):
            name = _h5_name(k)
            try:
                hard_linked(f, name, p)  # before anything resolves a link into another file
            except KeyError:
                raise ValueError(
                    f"{p}: the bundle lists {k!r} but the file has no dataset {name}"
                ) from None
            if not isinstance(f[name], h5py.Dataset):
                raise ValueError(f"{p}: the bundle lists {k!r} but {name} is not a dataset")
            check_h5_dataset(p, name, f[name], max_bytes)
            _check_size(p, k, f[name].shape, f[name].dtype, max_bytes)
            data[k] = f[name][()]
    return data, doc


def bundle_document(path) -> dict | None:
    """The JSON document of a bundle at ``path`` (``.npz`` or HDF5) without reading its arrays, or
    ``None`` when the file is not a bundle."""
    from ._readers import parse_json, reason, require_file
    from .files import _require_h5py

    p = Path(path)
    if p.suffix.lower() == ".zarr" and p.is_dir():
        return None  # a bundle is one file; a Zarr store is a cube
    require_file(p)
    raw = None
    try:
        if p.suffix.lower() in H5_SUFFIXES:
            with _require_h5py().File(p, "r") as f:
                raw = f.attrs.get("tensor_cosdi_bundle")
        elif p.suffix.lower() == ".npz":
            with np.load(p, allow_pickle=False) as z:
                raw = str(z["__bundle__"]) if "__bundle__" in z.files else None
    except ImportError:
        raise
    except Exception as e:  # zipfile, h5py and NumPy raise many kinds on a damaged file
        raise ValueError(f"{p}: cannot read the file — truncated or corrupted ({reason(e)})") from e
    if raw is None:
        return None
    try:
        return parse_json(raw, f"{p}: the bundle's document")  # too deep: a ValueError naming p
    except json.JSONDecodeError as e:
        raise ValueError(f"{p}: the bundle's document is corrupted ({e})") from e


def load_bundle(path, *, max_bytes: int | None = None) -> Bundle:
    """Read a bundle written by :func:`save_bundle` (arrays bit-identical, system rebuilt).

    ``.npz`` or HDF5 (``.h5``/``.hdf5``).  Array sizes (declared HDF5 shapes and
    chunks, the size each ``.npz`` member inflates to) are checked against
    ``max_bytes`` (default :data:`tensor_cosdi.io.files.MAX_ARRAY_BYTES`)
    before reading; HDF5 data stored outside the file (external storage,
    virtual datasets, links into other files) is refused.  The arrays and
    the JSON document are each checked against their SHA-256: an edited
    system description, like an edited array, is an error.
    """
    from ._readers import (
        HEADER_SLACK_BYTES,
        MAX_ARRAY_BYTES,
        UnsafeFile,
        parse_json,
        reason,
        require_file,
    )

    if max_bytes is not None:
        max_bytes = integer("max_bytes", max_bytes, low=1)
    p = Path(path)
    require_file(p, "bundle")
    if p.suffix.lower() in H5_SUFFIXES:
        try:
            data, doc = _read_h5(p, MAX_ARRAY_BYTES if max_bytes is None else max_bytes)
        except json.JSONDecodeError as e:
            raise ValueError(f"{p}: the bundle's document is corrupted ({e})") from e
        except ValueError:
            raise  # ours: sizes, shapes, a missing document — they name the file already
        except Exception as e:  # HDF5 raises OSError, KeyError, RuntimeError on a damaged file
            raise ValueError(
                f"{p}: not a readable HDF5 bundle — truncated or corrupted ({reason(e)})"
            ) from e
    else:
        limit = MAX_ARRAY_BYTES if max_bytes is None else max_bytes
        try:
            with np.load(p, allow_pickle=False) as z:
                for info in z.zip.infolist():  # the size each member inflates to, up front
                    if info.file_size > limit + HEADER_SLACK_BYTES:
                        raise UnsafeFile(
                            f"{p}: member {info.filename!r} inflates to {info.file_size} bytes, "
                            f"above the {limit}-byte limit (pass max_bytes= to allow it)"
                        )
                data = {k: z[k] for k in z.files}
        except UnsafeFile:
            raise
        except Exception as e:
            raise ValueError(f"{p}: not a readable .npz bundle ({reason(e)})") from e
        if "__bundle__" not in data:
            raise ValueError(
                f"{p}: an .npz file without the __bundle__ document — not a tensor_cosdi bundle"
            )
        try:
            doc = parse_json(str(data.pop("__bundle__")), f"{p}: the bundle's document")
        except json.JSONDecodeError as e:
            raise ValueError(f"{p}: the bundle's document is corrupted ({e})") from e
    if doc.get("format") != FORMAT:
        raise ValueError(f"{p}: unknown format {doc.get('format')!r}")
    if doc.get("format_version", 0) > FORMAT_VERSION:
        raise ValueError(
            f"{p}: bundle format {doc['format_version']} is newer than this tensor_cosdi reads "
            f"({FORMAT_VERSION}); upgrade tensor_cosdi"
        )
    if doc.get("format_version", 0) >= 2 and doc.get("document_sha256") != _document_digest(doc):
        raise ValueError(
            f"{p}: the bundle's document does not match its SHA-256 — the file was corrupted or "
            "edited (its system description or metadata changed)"
        )
    if "sha256" in doc and _arrays_digest(data) != doc["sha256"]:
        raise ValueError(
            f"{p}: the arrays do not match the bundle's SHA-256 — the file was corrupted or edited"
        )
    listed = set(doc.get("arrays", data))
    if listed != set(data):
        raise ValueError(f"{p}: the bundle lists arrays {sorted(listed)} but holds {sorted(data)}")
    system = None
    if "system" in doc:
        sys_arrays = {k[len("system.") :]: v for k, v in data.items() if k.startswith("system.")}
        system = system_from_state(doc["system"], sys_arrays)
    for name, want in (
        ("measurement", None if system is None else tuple(system.measurement_shape)),
        ("cube", None if system is None else tuple(system.cube_shape)),
    ):
        a = data.get(name)
        if a is None:
            continue
        if want is not None and a.shape != want:
            raise ValueError(f"{p}: {name} of shape {a.shape} does not match the system's {want}")
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise ValueError(f"{p}: the {name} holds NaN or infinite values")
    group = lambda g: {k[len(g) + 1 :]: v for k, v in data.items() if k.startswith(g + ".")}  # noqa: E731
    return Bundle(
        system,
        data.get("measurement"),
        data.get("cube"),
        data.get("depth"),
        group("calibration"),
        group("extra"),
        doc.get("metadata", {}),
        doc.get("provenance", []),
        doc,
    )
