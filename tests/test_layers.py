"""The package's layers: every module imports, no upward import, no import cycle.

Layers, lowest first: interval -> expr -> solver -> robot -> kinematics / force -> jobs ->
client -> api -> cli (``certsolve serve`` starts the api).  Small utilities -- ``lazy``,
``extras``, ``plotting``, ``inputs`` -- sit below everything and import nothing of the package.
Imports are read with :mod:`ast`, including those inside functions (a lazy import is still
a dependency) and those under ``if TYPE_CHECKING:`` (an annotation is a dependency too:
two modules that name each other's types belong together or share a lower module).
``from pkg import name`` depends on the module ``pkg.name`` when there is one, else on
``pkg``.
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


def imports_of(name: str) -> set[str]:
    """The package modules that module ``name`` imports."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return _edges(name, tree, MODULES, is_pkg=path.name == "__init__.py")


def _edges(name: str, tree: ast.AST, modules, *, is_pkg: bool = False) -> set[str]:
    """The modules of ``modules`` that the parsed module ``name`` imports, anywhere in it
    (inside functions and under ``if TYPE_CHECKING:`` included)."""
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name in modules)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for a in node.names:
                sub = f"{target}.{a.name}"
                if sub in modules:
                    out.add(sub)
                elif target in modules:
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


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of ``graph`` with more than one module."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return cycles


def test_no_import_cycle():
    """The module graph's strongly connected components are all of size one."""
    cycles = _cycles(GRAPH)
    assert not cycles, f"import cycles: {cycles}"


def test_the_checker_sees_real_edges():
    """The checks can fail: the resolver finds real edges, lazy imports included."""
    assert "certsolve.interval.rounding" in GRAPH["certsolve.interval.linalg"]
    # resolve_executor imports the Dask executor inside a function
    assert "certsolve.solver.dask_executor" in GRAPH["certsolve.solver.executors"]
    assert "certsolve.solver.search" in GRAPH["certsolve.solver.workers"]
    assert layer("certsolve.jobs.store")[1] > layer("certsolve.solver.search")[1]


def test_the_cycle_check_sees_type_checking_imports():
    """An import under ``if TYPE_CHECKING:`` is an edge: a cycle through it is caught."""
    source = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .b import B\n"
    graph = {"p.a": _edges("p.a", ast.parse(source), {"p.a", "p.b"}), "p.b": {"p.a"}}
    assert graph["p.a"] == {"p.b"}
    assert _cycles(graph) == [["p.a", "p.b"]]
    # the search driver and its checkpoints share a lower module instead of each other
    assert "certsolve.solver.search" not in GRAPH["certsolve.solver.checkpoint"]
    assert "certsolve.solver.checkpoint" not in GRAPH["certsolve.solver.search"]
