"""Speed of the SD-CASSI operator against a memory copy (issue: foundation).

For a 256×256×28 float32 cube, a 256×256 mask and a 2-px-per-band shear
(measurement 256×310), prints the median time of the SD-CASSI forward
(code → shear → sum over bands) and of its adjoint, each as a ratio to a copy
of the cube measured in the same run, for two memory layouts of the same
logical ``(x, y, λ)`` tensor:

* ``F (λ, y, x)``: Fortran order, what the adjoint returns (so solver
  iterates stay in it) and what the strided kernel of
  ``tensor_cosdi/operators/_kernels.py`` reads;
* ``band-major``: each band slice ``cube[:, :, l]`` C-contiguous (the
  per-band loop);
* ``C``: NumPy's default, λ fastest in memory (one sparse gather product,
  ``operators._kernels.GatherMatrix``).

Reference rows: the same composition executed factor by factor (no fusion)
and a plain per-band loop over the C layout.

    python benchmarks/operators.py [--repeats 50] [--mask PATH] [--out FILE]

The table and the run's provenance go to ``benchmarks/results/operators.md``.

Never asserts anything: machines are shared and noisy; read the ratios.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

from tensor_cosdi.operators import Code, Shear, SumAxis

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _protocol import RESULTS, write_results  # noqa: E402


def default_mask() -> str | None:
    """The real TSA mask of the research data (``TENSOR_COSDI_DATA``), or ``None``."""
    from tensor_cosdi import datasets

    try:
        return str(datasets.data_file("masks/tsa_mask256.mat"))
    except FileNotFoundError:
        return None


def median_seconds(fn, repeats):
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def load_mask(path):
    """The mask at ``path``; a seeded random binary one only for ``path`` ``"random"`` (the
    timing does not depend on the code's values, and the table says which was used)."""
    if path != "random":
        if path is None or not Path(path).is_file():
            raise SystemExit(
                f"mask file {path!r} not found (the research data: set TENSOR_COSDI_DATA); "
                "--mask random times a seeded random code instead"
            )
        import scipy.io

        return scipy.io.loadmat(path)["mask"].astype(np.float32), f"real mask {Path(path).name}"
    rng = np.random.default_rng(0)
    return (rng.random((256, 256)) < 0.5).astype(np.float32), "seeded random binary mask"


def verdicts(rows, target: float = 3.0) -> list[str]:
    """One line per operation kind, computed from the table: the layouts within ``target``
    copies and those above it."""
    out = []
    for op in ("forward (checked)", "adjoint (checked)"):
        got = [(layout, ratio) for layout, name, _, ratio, _ in rows if name == op]
        ok = [f"{layout} {ratio:.2f}×" for layout, ratio in got if ratio <= target]
        over = [f"{layout} {ratio:.2f}×" for layout, ratio in got if ratio > target]
        if len(got) == 1:  # the adjoint reads the measurement, whatever layout the cube has
            layout, ratio = got[0]
            within = "within" if ratio <= target else "above"
            out.append(f"* {op}: {ratio:.2f}× a copy, {within} {target:g}× (one measurement).")
            continue
        out.append(
            f"* {op}: within {target:g}× a copy in "
            + (", ".join(ok) if ok else "no layout")
            + ("; above it in " + ", ".join(over) if over else "; every layout within it")
            + "."
        )
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50)
    ap.add_argument("--mask", default=default_mask(), help="mask .mat file, or 'random'")
    ap.add_argument("--out", default=str(RESULTS / "operators.md"), help="results file")
    args = ap.parse_args(argv)

    nx, ny, nb, step = 256, 256, 28, 2
    mask, mask_note = load_mask(args.mask)
    shape = (nx, ny, nb)
    shear = Shear(shape, step)
    op = SumAxis(shear.output_shape, 2) @ shear @ Code(mask, shape)
    assert op.output_shape == (256, 310)

    rng = np.random.default_rng(1)
    cube_c = rng.random(shape, dtype=np.float32)
    cube_b = np.moveaxis(np.ascontiguousarray(np.moveaxis(cube_c, 2, 0)), 0, 2)
    cube_f = np.asfortranarray(cube_c)
    y = op.forward(cube_c)

    def naive_forward(x):
        w = x * mask[:, :, None]
        out = np.zeros(op.output_shape, np.float32)
        for l in range(nb):
            out[:, step * l : step * l + ny] += w[:, :, l]
        return out

    def unfused_forward(x):
        for f in reversed(op.factors):
            x = f.apply(x)
        return x

    def unfused_adjoint(v):
        for f in op.factors:
            v = f.apply_adjoint(v)
        return v

    rows = []
    r = args.repeats
    for layout, cube in (("F (λ, y, x)", cube_f), ("band-major", cube_b), ("C", cube_c)):
        t_copy = median_seconds(lambda: np.copy(cube, order="K"), r)
        entries = [
            ("forward (checked)", lambda: op.forward(cube)),
            ("forward (kernel)", lambda: op.apply(cube)),
            ("adjoint (checked)", lambda: op.adjoint(y)),
            ("adjoint (kernel)", lambda: op.apply_adjoint(y)),
            ("forward, unfused factors", lambda: unfused_forward(cube)),
            ("adjoint, unfused factors", lambda: unfused_adjoint(y)),
        ]
        if layout == "C":
            entries.append(("forward, naive per-band loop", lambda: naive_forward(cube)))
        if layout != "F (λ, y, x)":
            entries = [
                e for e in entries if "adjoint" not in e[0]
            ]  # the adjoint ignores the cube layout
        for name, fn in entries:
            t = median_seconds(fn, r)
            rows.append((layout, name, t * 1e3, t / t_copy, t_copy * 1e3))
    # the adjoint returns band-major output whatever the input layout
    lines = [
        f"SD-CASSI 256×256×28 float32, 2 px/band shear → 256×310, {mask_note}; "
        f"median of {r} repeats; {platform.processor() or platform.machine()}, "
        f"numpy {np.__version__}",
        "",
        "| cube layout | operation | ms | × copy | copy ms |",
        "|---|---|---:|---:|---:|",
    ]
    for layout, name, ms, ratio, copy_ms in rows:
        lines.append(f"| {layout} | {name} | {ms:.3f} | {ratio:.2f} | {copy_ms:.3f} |")
    lines += ["", *verdicts(rows)]
    write_results(args.out, lines)
    return rows


if __name__ == "__main__":
    main()
