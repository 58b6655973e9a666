"""``tensor-cosdi demo``: every registered imager with a demo scene, reconstructed and scored.

Each system of :data:`tensor_cosdi.systems.REGISTRY` whose class names a
``demo_scene`` is simulated on that seeded real-data scene
(``example_problem``) and reconstructed with OTD and GAP-TV; the table and
the PNG figures are described in :mod:`tensor_cosdi.cli`.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["run_demo", "demo_cases", "DEMO_METHODS"]


def demo_cases():
    """``(system, scene, options)`` of every registered system with a ``demo_scene`` (registry
    order)."""
    from ..systems import REGISTRY

    return tuple(
        (name, cls.demo_scene, dict(cls.demo_options))
        for name, cls in REGISTRY.items()
        if cls.demo_scene
    )


DEMO_METHODS = ("otd", "gap_tv")


def _samples_per_voxel(system) -> float:
    """Measured samples per voxel of ``system``'s cube: the size of its measurement (every
    snapshot and camera) over the size of its cube.  Below 1 the prior supplies what the
    measurement lacks; a single SD-CASSI snapshot of ``n`` bands through a shear of 1 px per
    band has about ``1/n``.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import SDCASSI
    >>> round(_samples_per_voxel(SDCASSI(np.ones((64, 64)), n_bands=28)), 4)  # 64×91 / 64×64×28
    0.0508
    """
    return float(np.prod(system.measurement_shape) / np.prod(system.cube_shape))


def _to_uint8(img: np.ndarray, lo=None, hi=None) -> np.ndarray:
    img = np.asarray(img, dtype=np.float64)
    lo = img.min() if lo is None else lo
    hi = img.max() if hi is None else hi
    scaled = np.zeros_like(img) if hi <= lo else np.clip((img - lo) / (hi - lo), 0.0, 1.0)
    return (255 * scaled).round().astype(np.uint8)


def _measurement_image(g: np.ndarray) -> np.ndarray:
    g = np.asarray(g, dtype=np.float64)
    if g.ndim == 3:  # frames / snapshots side by side
        g = np.concatenate(list(np.moveaxis(g, -1, 0)), axis=1)
    return _to_uint8(g)


def _has_depth(system: str) -> bool:
    from ..systems import REGISTRY

    return REGISTRY[system].has_depth


def _has_matplotlib() -> bool:
    import importlib.util

    return importlib.util.find_spec("matplotlib") is not None


def _demo_files(out: Path, cases, figures: bool) -> list[Path]:
    files = []
    for system, _, _ in cases:
        parts = ("measurement", "truth", *DEMO_METHODS, "error_otd") + (
            ("depth",) if _has_depth(system) else ()
        )
        files += [out / f"{system}_{part}.png" for part in parts]
        if figures:
            files.append(out / f"{system}_compare.png")
    if figures:
        files.append(out / "summary.png")
    return files


def _compare_figure(problem, results, title):
    """The labelled comparison (tensor_cosdi.plot.compare) plus the depth maps where there are
    any; returns the figure."""
    import matplotlib.pyplot as plt

    from .. import plot
    from ..studies import spectral_view

    truth = spectral_view(problem, problem.cube)
    ests = {r["method"]: spectral_view(problem, r["result"].cube) for r in results}
    depth = problem.system.depth_kind and results[0]["result"].depth is not None
    fig = plt.figure(figsize=(2.6 * (len(ests) + 1) + (2.8 if depth else 0), 5.6))
    sub = fig.subfigures(1, 2, width_ratios=[len(ests) + 1, 1.1]) if depth else [fig]
    plot.compare(truth, ests, problem.wavelengths, fig=sub[0])
    if depth:
        is_phase = "phase" in problem.extras
        d = np.asarray(results[0]["result"].depth, dtype=np.float64)
        ax = sub[1].subplots(1, 1)
        label = "wrapped phase (rad)" if is_phase else str(problem.system.depth_kind)
        plot.depth(d[..., 0] if d.ndim == 3 else d, ax=ax, label=f"{label}, OTD")
    fig.suptitle(title, fontsize=10)
    return fig


def _summary_figure(rows, title):
    import matplotlib.pyplot as plt

    systems = list(dict.fromkeys(s for s, _, _ in rows))
    fig, ax = plt.subplots(figsize=(1.3 * len(systems) + 2, 3.6))
    width = 0.8 / len(DEMO_METHODS)
    for k, m in enumerate(DEMO_METHODS):
        vals = [
            next(r["psnr"] for s2, _, r in rows if s2 == s and r["method"] == m) for s in systems
        ]
        ax.bar(np.arange(len(systems)) + k * width, vals, width, label=m)
    ax.set_xticks(np.arange(len(systems)) + width * (len(DEMO_METHODS) - 1) / 2, systems,
                  rotation=30, ha="right", fontsize=8)  # fmt: skip
    ax.set_ylabel("PSNR (dB)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _depth_text(scores: dict) -> str:
    if "planes_right" in scores:
        return f"{scores['planes_right']:.0%} planes"
    if "disparity_mae" in scores:
        return f"{scores['disparity_mae']:.2f} px"
    if "phase_mae" in scores:
        return f"{scores['phase_mae']:.2f} rad"
    return "-"


def _depth_image(truth, est, is_phase: bool) -> np.ndarray:
    """Truth | estimate side by side on one scale (wrapped phase: [−π, π])."""
    t = np.asarray(truth, dtype=np.float64)
    e = np.asarray(est, dtype=np.float64)
    if is_phase:
        from ..depth import wrap

        t, e, lo, hi = wrap(t[..., 0]), e[..., 0], -np.pi, np.pi
    else:
        lo, hi = float(min(t.min(), e.min())), float(max(t.max(), e.max()))
    gap = np.full((t.shape[0], 2), lo)
    return _to_uint8(np.concatenate([t, gap, e], axis=1), lo, hi)


def run_demo(args) -> int:
    from skimage import io
    from tqdm import tqdm

    from ..colour import to_srgb
    from ..io import atomic_write
    from ..studies import compare, make_problem, score_depth, spectral_view

    if args.size % 4:
        raise ValueError(
            f"--size must be a multiple of 4 (the light field has 4×4 views), got {args.size}"
        )
    out = Path(args.out)
    cases = demo_cases()
    figures = _has_matplotlib()
    targets = _demo_files(out, cases, figures)
    existing = [str(t) for t in targets if t.exists()]
    if existing and not args.force:  # refuse before computing or writing anything
        raise FileExistsError(
            f"{len(existing)} demo file(s) exist, e.g. {existing[0]}; pass --force to overwrite"
        )
    print(
        f"tensor_cosdi demo — {args.size}×{args.size} scenes, {args.bands} bands 450–650 nm, "
        f"SNR {args.snr_db:g} dB, seed {args.seed}; methods: {', '.join(DEMO_METHODS)}"
    )
    rows = []
    images = {}
    figs = {}
    setting = f"{args.size}×{args.size}, {args.bands} bands, {args.snr_db:g} dB, seed {args.seed}"
    if figures:
        import matplotlib

        matplotlib.use("Agg")
    t_all = time.perf_counter()
    bar = tqdm(total=len(cases) * len(DEMO_METHODS), desc="reconstructing", disable=args.quiet)
    ratios = {}
    for system, scene, extra in cases:
        problem = make_problem(
            system,
            scene,
            shape=(args.size, args.size),
            n_bands=args.bands,
            snr_db=args.snr_db,
            rng=args.seed,
            **extra,
        )
        ratios[system] = _samples_per_voxel(problem.system)
        results = []
        for method in DEMO_METHODS:
            results += compare(problem, [method])
            bar.update(1)
        for r in results:
            r["depth"] = (
                score_depth(problem, r["result"].depth) if problem.system.depth_kind else {}
            )
        rows += [(system, scene, r) for r in results]
        if problem.system.depth_kind:
            is_phase = "phase" in problem.extras
            truth_depth = problem.extras["phase"] if is_phase else problem.depth
            images[f"{system}_depth.png"] = _depth_image(
                truth_depth, results[0]["result"].depth, is_phase
            )
        wl = problem.wavelengths
        truth = spectral_view(problem, problem.cube)
        peak = float(truth.max())
        images[f"{system}_measurement.png"] = _measurement_image(problem.measurement)
        images[f"{system}_truth.png"] = _to_uint8(to_srgb(truth / peak, wl), 0.0, 1.0)
        for r in results:
            est = spectral_view(problem, r["result"].cube)
            images[f"{system}_{r['method']}.png"] = _to_uint8(
                to_srgb(np.clip(est / peak, 0, None), wl), 0.0, 1.0
            )
        otd = spectral_view(problem, results[0]["result"].cube)
        err = np.sqrt(np.mean((otd - truth) ** 2, axis=2))
        images[f"{system}_error_otd.png"] = _to_uint8(err, 0.0, 0.25 * peak)
        if figures:
            figs[f"{system}_compare.png"] = _compare_figure(
                problem, results, f"{system} — {scene}, {setting}"
            )
    bar.close()
    if figures:
        figs["summary.png"] = _summary_figure(rows, f"tensor-cosdi demo: {setting}")
    out.mkdir(parents=True, exist_ok=True)
    for name, img in images.items():  # each file atomic: a reader never sees half a PNG
        atomic_write(
            out / name,
            lambda tmp, img=img: io.imsave(tmp, img, check_contrast=False),
            overwrite=True,  # existing files were refused above unless --force
        )
    for name, fig in figs.items():
        import matplotlib.pyplot as plt

        atomic_write(
            out / name,
            lambda tmp, fig=fig: fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png"),
            overwrite=True,
        )
        plt.close(fig)

    head = (
        f"{'system':12s} {'scene':13s} {'cube':>16s} {'meas/vox':>8s} {'method':>7s} "
        f"{'PSNR dB':>8s} {'SSIM':>6s} "
        f"{'SAM °':>6s} "
        f"{'seconds':>8s}  {'depth error':>11s}"
    )
    print(head)
    print("-" * len(head))
    shapes = {}
    for system, scene, r in rows:
        shape = shapes.setdefault(system, "×".join(map(str, r["result"].cube.shape)))
        print(
            f"{system:12s} {scene:13s} {shape:>16s} {ratios[system]:8.3f} {r['method']:>7s} "
            f"{r['psnr']:8.2f} "
            f"{r['ssim']:6.3f} "
            f"{r['sam']:6.2f} {r['seconds']:8.2f}  {_depth_text(r['depth']):>11s}"
        )
    print(
        "meas/vox: measured samples per voxel of the cube (all snapshots and cameras together; "
        "the fewer, the more the prior must supply). "
        "PSNR/SSIM per band (extra axes folded into bands), data range = the truth's peak; SAM in "
        "degrees. "
        "Depth error (Result.depth): DFA depth planes right, C3SLFI disparity error (px per view), "
        f"CS2LI/Mu-CoSDI wrapped fringe-phase error. Total {time.perf_counter() - t_all:.1f} s."
    )
    print(
        f"figures written to {out.resolve()} (measurement, truth, otd, gap_tv, error_otd per "
        "system; depth: truth | OTD"
        + ("; SYSTEM_compare.png labelled comparisons and summary.png)" if figures else
           "; install matplotlib — pip install 'tensor_cosdi[plot]' — for labelled figures)")
    )  # fmt: skip
    return 0
