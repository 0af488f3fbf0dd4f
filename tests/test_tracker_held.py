"""The tracker's held Jacobian (:class:`certsolve.kinematics.tracking.HeldJacobian`): a path's
next steps reuse an earlier step's ``Y`` and ``|I - Y J|``, and each step is still a proof."""

import numpy as np
import pytest

from certsolve.kinematics import Tracker, inverse_kinematics
from certsolve.robot import Pose, Robot, platform_points

ROBOTS = "examples/robots"
START = (115.0, 60.0, 118.0, 0.0, 0.0, 0.0)  # marionet-t's reference pose


def _path(robot, n, seed=2):
    """Poses of a random walk (~0.2 mm a row) and their controls from IK."""
    rng = np.random.default_rng(seed)
    params = np.array(START)
    poses, us = [], []
    for _ in range(n):
        params = params + np.concatenate([rng.normal(0, 0.02, 3), rng.normal(0, 0.01, 3)])
        pose = Pose.from_params(6, params)
        poses.append(pose)
        us.append(np.asarray(inverse_kinematics(robot, pose).u, dtype=float))
    return poses, us


@pytest.fixture(scope="module")
def robot():
    return Robot.load(f"{ROBOTS}/marionet-t.json")


def test_reused_steps_hold_their_jacobian_and_are_the_fresh_steps(robot):
    poses, us = _path(robot, 12)
    tr = Tracker(robot)
    calls = []
    enclose = tr.jacobian_box
    tr.jacobian_box = lambda lo, hi: calls.append(1) or enclose(lo, hi)
    prev = Pose.from_params(6, START)
    for pose, u in zip(poses, us, strict=True):
        res = tr.step(u, prev)
        fresh = Tracker(robot).step(u, prev)  # nothing held: the stateless proof
        assert res.certified and fresh.certified
        assert res.half_width == fresh.half_width == pytest.approx(0.1)
        target = platform_points(robot, pose.position, pose.rotation)[0]
        assert np.max(np.abs(res.pose.platform_points - target)) < 1e-7
        box = np.array(res.pose.box)
        x = tr.initial_point(pose)
        assert np.all((box[:, 0] <= x + 1e-9) & (x - 1e-9 <= box[:, 1]))
        prev = res.pose
    assert tr.held is not None
    assert len(calls) < len(us) // 2  # most steps needed no Jacobian of their own


def test_a_held_jacobian_never_proves_a_box_without_the_equilibrium(robot):
    poses, us = _path(robot, 1)
    tr = Tracker(robot)
    res = tr.step(us[0], Pose.from_params(6, START))
    held = tr.held
    assert res.certified and held is not None
    x = tr.initial_point(poses[0])
    for shift in (0.05, -0.05):
        c = x.copy()
        c[0] += shift  # the first point's x moved 0.5 mm; the box is ±0.2 mm around it
        lo, hi = tr.box(c - 0.02, c + 0.02)
        assert held.covers(lo, hi, us[0])
        tr.set_controls(us[0])
        flo, fhi = tr.csys.f_point(c)
        ok, _, _ = held.prove(lo, hi, c, flo, fhi)
        assert not ok
    # and controls outside its range are not covered
    lo, hi = tr.box(x - 0.1, x + 0.1)
    assert held.covers(lo, hi, us[0])
    assert not held.covers(lo, hi, us[0] + 1.0)
