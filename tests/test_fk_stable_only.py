"""The stable-only search (``stable_only``): sound pruning, the same stable poses as the full
search, and the option at every entry point."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, forward_kinematics, with_tau_max
from certsolve.kinematics.stability import Stability
from certsolve.kinematics.stable_only import StableOnly
from certsolve.robot import Robot
from certsolve.robot.elastic import tension
from certsolve.solver import SearchStatus
from certsolve.solver.pipeline import find

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"


def _u(robot, pose):
    return inverse_kinematics(robot, pose, method="alg2").u


def _key(s):
    return tuple(np.round(s.platform_points.ravel(), 6))


def check_same_stable(robot, u, tau):
    """stable-only == the stable (and undecided) poses of the full answer; both complete."""
    full = forward_kinematics(robot, u, tau_max=tau)
    only = forward_kinematics(robot, u, tau_max=tau, stable_only=True)
    assert full.status == only.status == SearchStatus.COMPLETE
    want = sorted(_key(s) for s in full.solutions if s.stability.stability != Stability.UNSTABLE)
    assert sorted(_key(s) for s in only.solutions) == want
    assert all(s.stability.stability != Stability.UNSTABLE for s in only.solutions)
    assert want  # the pose u was computed from is stable
    return full, only


@pytest.mark.parametrize(
    ("name", "pose", "tau"),
    [
        ("planar", [90.0, 60.0, 0.0], 60.0),
        ("planar", [80.0, 50.0, 5.0], 60.0),
        ("planar", [90.0, 60.0, 0.0], None),
        ("marionet-t", [111.0, 58.0, 107.0, 0.0, 0.0, 0.0], None),
    ],
)
def test_stable_only_is_the_stable_subset(name, pose, tau):
    robot = Robot.load(ROBOTS / f"{name}.json")
    full, only = check_same_stable(robot, _u(robot, pose), tau)
    if len(full.solutions) > len(only.solutions):
        assert any("unstable pose(s) left out" in n for n in only.notes)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "pose", "tau"),
    [
        ("marionet-t", [111.0, 58.0, 107.0, 0.0, 0.0, 0.0], 20.0),  # 2 stable poses
        ("marionet", [111.0, 58.0, 107.0, 0.0, 0.0, 0.0], None),
    ],
)
def test_stable_only_is_the_stable_subset_slow(name, pose, tau):
    robot = Robot.load(ROBOTS / f"{name}.json")
    check_same_stable(robot, _u(robot, pose), tau)


def test_contractor_drops_boxes_around_unstable_poses_only():
    """Boxes around the unstable equilibrium are proven to hold no stable one; boxes around
    the stable equilibrium are kept (at several widths)."""
    robot = Robot.load(ROBOTS / "planar.json")
    u = _u(robot, [90.0, 60.0, 0.0])
    fk = FKSolver(with_tau_max(robot, 60.0))
    res = fk.solve(u)
    csys = fk.search(u).solver.csys  # the compiled system with u as its parameters
    prune = StableOnly(fk.hessian, csys, fk.robot, fk.form.rho_columns())
    by = {s.stability.stability: s for s in res.solutions}
    assert set(by) == {Stability.STABLE, Stability.UNSTABLE}
    for kind, dropped in ((Stability.STABLE, False), (Stability.UNSTABLE, True)):
        box = np.array(by[kind].box)
        mid = 0.5 * (box[:, 0] + box[:, 1])
        for h in (1e-6, 1e-3, 1e-2):
            lo, hi, empty = prune.contract((mid - h)[None], (mid + h)[None])
            assert bool(empty[0]) is dropped
            assert np.array_equal(lo[0], mid - h) and np.array_equal(hi[0], mid + h)


def test_tension_ranges_follow_the_tension_law():
    """The gate's tension ranges are eq. (6) at the boxes' wire lengths, for the search's u
    (the contractor found in the search's pipeline), and the search domain's tensions span
    the limits."""
    robot = with_tau_max(Robot.load(ROBOTS / "marionet-t.json"), 60.0)
    fk = FKSolver(robot, stable_only=True)
    u = _u(Robot.load(ROBOTS / "marionet-t.json"), [111.0, 58.0, 107.0, 0.0, 0.0, 0.0])
    search = fk.search(u)
    prune = find(search.solver.contractor, StableOnly)
    rho = fk.form.rho_columns()
    dom = search.domain
    full = prune.tension_ranges(dom[None, :, 0], dom[None, :, 1])[0]
    assert np.allclose(full, robot.tau_max - robot.tau_min, rtol=1e-9)
    rng = np.random.default_rng(3)
    a, b = np.sort(rng.uniform(dom[:, 0], dom[:, 1], (2, 50, dom.shape[0])), axis=0)
    want = tension(robot, b[:, rho], u) - tension(robot, a[:, rho], u)
    assert np.allclose(prune.tension_ranges(a, b), want, rtol=1e-9, atol=1e-9)
    assert np.all(want >= 0.0)


def test_fingerprint_tells_stable_only_apart():
    robot = Robot.load(ROBOTS / "planar.json")
    u = np.zeros(robot.m)
    a = FKSolver(robot).search(u).solver.fingerprint()
    b = FKSolver(robot, stable_only=True).search(u).solver.fingerprint()
    assert a != b


def test_stable_only_with_seed_planar():
    """The almost-planar robot: the seeded search keeps the stable subset too."""
    from certsolve.jobs.kinds.fk import FkParams

    robot = Robot.load(ROBOTS / "almost-planar.json")
    u = _u(robot, [90.0, 60.0, -1.0, 0.0, 0.0, 0.0])
    full = forward_kinematics(robot, u, seed_planar=True)
    only = forward_kinematics(robot, u, seed_planar=True, stable_only=True)
    assert full.status == only.status == SearchStatus.COMPLETE
    want = sorted(_key(s) for s in full.solutions if s.stability.stability != Stability.UNSTABLE)
    assert want and sorted(_key(s) for s in only.solutions) == want
    assert FkParams(u=[0.0] * 4, stable_only=True, seed_planar=True).stable_only


def test_cli_stable_only(capsys):
    from certsolve.cli import main

    robot = Robot.load(ROBOTS / "planar.json")
    u = _u(robot, [90.0, 60.0, 0.0])
    args = ["fk", str(ROBOTS / "planar.json"), "--u", ",".join(map(str, u)), "--tau-max", "60"]
    assert main([*args, "--stable-only", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert [s["stability"] for s in got["solutions"]] == ["stable"]
    assert got["status"] == "complete"
    assert main([*args, "--stable-only", "--near", "90,60,0"]) != 0
    assert "--stable-only" in capsys.readouterr().err
