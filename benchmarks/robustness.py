"""Bad input and faults over the public API: a fixed, seeded catalogue of cases, classified.

Every case calls one public entry (system constructors through
``studies.make_problem``, ``reconstruct`` with every method, the file
readers and writers, bundles, frames, metrics, noise, bases, denoisers) with
one bad argument, a corrupted file or an injected fault, and is classified:

* **clear** — an exception of a documented kind (``ValueError``,
  ``TypeError``, ``KeyError``, ``OSError`` and subclasses) whose message names
  the bad argument (one of the case's words); for corrupted or faulted
  cases where no error is due, a result identical to the original also counts
  (the corruption missed the data, the earlier file is intact);
* **obscure** — any other exception, or a message naming none of the words;
* **silent** — a result returned where an error was due, or data that differ
  from what was saved;
* **hang** — no answer within the per-case timeout (``--timeout``, 30 s);
* **crash** — ``MemoryError``, ``RecursionError``, ``SystemExit`` or another
  non-``Exception``, or the process running the case died (segfault, abort,
  out-of-memory kill).

Cases run one by one in a forked worker process: a case that kills its
process or hangs inside C code (where no alarm reaches it) is recorded, the
worker is replaced by a fresh fork and the run goes on (``--in-process``
runs them in this process instead, for debugging).

Targets (issue "nothing lost"): 0 silent, 0 hangs, 0 crashes, ≥ 95 % clear.

    python benchmarks/robustness.py [--only MODULE] [--timeout 30] [--list] [--in-process]
    python benchmarks/robustness.py --selftest --timeout 2   # crash and hang are caught

Prints one line per non-clear case and a table per module; writes
``benchmarks/results/robustness.md``.  Never asserts anything.
"""

from __future__ import annotations

import argparse
import errno
import json
import os
import select
import signal
import sys
import tempfile
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import metrics, noise, studies
from tensor_cosdi.bases import KroneckerBasis
from tensor_cosdi.io import (
    AcquisitionPlan,
    _atomic,
    load_bundle,
    read_frame,
    read_log,
    save_bundle,
    write_frames,
)  # fmt: skip
from tensor_cosdi.io.files import read_array, read_cube, write_cube
from tensor_cosdi.solvers.denoisers import denoise, self_ensemble
from tensor_cosdi.testing import (
    edit_bundle_document,
    hostile_arguments,
    hostile_files,
    rgb_values,
)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CLEAR = (ValueError, TypeError, KeyError, OSError)


@dataclass
class Case:
    module: str
    name: str
    run: Callable  # () -> None / bool (for "same" cases: True when the data are intact)
    words: tuple = ()  # lower-case words one of which the error message must contain
    expect: str = "error"  # "error", or "same" (an error or intact data are both fine)


class Hang(Exception):
    pass


def classify(case: Case, timeout: float) -> tuple[str, str]:
    def alarm(*_):
        raise Hang()

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        out = case.run()
    except Hang:
        return "hang", f"no answer in {timeout:g} s"
    except (MemoryError, RecursionError) as exc:
        return "crash", repr(exc)[:160]
    except Exception as exc:  # noqa: BLE001 - classifying is the point
        msg = str(exc).lower()
        if isinstance(exc, CLEAR) and (not case.words or any(w in msg for w in case.words)):
            return "clear", ""
        return "obscure", f"{type(exc).__name__}: {str(exc)[:160]}"
    except BaseException as exc:  # noqa: BLE001
        if isinstance(exc, KeyboardInterrupt):
            raise
        return "crash", repr(exc)[:160]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    if case.expect == "same" and out is True:
        return "clear", ""
    return "silent", f"returned {type(out).__name__} where an error was due"


# ---- catalogue ----------------------------------------------------------------------------------
SMALL = {"shape": (16, 16), "n_bands": 4}
BAD_INTS = [0, -1, 1.5, "4", True, None, float("nan")]


def system_cases():
    out = []
    for name in tc.systems.REGISTRY:

        def mk(**kw):
            return lambda: studies.make_problem(name, "colorchecker", **{**SMALL, **kw})

        for v in BAD_INTS:
            out.append(Case("systems", f"{name} n_bands={v!r}", mk(n_bands=v), ("n_bands",)))
        for v in [(0, 16), (16,), (-4, 16), (16.5, 16), "16x16", (16, 16, 16)]:
            out.append(Case("systems", f"{name} shape={v!r}", mk(shape=v), ("shape",)))
        for v in [float("nan"), float("inf"), "30", True]:  # −5 dB is valid (noise > signal)
            out.append(Case("systems", f"{name} snr_db={v!r}", mk(snr_db=v), ("snr",)))
        for v in [-1, float("nan"), "1", -2.5]:  # 1.5 px is valid (interpolated)
            out.append(Case("systems", f"{name} shifts={v!r}", mk(shifts=v), ("shift",)))
        out.append(Case("systems", f"{name} unknown option", mk(colour="red"), ("colour",)))
        out.append(Case("systems", f"{name} rng='a'", mk(rng="a"), ("rng", "seed")))
    return out


def _measurement_variants(g):
    rng = np.random.default_rng(0)
    nan = g.copy()
    nan.flat[rng.integers(g.size)] = np.nan
    inf = g.copy()
    inf.flat[rng.integers(g.size)] = np.inf
    return {
        "NaN": (nan, ("nan", "finite")),
        "inf": (inf, ("inf", "finite")),
        "all zero": (np.zeros_like(g), ("zero",)),
        "constant": (np.full_like(g, 0.3), ("constant",)),
        "wrong shape": (g[:-1], ("shape",)),
        "transposed": (g.T.copy() if g.ndim == 2 else g[..., ::-1].T, ("shape",)),
        "extra axis": (g[..., None], ("shape",)),
        "complex": (g.astype(np.complex128), ("complex", "real", "dtype")),
        "strings": (g.astype(str), ("dtype", "numeric", "real")),
        "empty": (np.zeros((0,)), ("shape",)),
    }


#: the thesis' per-system algorithms
ONLY_FOR = {n: m.systems for n, m in tc.solvers.METHODS.items() if m.systems}
ONLY_FOR["split_tv"] = ()  # CASSDI-DFA with PSFs: not among these problems
#: methods whose first requirement is an argument without a default: every call without it must
#: name it, whatever else is wrong
NEEDS = {"dl": "dictionary"}


def reconstruct_cases():
    out = []
    names = ("sd_cassi", "cassi_vsi", "cassdi_dfa", "cs2li", "mu_cosdi", "c3slfi")
    for sname in names:
        p = studies.make_problem(sname, "colorchecker", **SMALL)
        g, system = np.asarray(p.measurement, dtype=np.float64), p.system
        for method in tc.reconstruct.methods():
            if method == "dcosnet":
                continue  # needs torch and weights for 28 bands: covered by its own tests
            if sname not in ONLY_FOR.get(method, (sname,)):
                out.append(
                    Case("reconstruct", f"{sname} {method} (other system)",
                         lambda m=method, s=system, g=g: tc.reconstruct(s, g, m), ("reconstructs",))
                )  # fmt: skip
                continue
            needs = (NEEDS[method],) if method in NEEDS else ()
            for label, (bad, words) in _measurement_variants(g).items():
                out.append(
                    Case("reconstruct", f"{sname} {method} measurement {label}",
                         lambda m=method, b=bad, s=system: tc.reconstruct(s, b, m),
                         words + ("measurement",) + needs)
                )  # fmt: skip
            for opt, v in [("max_iter", 0), ("max_iter", -3), ("max_iter", 2.5), ("bogus", 1)]:

                def call(m=method, o=opt, v=v, s=system, g=g):
                    return tc.reconstruct(s, g, m, **{o: v})

                words = (opt, NEEDS[method]) if method in NEEDS else (opt,)
                out.append(Case("reconstruct", f"{sname} {method} {opt}={v!r}", call, words))
        out.append(
            Case("reconstruct", f"{sname} unknown method",
                 lambda s=system, g=g: tc.reconstruct(s, g, "x"), ("method",))
        )  # fmt: skip
    return out


def _files(folder: Path):
    """Valid files of every format, written fresh: ``{suffix: path}``."""
    cube = np.random.default_rng(1).random((12, 10, 5)).astype(np.float32)
    wl = np.linspace(450.0, 650.0, 5)
    paths = {}
    for suffix in (".h5", ".npz", ".mat", ".tif", ".npy"):
        paths[suffix] = write_cube(folder / f"cube{suffix}", cube, wl if suffix != ".npy" else None)
    return cube, wl, paths


def file_cases(folder: Path):
    out = []
    cube, wl, paths = _files(folder)
    rng = np.random.default_rng(2)
    for suffix, path in paths.items():
        raw = path.read_bytes()
        variants = {
            "empty": b"",
            "truncated to 10 %": raw[: len(raw) // 10],
            "truncated to 90 %": raw[: 9 * len(raw) // 10],
            "random bytes": rng.integers(0, 256, len(raw), dtype=np.uint8).tobytes(),
            "text": b"this is not an array file\n" * 20,
        }
        for label, data in variants.items():
            bad = folder / f"bad_{label.replace(' ', '_').replace('%', 'pc')}{suffix}"
            bad.write_bytes(data)
            for reader in (read_array, read_cube):
                out.append(
                    Case(
                        "io.files",
                        f"{reader.__name__} {suffix} {label}",
                        lambda r=reader, b=bad: r(b),
                        (bad.name.lower(), "file", "format", "cannot", "not a"),
                    )
                )
        for reader in (read_array, read_cube):
            out.append(
                Case(
                    "io.files",
                    f"{reader.__name__} {suffix} missing key",
                    lambda r=reader, p=path: r(p, "nokey"),
                    ("nokey",),
                )
            )
    forged = folder / "forged.npy"
    head = b"{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000, 1), }"
    forged.write_bytes(
        b"\x93NUMPY\x01\x00" + len(head + b"\n").to_bytes(2, "little") + head + b"\n"
    )
    out.append(
        Case(
            "io.files",
            "read_array forged huge .npy header",
            lambda: read_array(forged),
            ("bytes", "size", "large"),
        )
    )
    for target, words in [
        (folder / "nofile.h5", ("nofile",)),
        (folder, ("directory", "folder", str(folder).lower())),
    ]:
        out.append(
            Case("io.files", f"read_cube {target.name}", lambda t=target: read_cube(t), words)
        )
    out.append(
        Case(
            "io.files",
            "read_cube .xyz",
            lambda: read_cube(folder / "a.xyz"),
            (".xyz", "extension", "format"),
        )
    )
    out.append(
        Case(
            "io.files",
            "write_cube over existing",
            lambda: write_cube(paths[".h5"], cube, wl),
            ("exists",),
        )
    )
    out.append(
        Case(
            "io.files",
            "write_cube µm wavelengths",
            lambda: write_cube(folder / "u.h5", cube, wl / 1000),
            ("nm", "wavelength"),
        )
    )
    out.append(
        Case(
            "io.files",
            "write_cube wrong wavelength count",
            lambda: write_cube(folder / "w.h5", cube, wl[:3]),
            ("wavelength",),
        )
    )
    out.append(
        Case(
            "io.files",
            "write_cube into a missing folder",
            lambda: write_cube(folder / "no" / "c.h5", cube, wl),
            ("folder", "no"),
        )
    )
    return out


def bundle_cases(folder: Path, n_flips: int):
    """Bundles with seeded single-byte corruptions: an error, or arrays identical to the saved."""
    out = []
    p = studies.make_problem("sd_cassi", "colorchecker", **SMALL)
    cube = np.asarray(p.cube, dtype=np.float32)
    rng = np.random.default_rng(3)
    for suffix in (".h5", ".npz"):
        good = save_bundle(
            folder / f"good{suffix}", system=p.system, cube=cube, measurement=p.measurement
        )
        raw = bytearray(good.read_bytes())
        for i in range(n_flips):
            pos = int(rng.integers(len(raw)))
            data = bytearray(raw)
            data[pos] ^= 1 << int(rng.integers(8))
            bad = folder / f"flip{i}{suffix}"
            bad.write_bytes(bytes(data))

            def run(b=bad):
                got = load_bundle(b)
                return bool(
                    np.array_equal(got.cube, cube)
                    and np.array_equal(np.asarray(got.measurement), np.asarray(p.measurement))
                )

            out.append(
                Case(
                    "io.bundle",
                    f"bundle {suffix} bit flip at byte {pos}",
                    run,
                    ("sha-256", "checksum", bad.name.lower(), "corrupt", "bundle", "file"),
                    "same",
                )
            )
    return out


def fault_cases(folder: Path):
    """Injected full-disk / I/O errors while overwriting: the error, and the old file intact."""
    out = []
    cube = np.random.default_rng(4).random((12, 10, 5)).astype(np.float32)
    wl = np.linspace(450.0, 650.0, 5)

    def faulted(step, code, save, target):
        def run():
            before = target.read_bytes()
            real = getattr(_atomic.os, step)

            def boom(*a, **k):
                raise OSError(code, os.strerror(code))

            setattr(_atomic.os, step, boom)
            try:
                save()
            except OSError:
                return target.read_bytes() == before and not any(
                    q.name.startswith(".") for q in target.parent.iterdir()
                )
            finally:
                setattr(_atomic.os, step, real)
            return False  # no error: the fault was swallowed

        return run

    for suffix in (".h5", ".npz", ".mat", ".tif", ".npy"):
        target = write_cube(folder / f"keep{suffix}", cube, None if suffix == ".npy" else wl)
        for step in ("fsync", "replace", "chmod"):
            for code in (errno.ENOSPC, errno.EIO):

                def save(t=target, s=suffix):
                    return write_cube(t, cube, None if s == ".npy" else wl, overwrite=True)

                out.append(
                    Case(
                        "io.faults",
                        f"write_cube {suffix} {step} {errno.errorcode[code]}",
                        faulted(step, code, save, target),
                        expect="same",
                    )
                )
    frames_dir = folder / "frames"
    write_frames(cube, frames_dir, suffix=".npy")
    first = frames_dir / "frame_000.npy"
    for step in ("fsync", "replace", "chmod"):
        save = lambda: write_frames(cube + 1, frames_dir, suffix=".npy", overwrite=True)  # noqa: E731
        out.append(
            Case(
                "io.faults",
                f"write_frames {step} ENOSPC",
                faulted(step, errno.ENOSPC, save, first),
                expect="same",
            )
        )
    return out


def misc_cases(folder: Path):
    out = []
    x = np.random.default_rng(5).random((8, 8, 3))
    from tensor_cosdi import colour, optics, scenes

    wl5 = [450, 500, 550, 600, 650]
    nan_cube = np.ones((2, 2, 5))
    nan_cube[0, 0, 0] = np.nan
    phase = optics.projector_phase((1, 8), 2.0)[..., 0]
    sd_small = tc.systems.SDCASSI.example((8, 8, 4))
    nan_frame = np.ones(sd_small.measurement_shape)
    nan_frame[1, 1] = np.nan
    for module, label, call, words in [
        ("optics", "zernike_radial m > n", lambda: optics.zernike_radial(2, 4, x[0, 0]),
         ("zernike",)),
        ("optics", "zernike_radial n − m odd", lambda: optics.zernike_radial(3, 0, x[0, 0]),
         ("zernike",)),
        ("optics", "gray_code_patterns 80 bits", lambda: optics.gray_code_patterns(phase, 80),
         ("at most",)),
        ("colour", "to_srgb NaN cube", lambda: colour.to_srgb(nan_cube, wl5), ("nan",)),
        ("scenes", "default_wavelengths in micrometres",
         lambda: scenes.default_wavelengths(8, 0.45, 0.65), ("micrometres",)),
        ("noise", "snr_db shapes that broadcast", lambda: noise.snr_db(x, x[:, :1]), ("shape",)),
        ("noise", "snr_db NaN", lambda: noise.snr_db(x, np.full_like(x, np.nan)), ("finite",)),
        ("noise", "snr_db_from_sigma negative power",
         lambda: noise.snr_db_from_sigma(-1.0, 0.1), ("power",)),
        ("depth", "decode_gray_code with a NaN threshold",
         lambda: tc.depth.decode_gray_code(x, threshold=np.nan), ("threshold",)),
        ("depth", "calibrate_phase_to_height with a NaN height",
         lambda: tc.depth.calibrate_phase_to_height([x[..., 0]], x[..., 1], [np.nan]),
         ("heights",)),
        ("depth", "textured_mask with a negative threshold",
         lambda: tc.depth.textured_mask(x[..., 0], threshold=-1.0), ("threshold",)),
        ("depth", "depth_from_focus with a negative sigma",
         lambda: tc.depth.depth_from_focus(x, sigma=-1.0), ("sigma",)),
        ("io.lenslet", "LensletGrid with pitch 0",
         lambda: tc.io.LensletGrid(0.0, (4.0, 4.0), 0.0, (8, 8), np.zeros((0, 2)),
                                   np.zeros((0, 2)), np.zeros(0)), ("pitch",)),
        ("bases", "Dense basis holding NaN", lambda: tc.bases.Dense(np.full((2, 2), np.nan)),
         ("finite",)),
        ("bases", "as_transform with a matrix of the wrong size",
         lambda: tc.bases.as_transform(4, np.eye(3)), ("size",)),
        ("optics", "prism_grid with an unknown glass",
         lambda: tc.studies.prism_grid(glass_pairs=(("X", "SF4"),)), ("glass",)),
        ("optics", "prism_grid with a NaN apex", lambda: tc.studies.prism_grid(phi1=(np.nan,)),
         ("phi1",)),
        ("studies", "compare with options for a method not run",
         lambda: tc.studies.compare(
             tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4),
             ("gap_tv",), options={"otd": {}}), ("options",)),
        ("studies", "sweep over an axis without values",
         lambda: tc.studies.sweep({"x": []}, lambda x: {}, progress=False), ("no values",)),
        ("io.frames", "frames_to_measurement NaN pixel",
         lambda: tc.io.frames_to_measurement(sd_small, [nan_frame]), ("nan",)),
        ("io.frames", "frames_to_measurement complex frame",
         lambda: tc.io.frames_to_measurement(sd_small, nan_frame.astype(complex)), ("real",)),
    ]:  # fmt: skip
        out.append(Case(module, label, call, words))
    for label, (a, b, kw, words) in {
        "psnr shape mismatch": (x, x[:-1], {}, ("shape",)),
        "psnr data_range 0": (x, x, {"data_range": 0}, ("data_range",)),
        "psnr data_range nan": (x, x, {"data_range": np.nan}, ("data_range",)),
        "psnr NaN estimate": (x, np.full_like(x, np.nan), {}, ("nan", "finite")),
    }.items():
        out.append(Case("metrics", label, lambda a=a, b=b, kw=kw: metrics.psnr(a, b, **kw), words))
    for f in (metrics.ssim, metrics.sam, metrics.rmse):
        out.append(
            Case("metrics", f"{f.__name__} shape mismatch", lambda f=f: f(x, x[:, :-1]), ("shape",))
        )
        out.append(
            Case(
                "metrics",
                f"{f.__name__} NaN",
                lambda f=f: f(x, np.full_like(x, np.nan)),
                ("nan", "finite"),
            )
        )
    for v in (np.nan, np.inf, "30", True):  # None is valid: no noise
        out.append(
            Case(
                "noise",
                f"add_noise snr_db={v!r}",
                lambda v=v: noise.add_noise(x, v, rng=0),
                ("snr",),
            )
        )
    out.append(
        Case(
            "noise",
            "add_noise NaN signal",
            lambda: noise.add_noise(np.full_like(x, np.nan), 30, rng=0),
            ("nan", "finite"),
        )
    )
    for label, m in {
        "not orthonormal": np.ones((8, 8)),
        "wrong size": np.eye(7),
        "not square": np.eye(8)[:, :6],
    }.items():
        out.append(
            Case(
                "bases",
                f"KroneckerBasis {label}",
                lambda m=m: KroneckerBasis((8, 8, 3), {0: m}),
                ("basis", "orthonormal", "square"),
            )
        )
    out.append(
        Case(
            "bases",
            "KroneckerBasis mode 5",
            lambda: KroneckerBasis((8, 8, 3), {5: np.eye(8)}),
            ("mode",),
        )
    )
    out.append(
        Case("denoisers", "unknown denoiser", lambda: denoise("nope", x, 0.1), ("nope", "denoiser"))
    )
    for n in (0, 3, 16, "2"):
        out.append(
            Case(
                "denoisers",
                f"self_ensemble {n!r}",
                lambda n=n: self_ensemble("tv", n),
                ("ensemble",),
            )
        )
    for name in ("a/b.npy", "../x.npy", "/etc/passwd"):
        words = ("not found", "no such", name.split("/")[-1])
        out.append(
            Case("io.frames", f"read_frame {name}", lambda n=name: read_frame(folder / n), words)
        )
    return out + depth_cases()


def depth_cases():
    """Light-field depth and the scenes it is measured on."""
    from tensor_cosdi import depth, scenes

    lf = np.random.default_rng(6).random((3, 3, 12, 12))
    tex = np.random.default_rng(7).random((8, 8))
    Layer = scenes.LightFieldLayer
    cases = {
        "disparity_from_views method='sad'": (
            lambda: depth.disparity_from_views(lf, method="sad"), ("method",)),
        "disparity_from_views half_ratio=0": (
            lambda: depth.disparity_from_views(lf, half_ratio=0), ("half_ratio",)),
        "disparity_from_views half_ratio=True": (
            lambda: depth.disparity_from_views(lf, half_ratio=True), ("half_ratio",)),
        "disparity_from_views radius=1.5": (
            lambda: depth.disparity_from_views(lf, radius=1.5), ("radius",)),
        "disparity_from_views eps=nan": (
            lambda: depth.disparity_from_views(lf, eps=np.nan), ("eps",)),
        "disparity_from_views max_disparity='2'": (
            lambda: depth.disparity_from_views(lf, max_disparity="2"), ("max_disparity",)),
        "disparity_from_views order=0": (
            lambda: depth.disparity_from_views(lf, order=0), ("order",)),
        "disparity_from_views NaN views": (
            lambda: depth.disparity_from_views(lf * np.nan), ("nan",)),
        "disparity_from_views one view": (
            lambda: depth.disparity_from_views(lf[:1, :1]), ("view",)),
        "guided_filter shape mismatch": (
            lambda: depth.guided_filter(tex, np.ones((2, 7, 8))), ("guide", "src")),
        "occlusion_cost_volume decreasing candidates": (
            lambda: depth.occlusion_cost_volume(lf, [1.0, 0.0, -1.0]), ("disparities",)),
        "layered_light_field no layers": (
            lambda: scenes.layered_light_field([]), ("layers",)),
        "layered_light_field a plain array": (
            lambda: scenes.layered_light_field([tex]), ("layers", "LightFieldLayer")),
        "layered_light_field supersample=2": (
            lambda: scenes.layered_light_field([Layer(tex)], supersample=2), ("supersample",)),
        "layered_light_field supersample=True": (
            lambda: scenes.layered_light_field([Layer(tex)], supersample=True), ("supersample",)),
        "layered_light_field inf disparity": (
            lambda: scenes.layered_light_field([Layer(tex, np.inf)]), ("disparity",)),
        "layered_light_field integer mask": (
            lambda: scenes.layered_light_field([Layer(tex, 0.0, np.ones((8, 8), int))]),
            ("mask",)),
        "layered_light_field no background": (
            lambda: scenes.layered_light_field([Layer(tex, 1.0, np.ones((8, 8), bool))]),
            ("layer", "background")),
        "layered_light_field textures of two shapes": (
            lambda: scenes.layered_light_field([Layer(tex), Layer(tex[:4])]), ("shape",)),
        "layered_light_field views=(0, 3)": (
            lambda: scenes.layered_light_field([Layer(tex)], views=(0, 3)), ("views",)),
        "structured_light fringe_axis=2": (
            lambda: scenes.structured_light((8, 8), [550.0], fringe_axis=2), ("fringe_axis",)),
        "structured_light fringe_axis=True": (
            lambda: scenes.structured_light((8, 8), [550.0], fringe_axis=True),
            ("fringe_axis",)),
    }  # fmt: skip
    return [Case("depth", label, call, words) for label, (call, words) in cases.items()]


def plot_cases():
    """The figures: cubes, points, traces and records a figure cannot honestly show."""
    import matplotlib

    matplotlib.use("Agg")
    from tensor_cosdi import plot

    c = np.random.default_rng(8).random((6, 5, 4))
    wl = np.linspace(450, 650, 4)
    cases = {
        "preview complex cube": (lambda: plot.preview(c + 1j, wl), ("real", "complex")),
        "preview NaN cube": (lambda: plot.preview(c * np.nan, wl), ("nan",)),
        "preview 2-D wavelengths": (lambda: plot.preview(c, wl.reshape(2, 2)), ("wavelengths",)),
        "preview percentile='50'": (lambda: plot.preview(c, wl, percentile="50"),
                                    ("percentile",)),
        "preview ax=3": (lambda: plot.preview(c, wl, ax=3), ("ax",)),
        "bands NaN cube": (lambda: plot.bands(c * np.nan, wl), ("nan",)),
        "bands columns=0": (lambda: plot.bands(c, wl, columns=0), ("columns",)),
        "bands max_bands=0": (lambda: plot.bands(c, wl, max_bands=0), ("max_bands",)),
        "bands fig='x'": (lambda: plot.bands(c, wl, fig="x"), ("fig",)),
        "spectra fractional point": (lambda: plot.spectra(c, wl, [(1.7, 2)]), ("point",)),
        "spectra a lone pair": (lambda: plot.spectra(c, wl, (1, 2)), ("pair", "points")),
        "spectra no points": (lambda: plot.spectra(c, wl, []), ("points",)),
        "spectra NaN reference": (lambda: plot.spectra(c, wl, [(1, 1)], reference=c * np.nan),
                                  ("reference",)),
        "compare a list of cubes": (lambda: plot.compare(c, [c], wl), ("cubes", "dict")),
        "depth complex map": (lambda: plot.depth(c[..., 0] + 1j), ("depth_map",)),
        "convergence empty trace": (lambda: plot.convergence({"residual": []}), ("residual",)),
        "convergence negative residual": (lambda: plot.convergence({"residual": [1, -1]}),
                                          ("residual",)),
        "convergence change of another length": (
            lambda: plot.convergence({"residual": [1, 0.5], "change": [1]}), ("change",)),
        "study text results": (lambda: plot.study([{"x": 1, "y": "a"}], "x", "y"), ("'y'",)),
        "study logy with 0": (
            lambda: plot.study([{"x": 1, "y": 1.0}, {"x": 2, "y": 0.0}], "x", "y", logy=True),
            ("logy",)),
        "study x of two kinds": (
            lambda: plot.study([{"x": 1, "y": 1.0}, {"x": "a", "y": 2.0}], "x", "y"), ("'x'",)),
        "study records not dicts": (lambda: plot.study([3], "x", "y"), ("record",)),
        "to_srgb complex cube": (lambda: tc.colour.to_srgb(c + 1j, wl), ("real", "complex")),
        "to_srgb band_axis=3": (lambda: tc.colour.to_srgb(c, wl, band_axis=3), ("band_axis",)),
    }  # fmt: skip
    return [Case("plot", label, call, words) for label, (call, words) in cases.items()]


def parallel_cases():
    """Tiled reconstruction and sweeps: what is checked before any tile or cell runs."""
    p = tc.studies.make_problem("sd_cassi", "coffee", shape=(32, 32), n_bands=4, rng=0)
    g = np.asarray(p.measurement)
    nan_g = np.where(g > g.mean(), np.nan, g)

    def tiled(m=g, **kw):
        return tc.reconstruct_tiled(p.system, m, "gap_tv", tile=16, overlap=4, **kw)

    def cell(x):
        return {"v": x}

    cases = {
        "reconstruct_tiled client='local'": (lambda: tiled(client="local"), ("client",)),
        "reconstruct_tiled client=3": (lambda: tiled(client=3), ("client",)),
        "reconstruct_tiled progress='yes'": (lambda: tiled(progress="yes"), ("progress",)),
        "reconstruct_tiled max_iter=-1": (lambda: tiled(max_iter=-1), ("max_iter",)),
        "reconstruct_tiled complex capture": (lambda: tiled(g + 1j), ("real", "complex")),
        "reconstruct_tiled boolean capture": (lambda: tiled(g > 0.5), ("real", "bool")),
        "reconstruct_tiled NaN capture": (lambda: tiled(nan_g), ("nan",)),
        "sweep client=3": (lambda: tc.studies.sweep({"x": [1]}, cell, client=3), ("client",)),
        "sweep progress='no'": (lambda: tc.studies.sweep({"x": [1]}, cell, progress="no"),
                                ("progress",)),
        "sweep a dict as an axis": (lambda: tc.studies.sweep({"x": {"a": 1}}, cell), ("grid",)),
        "sweep a set as an axis": (lambda: tc.studies.sweep({"x": {1, 2}}, cell), ("grid",)),
        "sweep a number as a key": (lambda: tc.studies.sweep({3: [1]}, cell), ("grid", "key")),
    }  # fmt: skip
    return [Case("parallel", label, call, words) for label, (call, words) in cases.items()]


def complex_cases():
    """Complex arrays where real numbers are due: a cast would keep the real part only."""
    from tensor_cosdi import colour, scenes
    from tensor_cosdi.solvers.denoisers import denoise as run_denoiser

    x = np.random.default_rng(9).random((8, 8, 3))
    z = x + 1j
    wl = [450.0, 550.0, 650.0]
    wl2d = [[450.0, 500.0], [550.0, 600.0]]
    cases = [
        ("metrics", "psnr complex estimate", lambda: metrics.psnr(x, z), ("real", "complex")),
        ("metrics", "ssim complex estimate", lambda: metrics.ssim(x, z, data_range=1.0),
         ("real", "complex")),
        ("metrics", "sam complex truth", lambda: metrics.sam(z, x), ("real", "complex")),
        ("noise", "add_noise complex", lambda: noise.add_noise(z, 30.0, rng=0),
         ("real", "complex")),
        ("noise", "estimate_sigma complex", lambda: noise.estimate_sigma(z), ("real", "complex")),
        ("denoisers", "denoise tv complex", lambda: run_denoiser("tv", z, 0.1),
         ("real", "complex")),
        ("colour", "rgb_to_cube complex", lambda: colour.rgb_to_cube(x * 0.5 + 1j, wl),
         ("real", "complex")),
        ("colour", "rgb_to_cube 2-D wavelengths",
         lambda: colour.rgb_to_cube(x * 0.5, [[450, 500], [550, 600]]), ("wavelengths",)),
        ("scenes", "scene_cube complex wavelengths",
         lambda: scenes.scene_cube("coffee", (8, 8), np.array(wl) + 1j), ("wavelengths",)),
        ("scenes", "light_field complex cube", lambda: scenes.light_field(z, 0.5), ("cube",)),
        ("bases", "svd_basis complex", lambda: tc.bases.svd_basis(z[..., 0]), ("matrix",)),
        ("bases", "tucker_bases complex", lambda: tc.bases.tucker_bases(z), ("tensor",)),
        ("colour", "reflectance complex", lambda: colour.reflectance(z, x), ("cube",)),
        ("noise", "snr_db complex", lambda: noise.snr_db(x, z), ("noisy",)),
        ("depth", "wrapped_phase complex", lambda: tc.depth.wrapped_phase(z), ("frames",)),
        ("depth", "disparity_from_views complex", lambda: tc.depth.disparity_from_views(z),
         ("views",)),
        ("io.frames", "bin_frame complex", lambda: tc.io.bin_frame(z[..., 0], 2), ("frame",)),
        ("optics", "psf_width complex", lambda: tc.optics.psf_width(z[..., 0]), ("psf",)),
        ("systems", "SDCASSI complex wavelengths",
         lambda: tc.systems.SDCASSI(np.ones((8, 8)), n_bands=3, wavelengths=np.array(wl) + 1j),
         ("wavelengths",)),
        ("systems", "SDCASSI 2-D wavelengths",
         lambda: tc.systems.SDCASSI(np.ones((8, 8)), n_bands=4, wavelengths=wl2d),
         ("wavelengths",)),
        ("solvers", "train_dictionary complex", lambda: tc.solvers.train_dictionary([z], patch=4),
         ("training cube",)),
    ]  # fmt: skip
    return [Case(m, label, call, words) for m, label, call, words in cases]


def shape_and_kind_cases():
    """Empty shapes, objects of the wrong kind, and data paths that leave the data folder."""
    from tensor_cosdi import codes, datasets, operators, testing
    from tensor_cosdi.learn import dcosnet_train

    arr = np.zeros(3)
    cases = [
        ("codes", "random_binary of an empty shape", lambda: codes.random_binary(()), ("shape",)),
        ("codes", "random_binary of an array with no rows",
         lambda: codes.random_binary(np.zeros((0, 8))), ("shape",)),
        ("operators", "vec_index of an empty shape", lambda: operators.vec_index(()), ("shape",)),
        ("operators", "sensing_gain of an array", lambda: operators.sensing_gain(arr),
         ("tensoroperator",)),
        ("operators", "gram_eigenvalues of an array", lambda: operators.gram_eigenvalues(arr),
         ("structured",)),
        ("operators", "dot_test of an array", lambda: testing.dot_test(arr), ("tensoroperator",)),
        ("bases", "tucker_bases of an empty tensor",
         lambda: tc.bases.tucker_bases(np.zeros((0, 4, 3))), ("no entries",)),
        ("studies", "conditioning of an array", lambda: studies.conditioning(arr), ("imager",)),
        ("studies", "compare of an array", lambda: studies.compare(arr), ("problem",)),
        ("io.frames", "frame_count of an array", lambda: tc.io.frame_count(arr), ("imager",)),
        ("io.hostile", "data_file absolute path", lambda: datasets.data_file("/etc/passwd"),
         ("relative",)),
        ("io.hostile", "data_file climbing out", lambda: datasets.data_file("masks/../../x.mat"),
         ("relative",)),
        ("io.hostile", "data_file of a number", lambda: datasets.data_file(3), ("path",)),
        ("solvers", "lam_schedule of an array", lambda: tc.solvers.otd.lam_schedule(arr),
         ("imager",)),
        ("solvers", "has_many_bands of a name",
         lambda: tc.solvers.subspace.has_many_bands("sd_cassi"), ("imager",)),
        ("io.bundle", "save_bundle to a .mat name",
         lambda: tc.io.save_bundle(Path(tempfile.gettempdir()) / "never_written.mat",
                                   metadata={}), ("bundle is an .npz",)),
        ("io.bundle", "save_bundle into a file as a folder",
         lambda: tc.io.save_bundle(Path(__file__) / "b.npz", metadata={}), ("not a folder",)),
        ("learn", "dcosnet training_data of a dict",
         lambda: dcosnet_train.training_data({"n_bands": 28}), ("dcosnetconfig",)),
    ]  # fmt: skip
    return [Case(m, label, call, words) for m, label, call, words in cases]


class Worker:
    """Runs cases of ``cases`` by index in a forked child; a dead or stuck child is replaced."""

    def __init__(self, cases, timeout: float):
        self.cases, self.timeout, self.pid = cases, timeout, None

    def _start(self):
        to_child_r, to_child_w = os.pipe()
        to_parent_r, to_parent_w = os.pipe()
        pid = os.fork()
        if pid == 0:  # the worker: read an index, answer one JSON line, until EOF
            os.close(to_child_w)
            os.close(to_parent_r)
            inp, out = os.fdopen(to_child_r, "r"), os.fdopen(to_parent_w, "w")
            for line in inp:
                kind, detail = classify(self.cases[int(line)], self.timeout)
                out.write(json.dumps([kind, detail]) + "\n")
                out.flush()
            os._exit(0)
        os.close(to_child_r)
        os.close(to_parent_w)
        self.pid, self.inp = pid, os.fdopen(to_child_w, "w")
        self.out = os.fdopen(to_parent_r, "r")

    def _stop(self, sig=signal.SIGKILL):
        try:
            os.kill(self.pid, sig)
        except ProcessLookupError:
            pass
        _, status = os.waitpid(self.pid, 0)
        self.inp.close()
        self.out.close()
        self.pid = None
        return status

    def run(self, i: int) -> tuple[str, str]:
        if self.pid is None:
            self._start()
        self.inp.write(f"{i}\n")
        self.inp.flush()
        ready, _, _ = select.select([self.out], [], [], self.timeout + 15.0)
        if not ready:  # the in-process alarm did not get through: stuck in C code
            self._stop()
            return "hang", f"no answer in {self.timeout:g} s (worker killed)"
        line = self.out.readline()
        if not line:  # EOF: the worker died running this case
            status = self._stop()
            how = (
                f"signal {signal.Signals(os.WTERMSIG(status)).name}"
                if os.WIFSIGNALED(status)
                else f"exit status {os.WEXITSTATUS(status)}"
            )
            return "crash", f"worker process died ({how})"
        kind, detail = json.loads(line)
        return kind, detail

    def close(self):
        if self.pid is not None:
            self.inp.close()
            os.waitpid(self.pid, 0)
            self.out.close()
            self.pid = None


def harness_cases():
    """``--selftest``: cases that kill or wedge their process, to show the worker catches them."""

    def wedge():  # the alarm blocked: only the parent's hard timeout can end this
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})
        time.sleep(3600)

    return [
        Case("harness", "segfault", lambda: os.kill(os.getpid(), signal.SIGSEGV)),
        Case("harness", "abort", os.abort),
        Case("harness", "hang with the alarm blocked", wedge),
        Case("harness", "clear error after them", lambda: int("x"), ("invalid",)),
    ]


def hostile_file_cases(folder: Path):
    """Files built to read data from elsewhere or to inflate past ``max_bytes``, and files whose
    content is not what it looks like."""

    out = []
    hf = hostile_files(folder)
    rgb_data = rgb_values(0)
    mib = 1 << 20
    for name, call, words in [
        ("HDF5 external raw storage", lambda: read_cube(hf["hdf5_external"]), ("external",)),
        ("HDF5 virtual dataset", lambda: read_cube(hf["hdf5_virtual"]), ("virtual",)),
        ("HDF5 virtual dataset, source missing", lambda: read_array(hf["hdf5_virtual_missing"]),
         ("virtual",)),
        ("HDF5 external link by key", lambda: read_array(hf["hdf5_link"], "cube"),
         ("external link",)),
        ("HDF5 soft link by key", lambda: read_array(hf["hdf5_soft"], "cube"), ("soft link",)),
        ("HDF5 text by key", lambda: read_cube(hf["hdf5_text"], "cube"), ("text",)),
        ("MATLAB text by key", lambda: read_array(hf["mat_text"], "cube"), ("text",)),
        ("HDF5 chunks past max_bytes", lambda: read_cube(hf["hdf5_chunks"], max_bytes=mib),
         ("chunks",)),
        (".npz member inflating past max_bytes", lambda: read_cube(hf["npz_bomb"], max_bytes=mib),
         ("inflates",)),
        ("MATLAB variable inflating past max_bytes",
         lambda: read_cube(hf["mat_bomb"], max_bytes=mib), ("inflates",)),
        ("MATLAB element padded to 8 MiB", lambda: read_array(hf["mat_padded"], max_bytes=mib),
         ("inflates",)),
        ("MATLAB sparse matrix", lambda: read_array(hf["mat_sparse"]), ("sparse",)),
        ("complex cube", lambda: read_cube(hf["npz_complex"]), ("complex",)),
        ("complex MATLAB v5 cube (listed as double)", lambda: read_cube(hf["mat_complex"]),
         ("complex",)),
        ("3 wavelengths for 4 bands", lambda: read_cube(hf["npz_wavelengths"]), ("wavelengths",)),
        ("TIFF pages of two shapes", lambda: read_cube(hf["tiff_mixed"]), ("series", "pages")),
        ("plan of JSON nested 200,000 deep", lambda: AcquisitionPlan.load(hf["plan_deep"]),
         ("nested too deeply",)),
        ("frame log of JSON nested 200,000 deep", lambda: read_log(hf["log_deep"]),
         ("not json",)),
        (".npz bundle document nested 200,000 deep", lambda: load_bundle(hf["bundle_deep_npz"]),
         ("nested too deeply",)),
        ("ENVI cube of complex values", lambda: read_cube(hf["envi_complex"]), ("complex",)),
        ("ENVI interleave 'xyz'", lambda: read_cube(hf["envi_interleave"]), ("interleave",)),
        ("ENVI data file linked to another file", lambda: read_cube(hf["envi_link"]),
         ("symbolic link",)),
        ("HDF5 bundle document nested 200,000 deep",
         lambda: load_bundle(hf["bundle_deep_h5"]), ("nested too deeply",)),
    ] + [
        (f"a {what} named .npy", lambda k=key: read_array(hf[k]), ("regular file",))
        for key, what in (("fifo", "FIFO"), ("dev_zero", "link to /dev/zero")) if key in hf
    ] + [
        (f"a {what} as a frame", lambda k=key: read_frame(hf[k]), ("regular file",))
        for key, what in (("fifo", "FIFO"), ("dev_zero", "link to /dev/zero")) if key in hf
    ] + [
        ("a folder as a bundle", lambda: load_bundle(folder), ("regular file",)),
    ] + [
        (f"Zarr {what}", lambda k=key: read_array(hf[k]), words)
        for key, what, words in (
            ("zarr_link", "chunk linked to another file", ("symbolic link",)),
            ("zarr_fifo", "chunk that is a FIFO", ("regular file",)),
            ("zarr_pickle", "pickle filter", ("pickle",)),
            ("zarr_object", "object values", ("vlen", "only numbers")),
            ("zarr_bomb", "chunk inflating past its size", ("compression bomb",)),
            ("zarr_big_chunk", "chunks past max_bytes", ("declares chunks",)),
        ) if key in hf
    ]:  # fmt: skip
        out.append(Case("io.hostile", name, call, words))
    out.append(
        Case("io.hostile", "RGB TIFF as a (rows, columns, 3) cube",
             lambda: bool(np.array_equal(read_cube(hf["tiff_rgb"])[0], rgb_data)), expect="same")
    )  # fmt: skip
    # bundles: an edited document, a NaN that must never be written

    sd = tc.systems.SDCASSI((np.arange(36).reshape(6, 6) % 2).astype(float), n_bands=3)
    for suffix in (".npz", ".h5"):
        path = save_bundle(folder / f"doc{suffix}", system=sd,
                           measurement=np.ones(sd.measurement_shape))  # fmt: skip
        change = {"system.shifts": 2} if suffix == ".npz" else {"metadata": {"exposure_ms": 1}}
        edit_bundle_document(path, lambda doc, c=change: _apply(doc, c))
        out.append(Case("io.hostile", f"bundle {suffix} with an edited document",
                        lambda p=path: load_bundle(p), ("sha-256", "document")))  # fmt: skip
    nan_g = np.ones(sd.measurement_shape)
    nan_g[0, 0] = np.nan
    out.append(Case("io.hostile", "save_bundle NaN measurement",
                    lambda: save_bundle(folder / "nan.npz", system=sd, measurement=nan_g),
                    ("nan",)))  # fmt: skip
    out += _weights_file_cases(folder, sd)
    return out


class _Payload:
    """A pickle that would run a command when unpickled without ``weights_only``."""

    def __reduce__(self):
        import os

        return (os.system, ("echo pwned > /dev/null",))


def _weights_file_cases(folder: Path, sd):
    """Network weights that are empty, truncated, a code-running pickle, or another network."""
    import pickle

    from tensor_cosdi.learn import dcosnet
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser
    from tensor_cosdi.learn.train import train_denoiser

    files = {"empty": b"", "truncated": b"PK\x03\x04 not a whole file",
             "pickle payload": pickle.dumps({"config": _Payload()})}  # fmt: skip
    out = []
    g = np.random.default_rng(0).random(sd.measurement_shape)
    for what, data in files.items():
        path = folder / f"weights_{what.replace(' ', '_')}.pt"
        path.write_bytes(data)
        for name, call in (
            ("training_code", lambda p=path: dcosnet.training_code(p)),
            ("dcosnet weights=", lambda p=path: tc.reconstruct(sd, g, "dcosnet", weights=p)),
            ("SpectralDenoiser", lambda p=path: SpectralDenoiser(p)),
        ):
            out.append(Case("learn.hostile", f"{name} of a {what} file", call,
                            ("checkpoint", "weights", "not a")))  # fmt: skip
        # the same bytes as a training checkpoint to resume (no training data is read first)
        ckpt = folder / f"resume_{what.replace(' ', '_')}.pt.ckpt"
        ckpt.write_bytes(data)
        out.append(Case("learn.hostile", f"train_denoiser resume=True from a {what} checkpoint",
                        lambda c=ckpt: train_denoiser(c.with_suffix(""), resume=True,
                                                      progress=False, device="cpu"),
                        ("not a readable checkpoint",)))  # fmt: skip
    out += _nan_weights_cases(folder, sd, g)
    return out


def _nan_weights_cases(folder: Path, sd, g):
    """The shipped weights with one parameter set to NaN (a diverged training's file)."""
    import torch

    from tensor_cosdi.learn import dcosnet, spectral_net
    from tensor_cosdi.learn.dcosnet_train import DCoSNetConfig, train_dcosnet

    paths = {}
    for what, source in (("dcosnet", dcosnet.default_weights("sd_cassi")),
                         ("denoiser", spectral_net.default_weights())):  # fmt: skip
        ckpt = torch.load(source, map_location="cpu", weights_only=True)
        first = next(iter(ckpt["model"]))
        ckpt["model"][first] = torch.full_like(ckpt["model"][first], float("nan"))
        paths[what] = folder / f"nan_{what}.pt"
        torch.save(ckpt, paths[what])
    init = DCoSNetConfig(init=str(paths["dcosnet"]), stages=3, steps=1, start="adaptive",
                         noise_input=True)  # fmt: skip
    return [
        Case("learn.hostile", "dcosnet weights= holding NaN",
             lambda: tc.reconstruct(sd, g, "dcosnet", weights=paths["dcosnet"]), ("nan",)),
        Case("learn.hostile", "read_config of D-CoSNet weights holding NaN",
             lambda: dcosnet.read_config(paths["dcosnet"]), ("nan",)),
        Case("learn.hostile", "SpectralDenoiser of weights holding NaN",
             lambda: spectral_net.SpectralDenoiser(paths["denoiser"]), ("nan",)),
        Case("learn.hostile", "train_dcosnet init= weights holding NaN",
             lambda: train_dcosnet(folder / "from_nan.pt", init, progress=False, device="cpu"),
             ("nan",)),
    ]  # fmt: skip


def _apply(doc: dict, change: dict) -> None:
    """Set ``doc["a"]["b"] = v`` for each ``"a.b": v`` of ``change``."""
    for key, value in change.items():
        *parents, last = key.split(".")
        node = doc
        for p in parents:
            node = node[p]
        node[last] = value


def option_cases():
    """Every method's numeric and boolean options given a boolean, a string or inf, and sizes
    that would allocate without bound."""
    from tensor_cosdi.io.triggers import AcquisitionPlan
    from tensor_cosdi.learn import dcosnet, spectral_net
    from tensor_cosdi.learn.dcosnet_train import DCoSNetConfig
    from tensor_cosdi.solvers import METHODS, denoisers
    from tensor_cosdi.studies.learned import CODE_STUDY_WEIGHTS

    out = []
    problems = {}
    other_code = tc.systems.SDCASSI(np.ones((64, 64)), n_bands=28, shifts=2)

    def problem_for(method):
        """A small problem on an imager the method is written for (SD-CASSI when any)."""
        name = (METHODS[method].systems or ("sd_cassi",))[0]
        if name not in problems:
            p = studies.make_problem(name, "colorchecker", **SMALL)
            problems[name] = (p.system, np.asarray(p.measurement, dtype=np.float64))
        return problems[name]

    for method, opt in (
        ("pnp_gap", "warm_iter"),
        ("pnp_fast", "warm_iter"),
        ("dl", "warm_iter"),
        ("otd", "admm_iter"),
        ("pnp_gap", "pan_iter"),
    ):  # "auto" or a count: not caught by type below (0 is a count there: the first stage alone)
        if method not in tc.reconstruct.methods():
            continue
        system, g = problem_for(method)
        extra = (NEEDS[method],) if method in NEEDS else ()
        for v in (True, "0.5", float("inf"), -1, "many"):
            out.append(Case("options", f"{method} {opt}={v!r}",
                            lambda m=method, o=opt, v=v, s=system, g=g:
                            tc.reconstruct(s, g, m, **{o: v}), (opt, *extra)))  # fmt: skip
    for method in tc.reconstruct.methods():
        system, g = problem_for(method)
        # a method that needs an argument names it first, whatever else is wrong
        extra = (NEEDS[method],) if method in NEEDS else ()
        for opt, default in METHODS[method].defaults.items():
            if isinstance(default, bool):
                bad = ["yes", 1, None]
            elif isinstance(default, (int, float)):
                bad = [True, "0.5", float("inf")]
            else:
                continue
            for v in bad:
                out.append(Case("options", f"{method} {opt}={v!r}",
                                lambda m=method, o=opt, v=v, s=system, g=g:
                                tc.reconstruct(s, g, m, **{o: v}),
                                (opt, *extra)))  # fmt: skip
    code = np.ones((8, 8))
    reg_sd = tc.systems.SDCASSI(tc.codes.random_binary((16, 16), rng=0), n_bands=4, shifts=1)
    reg_g = np.random.default_rng(0).random(reg_sd.measurement_shape)
    vsi = tc.systems.REGISTRY["cassi_vsi"].example((16, 16, 4))
    for name, call, words in [
        ("SDCASSI n_bands=2**40", lambda: tc.systems.SDCASSI(code, n_bands=2**40), ("n_bands",)),
        ("SDCASSI shifts=1e15", lambda: tc.systems.SDCASSI(code, n_bands=3, shifts=1e15),
         ("shift",)),
        ("CASSIVSI alpha_t='0.5'", lambda: tc.systems.CASSIVSI(code, n_bands=3, alpha_t="0.5"),
         ("alpha_t",)),
        ("AcquisitionPlan.snapshots(10**8)", lambda: AcquisitionPlan.snapshots(10**8),
         ("frames",)),
        ("AcquisitionPlan.patterns(True)", lambda: AcquisitionPlan.patterns(True), ("frames",)),
        ("denoisers.tv sigma=-1", lambda: denoisers.tv(np.ones((4, 4, 2)), -1), ("sigma",)),
        ("SDCASSI shear_direction=0",
         lambda: tc.systems.SDCASSI(code, n_bands=3, shear_direction=0), ("shear_direction",)),
        ("SDCASSI shifts neither increasing nor decreasing",
         lambda: tc.systems.SDCASSI(code, n_bands=3, shifts=[0, 2, 1]), ("monotone",)),
        ("estimate_registration max_offset=True",
         lambda: tc.io.estimate_registration(reg_sd, reg_g, max_offset=True), ("max_offset",)),
        ("estimate_registration max_offset past a quarter of the code",
         lambda: tc.io.estimate_registration(reg_sd, reg_g, max_offset=40), ("max_offset",)),
        ("estimate_registration NaN measurement",
         lambda: tc.io.estimate_registration(reg_sd, reg_g * np.nan), ("nan",)),
        ("estimate_registration flat measurement",
         lambda: tc.io.estimate_registration(reg_sd, np.ones_like(reg_g)), ("texture",)),
        ("estimate_registration on CASSI-VSI",
         lambda: tc.io.estimate_registration(vsi, np.ones(vsi.measurement_shape)), ("movable",)),
        ("denoisers.wavelet sigma=nan", lambda: denoisers.wavelet(np.ones((4, 4, 2)), np.nan),
         ("sigma",)),
        ("estimate_registration direction='mirror'",
         lambda: tc.io.estimate_registration(reg_sd, reg_g, direction="mirror"), ("direction",)),
        ("estimate_registration direction=-1",
         lambda: tc.io.estimate_registration(reg_sd, reg_g, direction=-1), ("direction",)),
        ("estimate_registration direction search with even shifts",
         lambda: tc.io.estimate_registration(reg_sd, reg_g, direction="search"), ("evenly",)),
        ("estimate_registration direction search on CASSI-VSI",
         lambda: tc.io.estimate_registration(vsi, np.ones(vsi.measurement_shape),
                                             direction="search"), ("movable",)),
        ("mirror_symmetric NaN shift", lambda: tc.io.mirror_symmetric([0, np.nan]), ("shifts",)),
        ("mirror_symmetric no shifts", lambda: tc.io.mirror_symmetric([]), ("shifts",)),
        ("pnp_gap guard=0.5 with ADMM (the guard unused there)",
         lambda: tc.reconstruct(*problem_for("pnp_gap"), "pnp_gap", denoiser="tv",
                                splitting="admm", guard=0.5), ("guard",)),
        ("wdct wavelet_name=3", lambda: tc.reconstruct(*problem_for("wdct"), "wdct",
                                                       wavelet_name=3), ("wavelet",)),
        ("pnp_gap pan_iter with a GAP-TV start",
         lambda: tc.reconstruct(*problem_for("pnp_gap"), "pnp_gap", warm="gap_tv", pan_iter=30),
         ("pan_iter",)),
        ("train-dcosnet learn_code on TSA crops",
         lambda: DCoSNetConfig(learn_code=True, mask="tsa").check(), ("seeded",)),
        ("train-dcosnet learn_code for Mu-CoSDI",
         lambda: DCoSNetConfig(learn_code=True, mask="seeded", system="mu_cosdi").check(),
         ("sd_cassi",)),
        ("train-dcosnet code_until=0", lambda: DCoSNetConfig(code_until=0).check(),
         ("code_until",)),
        ("train-dcosnet code_until=nan", lambda: DCoSNetConfig(code_until=np.nan).check(),
         ("code_until",)),
        ("train-dcosnet code_until=True", lambda: DCoSNetConfig(code_until=True).check(),
         ("code_until",)),
        ("train-dcosnet learn_code='yes'",
         lambda: DCoSNetConfig(learn_code="yes", mask="seeded").check(), ("learn_code",)),
        ("tile_code of a 1-D code", lambda: dcosnet.tile_code(np.ones(3), (4, 4)), ("2-d",)),
        ("tile_code of an empty code", lambda: dcosnet.tile_code(np.ones((0, 3)), (4, 4)),
         ("2-d",)),
        ("seeded_code of shape (0, 5)", lambda: dcosnet.seeded_code((0, 5), 0), ("shape",)),
        ("learned_code without weights", lambda: studies.learned_code({}, progress=False),
         ("weights",)),
        ("learned_code with a missing weights file",
         lambda: studies.learned_code({"x": "/nonexistent/w.pt"}, progress=False), ("not found",)),
        ("learned_code with one scene name as a string",
         lambda: studies.learned_code(scenes="cave.face", progress=False), ("scenes",)),
        ("learned_code with the spectral denoiser's weights",
         lambda: studies.learned_code({"x": spectral_net.default_weights()}, progress=False),
         ("checkpoint", "d-cosnet")),
        ("learned_code with D-CoSNet weights of TSA crops",
         lambda: studies.learned_code({"x": dcosnet.default_weights("sd_cassi")},
                                             progress=False),
         ("seeded or learned",)),
        ("learned-code D-CoSNet through another code",
         lambda: tc.reconstruct(other_code, np.ones(other_code.measurement_shape), "dcosnet",
                                weights=CODE_STUDY_WEIGHTS["learned"]), ("code",)),
    ]:  # fmt: skip
        out.append(Case("options", name, call, words))
    system, g = problem_for("lsq")
    out.append(
        Case("reconstruct", "float16 measurement promoted",
             lambda: tc.reconstruct(system, g.astype(np.float16), "lsq").cube.dtype
             == np.float32, expect="same")
    )  # fmt: skip
    return out


def lab_cases(folder: Path):
    """The lab adapter: a frame already in the folder, a symbolic link for a frame, a frame log
    whose header was removed."""
    from tensor_cosdi.io import FolderCamera
    from tensor_cosdi.io.triggers import Acquisition, AcquisitionPlan

    out = []
    lab = folder / "lab"
    lab.mkdir()
    step = AcquisitionPlan.snapshots(1).steps[0]
    (lab / step.frame).write_bytes(b"an old frame")
    cam = FolderCamera(lab, timeout=0.3, poll=0.02)

    def old_frame():
        cam.before_trigger(step)
        return cam(step)

    out.append(Case("io.lab", "FolderCamera: a frame left from an earlier run", old_frame,
                    ("already",)))  # fmt: skip
    linked = folder / "lab2"
    linked.mkdir()
    (folder / "elsewhere.tif").write_bytes(b"x")
    os.symlink(folder / "elsewhere.tif", linked / step.frame)
    out.append(Case("io.lab", "FolderCamera: a symbolic link as the frame",
                    lambda: FolderCamera(linked, timeout=0.3)(step), ("symbolic",)))  # fmt: skip
    log = folder / "headless.jsonl"
    plan = AcquisitionPlan.snapshots(2)
    log.write_text("".join(
        json.dumps({"plan": plan.fingerprint(), "step": i, "index": {"k": i},
                    "frame": str(folder / "elsewhere.tif"), "sha256": "0" * 64}) + "\n"
        for i in range(2)
    ))  # fmt: skip

    def headless():
        return Acquisition(AcquisitionPlan.patterns(2), None, log, lambda s: None).run()

    out.append(Case("io.lab", "a frame log without its header line", headless, ("header",)))
    if hasattr(os, "mkfifo"):  # reading a FIFO would block for ever
        from tensor_cosdi.io.triggers import read_log

        os.mkfifo(folder / "fifo.jsonl")
        out.append(Case("io.lab", "a FIFO as the frame log",
                        lambda: read_log(folder / "fifo.jsonl"), ("regular file",)))  # fmt: skip
    return out


def _npz_declaring(path: Path, member: str, shape, extra: dict) -> Path:
    """An ``.npz`` whose ``member`` declares ``shape`` of float64 and holds 64 bytes."""
    import io
    import zipfile

    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": tuple(shape)}
    )
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(f"{member}.npy", header.getvalue() + b"\0" * 64)
        for name, value in extra.items():
            buf = io.BytesIO()
            np.save(buf, value)
            z.writestr(f"{name}.npy", buf.getvalue())
    return path


def reader_cases(folder: Path):
    """The readers outside :mod:`tensor_cosdi.io.files`: a scene file, a patch dictionary, a
    D-CoSNet training mask and an acquisition plan, each hostile or malformed."""
    from tensor_cosdi.datasets import load_hsi
    from tensor_cosdi.io.triggers import AcquisitionPlan
    from tensor_cosdi.solvers.dictionary import PatchDictionary

    out = []
    d = folder / "readers"
    d.mkdir()
    wl3 = np.linspace(400.0, 700.0, 3)
    scenes = {
        "complex cube": ({"cube": np.ones((4, 4, 3), complex)}, ("complex",)),
        "signed integer cube": ({"cube": -np.ones((4, 4, 3), np.int16)}, ("int16",)),
        "NaN cube": ({"cube": np.full((4, 4, 3), np.nan)}, ("nan",)),
        "negative cube": ({"cube": -np.ones((4, 4, 3))}, ("negative",)),
        "micrometre wavelengths": ({"wavelengths_nm": wl3 / 1000}, ("micrometres",)),
        "unsorted wavelengths": ({"wavelengths_nm": wl3[[1, 0, 2]]}, ("increase",)),
        "2-D wavelengths": (
            {"cube": np.ones((4, 4, 4)), "wavelengths_nm": np.full((2, 2), 500.0)},
            ("1-d",),
        ),
        "no wavelengths": ({"wavelengths_nm": None}, ("wavelengths_nm",)),
    }
    for what, (arrays, words) in scenes.items():
        doc = {"cube": np.ones((4, 4, 3)), "wavelengths_nm": wl3, **arrays}
        path = d / f"scene_{what.replace(' ', '_')}.npz"
        np.savez(path, **{k: v for k, v in doc.items() if v is not None})
        out.append(Case("io.readers", f"load_hsi: {what}", lambda p=path: load_hsi(p), words))
    bomb = _npz_declaring(d / "scene_bomb.npz", "cube", (30000, 30000, 1), {"wavelengths_nm": wl3})
    out.append(Case("io.readers", "load_hsi: a cube declaring 6.7 GiB",
                    lambda: load_hsi(bomb), ("limit",)))  # fmt: skip
    atoms = np.random.default_rng(0).random((27, 10))
    dictionaries = {
        "3 meta values": ({"atoms": atoms, "meta": np.array([3, 3, 1])}, ("4 integers",)),
        "fractional meta": ({"atoms": atoms, "meta": np.array([3.7, 3, 1, 2])}, ("4 integers",)),
        "NaN atoms": ({"atoms": np.full((27, 10), np.nan), "meta": np.array([3, 3, 1, 2])},
                      ("finite",)),
        "text atoms": ({"atoms": np.array(["a"]), "meta": np.array([3, 3, 1, 2])}, ("real",)),
    }  # fmt: skip
    for what, (arrays, words) in dictionaries.items():
        path = d / f"dict_{what.replace(' ', '_')}.npz"
        np.savez(path, **arrays)
        out.append(Case("io.readers", f"PatchDictionary.load: {what}",
                        lambda p=path: PatchDictionary.load(p), words))  # fmt: skip
    dbomb = _npz_declaring(d / "dict_bomb.npz", "atoms", (30000, 30000), {"meta": np.arange(4)})
    out.append(Case("io.readers", "PatchDictionary.load: atoms declaring 6.7 GiB",
                    lambda: PatchDictionary.load(dbomb), ("limit",)))  # fmt: skip
    try:
        from tensor_cosdi.learn.dcosnet_train import DCoSNetConfig, training_data
    except ImportError:  # no PyTorch: the D-CoSNet cases are left out
        training_data = None
    if training_data is not None:  # the mask is read (and refused) before any scene
        np.save(d / "mask_complex.npy", np.ones((8, 8), complex))
        with open(d / "mask_bomb.npy", "wb") as f:
            np.lib.format.write_array_header_1_0(
                f, {"descr": "<f8", "fortran_order": False, "shape": (100000, 100000)}
            )
            f.write(b"\0" * 64)
        for name, words in (("mask_complex.npy", ("real",)), ("mask_bomb.npy", ("limit",))):
            out.append(Case("io.readers", f"D-CoSNet mask: {name}",
                            lambda n=name: training_data(DCoSNetConfig(
                                mask=str(d / n), patch=16, hold_out=2)), words))  # fmt: skip
    ok = {"index": {"k": 0}, "commands": ["DMD 0"], "frame": "f0.tif"}
    plans = {
        "index a list": [dict(ok, index=[1, 2])],
        "negative index": [dict(ok, index={"k": -1})],
        "fractional index": [dict(ok, index={"k": 1.5})],
        "commands a string": [dict(ok, commands="DMD 0")],
        "two steps at one index": [ok, dict(ok, frame="f1.tif")],
    }
    for what, steps in plans.items():
        path = d / f"plan_{what.replace(' ', '_')}.json"
        path.write_text(json.dumps({"steps": steps}))
        out.append(Case("io.readers", f"AcquisitionPlan.load: {what}",
                        lambda p=path: AcquisitionPlan.load(p), ("index", "commands")))  # fmt: skip
    fifo = d / "plan_fifo.json"
    if hasattr(os, "mkfifo"):
        os.mkfifo(fifo)
        out.append(Case("io.readers", "AcquisitionPlan.load: a FIFO",
                        lambda: AcquisitionPlan.load(fifo), ("regular file",)))  # fmt: skip
    return out


def argument_cases():
    """One bad argument at a time for the public functions beyond ``reconstruct``
    (``tensor_cosdi.testing.hostile_arguments``, which the tests run too)."""
    return [Case(module, label, call, words) for module, label, call, words in hostile_arguments()]


def catalogue(folder: Path, n_flips: int = 150):
    return (
        system_cases()
        + reconstruct_cases()
        + file_cases(folder)
        + bundle_cases(folder, n_flips)
        + fault_cases(folder)
        + misc_cases(folder)
        + hostile_file_cases(folder)
        + option_cases()
        + lab_cases(folder)
        + reader_cases(folder)
        + plot_cases()
        + parallel_cases()
        + complex_cases()
        + shape_and_kind_cases()
        + argument_cases()
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=None, help="run one module's cases")
    ap.add_argument("--timeout", type=float, default=30.0)
    ap.add_argument("--flips", type=int, default=150, help="corrupted bundles per format")
    ap.add_argument("--list", action="store_true", help="list the cases and stop")
    ap.add_argument("--in-process", action="store_true", help="no worker process (debugging)")
    ap.add_argument("--selftest", action="store_true", help="only cases that crash or hang")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        t_build = time.perf_counter()
        cases = harness_cases() if args.selftest else catalogue(Path(tmp), args.flips)
        built = time.perf_counter() - t_build
        if args.only:
            cases = [c for c in cases if c.module == args.only]
        if args.list:
            for c in cases:
                print(f"{c.module:12s} {c.name}")
            return
        counts: dict = defaultdict(Counter)
        t0 = time.perf_counter()
        isolated = not args.in_process and hasattr(os, "fork")
        worker = Worker(cases, args.timeout) if isolated else None
        try:
            for i, c in enumerate(cases):
                kind, detail = worker.run(i) if worker else classify(c, args.timeout)
                counts[c.module][kind] += 1
                if kind != "clear":
                    print(f"{kind:8s} {c.module:12s} {c.name}: {detail}", flush=True)
        finally:
            if worker:
                worker.close()
    kinds = ("clear", "obscure", "silent", "hang", "crash")
    lines = ["| module | cases | " + " | ".join(kinds) + " |", "|---" * (len(kinds) + 2) + "|"]
    total = Counter()
    for mod in sorted(counts):
        total.update(counts[mod])
        n = sum(counts[mod].values())
        lines.append(f"| {mod} | {n} | " + " | ".join(str(counts[mod][k]) for k in kinds) + " |")
    n = sum(total.values())
    lines.append(f"| **all** | {n} | " + " | ".join(str(total[k]) for k in kinds) + " |")
    share = 100.0 * total["clear"] / max(n, 1)
    text = (
        f"{n} cases run in {time.perf_counter() - t0:.0f} s (the catalogue built in {built:.0f} s: "
        f"problems, files, bundles); clear {share:.1f} % "
        f"(targets: 0 silent, 0 hangs, 0 crashes, ≥ 95 % clear).\n\n" + "\n".join(lines) + "\n"
    )
    if args.only or args.selftest:
        print(text)
    else:  # prints it too, with the run's provenance
        write_results(Path(args.out) / "robustness.md", ["# Robustness catalogue\n", text])


if __name__ == "__main__":
    main()
