"""Anytime search: what a round sends back comes next, and solutions stream as proven."""

import contextlib
import io
import json
from pathlib import Path

import numpy as np

from certsolve.cli import main as cli_main
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.expr.node import var
from certsolve.expr.system import System
from certsolve.solver import Solver, solve
from certsolve.solver.bisectors import LargestFirst
from certsolve.solver.certify import Certifier
from certsolve.solver.pipeline import FixPoint

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"


class HalveFirst:
    """Halves the box whose x starts at 0 (a FixPoint sends it back); leaves the others."""

    def apply(self, batch):
        lo, hi = batch.lo.copy(), batch.hi.copy()
        first = lo[:, 0] == 0.0
        hi[first, 0] = 0.5 * hi[first, 0]
        batch.lo, batch.hi = lo, hi

    def describe(self):
        return "HalveFirst()"


def test_boxes_sent_back_are_on_top_of_the_halves():
    """Of two boxes, the one that shrank as much as a bisection goes round again and the
    other is split: the next batch pops the box sent back first, above the halves."""
    x, y = var("x"), var("y")
    system = System(["x", "y"], np.array([[0.0, 4.0], [0.0, 4.0]]), [x * x - 2, y - 1])
    csys = CompiledSystem(system)
    solver = Solver(system, FixPoint(HalveFirst()), Certifier(csys), LargestFirst())
    state = solver.start()
    lo = np.array([[0.0, 0.0], [3.0, 0.0]])
    hi = np.array([[3.0, 4.0], [4.0, 4.0]])
    solver.process(lo, hi, state)
    blo, bhi = state.stack.snapshot()
    assert len(blo) == 3 and state.stats.bisections == 1
    top_lo, top_hi = state.stack.pop(1)
    assert top_lo[0].tolist() == [0.0, 0.0] and top_hi[0].tolist() == [1.5, 4.0]


def test_progress_streams_each_solution_once():
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    streamed: list = []
    result = Solver.default(system, batch_size=64).solve(
        progress=lambda p: streamed.extend(p.found)
    )
    assert result.status == "complete" and len(result.solutions) == 16
    got = sorted(tuple(s.midpoint) for s in streamed)
    want = sorted(tuple(s.midpoint) for s in result.solutions)
    assert got == want


def test_cli_stream_prints_solutions_then_the_result():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = cli_main(["solve", str(SYSTEMS / "circle-line.mbx"), "--stream"])
    assert code == 0
    lines = [json.loads(line) for line in out.getvalue().splitlines()]
    *sols, last = lines
    assert len(sols) == 2 and all(set(s) == {"solution"} for s in sols)
    result = last["result"]
    assert result["status"] == "complete"
    assert sorted(s["solution"]["box"] for s in sols) == sorted(
        s["box"] for s in result["solutions"]
    )


def test_a_stopped_search_stores_the_solutions_found_so_far():
    """A job's partial result (``jobs.partial.stored_result``) holds what was streamed."""
    from certsolve.jobs.partial import stored_result

    streamed: list = []
    result = solve(
        load_minibex(SYSTEMS / "katsura-5.mbx"),
        max_boxes=2000,
        batch_size=64,
        progress=lambda p: streamed.extend(p.found),
    )
    assert result.status == "max_boxes" and result.pending_total > 0
    assert 0 < len(result.solutions) < 16
    data = stored_result(result, max_items=1000)
    assert data["status"] == "max_boxes"
    assert sorted(s["box"] for s in data["solutions"]) == sorted(s.box for s in streamed)
