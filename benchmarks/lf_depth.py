"""Light-field depth on rendered views with occlusions: the occlusion-aware estimator against
the plain SSD cost volume.

Scenes (:func:`tensor_cosdi.scenes.layered_light_field`): a slanted
background plane and three slanted foreground shapes (ellipses and
polygons) that occlude it and each other, each with its own texture, 5×5
views, 3×3 samples per pixel; the disparity of the centre view is known
exactly.  Geometry is seeded (background −1.5 … −0.5 px per view step,
shapes −0.3 … 1.5, slopes up to ±0.8 px across the image).

* ``tune``: textures from scikit-image's photographs and eight CAVE tuning
  scenes (what the defaults of :func:`tensor_cosdi.depth.disparity_from_views`
  were chosen on; needs the research data);
* ``report``: textures from the report split's real CAVE scenes (three
  band groups as channels; needs the research data), never tuned on.

Scores over the image without a 12-pixel border: mean absolute error
(MAE, px), the share of pixels off by more than 0.07 px (bad-0.07, the
HCI benchmark's measure) and by more than 0.3 px, and seconds per scene.

    python benchmarks/lf_depth.py [--size 128] [--seeds 0,1,2] [--sets tune,report]
        [--out benchmarks/results]

Writes ``lf_depth.md`` / ``.json`` with the run's date, machine, commit and command.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import tensor_cosdi as tc
from tensor_cosdi import depth, scenes

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import provenance, write_results  # noqa: E402

BORDER = 12
METHODS = {
    "ssd (window 5, shiftable)": {"method": "ssd"},
    "guided filter, all views": {"method": "occlusion", "half_ratio": 1e-9},
    "occlusion-aware (default)": {},
}
TUNE_IMAGES = ("astronaut", "coffee", "chelsea", "rocket", "brick", "grass", "gravel", "camera")


def _resize(img, size):
    from skimage.transform import resize

    return resize(img, (size, size, img.shape[2]), anti_aliasing=True)


def tune_textures(size):
    from skimage import data

    out = []
    for name in TUNE_IMAGES:
        img = np.asarray(getattr(data, name)(), dtype=np.float64)
        img = img / img.max()
        img = np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img[..., :3]
        out.append(img)
    return out


#: CAVE tuning scenes whose textures join the photographs in the tuning set.
CAVE_TUNE = ("balloons", "cd", "cloth", "feathers", "flowers", "paints", "sponges", "clay")


def cave_textures(names):
    out = []
    for name in names:
        cube, _ = tc.datasets.load_hsi(name)
        groups = np.array_split(np.arange(cube.shape[2]), 3)
        out.append(np.stack([cube[..., g].mean(axis=2) for g in groups], -1))
    return out


def textures(which, size):
    """The texture pool of a set: ``"tune"`` (photographs and CAVE tuning scenes) or
    ``"report"`` (the CAVE report scenes)."""
    if which == "tune":
        return tune_textures(size) + cave_textures(CAVE_TUNE), size
    return cave_textures(tc.datasets.REPORT_SCENES), size


def _crop(img, rng, size):
    """A random square crop of at least half the image's short side, resized to ``size``."""
    h, w = img.shape[:2]
    side = int(rng.integers(min(h, w) // 2, min(h, w) + 1))
    y, x = int(rng.integers(0, h - side + 1)), int(rng.integers(0, w - side + 1))
    return _resize(img[y : y + side, x : x + side], size)


def _shape_mask(rng, size):
    from skimage.draw import ellipse, polygon

    m = np.zeros((size, size), bool)
    cy, cx = rng.uniform(0.25, 0.75, 2) * size
    if rng.random() < 0.5:
        ry, rx = rng.uniform(0.1, 0.25, 2) * size
        rr, cc = ellipse(cy, cx, ry, rx, shape=m.shape, rotation=rng.uniform(0, np.pi))
    else:
        k = int(rng.integers(3, 7))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))
        rad = rng.uniform(0.1, 0.25, k) * size
        rr, cc = polygon(cy + rad * np.sin(ang), cx + rad * np.cos(ang), shape=m.shape)
    m[rr, cc] = True
    return m


def make_scene(textures, seed, size):
    """``(views (5, 5, H, W, 3), disparity)`` of one seeded layered scene."""
    rng = np.random.default_rng(seed)
    slope = 0.8 / size
    pick = rng.permutation(len(textures))
    layers = [
        scenes.LightFieldLayer(
            _crop(textures[pick[0]], rng, size),
            (rng.uniform(-1.5, -0.5), *rng.uniform(-slope, slope, 2)),
        )
    ]
    for i in range(3):
        layers.append(
            scenes.LightFieldLayer(
                _crop(textures[pick[(i + 1) % len(pick)]], rng, size),
                (rng.uniform(-0.3, 1.5), *rng.uniform(-slope / 2, slope / 2, 2)),
                _shape_mask(rng, size),
            )
        )
    return scenes.layered_light_field(layers, views=(5, 5))


def score(truth, est):
    b = BORDER
    err = np.abs(est - truth)[b:-b, b:-b]
    return {"mae": float(err.mean()), "bad007": float((err > 0.07).mean()),
            "bad03": float((err > 0.3).mean())}  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--sets", default="tune,report")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    sets = args.sets.split(",")
    for s in sets:
        if s not in ("tune", "report"):
            raise SystemExit(f"--sets: unknown set {s!r} (tune, report)")
    if sets:
        try:
            tc.datasets.data_dir()
        except FileNotFoundError as exc:
            raise SystemExit(f"the texture sets need the research data ({exc})") from None
    rows = []
    for which in sets:
        pool, size = textures(which, args.size)
        for seed in seeds:
            lf, truth = make_scene(pool, seed, size)
            for label, opts in METHODS.items():
                t0 = time.perf_counter()
                est = depth.disparity_from_views(lf, max_disparity=2.0, **opts)
                sec = time.perf_counter() - t0
                row = {"set": which, "seed": seed, "method": label, "s": sec, **score(truth, est)}
                print(json.dumps(row), flush=True)
                rows.append(row)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    prov = provenance()  # before either results file is rewritten: the commit as it ran
    lines = [
        "# Light-field depth on rendered occluding planes",
        "",
        f"{args.size}×{args.size}, 5×5 views, seeds {args.seeds}; MAE in px per view step, "
        f"bad-0.07 / bad-0.3 = share of pixels off by more (border of {BORDER} px left out); "
        "means over seeds, and each seed's MAE.",
        "",
        "| set | method | MAE px | bad-0.07 % | bad-0.3 % | s / scene | per-seed MAE |",
        "|---|---|---|---|---|---|---|",
    ]
    for which in sets:
        for label in METHODS:
            r = [x for x in rows if x["set"] == which and x["method"] == label]
            per = " / ".join(f"{x['mae']:.3f}" for x in r)
            lines.append(
                f"| {which} | {label} | {np.mean([x['mae'] for x in r]):.3f} | "
                f"{100 * np.mean([x['bad007'] for x in r]):.1f} | "
                f"{100 * np.mean([x['bad03'] for x in r]):.1f} | "
                f"{np.median([x['s'] for x in r]):.1f} | {per} |"
            )
    best = {
        which: min(METHODS, key=lambda m: np.mean(
            [x["mae"] for x in rows if x["set"] == which and x["method"] == m]))
        for which in sets
    }  # fmt: skip
    lines += ["", "Lowest MAE: " + "; ".join(f"{w}: {m}" for w, m in best.items()) + "."]
    write_results(out / "lf_depth.md", lines)
    (out / "lf_depth.json").write_text(json.dumps({"rows": rows, **prov}, indent=1))


if __name__ == "__main__":
    main()
