"""The README's "Ten lines" run as printed, from a folder without the project's data."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def ten_lines() -> str:
    text = README.read_text()
    section = text.split("## Ten lines", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_ten_lines_need_no_shared_data(tmp_path, monkeypatch, capsys):
    code = ten_lines()
    assert "../shared" not in code and "hsi_train" not in code
    assert len([line for line in code.splitlines() if line.strip()]) <= 11  # import + ten
    monkeypatch.chdir(tmp_path)  # no ../shared next to it
    monkeypatch.setenv("TENSOR_COSDI_DATA", str(tmp_path / "nowhere"))
    scope: dict = {}
    exec(compile(code, "README ten lines", "exec"), scope)
    out = capsys.readouterr().out
    psnr = float(out.splitlines()[-1].split()[0])
    assert psnr > 25.0, out  # OTD on the seeded colour checker at 30 dB
    assert scope["rgb"].shape == (256, 256, 3) and np.isfinite(scope["rgb"]).all()
    assert scope["p"].system.name == "cs2li"


def test_readme_is_a_front_page_not_a_notebook():
    text = README.read_text()
    assert len(text.splitlines()) <= 250
    docs = README.parent / "docs"
    for page in ("install.md", "own_data.md", "benchmarks.md", "findings.md", "contributing.md"):
        assert (docs / page).is_file(), page
        assert f"docs/{page}" in text, f"the README does not link docs/{page}"
    for history in ("stop 1", "stop 2", "this session", "in stop"):
        assert history not in text.lower()
