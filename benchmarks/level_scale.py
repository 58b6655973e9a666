"""The ratio of robust peak to RMS on the tuning scenes: the constant behind
``Denoiser(scale="rms")`` (:data:`tensor_cosdi.solvers.priors.PEAK_PER_RMS`).

A plug-and-play denoiser's level is relative to a scale of the start.  With
``scale="peak"`` it is the 99.9th percentile of ``|start|``
(:func:`~tensor_cosdi.solvers.priors.robust_peak`); with ``scale="rms"`` it is
``PEAK_PER_RMS`` times the start's RMS, a scale that follows the scene's mean
brightness as the noise of a measurement at a given SNR does.  ``PEAK_PER_RMS`` is the
median of ``P₉₉.₉ / RMS`` over the 28 tuning scenes as they are (the real-spectra
protocol's cubes: CAVE on the 28 KAIST bands), so a relative level means the same on a
typical scene under either scale.  The scenes magnified ``--zoom``× (``benchmarks/
real_spectra.py --zoom``) are listed beside them; the report scenes are not read.

    python benchmarks/level_scale.py [--zoom 4]

Never asserts anything; read the numbers.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _protocol import RESULTS, magnified, write_results  # noqa: E402

from tensor_cosdi import datasets  # noqa: E402
from tensor_cosdi.solvers import priors  # noqa: E402


def ratio(cube) -> float:
    return priors.robust_peak(cube) / priors.rms(cube)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--zoom", type=float, default=4.0, help="also each scene magnified ZOOM×")
    ap.add_argument("--out", default=str(RESULTS / "level_scale.md"))
    args = ap.parse_args(argv)
    if not args.zoom >= 1:
        raise SystemExit(f"--zoom must be a number ≥ 1, got {args.zoom:g}")
    rows = []
    for scene in datasets.TUNE_SCENES:
        cube, _ = datasets.load_hsi(scene, "kaist", dtype="float64")
        rows.append((scene, ratio(cube), ratio(magnified(cube, args.zoom))))
        print(scene, np.round(rows[-1][1:], 2), flush=True)
    as_is = np.array([r[1] for r in rows])
    zoomed = np.array([r[2] for r in rows])
    median = float(np.median(as_is))
    lines = [
        "# Robust peak against RMS on the tuning scenes",
        "",
        f"P₉₉.₉|x| / RMS(x) of each of the {len(rows)} tuning scenes (256×256×28, KAIST bands) "
        f"as it is and magnified {args.zoom:g}×.",
        "",
        f"| scene | as it is | magnified {args.zoom:g}× |",
        "|---|---|---|",
        *(f"| {s} | {a:.2f} | {z:.2f} |" for s, a, z in rows),
        "",
        "| views | min | 10th pct | median | 90th pct | max |",
        "|---|---|---|---|---|---|",
        *(
            f"| {label} | {v.min():.2f} | {np.percentile(v, 10):.2f} | {np.median(v):.2f} | "
            f"{np.percentile(v, 90):.2f} | {v.max():.2f} |"
            for label, v in (("as they are", as_is), (f"magnified {args.zoom:g}×", zoomed))
        ),
        "",
        f"Median as they are: **{median:.2f}**; `priors.PEAK_PER_RMS` in the library: "
        f"{priors.PEAK_PER_RMS:g} ("
        + ("the same" if round(median, 2) == priors.PEAK_PER_RMS else "they differ")
        + ").",
    ]
    write_results(args.out, lines)


if __name__ == "__main__":
    main()
