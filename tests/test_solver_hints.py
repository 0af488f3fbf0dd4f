"""Hints: the integers a contractor leaves beside a box for its next contraction (the
polytope hull's LP active sets) travel with the box -- through the buffer, a round's
rows, the boxes sent back, the halves of a bisection and the tasks of the workers -- and a
box may lose them anywhere (``-1`` rows) without changing what is proven."""

from __future__ import annotations

import numpy as np
from test_solver_contractors import SYSTEMS

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.solver import Limits, Solver
from certsolve.solver.batch import Batch
from certsolve.solver.buffer import BoxStack, no_hints
from certsolve.solver.pipeline import find
from certsolve.solver.relaxation import PolytopeHull
from certsolve.solver.search import run_task


def _boxes(k: int, n: int = 2, at: float = 0.0):
    lo = at + np.arange(k * n, dtype=float).reshape(k, n)
    return lo, lo + 1.0


def test_the_buffer_keeps_hints_beside_its_boxes():
    stack = BoxStack(2, capacity=2)
    stack.push(*_boxes(1))
    assert stack.pop_hinted(1)[2] is None and stack.hints() is None  # none brought yet
    stack.push(*_boxes(1))
    stack.push(*_boxes(3, at=10.0), hints=np.arange(12).reshape(3, 4))  # grows past 2
    stack.push(*_boxes(1, at=20.0))  # without hints: a "no hint" row
    stack.push(*_boxes(1, at=30.0), hints=np.ones((1, 5)))  # another width: taken without
    assert len(stack) == 6
    assert stack.hints()[:, 0].tolist() == [-1, 0, 4, 8, -1, -1]
    lo, hi, hints = stack.pop_hinted(3)
    assert lo[0, 0] == 14.0 and hints.tolist()[0] == [8, 9, 10, 11]
    assert hints[1:].tolist() == no_hints(2, 4).tolist()
    assert stack.pop(3)[0][0, 0] == 0.0  # pop() gives the boxes alone


def test_a_round_carries_hints_with_its_rows():
    """``keep`` selects them, a box sent back keeps its row, a box pushed back without is
    "no hint", and a part's hints on some rows leave ``-1`` on the others."""
    csys = CompiledSystem(load_minibex(SYSTEMS / "katsura-5.mbx"))
    lo, hi = _boxes(4, csys.n)
    stack = BoxStack(csys.n)
    batch = Batch(lo, hi, csys=csys, eps=1e-8, stack=stack, hints=np.arange(8).reshape(4, 2))
    batch.keep(np.array([True, False, True, True]))
    assert batch.hints[:, 0].tolist() == [0, 4, 6]
    batch.send_back(np.array([False, True, False]))
    batch.push_back(*_boxes(1, csys.n, at=100.0))
    batch.flush()
    assert stack.hints().tolist() == [[4, 5], [-1, -1]]
    fresh = Batch(lo, hi, csys=csys, eps=1e-8)
    fresh.set_hints(np.array([1, 3]), np.array([[7, 7, 7], [8, 8, 8]]))
    assert fresh.hints[:, 0].tolist() == [-1, 7, -1, 8]


def test_halves_inherit_the_hull_hints_and_tasks_return_them():
    """The hull leaves each box its programs' active sets; the halves of a bisection start
    from their parent's; a task hands back its unfinished boxes with theirs."""
    solver = Solver.default(load_minibex(SYSTEMS / "katsura-5.mbx"))
    hull = find(solver.contractor, PolytopeHull)
    width = hull.hint_width(solver.n)
    state = solver.start()
    dom = solver.domain
    state.stack.push(dom[:, 0][None], dom[:, 1][None])
    while len(state.stack) < 2 or state.stack.hints() is None:
        lo, hi, hints = state.stack.pop_hinted(solver.batch_size)
        solver.process(lo, hi, state, hints=hints)
    hints = state.stack.hints()
    assert hints.shape == (len(state.stack), width) and (hints >= 0).any()
    k = len(state.stack) // 2
    assert np.array_equal(hints[:k], hints[k:])  # the pairs of halves, pushed side by side
    lo, hi = state.stack.snapshot()
    res = run_task(solver, lo, hi, solver.known(state), Limits(max_boxes=1), hints)
    assert res.hints is not None and res.hints.shape == (res.lo.shape[0], width)
    assert (res.hints >= 0).any()
