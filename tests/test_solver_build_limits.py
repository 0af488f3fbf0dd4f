"""The time limit covers building the solver, and the mixed Jacobian's size is bounded.

* a compile past its deadline raises :class:`CompileTimeout` naming its stage, and
  :func:`certsolve.solver.solve` reports it as a search stopped by time: status
  ``timeout``, no solution, nothing undecided, the whole domain pending; a build is given
  at least ``MIN_BUILD_SECONDS`` however short the limit;
* a compile within its deadline builds the same system as one without a deadline;
* past :data:`~certsolve.solver.pipeline.MIXED_NODES`, ``newton_groups="variables"``
  falls back to the plain Jacobian (no stacked program is built), and the search still
  finds the system's solutions.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.compiled import CompiledSystem, CompileTimeout
from certsolve.expr.minibex import load_minibex
from certsolve.solver import branch_and_prune, pipeline, solve
from certsolve.solver.contractors import HC4, IntervalNewton

SYSTEMS = Path(__file__).resolve().parents[1] / "examples" / "systems"


def test_a_compile_past_its_deadline_names_its_stage():
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    with pytest.raises(CompileTimeout, match="differentiating the equations") as info:
        CompiledSystem(system, deadline=time.monotonic() - 1.0)
    assert info.value.stage == "differentiating the equations"
    assert isinstance(info.value, TimeoutError)


def test_a_compile_within_its_deadline_is_the_same_system():
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    plain = CompiledSystem(system)
    timed = CompiledSystem(system, deadline=time.monotonic() + 3600.0)
    assert timed.fj.n_nodes == plain.fj.n_nodes
    assert np.array_equal(timed.jac_structure, plain.jac_structure)


def test_a_limit_passed_while_compiling_is_a_timeout_with_the_domain_pending(monkeypatch):
    monkeypatch.setattr(branch_and_prune, "MIN_BUILD_SECONDS", 0.0)
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    result = solve(system, timeout=1e-9)  # passed before the first row of the Jacobian
    assert result.status == "timeout"
    assert result.solutions == [] and result.undecided == []
    assert result.pending_total == 1 and result.stats.boxes == 0
    assert result.stats.stopped_by == "timeout"
    assert result.pending == [system.domain.tolist()]
    data = result.to_dict()
    assert data["status"] == "timeout" and data["pending_boxes"] == [1]


def test_a_short_limit_still_gives_the_build_its_minimum(monkeypatch):
    seen = []
    default = branch_and_prune.Solver.default

    def recording(system, **options):
        seen.append(options["deadline"])
        return default(system, **options)

    monkeypatch.setattr(branch_and_prune.Solver, "default", recording)
    before = time.monotonic()
    result = solve(load_minibex(SYSTEMS / "katsura-5.mbx"), timeout=0.5, max_boxes=10)
    assert seen[0] >= before + branch_and_prune.MIN_BUILD_SECONDS
    assert result.stats.boxes > 0  # built: the search ran
    assert solve(load_minibex(SYSTEMS / "circle-line.mbx")).status == "complete"
    assert seen[-1] is None  # no limit, no deadline


def test_past_the_mixed_bound_newton_uses_the_plain_jacobian(monkeypatch):
    csys = CompiledSystem(load_minibex(SYSTEMS / "circle-line.mbx"))
    hc4 = HC4(csys, max_passes=4)
    newton = pipeline.core(csys, hc4=hc4)[-1]
    assert isinstance(newton, IntervalNewton) and newton.groups is not None
    assert csys._mixed_programs  # built at load time

    small = CompiledSystem(load_minibex(SYSTEMS / "circle-line.mbx"))
    monkeypatch.setattr(pipeline, "MIXED_NODES", small.n * small.fj.n_nodes - 1)
    newton = pipeline.core(small, hc4=hc4)[-1]
    assert isinstance(newton, IntervalNewton) and newton.groups is None
    assert not small._mixed_programs  # no stacked program


def test_a_search_with_the_plain_jacobian_finds_every_solution(monkeypatch):
    system = load_minibex(SYSTEMS / "brown-5.mbx")
    mixed = solve(system)
    monkeypatch.setattr(pipeline, "MIXED_NODES", 0)
    plain = solve(system)
    assert mixed.status == plain.status == "complete"
    assert len(plain.solutions) == len(mixed.solutions) > 0
    for s in mixed.solutions:  # each solution of one search lies in a box of the other
        assert any(np.all(t.lo <= s.hi) and np.all(s.lo <= t.hi) for t in plain.solutions)
