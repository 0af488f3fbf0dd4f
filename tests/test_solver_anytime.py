"""Anytime search: what a round sends back comes next, and solutions stream as proven."""

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.cli import main as cli_main
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.expr.node import var
from certsolve.expr.system import System
from certsolve.solver import Solver, SolverLimits, solve
from certsolve.solver.batching import BatchSizer
from certsolve.solver.bisectors import LargestFirst
from certsolve.solver.certify import Certifier
from certsolve.solver.dive import LowerFirst, NewtonSide
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


class Nothing:
    """Leaves every box as it is."""

    def apply(self, batch):
        pass

    def describe(self):
        return "Nothing()"


def _halves_after_one_round(domain, dive):
    """The top and the next box of the stack after one round (nothing contracts, the
    widest variable ``x`` is split at 0.45 of its width) on ``x^2 = 2, y = 1``."""
    x, y = var("x"), var("y")
    system = System(["x", "y"], np.array(domain, dtype=float), [x * x - 2, y - 1])
    csys = CompiledSystem(system)
    limits = SolverLimits(batch_size=1)  # so the order matters: one box a round
    solver = Solver(system, Nothing(), Certifier(csys), LargestFirst(), limits=limits, dive=dive)
    state = solver.start()
    dom = system.domain
    solver.process(dom[None, :, 0].copy(), dom[None, :, 1].copy(), state)
    assert state.stats.bisections == 1
    return state.stack.pop(1), state.stack.pop(1)


def test_the_lower_half_is_searched_first_with_ibex_order():
    """:class:`LowerFirst`: a split box's lower half goes on top of the stack (IBEX's
    order): the next batch dives into it, the upper half waits below."""
    (top_lo, top_hi), (below_lo, below_hi) = _halves_after_one_round(
        [[0.0, 2.0], [0.0, 1.0]], LowerFirst()
    )
    assert top_lo[0].tolist() == [0.0, 0.0] and below_hi[0].tolist() == [2.0, 1.0]
    assert top_hi[0, 0] == below_lo[0, 0] == 0.9


@pytest.mark.parametrize(
    ("domain", "upper"),
    [
        ([[0.0, 2.0], [0.0, 1.0]], True),  # N = 1 - (1 - 2) / 2 = 1.5 > 0.9: x* = 1.414 too
        ([[0.0, 4.0], [0.0, 2.0]], False),  # N = 2 - (4 - 2) / 4 = 1.5 < 1.8
        ([[-2.0, 2.0], [0.0, 1.0]], False),  # J(c) singular at x = 0: no Newton point
    ],
)
def test_the_half_holding_the_newton_point_is_searched_first(domain, upper):
    """The default dive (:class:`NewtonSide`) puts on top the half holding the float
    Newton point of the box's midpoint -- the half holding the solution here -- and the
    lower half where that point is not defined."""
    (top_lo, top_hi), (below_lo, below_hi) = _halves_after_one_round(domain, None)
    cut = domain[0][0] + 0.45 * (domain[0][1] - domain[0][0])
    lower, higher = (
        ((below_lo, below_hi), (top_lo, top_hi))
        if upper
        else (
            (top_lo, top_hi),
            (below_lo, below_hi),
        )
    )
    assert lower[0][0, 0] == domain[0][0] and lower[1][0, 0] == cut == higher[0][0, 0]
    assert higher[1][0, 0] == domain[0][1]


class NoDive:
    def upper_first(self, *args):
        raise AssertionError("the order was asked for where the next round takes all")


def test_the_dive_is_not_asked_where_the_next_round_takes_the_whole_stack():
    """katsura-5's stack never holds more than a round's 1,024 boxes: the order of the
    halves is moot, and the dive (its Newton points) is not computed; in rounds of 4 boxes
    it is."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    result = Solver.default(system, dive=NoDive()).solve()
    assert result.status == "complete" and len(result.solutions) == 16
    with pytest.raises(AssertionError, match="next round takes all"):
        Solver.default(system, dive=NoDive(), batch_size=4).solve()


def test_newton_side_needs_a_finite_newton_point():
    """``f(c)`` not finite (``1/x`` at ``c = 0``) or ``J(c)`` singular: the lower half."""
    x = var("x")
    csys = CompiledSystem(System(["x"], np.array([[-1.0, 1.0]]), [1 / x - 2]))
    lo, hi = np.array([[-1.0], [-1.0], [0.0]]), np.array([[1.0], [0.0], [1.0]])
    at = np.array([-0.1, -0.55, 0.45])
    got = NewtonSide().upper_first(csys, lo, hi, np.zeros(3, dtype=int), at)
    # c = 0: f infinite; c = -0.5: N = -0.5 - (-4)/(-4) = -1.5 < -0.55; c = 0.5: N = 0.5 -
    # 0/(-4) = 0.5 > 0.45
    assert got.tolist() == [False, False, True]


@pytest.mark.parametrize(
    "name",
    # katsura-5 (two searches of ~4,200 boxes in rounds of 16: 21 s) runs with -m slow
    [
        "circle-line",
        "brown-5",
        "trig-exp",
        "eco-6",
        pytest.param("katsura-5", marks=pytest.mark.slow),
    ],
)
def test_every_dive_certifies_the_same_solutions(name):
    """The dive orders the search, never what it proves: a complete search certifies the
    same solutions with the Newton side first and with IBEX's lower half first (the
    searches differ: eco-6 takes 543 and 499 boxes, katsura-5 4,177 and 4,262)."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    # rounds of 16 boxes: the stack holds more than a round, so the order matters
    runs = [Solver.default(system, dive=d, batch_size=16).solve() for d in (None, LowerFirst())]
    assert all(r.status == "complete" for r in runs)
    newton, lower = ([s.box for s in sorted(r.solutions, key=_mid)] for r in runs)
    assert len(newton) == len(lower) > 0
    for a, b in zip(newton, lower, strict=True):  # each box of one meets the other's
        assert all(x0 <= y1 and y0 <= x1 for (x0, x1), (y0, y1) in zip(a, b, strict=True))


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
        starts=None,  # the search alone: Newton from random points proves all 16 by then
    )
    assert result.status == "max_boxes" and result.pending_total > 0
    assert 0 < len(result.solutions) < 16
    data = stored_result(result, max_items=1000)
    assert data["status"] == "max_boxes"
    assert sorted(s["box"] for s in data["solutions"]) == sorted(s.box for s in streamed)


def test_batch_sizer_grows_while_the_per_box_time_falls_then_stays():
    """A round of ``k`` boxes costing ``10 + k`` ms: doubling to ``k`` pays while ``k <= 20``
    (per-box time down by a quarter or more), so the size grows 2 -> 4 -> 8 -> 16 -> 32 and stays
    (32 -> 64 would cut the per-box time by less than a quarter)."""
    sizer = BatchSizer(cap=1024, start=2, rounds=1)
    sizes = []
    for _ in range(12):
        k = sizer.next(None)
        sizes.append(k)
        sizer.record(k, 0.010 + 0.001 * k, None)
    assert sizes[:6] == [2, 4, 8, 16, 32, 32] and set(sizes[6:]) == {32}


def test_batch_sizer_cuts_a_round_to_the_time_left_and_caps_growth():
    sizer = BatchSizer(cap=64, start=8, rounds=1)
    sizer.record(8, 0.008, None)  # 1 ms a box, 2 ms with the margin: 16 next, 4.5 ms fit 2
    assert sizer.next(None) == 16 and sizer.next(0.0045) == 2 and sizer.next(0.0) == 1
    fixed = BatchSizer(cap=64, start=8, rounds=1, share=0.05)
    fixed.record(8, 0.008, 0.1)  # a 16-box round (16 ms) is over 5 % of 0.1 s: no growth
    assert fixed.size == 8
    capped = BatchSizer(cap=12, start=8, rounds=1)
    capped.record(8, 0.008, None)
    assert capped.size == 12


def test_batch_sizer_refuses_bad_settings():
    with pytest.raises(ValueError, match="start"):
        BatchSizer(cap=8, start=0)
    with pytest.raises(ValueError, match="share"):
        BatchSizer(cap=8, share=0.0)


def test_adaptive_and_fixed_batches_certify_the_same_solutions():
    """Only the grouping of the boxes changes: a complete search proves the same set."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    runs = [Solver.default(system, batch_start=s).solve() for s in (None, 4)]
    assert all(r.status == "complete" and len(r.solutions) == 16 for r in runs)
    fixed, adaptive = ([s.box for s in sorted(r.solutions, key=_mid)] for r in runs)
    for a, b in zip(fixed, adaptive, strict=True):  # each box of one meets the other's
        assert all(x0 <= y1 and y0 <= x1 for (x0, x1), (y0, y1) in zip(a, b, strict=True))


def test_first_rounds_are_small():
    """From 4 boxes the size at most doubles every two rounds: the first 9 rounds take at
    most 32 boxes, where a fixed size takes every box the stack holds (51 by the 9th)."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    steps = {}
    for start in (4, None):
        seen: list = []
        Solver.default(system, batch_start=start).solve(
            max_boxes=300, progress=lambda p, seen=seen: seen.append(p.boxes)
        )
        steps[start] = np.diff([0, *seen])
    assert steps[4][:9].max() <= 32 < steps[None][:9].max()
    assert len(steps[4]) > len(steps[None])


def _mid(s):
    return tuple(s.midpoint)


def test_newton_steps_of_a_stack_with_singular_and_infinite_members():
    """The dive's Newton steps (:func:`batched_solve`, the certifier's): one singular member
    makes numpy refuse the whole stack's solve; the others still get their step (as a solve
    of each alone gives it, to rounding), those two NaN."""
    from certsolve.solver.newton import batched_solve

    rng = np.random.default_rng(3)
    J = rng.standard_normal((6, 3, 3))
    f = rng.standard_normal((6, 3))
    J[1] = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]  # singular
    J[4, 0, 0] = np.inf
    for stack in (J, J[[0, 2, 3, 4, 5]]):  # with and without the singular member
        got, ok = batched_solve(stack, f[: len(stack)])
        assert ok.tolist() == np.all(np.isfinite(got), axis=1).tolist()
        for k, m in enumerate(stack):
            if np.all(np.isfinite(m)) and abs(np.linalg.det(m)) > 1e-9:
                want = np.linalg.solve(m, f[k])
                assert np.allclose(got[k], want, rtol=1e-9, atol=1e-12)
            else:
                assert np.all(np.isnan(got[k]))
