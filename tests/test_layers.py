"""The package's layers: every module imports, no upward import, no import cycle.

Layers, lowest first: interval -> expr -> solver -> robot -> kinematics / force -> jobs ->
client -> api -> cli (``certsolve serve`` starts the api).  Small utilities -- ``lazy``,
``extras``, ``plotting``, ``inputs`` -- sit below everything and import nothing of the package.
Imports are read with :mod:`ast`, including those inside functions (a lazy import is still
a dependency); imports under ``if TYPE_CHECKING:`` are ignored.  ``from pkg import name``
depends on the module ``pkg.name`` when there is one, else on ``pkg``.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# folder -> package name (setup.py installs the api/ folder as certsolve.api)
PACKAGES = {"certsolve": "certsolve", "api": "certsolve.api"}

RANK = {
    "lazy": 0,
    "extras": 0,
    "plotting": 0,
    "inputs": 0,
    "interval": 1,
    "expr": 2,
    "solver": 3,
    "robot": 4,
    "kinematics": 5,
    "force": 5,
    "jobs": 6,
    "client": 7,
    "api": 8,
    "cli": 9,  # certsolve serve runs the api's app
    "__main__": 10,
    "": 10,  # the package facade (certsolve/__init__.py) may re-export any layer
}


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            if parts and parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((package, *parts))] = path
    return out


MODULES = _modules()


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                skip.update(id(n) for n in ast.walk(child))
    return skip


def imports_of(name: str) -> set[str]:
    """The package modules that module ``name`` imports."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = _type_checking_nodes(tree)
    is_pkg = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name in MODULES)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for a in node.names:
                sub = f"{target}.{a.name}"
                if sub in MODULES:
                    out.add(sub)
                elif target in MODULES:
                    out.add(target)
    out.discard(name)
    return out


def layer(name: str) -> tuple[str, int]:
    parts = name.split(".")
    key = parts[0] if parts[0] != "certsolve" else (parts[1] if len(parts) > 1 else "")
    return key, RANK[key]


GRAPH = {name: imports_of(name) for name in MODULES}


def test_every_module_has_a_layer():
    assert len(MODULES) > 100
    for name in MODULES:
        layer(name)  # KeyError: a new top-level module needs a place in RANK


@pytest.mark.parametrize("name", sorted(n for n in MODULES if not n.endswith("__main__")))
def test_module_imports(name):
    importlib.import_module(name)


def test_no_upward_import():
    bad = []
    for name, targets in GRAPH.items():
        key, rank = layer(name)
        for t in targets:
            tkey, trank = layer(t)
            if tkey != key and trank >= rank:
                bad.append(f"{name} -> {t}")
    assert not bad, "imports against the layer order:\n" + "\n".join(sorted(bad))


def test_no_import_cycle():
    """Tarjan's strongly connected components of the module graph: all of size one."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_the_checker_sees_real_edges():
    """The checks can fail: the resolver finds real edges, lazy imports included."""
    assert "certsolve.interval.rounding" in GRAPH["certsolve.interval.linalg"]
    # resolve_executor imports the Dask executor inside a function
    assert "certsolve.solver.dask_executor" in GRAPH["certsolve.solver.executors"]
    assert "certsolve.solver.search" in GRAPH["certsolve.solver.workers"]
    assert layer("certsolve.jobs.store")[1] > layer("certsolve.solver.search")[1]
