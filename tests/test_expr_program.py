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


def _narrowed(p, lo, hi, x, csys, rel):
    """Forward values over the boxes, and their outputs narrowed to ``f(x) ± rel |f(x)|``
    (``x`` in every box: no box is empty)."""
    LO, HI = p.eval_interval(lo, hi, csys.param_lo, csys.param_hi)
    forward = (LO.copy(), HI.copy())
    V = p.eval_float(x, csys.param_mid)[p.outputs]
    pad = rel * np.abs(V) + 1e-9
    LO[p.outputs] = np.fmax(LO[p.outputs], V - pad)
    HI[p.outputs] = np.fmin(HI[p.outputs], V + pad)
    return LO, HI, forward


@pytest.mark.parametrize("name", [*NAMES, "katsura-6", "eco-7"])
def test_revise_skips_unnarrowed_groups_without_changing_a_bit(name):
    """HC4's backward pass skips the groups whose nodes still hold their forward values
    (their projections give the children back): every bound as with every projection.  The
    boxes hold a point ``x`` and the outputs are narrowed around ``f(x)``, so none is
    empty; a few passes first contract them, as a search does (where most skips happen)."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    p = csys.hc4
    dom = np.clip(np.asarray(system.domain, dtype=float), -100.0, 100.0)
    rng = np.random.default_rng(3)
    skipped = 0
    for B, scale, rel in [(1, 1 / 4, 1e-3), (5, 1e-2, 0.1), (60, 1e-4, 1e-6), (200, 1 / 32, 1)]:
        w = (dom[:, 1] - dom[:, 0]) * scale
        lo = dom[:, 0] + rng.random((B, csys.n)) * (dom[:, 1] - dom[:, 0] - w)
        hi = lo + w
        x = lo + rng.random((B, csys.n)) * w
        for _ in range(2):  # contract first
            LO, HI, forward = _narrowed(p, lo, hi, x, csys, rel)
            p.revise(LO, HI)
            lo, hi = np.fmax(lo, LO[: csys.n].T), np.fmin(hi, HI[: csys.n].T)
        LO, HI, forward = _narrowed(p, lo, hi, x, csys, rel)
        every = (LO.copy(), HI.copy())
        p.revise(*every)
        p.revise(LO, HI, forward)
        assert np.all(every[0] <= every[1])  # no box is empty
        for a, b in zip((LO, HI), every):
            assert np.array_equal(a.view(np.int64), b.view(np.int64))
        skipped += sum(
            not (np.any(every[0][g.start : g.stop] != forward[0][g.start : g.stop])
                 or np.any(every[1][g.start : g.stop] != forward[1][g.start : g.stop]))
            for g in p.groups
        )  # fmt: skip
    assert skipped > 0  # some group was left as the forward pass made it
