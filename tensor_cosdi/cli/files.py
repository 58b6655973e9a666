"""``tensor-cosdi reconstruct --system …`` (the direct path from a measurement and a mask
file), ``preview`` and ``info`` — the file-facing sub-commands of :mod:`tensor_cosdi.cli`."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .util import _method_defaults, check_output, done_line, option_dict, run_metadata


def _values(text: str, flag: str, what: str):
    """A comma-separated list or a text / ``.npy`` / ``.csv`` file of numbers (``None`` when
    ``text`` is neither)."""
    if "," in text:
        try:
            return np.array([float(v) for v in text.split(",") if v.strip()])
        except ValueError:
            raise ValueError(what) from None
    p = Path(text)
    if p.is_file():
        from ..io.files import read_array

        try:
            if p.suffix.lower() == ".npy":  # bounded: the declared size is checked first
                v = read_array(p)
            else:
                v = np.loadtxt(p, delimiter="," if p.suffix.lower() == ".csv" else None)
        except Exception as e:
            raise ValueError(f"{flag} {text}: not a file of numbers ({e})") from None
        v = np.asarray(v)
        if v.dtype.kind not in "biuf":
            raise ValueError(f"{flag} {text}: not a file of numbers (dtype {v.dtype})")
        return v.astype(np.float64).reshape(-1)
    return None


def parse_wavelengths(text: str, n: int) -> np.ndarray:
    """``--wavelengths`` → ``n`` band centres in nm, checked.

    ``START:STOP`` (evenly spaced), a comma-separated list of ``n`` values,
    ``kaist`` (the 28 KAIST band centres, :data:`tensor_cosdi.datasets.KAIST_WAVELENGTHS`)
    or a text / ``.npy`` file of ``n`` values.
    """
    from .._units import check_wavelengths_nm

    text = str(text).strip()
    what = (
        "--wavelengths must be START:STOP (nm), a comma-separated list, 'kaist' or a file of "
        f"values; got {text!r}"
    )
    if text.lower() == "kaist":
        from ..datasets import KAIST_WAVELENGTHS

        wl = np.asarray(KAIST_WAVELENGTHS, dtype=np.float64)
    elif ":" in text and "," not in text and not Path(text).is_file():
        try:
            lo, hi = (float(v) for v in text.split(":"))
        except ValueError:
            raise ValueError(what) from None
        wl = np.linspace(lo, hi, n)
    else:
        wl = _values(text, "--wavelengths", what)
        if wl is None:
            raise ValueError(what)
    if wl.size != n:
        raise ValueError(f"--wavelengths gives {wl.size} band centres for {n} bands")
    return check_wavelengths_nm(wl, "--wavelengths")


def parse_shifts(text: str, n):
    """``--shift`` → a step in pixels per band (a number) or one shift per band (a
    comma-separated list or a text / ``.npy`` / ``.csv`` file of ``n`` values, e.g. a prism's
    :meth:`~tensor_cosdi.optics.DoubleAmiciPrism.shifts`); the system checks the values."""
    text = str(text).strip()
    what = (
        "--shift must be a number of pixels per band, a comma-separated list or a file of "
        f"per-band shifts; got {text!r}"
    )
    try:
        step = float(text)
    except ValueError:
        step = None
    if step is not None:
        if not np.isfinite(step):
            raise ValueError(what)
        # an integral step as an int (the integer shear kernel), unless it is too large to be one
        return int(step) if step.is_integer() and abs(step) < 2**53 else step
    shifts = _values(text, "--shift", what)
    if shifts is None:
        raise ValueError(what)
    if n is None:
        raise ValueError("--shift with one shift per band needs --bands")
    if shifts.size != n:
        raise ValueError(f"--shift gives {shifts.size} shifts for {n} bands")
    if not np.all(np.isfinite(shifts)):
        raise ValueError(f"--shift holds NaN or inf: {text!r}")
    return shifts


def _system_from_args(args, code):
    import inspect

    from ..systems import REGISTRY

    cls = REGISTRY[args.system]  # an unknown name lists the registered ones
    params = inspect.signature(cls.__init__).parameters
    kwargs = option_dict(args.system_option, "--system-option")
    named = {"n_bands": args.bands}
    if args.shift is not None:
        named["shifts"] = parse_shifts(args.shift, args.bands)
    if args.wavelengths:
        if args.bands is None:
            raise ValueError("--wavelengths needs --bands")
        named["wavelengths"] = parse_wavelengths(args.wavelengths, args.bands)
    for k, v in named.items():
        if v is not None:
            if k not in params:
                raise ValueError(f"{args.system} takes no {k!r}; its arguments: {list(params)[1:]}")
            kwargs[k] = v
    takes_kwargs = any(p.kind is p.VAR_KEYWORD for p in params.values())
    unknown = [k for k in kwargs if k not in params and not takes_kwargs]
    if unknown:
        raise ValueError(
            f"{args.system} takes no argument(s) {unknown}; its arguments: {list(params)[1:]}"
        )
    missing = [
        k
        for k, p in list(params.items())[2:]
        if p.default is p.empty and p.kind is p.KEYWORD_ONLY and k not in kwargs
    ]
    if missing:
        flags = {"n_bands": "--bands"}
        raise ValueError(
            f"{args.system} needs "
            + ", ".join(flags.get(k, f"--system-option {k}=…") for k in missing)
        )
    return cls(code, **kwargs)


def _reconstruct_direct(args) -> int:
    from .. import reconstruct
    from ..io import read_array, save_bundle
    from ..io.files import split_key

    for name in ("system", "mask", "measurement"):
        if getattr(args, name) is None:
            raise ValueError(f"the direct path needs --{name}")
    out = Path(args.out)
    if out.suffix.lower() not in (".npz", ".h5", ".hdf5"):  # never a name other than the one asked
        raise ValueError(
            f"--out {args.out}: a reconstruction bundle is an .h5 or .npz file (e.g. {out.stem}.h5)"
        )
    check_output(out, args.force)
    defaults = _method_defaults(args.method)
    mask_path, mask_key = split_key(args.mask)
    meas_path, meas_key = split_key(args.measurement)
    code = np.asarray(read_array(mask_path, mask_key), dtype=np.float64)
    g = np.asarray(read_array(meas_path, meas_key))
    if g.dtype.kind not in "biuf":
        raise ValueError(f"{args.measurement}: the measurement must be numeric, got {g.dtype}")
    if not np.all(np.isfinite(g)):
        raise ValueError(f"{args.measurement}: the measurement holds NaN or infinite values")
    system = _system_from_args(args, code)
    if g.shape != tuple(system.measurement_shape):
        raise ValueError(
            f"{args.measurement}: measurement shape {g.shape} does not match the system's "
            f"{tuple(system.measurement_shape)} (code {code.shape}, options as given)"
        )
    g = g.astype(np.float32 if g.dtype.itemsize <= 4 else np.float64)
    registration = {}
    if getattr(args, "calibrate", False):
        system, registration = _registered(system, g)
    options = option_dict(args.option, "--option")
    if "progress" in defaults:
        options.setdefault("progress", not args.quiet)
    t0 = time.perf_counter()
    res = reconstruct(system, g, args.method, **options)
    seconds = time.perf_counter() - t0
    depth = res.depth
    out = save_bundle(
        out,
        system=system,
        measurement=g,
        cube=np.asarray(res.cube, dtype=np.float32),
        depth=None if depth is None else np.asarray(depth),
        sources=[Path(mask_path), Path(meas_path)],
        overwrite=args.force,
        metadata=run_metadata(
            args, res, seconds, mask=args.mask, measurement=args.measurement, **registration
        ),
    )
    print(done_line(system, args.method, res, seconds, out))
    return 0


def _registered(system, g):
    """``--calibrate``: the system with its code moved to where the capture says it sits, and
    what the bundle records; an estimate that does not stand out is an error, not a guess."""
    from ..io import estimate_registration, mirror_symmetric

    # the direction is searched only where a capture can decide it (unevenly spaced shifts)
    search = callable(getattr(system, "mirrored", None)) and not mirror_symmetric(system.shifts)
    # refuses imagers without a movable 2-D code
    reg = estimate_registration(system, g, direction="search" if search else "keep")
    line = (
        f"mask registration: rows {reg.row_offset:+.2f} px, columns {reg.col_offset:+.2f} px "
        f"(score {reg.score:.3f}, margin {reg.margin:.3f}); "
        + (
            f"dispersion {'as given' if reg.direction == 1 else 'mirrored'} (direction margin "
            f"{reg.direction_margin:.3f})"
            if search
            else "dispersion as given (evenly spaced shifts: a capture cannot tell its direction)"
        )
    )
    if not reg.reliable:
        raise ValueError(
            f"{line} does not stand out (needs score ≥ {reg.MIN_SCORE}, margin ≥ "
            f"{reg.MIN_MARGIN}"
            + (f", direction margin ≥ {reg.MIN_DIRECTION_MARGIN}" if search else "")
            + "); reconstruct without --calibrate or check the mask file"
        )
    print(line)
    keys = ("row_offset", "col_offset", "score", "margin", "direction", "direction_margin")
    return reg.apply(system), {"registration": {k: getattr(reg, k) for k in keys}}


def _cube_and_wavelengths(spec, wavelengths):
    from ..io import files, load_bundle
    from ..io.bundle import bundle_document

    path, key = files.split_key(spec)
    p = Path(path)
    files.cube_suffix(p)  # an unknown extension is an error naming the known ones
    bundle = load_bundle(p) if key is None and bundle_document(p) is not None else None
    if bundle is not None:
        if bundle.cube is None:
            raise ValueError(f"{p}: the bundle holds no cube (kind {bundle.info.get('kind')!r})")
        cube = np.asarray(bundle.cube)
        wl = None if bundle.system is None else getattr(bundle.system, "wavelengths", None)
        if cube.ndim > 3:  # a spectral view of 4-D cubes (patterns, depth planes)
            cube = np.asarray(bundle.system.spectral_view(cube))
    else:
        cube, wl = files.read_cube(p, key)
    if wavelengths:
        wl = parse_wavelengths(wavelengths, cube.shape[2])
    if wl is None:
        raise ValueError(
            f"{p} holds no wavelengths; pass --wavelengths START:STOP, a list or a file (nm)"
        )
    return p, cube, np.asarray(wl, dtype=np.float64)


def preview_target(spec: str, out, force: bool) -> Path:
    """The PNG a preview of ``spec`` goes to (``out``, else its name + ``_preview.png``), checked
    before any work: an existing file without ``force`` and a missing matplotlib are errors."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("a preview needs matplotlib: pip install 'tensor_cosdi[plot]'") from None
    from ..io import files

    path, _ = files.split_key(spec)
    target = Path(out) if out else Path(path).with_name(Path(path).stem + "_preview.png")
    if target.suffix.lower() != ".png":
        raise ValueError(f"--out {target}: a preview is a .png file")
    check_output(target, force)
    return target


def parse_points(texts) -> list[tuple[int, int]]:
    """``ROW,COL`` strings as integer pairs, or a one-line ``ValueError``."""
    points = []
    for text in texts or []:
        try:
            r, c = (int(v) for v in text.split(","))
        except ValueError:
            raise ValueError(f"--points takes ROW,COL pairs, got {text!r}") from None
        points.append((r, c))
    return points


def write_preview(spec: str, out: Path, points, wavelengths=None, force: bool = False) -> Path:
    """A labelled PNG of the cube in ``spec``: sRGB preview, spectra at ``points``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .. import plot
    from ..io import atomic_write

    path, cube, wl = _cube_and_wavelengths(spec, wavelengths)
    for r, c in points:
        if not (0 <= r < cube.shape[0] and 0 <= c < cube.shape[1]):
            raise ValueError(
                f"--points {r},{c} is outside the cube's {cube.shape[0]}×{cube.shape[1]} pixels"
            )
    fig, axes = plt.subplots(
        1, 2 if points else 1, figsize=(9 if points else 4.5, 4), squeeze=False
    )
    ax = plot.preview(cube, wl, ax=axes[0, 0], title=path.name)
    for k, (r, c) in enumerate(points):
        ax.plot(c, r, "o", mfc="none", color=f"C{k % 10}", ms=8)
    if points:
        plot.spectra(cube, wl, points, ax=axes[0, 1])
    fig.tight_layout()
    atomic_write(out, lambda tmp: fig.savefig(tmp, dpi=120, format="png"), overwrite=force)
    plt.close(fig)
    print(f"wrote {out}")
    return out


def run_preview(args) -> int:
    points = parse_points(args.points)
    write_preview(args.file, preview_target(args.file, args.out, args.force), points,
                  args.wavelengths, args.force)  # fmt: skip
    return 0


def run_info(args) -> int:
    import json

    from ..io import files
    from ..io.bundle import bundle_document

    path = Path(args.file)
    suffix = files.cube_suffix(path)
    if not path.exists():
        raise FileNotFoundError(f"file not found: {path}")
    if path.is_dir():  # a Zarr store: the files it holds (links are refused when read)
        size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file() and not f.is_symlink())
        print(f"{path} (Zarr store, {size} bytes)")
    else:
        print(f"{path} ({path.stat().st_size if path.is_file() else 0} bytes)")
    if suffix == ".hdr":
        cube, wl = files.read_cube(path)
        entries = {"cube": (cube.shape, cube.dtype, None)}
    else:
        entries = files.array_entries(path, suffix)
    for name, (shape, dtype, _) in entries.items():
        print(f"  {name}: {tuple(int(n) for n in shape)} {np.dtype(dtype)}")
    for name, (why, _) in getattr(entries, "skipped", {}).items():
        print(f"  {name}: not read ({why})")
    doc = bundle_document(path)
    if doc is None and suffix != ".hdr":
        try:
            _, wl = files.read_cube(path)
        except (ValueError, KeyError):  # not a cube (a mask, a measurement): no wavelengths
            wl = None
    elif doc is not None:
        wl = None
    if wl is not None:
        print(f"  wavelengths: {len(wl)} bands, {wl[0]:g}–{wl[-1]:g} nm")
    if doc is not None:
        system = doc.get("system", {})
        print(f"  bundle: {doc.get('kind')}, created {doc.get('created')}, {doc.get('software')}")
        if system:
            print(f"  system: {system.get('class')} {system.get('params')}")
            try:
                from ..io import load_bundle

                built = load_bundle(path).system
            except (ValueError, KeyError, OSError) as e:
                print(f"  system: cannot be rebuilt ({e})")
                built = None
            if built is not None:
                wl = np.asarray(built.wavelengths)
                print(
                    f"  wavelengths: {wl.size} bands, {wl[0]:g}–{wl[-1]:g} nm "
                    f"({', '.join(f'{v:g}' for v in wl)})"
                )
                shifts = getattr(built, "shifts", None)
                if shifts is not None:
                    sh = np.asarray(shifts).reshape(-1)
                    print(f"  shifts: {', '.join(f'{v:g}' for v in sh)} px (per band)")
                print(
                    f"  cube {tuple(built.cube_shape)} → measurement "
                    f"{tuple(built.measurement_shape)}"
                )
        for src in doc.get("provenance", []):
            print(f"  source: {src.get('path')} sha256 {src.get('sha256')}")
        for key, value in (doc.get("metadata") or {}).items():  # whole, one line per key
            print(f"  metadata.{key}: {json.dumps(value)}")
    return 0
