"""The house rules that the package's layout must keep, read from the sources (AST, no import):

* no import loop between modules (imports at module level and inside functions alike);
* no module imports another package's private (``_name``) module, or a private name defined in
  another package (``drake_mh._support`` is the shared support package: everyone may use it);
* the library never imports the command line (:mod:`drake_mh.cli`); only the ``python -m``
  entry points do.

The checks are tested on small made-up packages too, so that a check that finds nothing is
known to be able to find something.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "drake_mh"
SHARED = "drake_mh._support"
"""The shared support package: its private name is the package's, not a module's."""
ENTRY_POINTS = frozenset({"drake_mh.__main__", "drake_mh.smoke"})
"""Modules run by ``python -m`` that may import the command line (nothing imports them)."""


def modules(package: Path) -> dict[str, tuple[Path, bool]]:
    """``{dotted name: (file, is a package)}`` of every ``.py`` file under ``package``."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def _source(node: ast.ImportFrom, here: str) -> str:
    """The absolute name of the module a ``from ... import`` statement in package ``here`` reads."""
    if not node.level:
        return node.module or ""
    base = here.split(".")[: len(here.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def imports(package: Path) -> dict[str, set[tuple[str, str | None]]]:
    """``{module: {(imported module, imported name or None)}}`` for every import statement of the
    package's modules, wherever it stands; only modules of the package itself are kept (an
    imported name that is a module counts as that module)."""
    known = modules(package)
    out: dict[str, set[tuple[str, str | None]]] = {}
    for name, (path, is_package) in known.items():
        here = name if is_package else name.rpartition(".")[0]
        found = out.setdefault(name, set())
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            targets: list[tuple[str, str | None]] = []
            if isinstance(node, ast.Import):
                targets = [(alias.name, None) for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                source = _source(node, here)
                for alias in node.names:
                    full = f"{source}.{alias.name}"
                    targets.append((full, None) if full in known else (source, alias.name))
            for target, imported in targets:
                while target and target not in known:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    found.add((target, imported))
    return out


def module_attributes(package: Path) -> dict[str, set[tuple[str, str]]]:
    """``{module: {(imported module, attribute)}}``: the attributes read through a name that an
    import bound to a module of the package (``from drake_mh.a import b as x; x._y``)."""
    known = modules(package)
    out: dict[str, set[tuple[str, str]]] = {}
    for name, (path, is_package) in known.items():
        here = name if is_package else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        bound: dict[str, str] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                bound.update({a.asname: a.name for a in node.names if a.asname and a.name in known})
            elif isinstance(node, ast.ImportFrom):
                source = _source(node, here)
                bound.update({a.asname or a.name: f"{source}.{a.name}" for a in node.names
                              if f"{source}.{a.name}" in known})
        out[name] = {(bound[n.value.id], n.attr) for n in ast.walk(tree) if isinstance(n, ast.Attribute)
                     and isinstance(n.value, ast.Name) and n.value.id in bound}
    return out


def cycles(package: Path) -> list[list[str]]:
    """The import loops between modules: strongly connected components of more than one module
    (Tarjan's algorithm)."""
    graph = {a: sorted({b for b, _ in targets}) for a, targets in imports(package).items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def _owner(module: str) -> str | None:
    """The package a private module belongs to (the part before its first ``_name``), or None
    for a public module; the shared support package counts as public."""
    if module == SHARED or module.startswith(SHARED + "."):
        return None
    parts = module.split(".")
    for i, part in enumerate(parts[1:], start=1):
        if part.startswith("_") and not part.startswith("__"):
            return ".".join(parts[:i])
    return None


def _inside(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def private_imports(package: Path) -> list[str]:
    """Imports of another package's private module or private name (imported, or read as an
    attribute of an imported module), as ``importer -> what``."""
    known = modules(package)
    bad = []
    attributes = module_attributes(package)
    for importer, targets in imports(package).items():
        for target, name in sorted(targets | attributes[importer], key=str):
            owner = _owner(target)
            if owner is not None and not _inside(importer, owner):
                bad.append(f"{importer} -> {target}")
            if name is not None and name.startswith("_") and not name.startswith("__"):
                home = target if known[target][1] else target.rpartition(".")[0]
                if _owner(home) is None and not _inside(importer, home) and not _inside(home, SHARED):
                    bad.append(f"{importer} -> {target}.{name}")
    return sorted(set(bad))


def cli_imports(package: Path) -> list[str]:
    """Library modules that import the command line package."""
    cli = f"{package.name}.cli"
    return sorted(f"{importer} -> {target}" for importer, targets in imports(package).items()
                  for target, _ in targets if _inside(target, cli) and not _inside(importer, cli)
                  and importer not in ENTRY_POINTS)


def test_no_import_loop():
    assert cycles(PACKAGE) == []


def test_no_module_imports_another_packages_private_module_or_name():
    assert private_imports(PACKAGE) == []


def test_the_library_never_imports_the_command_line():
    assert cli_imports(PACKAGE) == []


def test_every_folder_of_the_package_is_a_package():
    folders = {p.parent for p in PACKAGE.rglob("*.py")}
    assert sorted(str(f) for f in folders if not (f / "__init__.py").is_file()) == []


# --- the checks find what they must find -------------------------------------------------


def _write(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root / "drake_mh"


@pytest.fixture
def toy(tmp_path):
    return _write(tmp_path, {
        "drake_mh/__init__.py": "",
        "drake_mh/_support/__init__.py": "",
        "drake_mh/_support/cache.py": "def _helper(): pass\n",
        "drake_mh/a/__init__.py": "from drake_mh.a.one import f\n",
        "drake_mh/a/one.py": "def f():\n    from drake_mh.b import two\n",  # inside a function
        "drake_mh/a/_private.py": "def g(): pass\n",
        "drake_mh/a/three.py": "from drake_mh.a import _private\nfrom ._private import g\n",
        "drake_mh/b/__init__.py": "",
        "drake_mh/b/two.py": "from drake_mh.a import f\nfrom drake_mh._support.cache import _helper\n",
        "drake_mh/b/four.py": "from drake_mh.a._private import g\nfrom drake_mh.a.one import _x\n",
        "drake_mh/b/five.py": "from drake_mh.a import one as o\nimport drake_mh.a.one as p\no._y, p._z, o.f\n",
        "drake_mh/cli/__init__.py": "import drake_mh.a\n",
        "drake_mh/c.py": "def main():\n    from drake_mh.cli import main\n",
        "drake_mh/__main__.py": "from drake_mh.cli import main\n",
    })


def test_the_loop_check_finds_a_loop_through_a_function_and_a_package(toy):
    assert cycles(toy) == [["drake_mh.a", "drake_mh.a.one", "drake_mh.b.two"]]


def test_the_private_check_finds_another_packages_private_module_and_name(toy):
    assert private_imports(toy) == ["drake_mh.b.five -> drake_mh.a.one._y", "drake_mh.b.five -> drake_mh.a.one._z",
                                    "drake_mh.b.four -> drake_mh.a._private", "drake_mh.b.four -> drake_mh.a.one._x"]


def test_the_cli_check_finds_a_library_module_and_spares_the_entry_point(toy):
    assert cli_imports(toy) == ["drake_mh.c -> drake_mh.cli"]
