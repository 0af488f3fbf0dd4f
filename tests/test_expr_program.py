"""The compile of a :class:`~certsolve.expr.program.Program` (whole-array steps) against the
definition it implements, written node by node here.

HC4's groups are the needed nodes sorted by (level, operation, power, id), cut where the
key changes; the level of a node is 0 for a leaf, else one more than its deepest child.
The forward groups hold the same nodes, each after its children.  A child repeated inside
a group is written back layer by layer, each node id at most once a layer.
"""

from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.expr.program import Program, _layers

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"
NAMES = ["katsura-5", "eco-6", "brown-5", "trig-exp", "kin2-6r", "double-root", "troesch-10"]


def reference_units(graph, outputs):
    """The HC4 groups by their definition, as lists of node ids."""
    n = len(graph.variables) + len(graph.parameters)
    needed = sorted(set(range(n)) | set(graph.ancestors(outputs)))
    level: dict[int, int] = {}
    for x in needed:
        args = graph.args[x]
        level[x] = 0 if not args else 1 + max(level[a] for a in args)

    def key(x):
        power = graph.param[x] if graph.op[x] == "pow" else 0
        return (level[x], graph.op[x], power)

    units: list[list[int]] = []
    for x in sorted((x for x in needed if level[x] > 0), key=lambda x: (key(x), x)):
        if units and key(units[-1][0]) == key(x):
            units[-1].append(x)
        else:
            units.append([x])
    return units


def programs(name):
    csys = CompiledSystem(load_minibex(SYSTEMS / f"{name}.mbx"))
    yield csys.graph, csys.hc4
    yield csys.graph, csys.fj


@pytest.mark.parametrize("name", NAMES)
def test_program_groups_follow_their_definition(name):
    for graph, prog in programs(name):
        outputs = prog.global_ids[prog.outputs].tolist()
        units = reference_units(graph, outputs)
        got = [prog.global_ids[g.start : g.stop].tolist() for g in prog.groups]
        assert got == units
        for g in prog.groups:
            x = prog.global_ids[g.start : g.stop]
            assert all(graph.op[i] == g.op for i in x.tolist())
            first = [graph.args[i][0] for i in x.tolist()]
            assert prog.global_ids[g.a].tolist() == first
        # the forward groups: the same nodes, every child computed before its group
        fwd = sorted(i for g in prog.fwd_groups for i in range(g.start, g.stop))
        assert fwd == sorted(i for g in prog.groups for i in range(g.start, g.stop))
        for g in prog.fwd_groups:
            assert np.all(g.a < g.start) and (g.b is None or np.all(g.b < g.start))


def test_layers_hold_each_id_once_per_layer():
    rng = np.random.default_rng(3)
    for size in (1, 2, 7, 40):
        idx = rng.integers(0, 5, size)
        layers = _layers(idx)
        seen = np.zeros(size, dtype=int)
        for r, (pos, ids) in enumerate(layers):
            assert np.all(np.diff(pos) > 0) and np.array_equal(ids, idx[pos])
            assert len(set(ids.tolist())) == len(ids)
            for p in pos.tolist():  # layer r: the r-th occurrence of the id
                assert int(np.sum(idx[:p] == idx[p])) == r
            seen[pos] += 1
        assert np.all(seen == 1)
    assert _layers(np.zeros(0, dtype=np.int64)) == ()


def test_compile_of_an_empty_program():
    csys = CompiledSystem(load_minibex(SYSTEMS / "katsura-5.mbx"))
    prog = Program(csys.graph, [0])  # a variable alone: no groups
    assert prog.groups == [] and prog.fwd_groups == [] and prog.n_levels == 1
    assert prog.global_ids[prog.outputs].tolist() == [0]
