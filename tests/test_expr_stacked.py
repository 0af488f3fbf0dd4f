"""Hansen's mixed Jacobian: the stacked program (:mod:`certsolve.expr.stacked`) against one
column program per group, on random boxes of the reference systems.

The two paths of this code apply the same operations to the same inputs, and the outward
rounding of a bound does not depend on the size of the array it is in; so they must give the
same floats and mark the same boxes defined, at every batch size, and the stacked program
must have merged the copies' groups.
"""

from pathlib import Path

import numpy as np
import pytest

from certsolve.expr import System, compiled, sqrt, var
from certsolve.expr.compiled import CHUNK_ELEMENTS, CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.interval.core import midpoint

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"
NAMES = ["katsura-5", "eco-6", "brown-5", "trig-exp", "kin2-6r", "double-root", "troesch-10"]


def boxes(domain, B, rng, scale):
    dom = np.clip(np.asarray(domain, dtype=float), -100.0, 100.0)
    w = (dom[:, 1] - dom[:, 0]) * scale
    lo = dom[:, 0] + rng.random((B, dom.shape[0])) * (dom[:, 1] - dom[:, 0] - w)
    return lo, lo + w


def partitions(n):
    """One variable per group (the solver's default), and two uneven groups."""
    yield list(np.eye(n, dtype=bool))
    first = np.arange(n) < (n + 1) // 3
    yield [first, ~first]


@pytest.mark.parametrize("name", NAMES)
def test_stacked_gives_the_per_group_floats(name):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(len(name))
    for groups in partitions(csys.n):
        csys.prepare_mixed(groups)
        for B, scale in [(1, 1 / 8), (3, 1e-3), (9, 1 / 64), (70, 1 / 16)]:
            lo, hi = boxes(system.domain, B, rng, scale)
            c = midpoint(lo, hi)
            got = csys.eval_fj_mixed(lo, hi, c, groups)
            want = csys._mixed_by_group(lo, hi, c, groups)
            for a, b in zip(got, want):
                assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("name", NAMES)
def test_stacked_merges_the_groups_of_the_copies(name):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(7)
    groups = list(np.eye(csys.n, dtype=bool))
    csys.prepare_mixed(groups)
    lo, hi = boxes(system.domain, 64, rng, 1 / 32)
    c = midpoint(lo, hi)
    key = tuple((j,) for j in range(csys.n))
    stacked = csys._mixed_program(key)
    assert 64 * stacked.program.n_nodes <= CHUNK_ELEMENTS  # the stacked path is the one run
    got = csys.eval_fj_mixed(lo, hi, c, groups)
    want = csys._mixed_by_group(lo, hi, c, groups)
    for a, b in zip(got, want):
        assert np.array_equal(a, b, equal_nan=True)
    # the copies were merged: far fewer groups than the column programs have together
    per_group = sum(len(csys._column_program(cols)[0].fwd_groups) for cols in key)
    assert len(stacked.program.fwd_groups) < per_group


def test_large_batches_take_the_stacked_program_in_chunks(monkeypatch):
    """Past :data:`CHUNK_ELEMENTS` node values the stacked program runs on chunks of the
    boxes: the floats of one program per group, at every batch size, and with a program
    too large for :data:`STACK_MIN_BOXES` boxes a chunk the per-group path itself."""
    system = load_minibex(SYSTEMS / "eco-6.mbx")
    csys = CompiledSystem(system)
    groups = list(np.eye(csys.n, dtype=bool))
    csys.prepare_mixed(groups)
    nodes = csys._mixed_program(tuple((j,) for j in range(csys.n))).program.n_nodes
    monkeypatch.setattr(compiled, "CHUNK_ELEMENTS", 16 * nodes)  # chunks of 16 boxes
    calls = []
    per_group = csys._mixed_by_group
    monkeypatch.setattr(csys, "_mixed_by_group", lambda *a: calls.append(1) or per_group(*a))
    rng = np.random.default_rng(1)
    for B in (15, 16, 17, 50):
        lo, hi = boxes(system.domain, B, rng, 1 / 16)
        c = midpoint(lo, hi)
        got = csys.eval_f_mixed(lo, hi, c, groups)
        want = (*csys.eval_f_at(c), *per_group(lo, hi, c, groups))
        for a, b in zip(got, want, strict=True):
            assert a.shape[0] == B
            assert np.array_equal(a, b, equal_nan=True)
    assert not calls  # every batch ran in the stacked program
    monkeypatch.setattr(compiled, "CHUNK_ELEMENTS", 8 * nodes)  # < STACK_MIN_BOXES a chunk
    lo, hi = boxes(system.domain, 9, rng, 1 / 16)
    csys.eval_fj_mixed(lo, hi, midpoint(lo, hi), groups)
    assert calls  # too large a program for a chunk: one program per group


@pytest.mark.parametrize("name", ["katsura-5", "trig-exp", "kin2-6r"])
def test_chunks_give_the_floats_of_one_call(name, monkeypatch):
    """Every batched evaluation of :class:`CompiledSystem` split in chunks of a few boxes
    (:func:`compiled._chunked`) gives the floats, the domain test and the HC4 contraction
    of one call over the whole batch."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(3)
    lo, hi = boxes(system.domain, 37, rng, 1 / 8)
    c = midpoint(lo, hi)
    groups = list(np.eye(csys.n, dtype=bool))
    cols = [0, csys.n - 1]

    def everything():
        return [
            *csys.eval_f(lo, hi),
            *csys.eval_f_at(c),
            *csys.eval_fj(lo, hi, check_domain=True),
            *csys.eval_fj_columns(lo, hi, cols),
            *csys.eval_f_mixed(lo, hi, c, groups),
            *csys.hc4_revise(lo, hi),
        ]

    whole = everything()
    monkeypatch.setattr(compiled, "CHUNK_ELEMENTS", 5 * csys.hc4.n_nodes)
    chunked = everything()
    for a, b in zip(chunked, whole, strict=True):
        assert a.shape == b.shape
        assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("name", NAMES)
def test_f_at_the_centre_comes_with_the_mixed_jacobian(name):
    """``eval_f_mixed``: the stacked program's copy of ``f`` at ``c`` gives the floats of
    ``f``'s own program at ``c``, and the Jacobian and domain test are those of
    ``eval_fj_mixed`` (the copy at ``c`` is not tested: the boxes reaching outside the
    domain, here too, are those of the ``n`` copies)."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(11)
    for groups in partitions(csys.n):
        csys.prepare_mixed(groups)
        for B, scale in [(1, 1 / 8), (5, 1e-3), (40, 1 / 4)]:
            lo, hi = boxes(system.domain, B, rng, scale)
            c = midpoint(lo, hi)
            got = csys.eval_f_mixed(lo, hi, c, groups)
            want = (*csys.eval_f_at(c), *csys._mixed_by_group(lo, hi, c, groups))
            for a, b in zip(got, want):
                assert np.array_equal(a, b, equal_nan=True)


def test_the_copy_at_the_centre_is_left_out_of_the_domain_test():
    """``sqrt(x)`` over ``X = [-1, 1]``: not defined on the box, defined at ``c = 0``; over
    ``[1, 2]`` defined everywhere.  The test says so for the stacked program with the copy
    at ``c`` (whose own test would pass at ``c = 0`` and must not hide the box's failure)."""
    x, y = var("x"), var("y")
    system = System.build({"x": (-1, 2), "y": (-1, 2)}, [sqrt(x) + y - 1.0, x - y])
    csys = CompiledSystem(system)
    groups = list(np.eye(2, dtype=bool))
    lo = np.array([[-1.0, -1.0], [1.0, 1.0]])
    hi = np.array([[1.0, 1.0], [2.0, 2.0]])
    c = midpoint(lo, hi)
    flo, fhi, _, _, defined = csys.eval_f_mixed(lo, hi, c, groups)
    assert defined.tolist() == [False, True]
    assert np.array_equal(flo, csys.eval_f_at(c)[0]) and np.array_equal(fhi, csys.eval_f_at(c)[1])
    # the rows a domain test skips are those given
    p = csys.f
    LO, HI = p.eval_interval(lo, hi, csys.param_lo, csys.param_hi)
    assert p.defined_mask(LO, HI).tolist() == [False, True]
    assert p.defined_mask(LO, HI, skip=np.ones(p.n_nodes, dtype=bool)).tolist() == [True, True]
