"""The real-spectra protocol shared by the benchmark scripts: problems, scores, provenance,
cross-validation over scene folds.

Problems: a CAVE scene of the research data resampled onto the 28 KAIST band
centres (256×256), SD-CASSI with 2 px per band and one of two codes:

* ``"tsa"``: the real 256×256 TSA mask (``masks/tsa_mask256.mat`` of the
  research data);
* ``"random"``: a seeded random binary code of density ½ (seed
  :data:`RANDOM_MASK_SEED`): a user's code is not the TSA mask.

Noise: noiseless (``None``) or white Gaussian at a given SNR (seed 0).  PSNR
is the mean of per-band PSNRs over the cube with data range 1, the estimate
clipped to [0, 1]; SSIM per band; SAM in degrees.

Cross-validation (:func:`cross_validate`): the 28 tuning scenes fall into the
folds of :func:`tensor_cosdi.datasets.tune_folds`; for each fold, the
candidate setting with the best mean PSNR on the *other* folds is scored on
that fold.  The fold scores' mean and spread say how well choosing on some
scenes carries over to others; the setting chosen on all 28 is the one a
default may take, and only then is it scored on the report scenes.
"""

from __future__ import annotations

import datetime
import itertools
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import datasets, metrics
from tensor_cosdi.solvers.snr import clear_cache as clear_snr_cache

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
MASKS = ("tsa", "random")
#: Every registered imager, in the order the per-imager benchmarks list them.
IMAGERS = (
    "sd_cassi", "dd_cassi", "dual_camera_cassi", "cassi_vsi", "lytro_cassi", "c3slfi",
    "cassdi_dfa", "cs2li", "mu_cosdi",
)  # fmt: skip
RANDOM_MASK_SEED = 2024


def load_mask(kind: str) -> np.ndarray:
    """The 256×256 code of :data:`MASKS` (the TSA mask needs the research data)."""
    if kind == "tsa":
        import scipy.io

        path = datasets.data_file("masks/tsa_mask256.mat")
        return scipy.io.loadmat(path)["mask"].astype(np.float64)
    if kind == "random":
        rng = np.random.default_rng(RANDOM_MASK_SEED)
        return (rng.random((256, 256)) < 0.5).astype(np.float64)
    raise ValueError(f"mask must be one of {MASKS}, got {kind!r}")


def problem(scene: str, snr, mask, seed: int = 0, zoom: float = 1.0, illuminant=None):
    """``(system, cube, measurement)``: ``scene`` through SD-CASSI with ``mask`` (an array).

    ``zoom > 1``: the scene's centre crop of ``1/zoom`` its side, magnified back to the
    full size (:func:`magnified`).  ``illuminant`` (a key of ``colour.SDS_ILLUMINANTS``):
    the reflectance lit by that light and scaled to a peak of 1
    (:func:`tensor_cosdi.colour.radiance`), as radiance databases are.
    """
    system, cube, (g,) = problems(scene, [snr], mask, seed, zoom, illuminant)
    return system, cube, g


def problems(scene: str, snrs, mask, seed: int = 0, zoom: float = 1.0, illuminant=None):
    """``(system, cube, measurements)``: :func:`problem` at each SNR of ``snrs`` (the scene
    loaded once)."""
    cube, wl = datasets.load_hsi(scene, "kaist", dtype="float32")
    if zoom != 1:
        cube = magnified(cube, zoom)
    if illuminant is not None:
        cube = tc.colour.radiance(cube, wl, illuminant).astype(np.float32)
    system = tc.systems.SDCASSI(mask, n_bands=28, shifts=2, wavelengths=wl)
    gs = [np.asarray(system.simulate(cube, snr_db=snr, rng=seed), dtype=np.float32) for snr in snrs]
    return system, cube, gs


def magnified(cube, zoom: float):
    """The centre crop of ``cube`` of ``1/zoom`` its side, magnified back to its size (cubic
    spline, floored at 0): a scene seen closer, with the smoother, larger-scale structure of
    a camera of higher resolution than the 2×2-downsampled CAVE scenes."""
    from scipy.ndimage import zoom as nd_zoom

    if not zoom >= 1:
        raise ValueError(f"zoom must be ≥ 1, got {zoom!r}")
    h, w = cube.shape[:2]
    ch, cw = int(round(h / zoom)), int(round(w / zoom))
    r0, c0 = (h - ch) // 2, (w - cw) // 2
    crop = np.asarray(cube[r0 : r0 + ch, c0 : c0 + cw], dtype=np.float64)
    out = nd_zoom(crop, (h / ch, w / cw, 1), order=3, grid_mode=True, mode="grid-mirror")
    return np.maximum(out, 0.0).astype(cube.dtype)


def scene_view(label: str) -> tuple[str, float, str | None]:
    """``(scene, zoom, illuminant)`` of a scene label ``name[@zoom][~illuminant]``: ``"cloth"``
    is the scene as it is, ``"cloth@2"`` its centre half magnified 2× (:func:`magnified`),
    ``"cloth~A"`` the scene lit by CIE illuminant A and scaled to a peak of 1 (a radiance
    database's kind of scene; :func:`tensor_cosdi.colour.radiance`), ``"cloth@2~A"`` both."""
    rest, tilde, illuminant = str(label).partition("~")
    if tilde:
        known = tc.colour.colour_science().SDS_ILLUMINANTS
        if illuminant not in list(known):  # exact keys: the mapping also takes other cases
            raise ValueError(
                f"scene view {label!r}: the illuminant after '~' must be a key of "
                f"colour.SDS_ILLUMINANTS (e.g. A, D65, LED-B3), got {illuminant!r}"
            )
    name, sep, z = rest.partition("@")
    zoom = 1.0
    if sep:
        try:
            zoom = float(z)
        except ValueError:
            zoom = float("nan")
        if not zoom >= 1:
            raise ValueError(f"scene view {label!r}: the zoom after '@' must be a number ≥ 1")
    return name, zoom, (illuminant if tilde else None)


def views(scenes, zoom, lights=()) -> tuple[str, ...]:
    """``scenes`` followed by their ``@zoom`` views (``zoom`` ``None`` or 1: none) and their
    ``~light`` views, one per illuminant of ``lights``."""
    scenes = tuple(scenes)
    out = scenes
    if zoom is not None and zoom != 1:
        out += tuple(f"{s}@{zoom:g}" for s in scenes)
    for light in lights:
        out += tuple(f"{s}~{light}" for s in scenes)
    return out


def score(truth, est) -> dict:
    est = np.clip(np.asarray(est, dtype=np.float64), 0.0, 1.0)
    truth = np.asarray(truth, dtype=np.float64)
    return {
        "psnr": metrics.psnr(truth, est, data_range=1.0),
        "ssim": metrics.ssim(truth, est, data_range=1.0),
        "sam": metrics.sam(truth, est),
    }


def plain_gap_tv(system, g, *, iters=80, weight=0.2, tv_iter=10):
    """The reference: accelerated GAP-TV in a few lines (Φsum = A Aᵀ's diagonal)."""
    from skimage.restoration import denoise_tv_chambolle

    op = system.operator
    phisum = np.asarray(op.gram_dual().d, dtype=g.dtype)
    phisum = np.where(phisum == 0, 1, phisum)
    x = op.adjoint(g / phisum)
    y1 = np.zeros_like(g)
    for _ in range(iters):
        ax = op.forward(x)
        y1 = y1 + (g - ax)
        x = x + op.adjoint((y1 - ax) / phisum)
        x = denoise_tv_chambolle(x, weight=weight, max_num_iter=tv_iter, channel_axis=-1)
    return x


_WARMED: set = set()


def _warm_up(method: str, options: dict) -> None:
    """Run ``method`` once, untimed, on a small problem: the first call in a process pays
    one-time costs (torch's import, loading a network, thread pools) that are not the
    method's, and would land on whichever scene comes first."""
    key_ = json.dumps([method, options], sort_keys=True)
    if method == "plain_gap_tv" or key_ in _WARMED:
        return
    rng = np.random.default_rng(0)
    system = tc.systems.SDCASSI((rng.random((32, 32)) < 0.5).astype(float), n_bands=28, shifts=2)
    tc.reconstruct(system, system.simulate(rng.random(system.cube_shape)), method, **options)
    _WARMED.add(key_)


def run(method: str, system, g, options: dict):
    """``(estimate, seconds)`` of a registered method or ``"plain_gap_tv"`` (after an untimed
    warm-up call of the method in this process).

    The SNR estimates cached by earlier calls are forgotten first: the time is that of a user's
    single call, the measurement's SNR fit included, whichever method ran on it before."""
    _warm_up(method, options)
    clear_snr_cache()
    t0 = time.perf_counter()
    if method == "plain_gap_tv":
        cube = plain_gap_tv(system, g, **options)
    else:
        cube = tc.reconstruct(system, g, method, **options).cube
    return cube, time.perf_counter() - t0


def median_ms(fn, repeats: int) -> float:
    """Median milliseconds of ``repeats`` calls of ``fn`` after one untimed call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def provenance() -> dict:
    """Date, machine, commit and command of this run (for every results file)."""
    try:
        if os.environ.get("TENSOR_COSDI_COMMIT"):  # a copy run on another machine
            raise OSError
        commit = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
            capture_output=True, text=True, check=True,
        ).stdout.strip()  # fmt: skip
        dirty = subprocess.run(
            ["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True, text=True, check=True,
        ).stdout.strip()  # fmt: skip
        commit += "+changes" if dirty else ""
    except (OSError, subprocess.CalledProcessError):
        commit = os.environ.get("TENSOR_COSDI_COMMIT", "unknown")
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": _numba_version(),
        "tensor_cosdi": tc.__version__,
        "commit": commit,
        "command": "python " + shlex.join([Path(sys.argv[0]).as_posix(), *sys.argv[1:]]),
    }


def _numba_version() -> str:
    """numba's version where the compiled TV steps run (``fast`` extra), else ``"off"``: the
    warm TV steps of OTD's and ``pnp_fast``'s first stages are 3–4× faster with them
    (``results/tv_speed.md``), so a time means little without it."""
    from tensor_cosdi.solvers.denoisers import compiled_tv

    if not compiled_tv():
        return "off"
    import numba

    return numba.__version__


def cpu_model() -> str:
    """The CPU's model name (Linux ``/proc/cpuinfo``; else ``platform.processor()``), or
    ``"unknown CPU"``."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.lower().startswith("model name"):
                    return " ".join(line.split(":", 1)[1].split()) or "unknown CPU"
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine() -> str:
    """Architecture, CPU model, CPU count and system; where torch is loaded (a run of a learned
    method), whether the CPU runs bfloat16 natively: ``precision="auto"`` (``pnp_fast``) runs
    the network in bfloat16 only there, about twice as fast, so a time means little without
    it."""
    text = f"{platform.machine()} {cpu_model()}, {os.cpu_count()} CPUs, {platform.system()}"
    if "torch" in sys.modules:
        from tensor_cosdi.learn.spectral_net import bfloat16_is_fast

        text += ", bfloat16 native" if bfloat16_is_fast() else ", no native bfloat16"
    return text


def provenance_lines(prov: dict) -> str:
    return (
        f"Run {prov['date']} on {prov['machine']} (Python {prov['python']}, NumPy "
        f"{prov['numpy']}, numba {prov.get('numba', 'off')}, tensor_cosdi "
        f"{prov['tensor_cosdi']}, commit {prov['commit']}).  \n"
        f"Command: `{prov['command']}`"
    )


def write_results(path, lines) -> str:
    """Write ``lines`` and the run's provenance to the results file ``path``; print and return
    the text."""
    text = "\n".join(lines) + "\n\n" + provenance_lines(provenance()) + "\n"
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    print(text)
    return text


def candidates(grid: dict) -> list[dict]:
    """Every combination of a ``{option: [values]}`` grid, in a fixed order."""
    if not grid:
        return [{}]
    names = sorted(grid)
    for n in names:
        if not isinstance(grid[n], list) or not grid[n]:
            raise ValueError(f"grid option {n!r} needs a non-empty list of values")
    return [dict(zip(names, vals)) for vals in itertools.product(*(grid[n] for n in names))]


def pnp_fast_settings(system, g) -> dict:
    """``pnp_fast``'s own settings on the measurement ``g`` as ``pnp_gap`` options, less
    ``precision`` (:func:`tensor_cosdi.solvers.pnp_gap.fast_settings`): ``pnp_gap`` with these
    and another denoiser is ``pnp_fast`` with it."""
    from tensor_cosdi.solvers.pnp_gap import fast_settings

    out = fast_settings(system, g)
    del out["precision"]
    return out


def pnp_fast_with(system, g, denoiser):
    """The cube of ``pnp_fast`` on ``g`` with another ``denoiser`` (``pnp_gap`` with
    :func:`pnp_fast_settings`)."""
    return tc.reconstruct(
        system, g, "pnp_gap", denoiser=denoiser, **pnp_fast_settings(system, g)
    ).cube


def key(scene, snr, mask, method, options) -> str:
    return json.dumps([scene, snr, mask, method, options], sort_keys=True)


class Store:
    """Runs appended to a JSON file as they finish; a killed run resumes where it stopped.

    A stored row is reused only while its method is not in ``fresh`` (method names, or
    ``{"all"}``): a fresh row replaces the stored one.  Each new row records the commit it was
    computed at; :meth:`commits` says which commits the rows a run used came from, so a table
    rendered from stored rows never passes them off as the current code's.
    """

    def __init__(self, path: Path, *, fresh=()):
        self.path = Path(path)
        self.runs = json.loads(self.path.read_text())["runs"] if self.path.exists() else []
        self.index = {
            key(r["scene"], r["snr_db"], r["mask"], r["method"], r["options"]): r for r in self.runs
        }
        self.fresh, self.used, self.commit = set(fresh), {}, provenance()["commit"]

    def get(self, scene, snr, mask_kind, method, options):
        return self.index.get(key(scene, snr, mask_kind, method, options))

    def commits(self) -> str:
        """``"abc1234 (12 rows), def5678 (3 rows)"``: where this run's rows were computed."""
        counts: dict = {}
        for row in self.used.values():
            c = row.get("commit", "not recorded")
            counts[c] = counts.get(c, 0) + 1
        return ", ".join(f"{c} ({n} row{'s' * (n != 1)})" for c, n in counts.items())

    def ensure(self, scene, snr, mask_kind, method, options, *, cache):
        """The run's row, computing it (and saving) when missing or asked fresh."""
        k = key(scene, snr, mask_kind, method, options)
        row = self.get(scene, snr, mask_kind, method, options)
        if row is not None and (k in self.used or not self.fresh & {method, "all"}):
            self.used[k] = row
            return row
        pk = (scene, snr, mask_kind)
        if pk not in cache:
            cache.clear()
            name, zoom, light = scene_view(scene)
            cache[pk] = problem(name, snr, load_mask(mask_kind), zoom=zoom, illuminant=light)
        system, cube, g = cache[pk]
        est, sec = run(method, system, g, options)
        row = {
            "scene": scene, "snr_db": snr, "mask": mask_kind, "method": method,
            "options": options, "seconds": sec, **score(cube, est), "commit": self.commit,
        }  # fmt: skip
        old = self.index.get(k)
        self.runs = [r for r in self.runs if r is not old] + [row]
        self.index[k] = self.used[k] = row
        tmp = self.path.with_name(self.path.name + ".tmp")
        tmp.write_text(json.dumps({"runs": self.runs}, indent=1))
        os.replace(tmp, self.path)
        print(
            f"{scene:26s} {snr_label(snr):9s} {mask_kind:6s} {method:12s} "
            f"{json.dumps(options, sort_keys=True):40s} PSNR {row['psnr']:6.2f} {sec:6.1f} s",
            flush=True,
        )
        return row


def positive_numbers(text: str, flag: str) -> list[float]:
    """A command line's comma-separated finite numbers > 0, or ``SystemExit`` naming ``flag``."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(np.isfinite(v) and v > 0 for v in values):
        raise SystemExit(f"{flag} takes finite numbers > 0, comma-separated, got {text!r}")
    return values


def snr_label(snr) -> str:
    return "noiseless" if snr is None else f"{snr:g} dB"


def pick(
    means, seconds=None, tie_db: float = 0.0, keep: int | None = None, no_slower: bool = False,
    budget_s: float | None = None,
) -> int:  # fmt: skip
    """Index of the best mean PSNR.  With ``tie_db > 0`` the candidates within ``tie_db`` of
    the best are a tie: won by ``keep`` (the default in use: a change must gain more than
    ``tie_db``) when it is among them, else by the fastest (``seconds``).  ``no_slower``
    (with ``keep`` and ``seconds``): only candidates whose median seconds are at most
    ``keep``'s compete (a time budget the default in use already meets).  ``budget_s`` (with
    ``seconds``): only candidates whose median seconds are at most ``budget_s`` compete (a
    method's stated time budget); where none is, the fastest is chosen."""
    allowed = range(len(means))
    if no_slower:
        if keep is None or seconds is None:
            raise ValueError("no_slower needs the candidate in use (keep) and the seconds")
        allowed = [i for i in allowed if seconds[i] <= seconds[keep]]
    if budget_s is not None:
        if seconds is None or not budget_s > 0:
            raise ValueError(f"budget_s needs the seconds and a budget > 0, got {budget_s!r}")
        within = [i for i in allowed if seconds[i] <= budget_s]
        allowed = within or [min(allowed, key=lambda i: seconds[i])]
    best = max(allowed, key=lambda i: means[i])
    if tie_db <= 0:
        return best
    near = [i for i in allowed if means[i] >= means[best] - tie_db]
    if keep is not None and keep in near:
        return keep
    if seconds is None:
        return best
    return min(near, key=lambda i: (seconds[i], -means[i]))


def cross_validate(
    rows_of, cands, folds, *, seconds_of=None, tie_db: float = 0.0, keep=None,
    no_slower: bool = False, budget_s: float | None = None,
):  # fmt: skip
    """Fold-wise choice: ``rows_of(candidate, scenes) -> [PSNR]``.

    With ``tie_db > 0``, candidates within ``tie_db`` dB of the best mean are a tie, won by
    ``keep`` (a candidate of ``cands``, the default in use) when it is one of them, else by
    the smallest median of ``seconds_of(candidate, scenes) -> [seconds]`` (:func:`pick`).
    ``no_slower``: only candidates no slower (median seconds) than ``keep`` on the same
    scenes are chosen; ``budget_s``: only candidates whose median seconds on them are at most
    ``budget_s`` (:func:`pick`).

    Returns ``{"folds": [{"chosen", "held_out_psnr", "train_psnr"}], "mean", "spread",
    "chosen_on_all", "all_means", "all_seconds"}`` where ``spread`` is the standard deviation
    of the held-out fold means.
    """

    def secs(scenes):
        if seconds_of is None:
            return None
        return [float(np.median(seconds_of(c, scenes))) for c in cands]

    k_keep = None if keep is None else cands.index(keep)
    out = []
    for k, fold in enumerate(folds):
        rest = [s for j, f in enumerate(folds) if j != k for s in f]
        means = [float(np.mean(rows_of(c, rest))) for c in cands]
        best = pick(means, secs(rest), tie_db, k_keep, no_slower, budget_s)
        out.append(
            {
                "fold": k,
                "chosen": cands[best],
                "train_psnr": means[best],
                "held_out_psnr": float(np.mean(rows_of(cands[best], list(fold)))),
            }
        )
    every = [s for f in folds for s in f]
    all_means = [float(np.mean(rows_of(c, every))) for c in cands]
    all_seconds = secs(every)
    held = [f["held_out_psnr"] for f in out]
    return {
        "folds": out,
        "mean": float(np.mean(held)),
        "spread": float(np.std(held)),
        "chosen_on_all": cands[pick(all_means, all_seconds, tie_db, k_keep, no_slower, budget_s)],
        "all_means": all_means,
        "all_seconds": all_seconds,
    }
