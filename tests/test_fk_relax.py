"""The polytope hull in the forward-kinematics search (``FKSolver(relax=...)``): on by
default for the general-19 system, named in the search's fingerprint, on every narrow box and on
the wide ones as its learnt share plans, and a search with it finds the same poses as one
without, in no more boxes on these cases."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.robot import Pose, Robot
from certsolve.solver import SearchStatus
from certsolve.solver.batch import Batch
from certsolve.solver.pipeline import find
from certsolve.solver.relaxation import HullShare, PolytopeHull

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


def test_the_hull_on_every_narrow_box_and_the_wide_ones_as_learnt():
    """``PolytopeHull(always=...)``: a box narrower than the formulation's hull widths gets the hull
    whatever the learnt share says; the share plans the wider ones and learns from them
    only."""
    base = Robot.load(ROBOTS / "marionet.json")
    u = inverse_kinematics(base, REAL_POSE, method="alg2").u
    fk = FKSolver(with_tau_max(base, 60.0), prepare_search=False)
    search = fk.search(u)
    gate = find(search.solver.contractor, PolytopeHull)
    assert gate is not None and gate.always is not None
    pose = Pose.from_params(6, REAL_POSE)
    boxes = [
        fk.form.pose_box(np.asarray(pose.position) + off, pose.rotation, r, search.domain)
        for r, off in [(1.0, 0.0), (1.0, 2.5), (8.0, 0.0), (1.0, -2.5), (8.0, 3.0)]
    ]
    lo = np.array([b[0] for b in boxes])
    hi = np.array([b[1] for b in boxes])
    narrow = np.all(hi - lo < fk.form.hull_widths(), axis=1)
    assert narrow.tolist() == [True, True, False, True, False]
    clo, chi, _ = gate.contract(lo, hi)
    learnt = HullShare(share=0.0)  # below its threshold: one wide box in 16, the first
    batch = Batch(
        lo, hi, csys=search.solver.csys, eps=fk.eps, mask=fk.form.bisect_mask(), hull=learnt
    )
    gate.apply(batch)
    assert np.all(np.any(chi - clo < hi - lo, axis=1)[narrow])  # the hull narrows them
    assert np.array_equal(batch.lo[narrow], clo[narrow])
    assert np.array_equal(batch.hi[narrow], chi[narrow])
    assert np.array_equal(batch.lo[~narrow], lo[~narrow])
    # the one wide box contracted did not halve: the share learnt that, not the narrow ones
    assert learnt.boxes == 2 and learnt.share == 0.0
