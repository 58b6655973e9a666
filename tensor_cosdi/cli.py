"""The ``tensor-cosdi`` command line.

Sub-commands so far:

``demo``
    The five imagers of the thesis (CASSI-VSI, CASSDI-DFA, C3SLFI, CS2LI,
    Mu-CoSDI) and the SD-CASSI baseline, each simulated on a seeded scene
    built from real data (:func:`tensor_cosdi.studies.make_problem`) and
    reconstructed with the online Tucker dictionary ADMM (``otd``) and
    GAP-TV.  Prints a table (system, method, PSNR, SSIM, SAM, seconds) and
    writes PNG figures per system — measurement, sRGB of the truth and of
    each reconstruction (CIE 1931 2° + D65 via colour-science), the OTD
    error map and, for the depth imagers, the depth channel (truth | OTD)
    with its error in the table — into an output folder it reports.  Never overwrites files
    unless ``--force``.

``plan``
    Write an acquisition plan (``snapshots``, ``patterns`` or ``focal-sweep``)
    as JSON for ``acquire``.

``acquire``
    Run a plan against a serial trigger device (:mod:`tensor_cosdi.io.triggers`):
    per frame, send the DMD / mirror / projector commands, trigger the camera,
    wait for the camera software to write the frame into ``--frames-dir``, and
    log it (resumable: run again after an interruption).

``reconstruct``
    Capture files + a calibration bundle (the system) → a reconstruction
    bundle: dark/flat correction, region of interest, binning, the system's
    frame layout, any registered method, provenance hashes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["main", "build_parser"]


from .demo import demo_cases, run_demo  # noqa: E402  (the demo sub-command)


def __getattr__(name):
    if name == "DEMO_CASES":  # built from the registry on first use
        return demo_cases()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _option_value(text: str):
    import json

    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    key, value = text.split("=", 1)
    try:
        return key, json.loads(value)
    except ValueError:
        return key, value


def run_plan(args) -> int:
    from .io import AcquisitionPlan

    if args.kind == "snapshots":
        plan = AcquisitionPlan.snapshots(args.count, suffix=args.suffix)
    elif args.kind == "patterns":
        plan = AcquisitionPlan.patterns(args.count, suffix=args.suffix)
    else:
        if not args.zernike:
            raise ValueError(
                "focal-sweep needs --zernike J:A[,J:A…] per step, e.g. --zernike 4:-1,6:0.9 "
                "--zernike 4:0,6:0.9"
            )
        steps = []
        for spec in args.zernike:
            try:
                steps.append(
                    {int(j): float(a) for j, a in (item.split(":") for item in spec.split(","))}
                )
            except ValueError:
                raise ValueError(
                    f"--zernike {spec!r}: expected J:A pairs separated by commas, e.g. 4:0.5,6:0.9"
                ) from None
        if args.count != len(steps):
            raise ValueError(f"count {args.count} does not match the {len(steps)} --zernike steps")
        plan = AcquisitionPlan.focal_sweep(steps, suffix=args.suffix)
    path = plan.save(args.out, overwrite=args.force)
    print(f"plan with {len(plan.steps)} frames written to {path}")
    return 0


def run_acquire(args) -> int:
    from .io import Acquisition, AcquisitionPlan, DeviceError, FolderCamera, SerialDevice

    plan = AcquisitionPlan.load(args.plan)
    camera = FolderCamera(args.frames_dir, timeout=args.frame_timeout)
    with SerialDevice(
        args.port, baudrate=args.baudrate, timeout=args.timeout, retries=args.retries
    ) as dev:
        acq = Acquisition(plan, dev, args.log, camera)
        before = len(plan.steps) - len(acq.remaining())
        try:
            written = acq.run(progress=not args.quiet)
        except DeviceError as e:
            print(f"tensor-cosdi acquire: device error: {e}", file=sys.stderr)
            return 3
    print(
        f"{len(written)} frame(s) acquired ({before} already in {args.log}); {len(plan.steps)} of "
        f"{len(plan.steps)} done"
    )
    return 0


def run_reconstruct(args) -> int:
    direct = [n for n in ("system", "mask", "measurement") if getattr(args, n) is not None]
    if direct:
        if args.calibration or args.frames:
            raise ValueError(
                "give either --system/--mask/--measurement (direct path) or a calibration bundle "
                "and frames, not both"
            )
        return _reconstruct_direct(args)
    if not args.calibration or not args.frames:
        raise ValueError(
            "reconstruct needs --system, --mask and --measurement (direct path) or a calibration "
            "bundle and frames"
        )
    from . import reconstruct
    from .colour import reflectance
    from .io import frame_paths, frames_to_measurement, load_bundle, load_frames, save_bundle

    out = Path(args.out)
    if out.suffix != ".npz":
        out = out.with_name(out.name + ".npz")
    if out.exists() and not args.force:
        raise FileExistsError(f"{out} exists; pass --force to replace it")
    defaults = _method_defaults(args.method)  # an unknown method fails before any file is read
    cal = load_bundle(args.calibration)
    if cal.system is None:
        raise ValueError(
            f"{args.calibration}: the calibration bundle holds no system; save one with "
            f"save_bundle(system=…)"
        )
    refs = {
        Path(x).resolve() for x in (args.dark, args.flat) if x
    }  # a dark/flat kept beside the frames is not a frame
    sources = [
        p
        for src in args.frames
        for p in frame_paths(src, pattern=args.pattern, exclude=refs)
        if p.resolve() not in refs
    ]
    frames = load_frames(
        sources, dark=args.dark, flat=args.flat, roi=args.roi, binning=args.binning
    )
    g = frames_to_measurement(cal.system, frames)
    options = dict(args.option or [])
    if "progress" in defaults:
        options.setdefault("progress", not args.quiet)
    t0 = time.perf_counter()
    res = reconstruct(cal.system, g, args.method, **options)
    seconds = time.perf_counter() - t0
    extra = {}
    if "white" in cal.calibration and cal.calibration["white"].shape == tuple(
        cal.system.cube_shape
    ):
        extra["reflectance"] = reflectance(
            res.cube, cal.calibration["white"], cal.calibration.get("dark", 0.0)
        )
    depth = res.depth
    files = [*sources, Path(args.calibration)] + [Path(p) for p in (args.dark, args.flat) if p]
    save_bundle(
        out,
        system=cal.system,
        measurement=g,
        cube=res.cube,
        depth=None if depth is None else np.asarray(depth),
        calibration=cal.calibration,
        arrays=extra,
        sources=files,
        overwrite=args.force,
        metadata={
            "method": args.method,
            "options": {k: v for k, v in res.options.items() if _jsonable(v)},
            "seconds": seconds,
            "iterations": res.iterations,
            "roi": args.roi,
            "binning": args.binning,
        },
    )
    print(
        f"{type(cal.system).__name__} {tuple(cal.system.cube_shape)} reconstructed with "
        f"{args.method} in "
        f"{seconds:.1f} s ({res.iterations} iterations, residual "
        f"{res.history['residual'][-1]:.3g}); written to {out}"
    )
    return 0


def _wavelength_range(text: str, n: int) -> np.ndarray:
    """``"START:STOP"`` (nm) → ``n`` evenly spaced band centres."""
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise ValueError(f"--wavelengths must be START:STOP in nm, got {text!r}") from None
    return np.linspace(lo, hi, n)


def _system_from_args(args, code):
    import inspect

    from .systems import REGISTRY

    cls = REGISTRY[args.system]  # an unknown name lists the registered ones
    params = inspect.signature(cls.__init__).parameters
    kwargs = dict(args.system_option or [])
    named = {"n_bands": args.bands, "shifts": args.shift}
    if args.wavelengths:
        if args.bands is None:
            raise ValueError("--wavelengths needs --bands")
        named["wavelengths"] = _wavelength_range(args.wavelengths, args.bands)
    for k, v in named.items():
        if v is not None:
            if k not in params:
                raise ValueError(f"{args.system} takes no {k!r}; its arguments: {list(params)[1:]}")
            kwargs[k] = int(v) if k == "shifts" and float(v).is_integer() else v
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
    from . import reconstruct
    from .io import read_array, save_bundle
    from .io.files import split_key

    for name in ("system", "mask", "measurement"):
        if getattr(args, name) is None:
            raise ValueError(f"the direct path needs --{name}")
    out = Path(args.out)
    if out.exists() and not args.force:
        raise FileExistsError(f"{out} exists; pass --force to replace it")
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
    options = dict(args.option or [])
    if "progress" in defaults:
        options.setdefault("progress", not args.quiet)
    t0 = time.perf_counter()
    res = reconstruct(system, g, args.method, **options)
    seconds = time.perf_counter() - t0
    depth = res.depth
    save_bundle(
        out,
        system=system,
        measurement=g,
        cube=np.asarray(res.cube, dtype=np.float32),
        depth=None if depth is None else np.asarray(depth),
        sources=[Path(mask_path), Path(meas_path)],
        overwrite=args.force,
        metadata={
            "method": args.method,
            "options": {k: v for k, v in res.options.items() if _jsonable(v)},
            "seconds": seconds,
            "iterations": res.iterations,
            "mask": args.mask,
            "measurement": args.measurement,
        },
    )
    print(
        f"{type(system).__name__} {tuple(system.cube_shape)} reconstructed with {args.method} in "
        f"{seconds:.1f} s ({res.iterations} iterations, residual "
        f"{res.history['residual'][-1]:.3g}); written to {out}"
    )
    return 0


def _cube_and_wavelengths(spec, wavelengths):
    from .io import files, load_bundle

    path, key = files.split_key(spec)
    p = Path(path)
    suffix = files._suffix(p)
    bundle = None
    if key is None and suffix in (".h5", ".hdf5"):
        import h5py

        with h5py.File(p, "r") as f:
            is_bundle = "tensor_cosdi_bundle" in f.attrs
        bundle = load_bundle(p) if is_bundle else None
    elif key is None and suffix == ".npz":
        with np.load(p, allow_pickle=False) as z:
            is_bundle = "__bundle__" in z.files
        bundle = load_bundle(p) if is_bundle else None
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
        wl = _wavelength_range(wavelengths, cube.shape[2])
    if wl is None:
        raise ValueError(f"{p} holds no wavelengths; pass --wavelengths START:STOP (nm)")
    return p, cube, np.asarray(wl, dtype=np.float64)


def run_preview(args) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from . import plot
    from .io._atomic import atomic_write

    path, cube, wl = _cube_and_wavelengths(args.file, args.wavelengths)
    out = Path(args.out) if args.out else path.with_name(path.stem + "_preview.png")
    if out.exists() and not args.force:
        raise FileExistsError(f"{out} exists; pass --force to replace it")
    points = []
    for text in args.points:
        try:
            r, c = (int(v) for v in text.split(","))
        except ValueError:
            raise ValueError(f"--points takes ROW,COL pairs, got {text!r}") from None
        points.append((r, c))
    fig, axes = plt.subplots(
        1, 2 if points else 1, figsize=(9 if points else 4.5, 4), squeeze=False
    )
    ax = plot.preview(cube, wl, ax=axes[0, 0], title=path.name)
    for k, (r, c) in enumerate(points):
        ax.plot(c, r, "o", mfc="none", color=f"C{k % 10}", ms=8)
    if points:
        plot.spectra(cube, wl, points, ax=axes[0, 1])
    fig.tight_layout()
    atomic_write(out, lambda tmp: fig.savefig(tmp, dpi=120, format="png"), overwrite=args.force)
    plt.close(fig)
    print(f"wrote {out}")
    return 0


def run_info(args) -> int:
    import json

    from .io import files

    path = Path(args.file)
    suffix = files._suffix(path)
    print(f"{path} ({path.stat().st_size if path.is_file() else 0} bytes)")
    if suffix == ".hdr":
        cube, wl = files.read_cube(path)
        entries = {"cube": (cube.shape, cube.dtype, None)}
    else:
        entries = files._entries(path, suffix)
    for name, (shape, dtype, _) in entries.items():
        print(f"  {name}: {tuple(int(n) for n in shape)} {np.dtype(dtype)}")
    doc = None
    if suffix in (".h5", ".hdf5"):
        import h5py

        with h5py.File(path, "r") as f:
            raw = f.attrs.get("tensor_cosdi_bundle")
        doc = None if raw is None else json.loads(raw)
    elif suffix == ".npz" and "__bundle__" in entries:
        doc = json.loads(str(entries["__bundle__"][2]()))
    if doc is None and suffix != ".hdr":
        try:
            _, wl = files.read_cube(path)
        except (ValueError, KeyError):
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
        for src in doc.get("provenance", []):
            print(f"  source: {src.get('path')} sha256 {src.get('sha256')}")
        if doc.get("metadata"):
            print(f"  metadata: {json.dumps(doc['metadata'])[:400]}")
    return 0


def _method_defaults(name):
    from .solvers import METHODS

    return METHODS[name].defaults  # an unknown name is an error listing the registered ones


def _jsonable(v) -> bool:
    import json

    try:
        json.dumps(v)
        return True
    except (TypeError, ValueError):
        return False


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tensor-cosdi", description="Compressive spectral and spectral-depth imaging"
    )
    from . import __version__

    parser.add_argument("--version", action="version", version=f"tensor-cosdi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser(
        "demo",
        help="simulate and reconstruct the five imagers (and SD-CASSI) on seeded real-data scenes",
    )
    demo.add_argument(
        "--size",
        type=_positive_int,
        default=64,
        help="rows and columns, a multiple of 4 (default 64)",
    )
    demo.add_argument(
        "--bands", type=_positive_int, default=28, help="spectral bands, 450–650 nm (default 28)"
    )
    demo.add_argument(
        "--snr-db", type=float, default=30.0, help="measurement SNR in dB (default 30)"
    )
    demo.add_argument("--seed", type=int, default=0, help="seed of codes and noise (default 0)")
    demo.add_argument("--out", default="tensor-cosdi-demo", help="output folder for PNG files")
    demo.add_argument("--force", action="store_true", help="overwrite existing PNG files")
    demo.add_argument("--quiet", action="store_true", help="no progress bar")
    demo.set_defaults(func=run_demo)

    plan = sub.add_parser("plan", help="write an acquisition plan (JSON) for `acquire`")
    plan.add_argument("kind", choices=("snapshots", "patterns", "focal-sweep"))
    plan.add_argument("count", type=_positive_int, help="number of frames")
    plan.add_argument("out", help="plan file to write")
    plan.add_argument(
        "--zernike", action="append", help="focal-sweep: J:A[,J:A…] Zernike waves per step (repeat)"
    )
    plan.add_argument("--suffix", default=".tif", help="frame file suffix (default .tif)")
    plan.add_argument("--force", action="store_true", help="overwrite an existing plan file")
    plan.set_defaults(func=run_plan)

    acq = sub.add_parser("acquire", help="run an acquisition plan against a serial trigger device")
    acq.add_argument("plan", help="plan file (tensor-cosdi plan …)")
    acq.add_argument(
        "--port",
        required=True,
        help="serial port or pyserial URL (/dev/ttyACM0, socket://…, loop://)",
    )
    acq.add_argument(
        "--frames-dir", required=True, help="folder the camera software writes frames into"
    )
    acq.add_argument(
        "--log",
        required=True,
        help="frame log (JSON lines); an existing log for this plan is resumed",
    )
    acq.add_argument("--baudrate", type=_positive_int, default=115200)
    acq.add_argument(
        "--timeout", type=float, default=1.0, help="seconds to wait for each acknowledgement"
    )
    acq.add_argument(
        "--retries", type=int, default=2, help="re-sends after a timeout or garbage reply"
    )
    acq.add_argument(
        "--frame-timeout", type=float, default=10.0, help="seconds to wait for each frame file"
    )
    acq.add_argument("--quiet", action="store_true", help="no progress bar")
    acq.set_defaults(func=run_acquire)

    rec = sub.add_parser(
        "reconstruct",
        help="measurement + mask files → cube (direct), or frames + calibration bundle → bundle",
        description=(
            "Direct path: tensor-cosdi reconstruct --system sd_cassi --mask MASK[:KEY] --shift 2 "
            "--bands 28 --measurement MEAS[:KEY] --out cube.h5.  Bundle path: tensor-cosdi "
            "reconstruct CALIBRATION FRAMES… --out out.npz."
        ),
    )
    rec.add_argument(
        "calibration", nargs="?", help="bundle holding the system (tensor_cosdi.io.save_bundle)"
    )
    rec.add_argument(
        "frames", nargs="*", help="frame files or a folder, in the system's frame order"
    )
    rec.add_argument("--system", help="direct path: a name of systems.REGISTRY (e.g. sd_cassi)")
    rec.add_argument("--mask", help="direct path: coded aperture file[:variable]")
    rec.add_argument("--measurement", help="direct path: measurement file[:variable]")
    rec.add_argument("--bands", type=_positive_int, help="direct path: number of bands")
    rec.add_argument("--shift", type=float, help="direct path: dispersion in pixels per band")
    rec.add_argument(
        "--wavelengths", help="direct path: START:STOP in nm (band centres, evenly spaced)"
    )
    rec.add_argument(
        "--system-option",
        action="append",
        type=_option_value,
        help='direct path: another system argument key=value, e.g. modality="lf" (repeat)',
    )
    rec.add_argument(
        "--out", required=True, help="bundle to write: .h5 (HDF5) or .npz (bundle path: .npz)"
    )
    rec.add_argument("--method", default="otd", help="reconstruction method (default otd)")
    rec.add_argument(
        "--option", action="append", type=_option_value, help="method option key=value (repeat)"
    )
    rec.add_argument(
        "--pattern",
        default="*",
        help="glob for frame files inside a folder (default: all frame files)",
    )
    rec.add_argument("--dark", help="dark frame file")
    rec.add_argument("--flat", help="flat/white frame file")
    rec.add_argument(
        "--roi",
        type=int,
        nargs=4,
        metavar=("ROW0", "ROW1", "COL0", "COL1"),
        help="region of interest",
    )
    rec.add_argument(
        "--binning", type=_positive_int, default=1, help="sum BINNING×BINNING pixel blocks"
    )
    rec.add_argument("--force", action="store_true", help="overwrite an existing output bundle")
    rec.add_argument("--quiet", action="store_true", help="no progress bar")
    rec.set_defaults(func=run_reconstruct)

    pv = sub.add_parser(
        "preview", help="a labelled PNG of a cube: sRGB preview and spectra at chosen pixels"
    )
    pv.add_argument("file", help="a bundle or cube file (.h5/.mat/.npz/.npy/.hdr/.tif)[:KEY]")
    pv.add_argument("--out", help="PNG to write (default: FILE's name + _preview.png)")
    pv.add_argument(
        "--points", nargs="*", default=[], metavar="ROW,COL", help="pixels whose spectra to plot"
    )
    pv.add_argument("--wavelengths", help="START:STOP in nm when the file holds none")
    pv.add_argument("--force", action="store_true", help="overwrite an existing PNG")
    pv.set_defaults(func=run_preview)

    info = sub.add_parser(
        "info", help="arrays, shapes, dtypes, wavelengths and provenance of a data file"
    )
    info.add_argument("file", help="a .mat/.h5/.npz/.npy/.hdr/.tif file or a bundle")
    info.set_defaults(func=run_info)

    tr = sub.add_parser(
        "train-denoiser",
        help="train the learned spectral denoiser (needs torch) on the tuning scenes",
    )
    _training_options(tr, steps=6000, batch=16)
    tr.add_argument("--patch", type=_positive_int, default=64, help="patch side (even)")
    tr.add_argument("--width", type=_positive_int, default=64, help="convolution channels")
    tr.add_argument("--blocks", type=_positive_int, default=4, help="residual blocks")
    tr.set_defaults(func=run_train_denoiser)

    dc = sub.add_parser(
        "train-dcosnet",
        help="train D-CoSNet (thesis §7, needs torch) for one system on the tuning scenes",
    )
    _training_options(dc, steps=3000, batch=8)
    dc.add_argument("--system", default="sd_cassi", help="sd_cassi or mu_cosdi (default sd_cassi)")
    dc.add_argument("--bands", type=_positive_int, default=28, help="spectral bands (default 28)")
    dc.add_argument("--shift", type=_positive_int, default=2, help="pixels per band (default 2)")
    dc.add_argument("--stages", type=_positive_int, default=3, help="unfolded ADMM stages")
    dc.add_argument("--width", type=_positive_int, default=16, help="channels of the arms' convs")
    dc.add_argument("--unet-width", type=_positive_int, default=32, help="U-Net base channels")
    dc.add_argument(
        "--loss", default="l1+ssim", help="l1+ssim (Eq. 152), l1 or ssim (Table 2's ablation)"
    )
    dc.add_argument(
        "--mask", default="tsa", help="tsa (crops of the real TSA mask), random, or a .npy/.mat"
    )
    dc.add_argument("--patch", type=_positive_int, default=64, help="patch side (multiple of 4)")
    dc.set_defaults(func=run_train_dcosnet)
    return parser


def _training_options(p, *, steps: int, batch: int):
    p.add_argument("--out", required=True, help="weights file to write (.pt)")
    p.add_argument("--steps", type=_positive_int, default=steps, help="optimiser steps")
    p.add_argument("--batch", type=_positive_int, default=batch, help="samples per step")
    p.add_argument("--seed", type=int, default=0, help="seed of samples and noise (default 0)")
    p.add_argument("--data", help="folder of the NAME.npz scenes (default: datasets.data_dir())")
    p.add_argument("--device", help="cpu, cuda, … (default: cuda when available)")
    p.add_argument("--threads", type=_positive_int, help="CPU threads for torch")
    p.add_argument("--resume", action="store_true", help="continue from OUT.ckpt")
    p.add_argument(
        "--stop-after", type=_positive_int, help="stop this run after N steps (resume later)"
    )
    p.add_argument("--force", action="store_true", help="overwrite OUT and start over")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _run_training(args, train, cfg) -> int:
    from .learn import require_torch

    torch = require_torch()
    if args.threads:
        torch.set_num_threads(args.threads)
    summary = train(
        args.out,
        cfg,
        resume=args.resume,
        force=args.force,
        device=args.device,
        folder=args.data,
        progress=not args.quiet,
        command="tensor-cosdi " + " ".join(sys.argv[1:]) if sys.argv else None,
        stop_after=args.stop_after,
    )
    if not summary["finished"]:
        print(f"stopped at step {summary['steps']}; continue with the same command and --resume")
        return 0
    print(
        f"wrote {args.out}: {summary['steps']} steps, loss {summary['final_loss']:.3e}, "
        f"{summary['seconds']:.0f} s on {summary['device']}"
    )
    return 0


def run_train_denoiser(args) -> int:
    from .learn.train import TrainConfig, train_denoiser

    cfg = TrainConfig(
        steps=args.steps,
        batch=args.batch,
        patch=args.patch,
        width=args.width,
        blocks=args.blocks,
        seed=args.seed,
    )
    return _run_training(args, train_denoiser, cfg)


def run_train_dcosnet(args) -> int:
    from .learn.dcosnet import DCoSNetConfig, train_dcosnet

    cfg = DCoSNetConfig(
        system=args.system,
        n_bands=args.bands,
        shift=args.shift,
        stages=args.stages,
        width=args.width,
        unet_width=args.unet_width,
        loss=args.loss,
        mask=args.mask,
        steps=args.steps,
        batch=args.batch,
        patch=args.patch,
        seed=args.seed,
    )
    return _run_training(args, train_dcosnet, cfg.check())


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


from .io.triggers import LockedError  # noqa: E402  (an expected error, reported like the others)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, FileExistsError, FileNotFoundError, ImportError, LockedError) as exc:
        print(f"tensor-cosdi {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
