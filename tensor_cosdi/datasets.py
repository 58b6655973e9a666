"""Real hyperspectral scenes for tuning and evaluating reconstruction (not shipped with the
package).

The project's tests and benchmarks read the CAVE scenes of
``../shared/data/hsi_train`` (research use; see that folder's README); a user
points :func:`data_dir` at their own copy with the ``TENSOR_COSDI_DATA``
environment variable or passes a path.  Each scene is a ``NAME.npz`` with a
``cube`` (rows, columns, bands; uint16 reflectance × 65535) and
``wavelengths_nm``.

:data:`KAIST_WAVELENGTHS` are the 28 band centres (453–648 nm) of the
standard 256×256×28 CASSI simulation protocol (TSA-Net, MST, DAUHST);
:func:`load_hsi` resamples a scene onto them (linear interpolation along the
band axis, never dropping bands).  :data:`TUNE_SCENES` / :data:`REPORT_SCENES`
is the fixed split of the project: tune on the first, report on the second,
never the other way round.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ._units import check_wavelengths_nm
from .validate import integer, precision

__all__ = [
    "KAIST_WAVELENGTHS",
    "HSI_SCENES",
    "TUNE_SCENES",
    "REPORT_SCENES",
    "training_scenes",
    "tune_folds",
    "data_dir",
    "data_file",
    "scene_or",
    "stand_in",
    "FALLBACK_ENV",
    "load_hsi",
    "cave",
]

#: Band centres (nm) of the 28-band KAIST / TSA-Net CASSI protocol.
KAIST_WAVELENGTHS = np.array(
    [453.3, 457.6, 462.1, 466.8, 471.6, 476.5, 481.6, 486.9, 492.4, 498.0, 503.9, 509.9, 516.2,
     522.7, 529.5, 536.5, 543.8, 551.4, 558.6, 567.5, 575.3, 584.3, 594.4, 604.2, 614.4, 625.1,
     636.3, 648.1]
)  # fmt: skip

#: The 31 CAVE scenes of ``hsi_train`` (2×2-averaged to 256×256, 31 bands 400–700 nm): the
#: eleven of the first release first, so that earlier prefixes of :data:`TUNE_SCENES` are kept.
HSI_SCENES = (
    "balloons", "beads", "cd", "chart_and_stuffed_toy", "clay", "face", "fake_and_real_peppers",
    "feathers", "flowers", "real_and_fake_apples", "thread_spools",
    "cloth", "egyptian_statue", "fake_and_real_beers", "fake_and_real_food",
    "fake_and_real_lemon_slices", "fake_and_real_lemons", "fake_and_real_strawberries",
    "fake_and_real_sushi", "fake_and_real_tomatoes", "glass_tiles", "hairs", "jelly_beans",
    "oil_painting", "paints", "photo_and_face", "pompoms", "real_and_fake_peppers", "sponges",
    "stuffed_toys", "superballs",
)  # fmt: skip
#: Held back: every figure the project reports on real spectra is a mean over these.
REPORT_SCENES = ("beads", "face", "real_and_fake_apples")
#: The 28 scenes defaults are chosen on and networks trained on; never reported on.
TUNE_SCENES = tuple(s for s in HSI_SCENES if s not in REPORT_SCENES)


def tune_folds(k: int = 4, seed: int = 0) -> tuple[tuple[str, ...], ...]:
    """:data:`TUNE_SCENES` split into ``k`` disjoint folds for cross-validation.

    A seeded permutation dealt round-robin, so the folds differ in size by at
    most one and are the same on every machine.  Choose a setting on ``k − 1``
    folds, score it on the one left out, and rotate.

    Examples
    --------
    >>> folds = tune_folds(4)
    >>> len(folds), sum(len(f) for f in folds)
    (4, 28)
    """
    n = len(TUNE_SCENES)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 2 <= k <= n:
        raise ValueError(f"k must be an integer in [2, {n}], got {k!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    order = np.random.default_rng(int(seed)).permutation(n)
    return tuple(tuple(TUNE_SCENES[i] for i in sorted(order[j :: int(k)])) for j in range(int(k)))


#: Folds of :func:`tune_folds` that :func:`training_scenes`' ``hold_out`` picks from.
HOLD_OUT_FOLDS = 4


def training_scenes(hold_out: int = -1) -> tuple[str, ...]:
    """The scenes a network is trained on: every one of :data:`TUNE_SCENES`, or all but fold
    ``hold_out`` of ``tune_folds(4)``, which then stays unseen for choosing between trained
    candidates (``tensor-cosdi train-denoiser … --hold-out K``).

    Parameters
    ----------
    hold_out : int
        ``-1`` (every tuning scene) or a fold index ``0 … 3``.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> len(training_scenes()), len(training_scenes(3)) + len(tune_folds(4)[3])
    (28, 28)
    """
    if isinstance(hold_out, bool) or not isinstance(hold_out, (int, np.integer)):
        raise ValueError(f"hold_out must be -1 or a fold index 0..3, got {hold_out!r}")
    if hold_out == -1:
        return TUNE_SCENES
    if not 0 <= hold_out < HOLD_OUT_FOLDS:
        raise ValueError(
            f"hold_out must be -1 (train on every tuning scene) or a fold index "
            f"0..{HOLD_OUT_FOLDS - 1}, got {hold_out}"
        )
    held = set(tune_folds(HOLD_OUT_FOLDS)[int(hold_out)])
    return tuple(s for s in TUNE_SCENES if s not in held)


def _roots() -> list[Path]:
    """Where the project's research data may be: ``$TENSOR_COSDI_DATA`` alone where it is set (a
    folder named there that is wrong is an error, never passed over for another), else
    ``../shared/data`` next to the source checkout this module was imported from, then
    ``shared/data`` in the current folder or one of its three nearest parents (an installed
    package run from inside its checkout: ``site-packages`` has no data beside it)."""
    env = os.environ.get("TENSOR_COSDI_DATA")
    if env:
        if not Path(env).is_dir():
            state = "is not a folder" if Path(env).exists() else "does not exist"
            raise FileNotFoundError(f"TENSOR_COSDI_DATA={env} {state}; point it at the data folder")
        return [Path(env)]
    roots = [Path(__file__).resolve().parents[1] / ".." / "shared" / "data"]
    try:
        here = Path.cwd().resolve()
    except OSError:  # the current folder was removed
        return roots
    roots += [d / "shared" / "data" for d in (here, *here.parents[:3])]
    return roots


def data_dir(path=None) -> Path:
    """The folder holding the ``NAME.npz`` scenes.

    ``path`` if given, else ``$TENSOR_COSDI_DATA/hsi_train`` (or
    ``$TENSOR_COSDI_DATA`` itself when it holds the scenes) where that variable is set, else
    ``../shared/data/hsi_train`` next to a source checkout or near the
    current folder (:func:`_roots`).  Raises ``FileNotFoundError`` saying
    where it looked.
    """
    if path is not None:
        candidates = [Path(path)]
    else:
        candidates = [c for r in _roots() for c in (r / "hsi_train", r)]
    for c in candidates:
        if c.is_dir() and any(c.glob("*.npz")):
            return c
    raise FileNotFoundError(
        "no hyperspectral scenes (NAME.npz) found; looked in "
        + ", ".join(map(str, candidates))
        + " — set TENSOR_COSDI_DATA to the research data folder (the one holding hsi_train/ "
        "and masks/)"
    )


#: The environment variable that lets the gallery examples run on seeded stand-ins where the
#: research data are absent (``TENSOR_COSDI_ALLOW_FALLBACK=1``); without it they stop.
FALLBACK_ENV = "TENSOR_COSDI_ALLOW_FALLBACK"


def stand_in(err: Exception, instead: str) -> str:
    """What an example says when it runs on ``instead`` because the research data are missing
    (``err``, the ``FileNotFoundError`` of :func:`data_dir` / :func:`data_file`) — only where
    :data:`FALLBACK_ENV` is ``1``.  Otherwise a ``FileNotFoundError`` saying what is missing,
    how to point to the data and how to allow the stand-in: nothing falls back unasked.

    Examples
    --------
    >>> import os
    >>> os.environ[FALLBACK_ENV] = "1"
    >>> stand_in(FileNotFoundError("no hsi_train folder"), "the ColorChecker")
    'no hsi_train folder; using the ColorChecker instead'
    >>> del os.environ[FALLBACK_ENV]
    >>> stand_in(FileNotFoundError("no hsi_train folder"), "the ColorChecker")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    FileNotFoundError: no hsi_train folder — set TENSOR_COSDI_DATA ... to run on the ColorChecker...
    """
    if os.environ.get(FALLBACK_ENV, "").strip() != "1":
        raise FileNotFoundError(
            f"{err} — set TENSOR_COSDI_DATA to the research data, or {FALLBACK_ENV}=1 to run "
            f"on {instead} instead"
        )
    return f"{err}; using {instead} instead"


def scene_or(name: str, fallback: str) -> tuple[str, str | None]:
    """``(name, None)`` when the research scenes are here; else ``(fallback, note)`` where
    :data:`FALLBACK_ENV` allows it (:func:`stand_in`), and a ``FileNotFoundError`` otherwise.

    Examples
    --------
    >>> import os
    >>> os.environ[FALLBACK_ENV] = "1"
    >>> scene, note = scene_or("cave.face", "colorchecker")
    >>> scene in ("cave.face", "colorchecker")
    True
    >>> del os.environ[FALLBACK_ENV]
    """
    try:
        data_dir()
    except FileNotFoundError as exc:
        return fallback, stand_in(f"no hsi_train folder ({exc})", repr(fallback))
    return name, None


def data_file(relative) -> Path:
    """A file or folder of the research data (not shipped), e.g. ``"masks/tsa_mask256.mat"``:
    under ``$TENSOR_COSDI_DATA``, else under ``../shared/data`` next to a source checkout.

    Raises ``FileNotFoundError`` saying where it looked, so an example can
    fall back to seeded stand-ins and say so.

    Examples
    --------
    >>> try:
    ...     path = data_file("masks/tsa_mask256.mat")
    ... except FileNotFoundError as err:
    ...     path = None  # a plain install: use a seeded random code instead
    """
    if not isinstance(relative, (str, os.PathLike)):
        raise ValueError(
            f"data_file takes a path inside the research data folder (e.g. "
            f"'masks/tsa_mask256.mat'), got {type(relative).__name__}"
        )
    rel = Path(relative)
    if rel.is_absolute() or ".." in rel.parts or not rel.parts:
        raise ValueError(
            f"data_file takes a relative path inside the research data folder, got {str(rel)!r}"
        )
    tried = [r / rel for r in _roots()]
    for p in tried:
        if p.exists():
            return p
    raise FileNotFoundError(
        f"{relative} is not in the research data; looked in "
        + ", ".join(map(str, tried))
        + " — set TENSOR_COSDI_DATA to the folder that holds it"
    )


def _scene_arrays(p: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(cube, wavelengths)`` of a scene file, read through the bounded readers of
    :mod:`tensor_cosdi.io.files` (declared sizes checked before anything is allocated; no
    pickles; regular files only) and checked: a 3-D cube of unsigned integers or floats,
    finite and non-negative, and one increasing band centre in nm per band."""
    from .io.files import read_array, require_file

    require_file(p, "scene file")
    try:
        raw = read_array(p, "cube")
        wl = read_array(p, "wavelengths_nm")
    except KeyError as e:  # its message lists what the file holds
        raise ValueError(
            f"expected arrays 'cube' and 'wavelengths_nm' in a scene file: {e.args[0]}"
        ) from None
    if raw.dtype.kind not in "uf":
        raise ValueError(
            f"{p}: 'cube' must hold unsigned integers or floats, got {raw.dtype} "
            "(signed, boolean and complex values are not light)"
        )
    if raw.ndim != 3:
        raise ValueError(f"{p}: 'cube' must be (rows, columns, bands), got shape {raw.shape}")
    if wl.dtype.kind not in "iuf" or wl.ndim != 1:
        raise ValueError(
            f"{p}: 'wavelengths_nm' must be 1-D numbers, got {wl.dtype} of shape {wl.shape}"
        )
    wl = check_wavelengths_nm(wl, f"{p}: wavelengths_nm")
    if wl.size != raw.shape[2]:
        raise ValueError(f"{p}: cube of shape {raw.shape} does not match {wl.size} wavelengths")
    if wl.size > 1 and not np.all(np.diff(wl) > 0):
        raise ValueError(f"{p}: wavelengths_nm must increase strictly, got {wl.tolist()}")
    if raw.dtype.kind == "f" and not np.all(np.isfinite(raw)):
        raise ValueError(f"{p}: 'cube' holds NaN or infinite values")
    if raw.dtype.kind == "f" and raw.size and raw.min() < 0:
        raise ValueError(f"{p}: 'cube' holds negative values (min {raw.min():g}); light is ≥ 0")
    return raw, wl


def _crop_shape(shape) -> tuple[int, int]:
    try:
        h, w = shape
    except (TypeError, ValueError):
        raise ValueError(f"shape must be (rows, columns), got {shape!r}") from None
    return integer("shape rows", h, low=1), integer("shape columns", w, low=1)


def load_hsi(
    name, wavelengths=None, *, shape=None, folder=None, dtype="float64"
) -> tuple[np.ndarray, np.ndarray]:
    """A real scene as ``(cube, wavelengths)``: reflectance in [0, 1], ``(rows, columns, bands)``.

    Parameters
    ----------
    name : str or path
        A scene of :data:`HSI_SCENES` (looked up in :func:`data_dir`) or a
        path to an ``.npz`` with ``cube`` (unsigned integers, scaled by their
        type's maximum, or floats; finite and non-negative) and
        ``wavelengths_nm`` (strictly increasing nm, one per band).  The file is
        read with :func:`tensor_cosdi.io.read_array`: its declared sizes are
        checked before anything is allocated, and pickles are refused.
    wavelengths : array of nm, optional
        Resample onto these band centres by linear interpolation (each must
        lie inside the scene's range); default the scene's own bands.
        ``"kaist"`` means :data:`KAIST_WAVELENGTHS`.
    shape : (rows, columns), optional
        A centred crop of this size.
    dtype : "float64" or "float32"

    Raises
    ------
    FileNotFoundError
        No such scene file (or no data folder).
    ValueError
        An unknown scene name, a file that is not a regular file, or one whose arrays
        break the rules above (each message names the file and what was wrong).
    """
    dtype = precision("dtype", dtype)
    p = Path(name)
    if p.suffix != ".npz":
        if name not in HSI_SCENES:
            raise ValueError(
                f"unknown scene {name!r}; the hsi_train scenes are {list(HSI_SCENES)} "
                "(or pass a path to an .npz)"
            )
        p = data_dir(folder) / f"{name}.npz"
    raw, wl = _scene_arrays(p)
    scale = float(np.iinfo(raw.dtype).max) if raw.dtype.kind == "u" else 1.0
    cube = raw.astype(np.float64) / scale
    if shape is not None:
        h, w = _crop_shape(shape)
        if h > cube.shape[0] or w > cube.shape[1]:
            raise ValueError(f"crop {shape} is larger than the scene's {cube.shape[:2]}")
        r0, c0 = (cube.shape[0] - h) // 2, (cube.shape[1] - w) // 2
        cube = cube[r0 : r0 + h, c0 : c0 + w]
    if wavelengths is not None:
        if isinstance(wavelengths, str) and wavelengths == "kaist":
            target = KAIST_WAVELENGTHS
        else:
            target = check_wavelengths_nm(wavelengths, "wavelengths")
            if target.ndim != 1:
                raise ValueError(f"wavelengths must be 1-D band centres, got shape {target.shape}")
        if target.min() < wl.min() or target.max() > wl.max():
            raise ValueError(
                f"wavelengths {target.min():g}–{target.max():g} nm lie outside the scene's "
                f"{wl.min():g}–{wl.max():g} nm"
            )
        idx = np.clip(np.searchsorted(wl, target) - 1, 0, wl.size - 2)
        t = (target - wl[idx]) / (wl[idx + 1] - wl[idx])
        cube = cube[:, :, idx] * (1 - t) + cube[:, :, idx + 1] * t
        wl = target
    return np.ascontiguousarray(cube, dtype=dtype), wl


def cave(name: str, shape, wavelengths) -> np.ndarray:
    """A real CAVE scene as a reflectance cube (the scene ``"cave.<name>"`` of
    :data:`tensor_cosdi.scenes.SCENES`).

    Parameters
    ----------
    name : str
        A scene of :data:`tensor_cosdi.datasets.HSI_SCENES` (256×256, 400-700 nm).
    shape : (rows, columns)
        A centred crop, at most 256×256.
    wavelengths : array of nm
        Band centres inside 400-700 nm (linear interpolation,
        :func:`tensor_cosdi.datasets.load_hsi`).

    Returns
    -------
    ndarray (rows, columns, bands), float64 in [0, 1]

    Raises
    ------
    FileNotFoundError
        Without the data folder (``TENSOR_COSDI_DATA`` or ``../shared/data``),
        naming where it looked.
    """
    return load_hsi(name, wavelengths, shape=shape)[0]
