"""The ``tensor-cosdi`` command line: this module builds the parser and runs
``plan``, ``acquire`` and the bundle path of ``reconstruct``; :mod:`.files`
holds the direct ``reconstruct`` path, ``preview`` and ``info``,
:mod:`.train` the training commands, :mod:`.demo` the demo, :mod:`.util` the
argument helpers.

Sub-commands:

``demo``
    The five imagers of the thesis (CASSI-VSI, CASSDI-DFA, C3SLFI, CS2LI,
    Mu-CoSDI) and the SD-CASSI baseline, each simulated on a seeded scene
    built from real data (:func:`tensor_cosdi.studies.make_problem`) and
    reconstructed with the online Tucker dictionary ADMM (``otd``) and
    GAP-TV.  Prints a table (system, measured samples per voxel, method, PSNR,
    SSIM, SAM, seconds) and writes PNG figures per system — measurement, sRGB of the truth and of
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

from .demo import demo_cases, run_demo
from .files import (
    _reconstruct_direct,
    parse_points,
    preview_target,
    run_info,
    run_preview,
    write_preview,
)
from .train import _training_options, run_train_dcosnet, run_train_denoiser
from .util import (
    LazyHelp,
    _method_defaults,
    _option_value,
    _positive_int,
    check_output,
    done_line,
    option_dict,
    run_metadata,
)

__all__ = ["main", "build_parser"]


def __getattr__(name):
    if name == "DEMO_CASES":  # built from the registry on first use
        return demo_cases()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def run_plan(args) -> int:
    from ..io import AcquisitionPlan

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
    from ..io import Acquisition, AcquisitionPlan, DeviceError, FolderCamera, SerialDevice

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
    """Either path; with ``--preview``, the PNG's name and matplotlib are checked first and the
    preview is written from the bundle just saved."""
    points = parse_points(args.points)
    if points and not args.preview:
        raise ValueError("--points picks the spectra of --preview; add --preview or drop them")
    target = preview_target(args.out, None, args.force) if args.preview else None
    rc = _reconstruct(args)
    if target is not None:
        write_preview(args.out, target, points, None, args.force)
    return rc


#: Options of ``reconstruct``'s frames path and their unset values: given on the direct path,
#: they are an error (they would do nothing there).
FRAMES_ONLY = {"pattern": "*", "dark": None, "flat": None, "roi": None, "binning": 1}


def _reconstruct(args) -> int:
    direct = [n for n in ("system", "mask", "measurement") if getattr(args, n) is not None]
    if direct:
        if args.calibration or args.frames:
            raise ValueError(
                "give either --system/--mask/--measurement (direct path) or a calibration bundle "
                "and frames, not both"
            )
        frames_only = [
            f"--{name}" for name, unset in FRAMES_ONLY.items() if getattr(args, name) != unset
        ]
        if frames_only:  # each would be ignored on a measurement file: say so, never drop it
            verb = "applies" if len(frames_only) == 1 else "apply"
            raise ValueError(
                f"{', '.join(frames_only)} {verb} to frames (a calibration bundle and --frames); "
                "a file given with --measurement is used as it is"
            )
        return _reconstruct_direct(args)
    if not args.calibration or not args.frames:
        raise ValueError(
            "reconstruct needs --system, --mask and --measurement (direct path) or a calibration "
            "bundle and frames"
        )
    if args.calibrate:
        raise ValueError(
            "--calibrate belongs to the direct path (--system/--mask/--measurement); a "
            "calibration bundle already holds the registered code"
        )
    from .. import reconstruct
    from ..colour import reflectance
    from ..io import frame_paths, frames_to_measurement, load_bundle, load_frames, save_bundle

    defaults = _method_defaults(args.method)  # an unknown method fails before any file is read
    out = Path(args.out)
    if out.suffix != ".npz":  # never a name other than the one asked for
        raise ValueError(
            f"--out {args.out}: a reconstruction bundle is an .npz file (e.g. {out.stem}.npz); "
            "for a plain cube file use the direct path (--system/--mask/--measurement)"
        )
    check_output(out, args.force)
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
    options = option_dict(args.option, "--option")
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
        metadata=run_metadata(args, res, seconds, roi=args.roi, binning=args.binning),
    )
    print(done_line(cal.system, args.method, res, seconds, out))
    return 0


def _systems_help() -> str:
    from ..systems import REGISTRY

    return f"direct path: the imager, one of {', '.join(REGISTRY.names())}"


def _methods_help() -> str:
    from ..solvers import METHODS, methods

    listed = ", ".join(
        f"{n} ({'/'.join(METHODS[n].systems)} only)" if METHODS[n].systems else n for n in methods()
    )
    return f"reconstruction method (default otd): {listed}"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tensor-cosdi", description="Compressive spectral and spectral-depth imaging"
    )
    from .. import __version__

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
    rec.add_argument("--system", help=LazyHelp(_systems_help))
    rec.add_argument("--mask", help="direct path: coded aperture file[:variable]")
    rec.add_argument("--measurement", help="direct path: measurement file[:variable]")
    rec.add_argument("--bands", type=_positive_int, help="direct path: number of bands")
    rec.add_argument(
        "--shift",
        help="direct path: dispersion in pixels per band, or one shift per band (a "
        "comma-separated list or a file of values, e.g. a prism's)",
    )
    rec.add_argument(
        "--wavelengths",
        help="direct path: band centres in nm: START:STOP (evenly spaced), a comma-separated "
        "list, 'kaist' (the 28 KAIST bands) or a text/.npy file with one per band",
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
    rec.add_argument("--method", default="otd", help=LazyHelp(_methods_help))
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
    rec.add_argument(
        "--calibrate",
        action="store_true",
        help="direct path, SD-CASSI: estimate where the mask sits on the sensor (sub-pixel) from "
        "the capture, and the dispersion direction where the shifts are unevenly spaced, and "
        "reconstruct with the mask moved (and the dispersion mirrored) there",
    )
    rec.add_argument(
        "--preview",
        action="store_true",
        help="also write OUT's name + _preview.png (sRGB and spectra; needs matplotlib)",
    )
    rec.add_argument(
        "--points", nargs="*", default=[], metavar="ROW,COL", help="with --preview: spectra here"
    )
    rec.set_defaults(func=run_reconstruct)

    pv = sub.add_parser(
        "preview", help="a labelled PNG of a cube: sRGB preview and spectra at chosen pixels"
    )
    pv.add_argument("file", help="a bundle or cube file (.h5/.mat/.npz/.npy/.hdr/.tif)[:KEY]")
    pv.add_argument("--out", help="PNG to write (default: FILE's name + _preview.png)")
    pv.add_argument(
        "--points", nargs="*", default=[], metavar="ROW,COL", help="pixels whose spectra to plot"
    )
    pv.add_argument(
        "--wavelengths",
        help="band centres in nm when the file holds none: START:STOP, a list, 'kaist' or a file",
    )
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
    tr.add_argument(
        "--conv-rank", type=int, default=0, metavar="K",
        help="each 3x3 convolution in Tucker-2 form through K channels (a faster network; "
        "with --init, factored from that full network's kernels; default 0: full)",
    )  # fmt: skip
    tr.add_argument(
        "--zoom", type=float, default=0.0, metavar="P",
        help="probability that a batch is a magnified view (a smaller crop upsampled to the "
        "patch; default 0)",
    )  # fmt: skip
    tr.add_argument("--zoom-max", type=float, default=3.0, help="largest magnification (default 3)")
    tr.add_argument(
        "--illumination", type=float, default=0.5, metavar="P",
        help="probability of a random illuminant and, apart, of a shading ramp (default 0.5)",
    )  # fmt: skip
    tr.add_argument(
        "--max-shift", type=_positive_int, default=3,
        help="null-space noise: shifts of 1 to this many pixels per band (default 3)",
    )  # fmt: skip
    tr.add_argument(
        "--density-spread", type=float, default=0.2,
        help="null-space noise: code densities in 0.5 ± this (default 0.2)",
    )  # fmt: skip
    tr.add_argument(
        "--init", default="",
        help="starting weights: shipped (fine-tune the package's network) or a train-denoiser "
        ".pt file of the same --width/--blocks (default: random, from --seed)",
    )  # fmt: skip
    tr.add_argument("--warmup", type=int, default=200, help="linear warm-up steps (default 200)")
    tr.set_defaults(func=run_train_denoiser)

    dc = sub.add_parser(
        "train-dcosnet",
        help="train D-CoSNet (thesis §7, needs torch) for one system on the tuning scenes",
    )
    _training_options(dc, steps=3000, batch=8)
    dc.add_argument(
        "--system", default="sd_cassi",
        help="sd_cassi, mu_cosdi or cassi_vsi (default sd_cassi)",
    )  # fmt: skip
    dc.add_argument(
        "--alpha-t", type=float, default=0.7,
        help="CASSI-VSI's beam-splitting ratio (--system cassi_vsi; default 0.7)",
    )  # fmt: skip
    dc.add_argument("--bands", type=_positive_int, default=28, help="spectral bands (default 28)")
    dc.add_argument("--shift", type=_positive_int, default=2, help="pixels per band (default 2)")
    dc.add_argument("--stages", type=_positive_int, default=3, help="unfolded ADMM stages")
    dc.add_argument("--width", type=_positive_int, default=16, help="channels of the arms' convs")
    dc.add_argument("--unet-width", type=_positive_int, default=32, help="U-Net base channels")
    dc.add_argument(
        "--prior", default="unet",
        help="unet (the thesis' per-stage U-Net, from scratch) or spectral (the learned spectral "
        "denoiser shared by the stages, starting from --prior-weights)",
    )  # fmt: skip
    dc.add_argument(
        "--prior-weights", default="shipped",
        help="the spectral prior's starting weights: shipped, or a train-denoiser .pt file",
    )  # fmt: skip
    dc.add_argument(
        "--loss", default="l1+ssim", help="l1+ssim (Eq. 152), l1 or ssim (Table 2's ablation)"
    )
    dc.add_argument(
        "--mask", default="tsa",
        help="tsa (crops of the real TSA mask), random (Bernoulli ½ codes), mixed (TSA crops and "
        "binary codes of density 0.3-0.7, half and half), seeded (one fixed Bernoulli ½ code of "
        "the patch's size drawn from --seed), or a .npy/.mat",
    )  # fmt: skip
    dc.add_argument(
        "--learn-code", action="store_true",
        help="learn the binary code with the network (thesis §7.3), starting from --mask seeded",
    )  # fmt: skip
    dc.add_argument(
        "--code-until", type=float, default=0.5,
        help="fraction of the steps during which a learned code changes; then it is held while "
        "the network adapts (default 0.5)",
    )  # fmt: skip
    dc.add_argument("--patch", type=_positive_int, default=64, help="patch side (multiple of 4)")
    dc.add_argument(
        "--start", default="zero",
        help="zero (the thesis: the ADMM starts at 0), fast (from the first-stage cube that "
        "pnp_fast starts from on clean data) or adaptive (pnp_fast's start on any data: 10 ADMM "
        "iterations more where the sample reads noisy); computed per sample, and by the method",
    )  # fmt: skip
    dc.add_argument(
        "--noise-input", action="store_true",
        help="condition each stage's penalty and U-Net on the estimated SNR (the method "
        "estimates it too)",
    )  # fmt: skip
    dc.add_argument(
        "--init", default=None, metavar="WEIGHTS",
        help="start from these train-dcosnet weights of the same network (a fine-tune; a noise "
        "input they lack starts at 0)",
    )  # fmt: skip
    dc.set_defaults(func=run_train_dcosnet)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except Exception as exc:
        from ..io.triggers import LockedError  # here: --help imports no I/O stack

        if not isinstance(exc, (ValueError, KeyError, OSError, ImportError, LockedError)):
            raise
        # KeyError: a variable missing from a file (its message, not its quoted repr); OSError:
        # a folder given as an output, a missing port, a full disk — one line, no traceback
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"tensor-cosdi {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
