"""Multistart float Newton, certified (:mod:`certsolve.solver.starts`): solutions early,
nothing lost, nothing certified that the search would not certify."""

from __future__ import annotations

import numpy as np
import pytest
from test_solver_systems import SYSTEMS, check_against_reference, in_box, ref_points

from certsolve.expr.minibex import load_minibex, parse_minibex
from certsolve.solver.branch_and_prune import Solver
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

    def points(certifier, domain, blo, bhi, phase):
        seen.append(blo.shape[0])
        return draw(certifier, domain, blo, bhi, phase)

    object.__setattr__(solver.starts, "points", points)
    back = np.repeat(dom[None], 3, axis=0)
    result = TaskResult(
        found=([], [], (100, 0, 0)), lo=back[:, :, 0], hi=back[:, :, 1],
        boxes=1, batches=1, cpu=0.0, wall=0.0,
    )  # fmt: skip
    search.absorb(lo, result)
    assert seen == [3]  # the task's three boxes, not the domain's one
