"""The table of FK formulations: names -> builders, each with a geometric precondition.

* ``check_formulation`` refuses exactly what ``build_formulation`` refuses, with the same
  message, and builds no expression;
* a solver reused for another ``u`` searches as a new one does (nothing carried over);
* the recipe of docs/architecture.md, "Adding an FK formulation": a class and one entry in
  the table, and FK runs with it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

from certsolve.kinematics import fk_points, fk_pose, fk_systems
from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.kinematics.fk_geometry import PlatformPoints
from certsolve.kinematics.fk_points import PointsFormulation
from certsolve.kinematics.fk_systems import FORMULATIONS, build_formulation, check_formulation
from certsolve.robot import Robot
from certsolve.solver.bisectors import LargestFirst

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
PATHS = sorted(ROBOTS.glob("*.json"))


def _error(fn, robot, name) -> str | None:
    try:
        fn(robot, name)
    except ValueError as exc:
        return str(exc)
    return None


@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_check_refuses_what_the_builder_refuses(path):
    robot = Robot.load(path)
    refused = 0
    for name in [*FORMULATIONS, "no-such"]:
        expected = _error(build_formulation, robot, name)
        assert _error(check_formulation, robot, name) == expected, name
        refused += expected is not None
    assert refused >= 1  # "no-such" at least: the comparison has a refusal to compare


def test_check_builds_no_expression(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("the precondition built a system")

    monkeypatch.setattr(fk_points, "_platform_system", refuse)
    monkeypatch.setattr(fk_pose.PoseFormulation, "build", refuse)
    accepted = 0
    for path in PATHS:
        robot = Robot.load(path)
        for name in FORMULATIONS:
            accepted += _error(check_formulation, robot, name) is None
    assert accepted >= 20  # the bundled robots' formulations (tests/reference)
    with pytest.raises(AssertionError, match="built a system"):
        build_formulation(Robot.load(ROBOTS / "planar.json"), "planar-10")


def test_a_solver_reused_for_another_u_searches_as_a_new_one():
    robot = with_tau_max(Robot.load(ROBOTS / "marionet-t.json"), 10.0)
    u1, u2 = np.zeros(robot.m), np.full(robot.m, 1.0)
    fk = FKSolver(robot)
    fk.solve(u1)
    again = fk.solve(u2)
    fresh = FKSolver(robot).solve(u2)
    assert again.status == fresh.status == "complete"
    assert again.stats.boxes == fresh.stats.boxes
    assert [s.box for s in again.solutions] == [s.box for s in fresh.solutions]


# -- the recipe: a formulation of its own, one entry in the table --------------------------------


@dataclass(kw_only=True)
class Toy(PointsFormulation):
    """planar-10 with a solver part of its own: the widest variable is split first."""

    kind: ClassVar[str] = "toy"

    def bisector(self, domain: np.ndarray) -> Any:
        return LargestFirst()


@dataclass(frozen=True, kw_only=True)
class ToyBuilder:
    dofs: tuple[int, ...] = (3,)

    def check(self, robot: Robot) -> PlatformPoints:
        return FORMULATIONS["planar-10"].check(robot)  # the same geometry

    def build(self, robot: Robot) -> Toy:
        return Toy.build(robot, "toy", self.check(robot))


def test_adding_a_formulation_recipe(monkeypatch):
    monkeypatch.setitem(fk_systems.FORMULATIONS, "toy", ToyBuilder())
    robot = with_tau_max(Robot.load(ROBOTS / "planar.json"), 60.0)
    u = [0.8, 1.8, -2.5, -3.6]
    check_formulation(robot, "toy")
    with pytest.raises(ValueError, match="planar robots"):
        check_formulation(Robot.load(ROBOTS / "marionet.json"), "toy")
    fk = FKSolver(robot, "toy")
    assert isinstance(fk.form, Toy) and isinstance(fk.search(u).solver.bisector, LargestFirst)
    res = fk.solve(u, timeout=120)
    paper = FKSolver(robot, "planar-10").solve(u, timeout=120)
    assert res.formulation == "toy"
    assert res.status == paper.status == "complete" and not res.undecided
    assert len(res.solutions) == len(paper.solutions) == 2
    for a, b in zip(
        sorted(res.solutions, key=lambda s: s.position.tolist()),
        sorted(paper.solutions, key=lambda s: s.position.tolist()),
        strict=True,
    ):
        assert np.allclose(a.platform_points, b.platform_points, atol=1e-6)
        assert a.stability.stability == b.stability.stability


def test_the_fk_job_builds_the_robot_with_its_tension_limit_once(monkeypatch):
    """``run_fk`` gives ``forward_kinematics`` the robot built with ``tau_max`` (one model,
    one FK solver: the system is built once per job) and finds what the library finds."""
    import json

    from certsolve.jobs.kinds.base import RunContext
    from certsolve.jobs.kinds.fk import FkJob, run_fk
    from certsolve.kinematics import forward_kinematics

    u = [0.8, 1.8, -2.5, -3.6]
    builds = []  # every FK system written, from the job's validation to its result
    real = fk_points._platform_system
    monkeypatch.setattr(fk_points, "_platform_system", lambda *a: builds.append(a) or real(*a))
    robot = json.loads((ROBOTS / "planar.json").read_text())
    job = FkJob.model_validate({"kind": "fk", "robot": robot, "params": {"u": u, "tau_max": 60.0}})
    res = run_fk(job.params, job.robot, RunContext(time_limit=120.0, max_boxes=10**6))
    assert len(builds) == 1
    assert float(builds[0][0].tau_max.max()) == 60.0
    lib = forward_kinematics(Robot.load(ROBOTS / "planar.json"), u, tau_max=60.0)
    assert res.status == lib.status == "complete"
    assert res.stats.boxes == lib.stats.boxes and len(res.solutions) == 2
