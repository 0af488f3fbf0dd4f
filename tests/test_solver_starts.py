"""Multistart float Newton, certified (:mod:`certsolve.solver.starts`): solutions early,
nothing lost, nothing certified that the search would not certify."""

from __future__ import annotations

import numpy as np
import pytest
from test_solver_systems import SYSTEMS, check_against_reference, in_box, ref_points

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex, parse_minibex
from certsolve.solver.branch_and_prune import Solver
from certsolve.solver.certify import Certifier
from certsolve.solver.starts import NEAR, NewtonStarts, draw_points

#: the first phase after the first bisection, the next ones at 4, 16 and 64: every search
#: below runs its phases early
EARLY = NewtonStarts(after=1)


@pytest.mark.parametrize(
    "name",
    ["circle-line", "brown-5", "troesch-10", "broyden-banded-10", "eco-6", "trig-exp", "katsura-5"],
)
def test_a_search_with_early_phases_finds_exactly_the_reference_solutions(name):
    """The phases' solutions are the search's: each reference solution in exactly one
    certified box, each box holding exactly one, the search complete and nothing undecided."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    result = Solver.default(system, starts=EARLY).solve(timeout=300)
    check_against_reference(name, system, result)


def test_a_singular_root_found_by_newton_is_still_not_certified():
    """At double-root's root Newton converges only linearly and Krawczyk cannot prove
    anything: with the phases on, the root still stays undecided and nothing is
    certified."""
    system = load_minibex(SYSTEMS / "double-root.mbx")
    result = Solver.default(system, starts=EARLY).solve(timeout=60)
    assert result.status == "complete" and result.solutions == []
    (root,) = ref_points("double-root")
    assert any(in_box(root, u.lo, u.hi) for u in result.undecided)


def test_a_root_on_the_domain_boundary_found_by_newton_stays_undecided():
    system = parse_minibex(
        "Variables\n  x in [0, 1];\n  y in [0, 1];\n"
        "Constraints\n  x^2 + y^2 = 2;\n  x - y = 0;\nend\n"
    )
    result = Solver.default(system, starts=EARLY).solve(timeout=60)
    assert result.status == "complete" and result.solutions == []
    assert any(in_box([1, 1], u.lo, u.hi) for u in result.undecided)


def test_phases_certify_solutions_the_search_has_not_reached():
    """katsura-6 stopped after 300 boxes: the search alone has certified none of its 32
    solutions, the phases most of them, each a true solution."""
    system = load_minibex(SYSTEMS / "katsura-6.mbx")
    alone = Solver.default(system, starts=None).solve(max_boxes=300)
    early = Solver.default(system, starts=EARLY).solve(max_boxes=300)
    assert alone.status == early.status == "max_boxes"
    assert len(early.solutions) >= 16 > len(alone.solutions)
    assert alone.stats.started == 0 and 16 <= early.stats.started <= len(early.solutions)
    ref = ref_points("katsura-6")
    for s in early.solutions:
        assert s.certificate == "unique"
        assert sum(in_box(p, s.lo, s.hi) for p in ref) == 1


def test_phases_come_at_their_bisection_counts_and_not_in_tasks():
    starts = NewtonStarts(after=10)
    assert [starts.due(b, b + 5) for b in (0, 5, 9, 10, 38, 39, 150, 159, 700)] == [
        None, 0, 0, None, 1, 1, None, 2, None,
    ]  # fmt: skip
    solver = Solver.default(load_minibex(SYSTEMS / "circle-line.mbx"))
    state = solver.start()
    assert state.starts  # the search's own state
    assert not solver.start(solver.known(state)).starts  # a worker task's


def test_larger_systems_run_their_first_phase_sooner():
    """A bisection of ``n`` variables costs more past 16: the first phase comes after
    ``after * (16 / n)^2`` bisections, at least one; the others at 4, 16 ... times that."""
    starts = NewtonStarts(after=64)
    assert [starts.first(n) for n in (1, 10, 16, 32, 64, 100, 1000)] == [64, 64, 64, 16, 4, 2, 1]
    assert starts.due(0, 15, n=32) is None and starts.due(15, 16, n=32) == 0
    assert starts.due(16, 64, n=32) == 1 and starts.due(16, 64) == 0
    assert NewtonStarts(after=10, spacing=2).due(10, 20) == 1


ATAN = "Variables\n  x in [-10, 10];\nConstraints\n  atan(x) = 0;\nend\n"


def test_a_damped_step_converges_where_a_full_step_runs_away():
    """Full Newton steps on ``atan(x)`` from ``|x| >= 1.4`` overshoot further every time;
    halved until ``|f|`` falls, they reach the root 0.  A point already at a root (``f =
    0``: no step makes ``|f|`` fall) counts as converged."""
    certifier = Certifier(CompiledSystem(parse_minibex(ATAN)))
    x0 = np.array([[3.0], [3.0], [-2.0], [0.0]])
    x, conv = certifier.newton_point(x0, iterations=60)
    assert conv.tolist() == [False, False, False, True]
    damped = np.array([True, False, True, True])
    x, conv = certifier.newton_point(x0, iterations=60, damped=damped)
    assert conv.tolist() == [True, False, True, True]
    assert np.all(np.abs(x[damped]) <= 1e-12)


def test_newton_takes_no_step_past_its_deadline():
    certifier = Certifier(CompiledSystem(parse_minibex(ATAN)))
    x0 = np.array([[0.5], [-1.5]])
    x, conv = certifier.newton_point(x0, iterations=60, damped=True, deadline=0.0)
    assert not conv.any() and np.array_equal(x, x0)


def test_a_phase_damps_its_share_of_the_points(monkeypatch):
    """``damped=0.5``: every other point of a phase takes damped steps."""
    certifier = Certifier(CompiledSystem(parse_minibex(ATAN)))
    seen = []
    newton = certifier.newton_point

    def spy(x0, lo=None, hi=None, **kw):
        seen.append(np.broadcast_to(kw["damped"], x0.shape[:1]).copy())
        return newton(x0, lo, hi, **kw)

    monkeypatch.setattr(certifier, "newton_point", spy)
    dom = np.array([[-10.0, 10.0]])
    for share in (0.0, 0.5, 1.0):
        x = NewtonStarts(count=8, damped=share).points(certifier, dom, dom[:, :1], dom[:, 1:], 0)
        assert np.allclose(x, [[0.0]], atol=1e-12)
    assert [m[:4].tolist() for m in seen] == [
        [False] * 4, [False, True, False, True], [True] * 4,
    ]  # fmt: skip
    assert [int(m.sum()) for m in seen] == [0, 16, 32]  # 32 points at least a phase


GRID = (
    "Variables\n  x in [0, 5];\n  y in [0, 5];\nConstraints\n"
    "  (x - 1)*(x - 2)*(x - 3)*(x - 4) = 0;\n  (y - 1)*(y - 2)*(y - 3)*(y - 4) = 0;\nend\n"
)


def test_a_phase_draws_again_while_a_quarter_of_its_points_prove_new_solutions():
    """16 solutions on a grid, 32 points a draw: the first draw proves at least 8 new
    ones, so with ``draws=4`` the next rounds draw again, one draw a round, each its own
    points, until a draw proves fewer than 8; with ``draws=1`` they do not.  Every proven
    point is a grid point."""
    system = parse_minibex(GRID)
    for draws in (1, 4):
        solver = Solver.default(system, starts=NewtonStarts(count=32, again=0.25, draws=draws))
        news = _phase_news(solver)
        state = solver.start()
        dom = solver.domain
        state.stack.push(dom[:, 0][None], dom[:, 1][None])
        solver._newton_starts(state, 0)  # the phase's first draw
        for _ in range(5):  # rounds without a new bisection: the next draw if the last paid
            solver._phase_if_due(state, state.stats.bisections)
        assert news[0] >= 8
        assert len(news) == 1 if draws == 1 else 2 <= len(news) <= 4
        assert all(k >= 8 for k in news[:-1]) and (len(news) == draws or news[-1] < 8)
        assert state.stats.started == sum(news) == len(state.solutions) <= 16
        boxes = [state.solutions.entry(i) for i in range(len(state.solutions))]
        mid = np.array([(elo + ehi) / 2 for elo, ehi, _, _ in boxes])
        assert np.allclose(mid, np.round(mid), atol=1e-9)
        assert np.all(np.isin(np.round(mid), [1, 2, 3, 4]))


def _phase_news(solver) -> list[int]:
    """The new solutions each ``_record`` call of ``solver`` brings, as they come."""
    news: list[int] = []
    record = solver._record

    def counted(*args, **kw):
        news.append(record(*args, **kw))
        return news[-1]

    object.__setattr__(solver, "_record", counted)
    return news


def test_points_are_drawn_in_their_boxes_near_zero_where_they_reach_it():
    lo = np.array([[-1e8, 1e9, -np.inf, -np.inf, 0.5]])
    hi = np.array([[1e8, 1e10, -1e12, np.inf, 0.75]])
    x = draw_points(lo, hi, 200, np.random.default_rng(1))
    assert np.all(np.abs(x[:, 0]) <= NEAR) and np.all(np.abs(x[:, 3]) <= NEAR)
    assert np.all((x[:, 1] >= 1e9) & (x[:, 1] <= 2e9))
    assert np.all((x[:, 2] >= -2e12) & (x[:, 2] <= -1e12))
    assert np.all((x[:, 4] >= 0.5) & (x[:, 4] <= 0.75))
    assert np.ptp(x, axis=0).min() > 0  # random, not a fixed point
    # near=None (forward kinematics' robot domains, in cm): uniform in the whole box
    lo, hi = np.array([[0.0, -300.0]]), np.array([[300.0, 300.0]])
    x = draw_points(lo, hi, 400, np.random.default_rng(2), near=None)
    assert np.all((x >= lo) & (x <= hi))
    assert x[:, 0].max() > 200.0 and x[:, 1].min() < -200.0  # not held near 0


def test_the_command_line_turns_the_phases_off(capsys):
    """``certsolve solve`` runs the phases by default (katsura-6 at 300 boxes: all 32 of
    its solutions); ``--no-newton-starts`` is the search alone (none)."""
    import json

    from certsolve.cli import main

    counts = []
    for flag in ((), ("--no-newton-starts",)):
        argv = ["solve", str(SYSTEMS / "katsura-6.mbx"), "--max-boxes", "300", "--workers", "1"]
        assert main([*argv, "--json", *flag]) == 0
        counts.append(len(json.loads(capsys.readouterr().out)["solutions"]))
    assert counts[0] >= 16 and counts[1] == 0


def test_a_task_brought_home_past_a_phase_runs_it_in_the_driver_a_restore_does_not():
    """With workers the bisections come home with the tasks (``Solver.merge``): the
    driver runs the phase they reach; a checkpoint restored into a new state (from 0
    bisections) runs none, as its search already did."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    solver = Solver.default(system, starts=NewtonStarts(after=50))
    dom = solver.domain
    home = ([], [], (100, 0, 0))  # a task's findings: nothing but 100 bisections
    for before, phases in ((10, True), (0, False)):
        state = solver.start()
        state.stack.push(dom[:, 0][None], dom[:, 1][None])
        state.stats.bisections = before
        solver.merge(state, home)
        assert (len(state.solutions) > 0) is phases


def test_a_phase_does_not_prove_a_known_solution_again():
    """The same phase twice on one state: the second draws the same points, all in known
    unicity boxes, and proves nothing (no Krawczyk test, no duplicate, nothing started)."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    solver = Solver.default(system, starts=EARLY)
    dom = solver.domain
    state = solver.start()
    state.stack.push(dom[:, 0][None], dom[:, 1][None])
    solver._newton_starts(state, 0)
    first = (len(state.solutions), state.stats.certified, state.stats.started)
    assert first[0] > 0 and first[0] == first[2]
    solver._newton_starts(state, 0)
    assert (len(state.solutions), state.stats.certified, state.stats.started) == first
    assert state.stats.duplicates == 0


def test_a_phase_a_task_brings_home_draws_from_the_boxes_it_brings():
    """``Search.absorb`` puts a task's unfinished boxes back on the driver's stack before
    it merges the task's findings: the phase the merge runs draws from them, not from the
    whole domain (with 2 workers every other pending box is out at a task)."""
    from certsolve.solver.search import Search, TaskResult

    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    solver = Solver.default(system, starts=NewtonStarts(after=50))
    state = solver.start()
    state.stats.bisections = 10
    search = Search(solver, state)
    dom = solver.domain
    state.stack.push(dom[:, 0][None], dom[:, 1][None])
    lo, _, _ = search.take(1)  # the whole domain out at a task: the stack is empty
    seen = []
    draw = solver.starts.points

    def points(certifier, domain, blo, bhi, *args, **kw):
        seen.append(blo.shape[0])
        return draw(certifier, domain, blo, bhi, *args, **kw)

    object.__setattr__(solver.starts, "points", points)
    back = np.repeat(dom[None], 3, axis=0)
    result = TaskResult(
        found=([], [], (100, 0, 0)), lo=back[:, :, 0], hi=back[:, :, 1],
        boxes=1, batches=1, cpu=0.0, wall=0.0,
    )  # fmt: skip
    search.absorb(lo, result)
    assert seen == [3]  # the task's three boxes, not the domain's one
