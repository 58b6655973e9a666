"""Where benchmark scripts keep their tables: ``benchmarks/results/``."""

from pathlib import Path


def append(out, name: str, text: str) -> Path:
    """Append ``text`` to ``out/name`` (folder created) and print it; returns the file."""
    path = Path(out) / name
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as f:
        f.write(text)
    print(text)
    return path
