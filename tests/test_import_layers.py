"""The package's modules form layers that only point down: no import circle, not even one hidden
inside a function (issue 19). Every ``.py`` file of ``gaitopt`` is parsed; every import in it —
at module level, under ``if TYPE_CHECKING``, inside functions — is an edge of the module graph;
the graph's strongly connected components of more than one module, and modules importing
themselves, are the circles, each reported with its modules."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import gaitopt

ROOT = Path(gaitopt.__file__).parent
PACKAGE = "gaitopt"


def module_files(root: Path = ROOT, package: str = PACKAGE) -> dict[str, Path]:
    """Every module of the package by dotted name; a package is named by its ``__init__``."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join([package, *parts])] = path
    return found


def _absolute(module: str, is_package: bool, level: int, name: str | None) -> str:
    """The absolute module name of ``from <level dots><name> import …`` written in ``module``."""
    if level == 0:
        return name or ""
    base = module.split(".")
    if not is_package:
        base.pop()  # a plain module's relative imports start from its package
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join(base + ([name] if name else []))


def imports_of(module: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package's modules ``module`` imports anywhere in its file. ``from P import n`` is an
    import of the submodule ``P.n`` when there is one, else of ``P`` (a package: its
    ``__init__``); ``import a.b.c`` is an import of the deepest of those that is a module."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_package = path.name == "__init__.py"
    targets: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                for end in range(len(parts), 0, -1):
                    if ".".join(parts[:end]) in modules:
                        targets.add(".".join(parts[:end]))
                        break
        elif isinstance(node, ast.ImportFrom):
            source = _absolute(module, is_package, node.level, node.module)
            for alias in node.names:
                if f"{source}.{alias.name}" in modules:
                    targets.add(f"{source}.{alias.name}")
                elif source in modules:
                    targets.add(source)
    return targets


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components (Tarjan, iterative) of more than one module, and single
    modules importing themselves; each sorted, the list sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    found: list[list[str]] = []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1 or node in graph[node]:
                        found.append(sorted(component))
    return sorted(found)


def _describe(component: list[str], graph: dict[str, set[str]]) -> str:
    inside = set(component)
    edges = [f"{a} -> {b}" for a in component for b in sorted(graph[a] & inside)]
    return "circle of " + ", ".join(component) + "\n    " + "\n    ".join(edges)


def test_the_module_graph_has_no_circles():
    graph = import_graph(module_files())
    found = circles(graph)
    assert not found, f"{len(found)} import circle(s):\n" + "\n".join(
        _describe(c, graph) for c in found
    )


# The check itself: it must see relative imports, imports inside functions, packages as their
# __init__, and report circles of every size (a check that cannot fail checks nothing).


def _tree(tmp_path: Path, files: dict[str, str]) -> dict[str, set[str]]:
    root = tmp_path / "pkg"
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    modules = module_files(root, "pkg")
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def test_the_check_sees_imports_hidden_in_functions_and_relative_imports(tmp_path):
    graph = _tree(
        tmp_path,
        {
            "__init__.py": "from .a import f\n",
            "a.py": "from .sub.b import g\ndef f():\n    return g()\n",
            "sub/__init__.py": "",
            "sub/b.py": "def g():\n    from ..a import f\n    return f\n",
            "c.py": "from . import d\n",
            "d.py": "import pkg.sub\n",
        },
    )
    assert graph["pkg"] == {"pkg.a"}
    assert graph["pkg.sub.b"] == {"pkg.a"}
    assert graph["pkg.c"] == {"pkg.d"}
    assert graph["pkg.d"] == {"pkg.sub"}
    assert circles(graph) == [["pkg.a", "pkg.sub.b"]]


def test_the_check_reports_a_package_init_and_self_loops(tmp_path):
    graph = _tree(
        tmp_path,
        {
            "__init__.py": "",
            "p/__init__.py": "from .x import y\n",
            "p/x.py": "def y():\n    from . import z\n",
            "p/z.py": "from ..p import y\n",
            "s.py": "import pkg.s\n",
        },
    )
    assert circles(graph) == [["pkg.p", "pkg.p.x", "pkg.p.z"], ["pkg.s"]]


@pytest.mark.parametrize(
    "module, is_package, level, name, expected",
    [
        ("pkg.a.b", False, 1, "c", "pkg.a.c"),
        ("pkg.a.b", False, 2, None, "pkg"),
        ("pkg.a", True, 1, "c", "pkg.a.c"),
        ("pkg.a", True, 2, "c", "pkg.c"),
        ("pkg.a.b", False, 0, "pkg.x", "pkg.x"),
    ],
)
def test_relative_imports_resolve(module, is_package, level, name, expected):
    assert _absolute(module, is_package, level, name) == expected
