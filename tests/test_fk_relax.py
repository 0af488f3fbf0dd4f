"""The polytope hull in the forward-kinematics search (``FKSolver(relax=...)``): on by
default for the general-19 system, named in the search's fingerprint, and a search with it finds
the same poses as one without, in no more boxes on these cases."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.robot import Robot
from certsolve.solver import SearchStatus

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
REAL_POSE = [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]


def _key(res) -> list[tuple[float, ...]]:
    return sorted(tuple(np.round(s.platform_points.ravel(), 5)) for s in res.solutions)


@pytest.mark.parametrize(
    ("name", "tau", "pose"),
    [
        ("planar", 60.0, [90.0, 60.0, 0.0]),
        ("marionet-t", 10.0, REAL_POSE),
        pytest.param("marionet-t", 60.0, None, marks=pytest.mark.slow),  # ~40 s
        pytest.param("marionet", 10.0, None, marks=pytest.mark.slow),
    ],
)
def test_search_finds_the_same_poses(name, tau, pose):
    base = Robot.load(ROBOTS / f"{name}.json")
    robot = with_tau_max(base, tau)
    u = np.zeros(robot.m) if pose is None else inverse_kinematics(base, pose, method="alg2").u
    plain = FKSolver(robot, relax=False).solve(u)
    relaxed = FKSolver(robot, relax=True).solve(u)
    assert plain.status == relaxed.status == SearchStatus.COMPLETE
    assert _key(relaxed) == _key(plain)
    if name == "marionet":
        assert plain.solutions
        assert relaxed.stats.boxes < plain.stats.boxes


def test_on_for_general_19_and_in_the_fingerprint():
    """A checkpoint of a search with the hull is not resumed without it."""
    general = FKSolver(Robot.load(ROBOTS / "marionet.json"), prepare_search=False)
    t16 = FKSolver(Robot.load(ROBOTS / "marionet-t.json"), prepare_search=False)
    planar = FKSolver(Robot.load(ROBOTS / "planar.json"), prepare_search=False)
    assert general.relax and not t16.relax and not planar.relax
    assert "PolytopeHull" in general.search(np.zeros(7)).solver.fingerprint()
    assert "PolytopeHull" not in t16.search(np.zeros(7)).solver.fingerprint()
    on = FKSolver(Robot.load(ROBOTS / "marionet-t.json"), relax=True, prepare_search=False)
    assert "PolytopeHull" in on.search(np.zeros(7)).solver.fingerprint()
