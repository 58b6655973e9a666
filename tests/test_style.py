"""House style CI enforces: `ruff check` clean (pyproject.toml rules), `ruff format` applied
(the Markdown docs' code blocks too), and a package without import cycles (module- and
function-level imports alike): split by concern into sub-packages, never into siblings that
import each other."""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _ruff(*args) -> subprocess.CompletedProcess:
    ruff = shutil.which("ruff", path=str(Path(sys.executable).parent)) or shutil.which("ruff")
    assert ruff, "ruff is part of the test extra (pip install '.[test]')"
    return subprocess.run([ruff, *args, str(ROOT)], capture_output=True, text=True, cwd=ROOT)


def test_ruff_check_is_clean():
    out = _ruff("check", "--output-format", "concise")
    assert out.returncode == 0, out.stdout + out.stderr


def test_ruff_format_is_applied():
    """Every file as `ruff format` writes it (run `ruff format .` to fix; `# fmt: skip` keeps a
    hand-aligned table)."""
    out = _ruff("format", "--check", "--output-format", "concise")
    assert out.returncode == 0, out.stdout + out.stderr


def import_graph(package_dir: Path, package: str) -> dict[str, set[str]]:
    """``module → {package modules it imports}``, from the AST of every ``.py`` file (imports
    inside functions and classes included; ``from pkg import name`` counts as importing the
    sub-module ``pkg.name`` when one exists, else ``pkg``)."""
    mods = {}
    for p in package_dir.rglob("*.py"):
        parts = list(p.relative_to(package_dir.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = p

    def owner(name):
        while name not in mods and "." in name:
            name = name.rsplit(".", 1)[0]
        return name if name in mods else None

    graph = {m: set() for m in mods}
    for mod, path in mods.items():
        here = mod.split(".") if path.name == "__init__.py" else mod.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = here[: len(here) - node.level + 1] if node.level else []
                target = ".".join(base + ([node.module] if node.module else []))
                targets = [
                    f"{target}.{a.name}" if f"{target}.{a.name}" in mods else target
                    for a in node.names
                ]
            for t in targets:
                if t.split(".")[0] == package and (o := owner(t)) and o != mod:
                    graph[mod].add(o)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def test_the_cycle_finder_finds_a_function_level_cycle(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from . import a\n")
    (pkg / "a.py").write_text("import numpy\nfrom .sub import b\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..a import g\n")
    (pkg / "c.py").write_text("from pkg.sub import b\n")
    graph = import_graph(pkg, "pkg")
    assert graph["pkg.a"] == {"pkg.sub.b"} and graph["pkg.c"] == {"pkg.sub.b"}
    assert cycles(graph) == [["pkg.a", "pkg.sub.b"]]


def test_the_package_has_no_import_cycle():
    found = cycles(import_graph(ROOT / "tensor_cosdi", "tensor_cosdi"))
    assert found == [], "import cycles: " + "; ".join(" ↔ ".join(c) for c in found)


def private_imports(graph: dict[str, set[str]], package: str) -> list[str]:
    """``"importer → module"`` for every import of an underscore module that belongs to another
    sub-package (``pkg.sub._mod`` from outside ``pkg.sub``).  Underscore modules at the package
    root (``pkg._backend``) are the package's shared internals."""
    bad = []
    for mod, targets in graph.items():
        for t in targets:
            parts = t.split(".")
            private = [i for i, p in enumerate(parts) if p.startswith("_") and i >= 2]
            if private:
                owner = ".".join(parts[: private[0]])
                if not (mod == owner or mod.startswith(owner + ".")):
                    bad.append(f"{mod} → {t}")
    return sorted(bad)


def test_the_private_import_finder_finds_one(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "other").mkdir()
    for d in (pkg, pkg / "sub", pkg / "other"):
        (d / "__init__.py").write_text("")
    (pkg / "sub" / "_inner.py").write_text("X = 1\n")
    (pkg / "sub" / "a.py").write_text("from ._inner import X\n")  # its own: fine
    (pkg / "other" / "b.py").write_text("def f():\n    from ..sub._inner import X\n")
    assert private_imports(import_graph(pkg, "pkg"), "pkg") == ["pkg.other.b → pkg.sub._inner"]


def test_no_sub_package_imports_another_ones_private_module():
    found = private_imports(import_graph(ROOT / "tensor_cosdi", "tensor_cosdi"), "tensor_cosdi")
    assert found == [], "private modules imported from outside: " + "; ".join(found)


def private_members(package_dir: Path) -> dict[str, set[str]]:
    """``_name → {sub-packages whose classes define it}`` (methods and class attributes with one
    leading underscore; a root module counts as its own sub-package)."""
    found: dict[str, set[str]] = {}
    for p in package_dir.rglob("*.py"):
        rel = p.relative_to(package_dir).parts
        sub = rel[0] if len(rel) > 1 else rel[0].removesuffix(".py")
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ClassDef):
                continue
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    names = [item.name]
                elif isinstance(item, ast.Assign):
                    names = [t.id for t in item.targets if isinstance(t, ast.Name)]
                else:
                    names = []
                for n in names:
                    if n.startswith("_") and not n.endswith("__"):
                        found.setdefault(n, set()).add(sub)
    return found


def private_calls(path: Path, members: dict[str, set[str]], here: str | None) -> list[str]:
    """``"file:line ._name"`` for every call ``obj._name(…)`` in ``path`` of a private member
    that only other sub-packages define (``here``: the file's own sub-package, ``None`` for a
    test, example or benchmark, for which every package member is foreign).  Calls on ``self``,
    ``cls`` and ``super()`` are a class's own business."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
            continue
        name, owner = node.func.attr, node.func.value
        if name not in members or (here is not None and here in members[name]):
            continue
        if isinstance(owner, ast.Name) and owner.id in ("self", "cls"):
            continue
        if isinstance(owner, ast.Call) and getattr(owner.func, "id", None) == "super":
            continue
        bad.append(f"{path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name}:"
                   f"{node.lineno} .{name}")  # fmt: skip
    return bad


def test_the_private_call_finder_finds_one(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "ops").mkdir(parents=True)
    (pkg / "ops" / "base.py").write_text(
        "class Op:\n    def _apply(self, x):\n        return x\n"
        "    def run(self, other):\n        return self._apply(other._apply(1))\n"
    )
    (pkg / "solve.py").write_text("def f(op):\n    return op._apply(1) + op.run(op)\n")
    members = private_members(pkg)
    assert members == {"_apply": {"ops"}}
    # inside its own sub-package, on self or on another instance: fine
    assert private_calls(pkg / "ops" / "base.py", members, "ops") == []
    assert private_calls(pkg / "solve.py", members, "solve") == ["solve.py:2 ._apply"]
    assert private_calls(pkg / "solve.py", members, None) == ["solve.py:2 ._apply"]


def python_files_and_their_sub_package():
    """Every ``.py`` file of the package, tests, examples and benchmarks with its sub-package
    (``None`` outside the package)."""
    package = ROOT / "tensor_cosdi"
    for top in ("tensor_cosdi", "tests", "examples", "benchmarks"):
        for p in sorted((ROOT / top).rglob("*.py")):
            rel = p.relative_to(package).parts if top == "tensor_cosdi" else None
            yield p, None if rel is None else rel[0] if len(rel) > 1 else rel[0][:-3]


def test_no_private_method_is_called_from_another_sub_package_a_test_or_an_example():
    members = private_members(ROOT / "tensor_cosdi")
    bad = [b for p, here in python_files_and_their_sub_package()
           for b in private_calls(p, members, here)]  # fmt: skip
    assert bad == [], "private members called from outside their sub-package: " + "; ".join(bad)


def private_module_uses(path: Path, package_dir: Path, here: str | None) -> list[str]:
    """``"file:line name"`` for every use of another sub-package's module-level private name:
    ``from pkg.sub.mod import _name`` or ``mod._name`` on a module bound by an import (``here``
    as in :func:`private_calls`)."""
    package = package_dir.name
    tree = ast.parse(path.read_text(encoding="utf-8"))
    if path.is_relative_to(package_dir):
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        base_parts = parts[:-1]
    else:
        base_parts = []

    def resolve(node):
        if node.level:
            return ".".join(base_parts[: len(base_parts) - node.level + 1] + [node.module or ""])
        return node.module or ""

    def sub_package(module: str) -> str | None:
        parts = module.split(".")
        return parts[1] if len(parts) > 1 and parts[0] == package else None

    def is_module(dotted: str) -> bool:
        rel = Path(*dotted.split("."))
        return (package_dir.parent / rel).with_suffix(".py").is_file() or (
            package_dir.parent / rel / "__init__.py"
        ).is_file()

    modules, bad = {}, []
    where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            src = resolve(node).rstrip(".")
            for a in node.names:
                full = f"{src}.{a.name}"
                if is_module(full):
                    modules[a.asname or a.name] = full
                elif (
                    a.name.startswith("_")
                    and not a.name.startswith("__")
                    and sub_package(src) is not None
                    and sub_package(src) != here
                    and not src.rsplit(".", 1)[-1].startswith("_")  # counted by the import test
                ):
                    bad.append(f"{where}:{node.lineno} {src}.{a.name}")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.asname and is_module(a.name):
                    modules[a.asname] = a.name
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in modules
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and sub_package(modules[node.value.id]) not in (None, here)
        ):
            bad.append(f"{where}:{node.lineno} {modules[node.value.id]}.{node.attr}")
    return bad


def test_the_private_name_finder_finds_imports_and_module_attributes(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "io").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "io" / "__init__.py").write_text("")
    (pkg / "io" / "files.py").write_text("def _suffix(p):\n    return p\n")
    (pkg / "cli.py").write_text(
        "from .io import files\nfrom .io.files import _suffix\n"
        "def f(p):\n    return files._suffix(p), _suffix(p)\n"
    )
    (pkg / "io" / "use.py").write_text("from . import files\nx = files._suffix(1)\n")
    assert private_module_uses(pkg / "cli.py", pkg, "cli") == [
        "cli.py:2 pkg.io.files._suffix",
        "cli.py:4 pkg.io.files._suffix",
    ]
    assert private_module_uses(pkg / "io" / "use.py", pkg, "io") == []  # its own sub-package


def test_no_module_private_name_is_used_from_another_sub_package():
    package = ROOT / "tensor_cosdi"
    bad = [b for p, here in python_files_and_their_sub_package()
           for b in private_module_uses(p, package, here)]  # fmt: skip
    assert bad == [], "private names used from outside their sub-package: " + "; ".join(bad)
