"""Every sphinx-gallery example runs to completion (headless)."""

import runpy
from pathlib import Path

import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*/plot_*.py"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs(path, monkeypatch):
    monkeypatch.setattr(plt, "show", lambda *a, **k: None)
    try:
        runpy.run_path(str(path), run_name="__main__")
    finally:
        plt.close("all")


def test_every_system_has_an_example():
    import tensor_cosdi.systems as S

    text = "\n".join(p.read_text() for p in EXAMPLES)
    for name in S.__all__:
        if isinstance(getattr(S, name), type) and name != "System":
            assert name in text, f"no gallery example uses {name}"
