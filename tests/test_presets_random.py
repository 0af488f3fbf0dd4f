"""Perturbed MARIONET designs (benchmarks): valid robots, u = 0 in the middle, reproducible."""

from __future__ import annotations

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.robot import Pose, Robot
from certsolve.robot.presets import MARIONET_MIDDLE, MARIONET_T_MIDDLE, random_marionet


@pytest.mark.parametrize("kind, middle", [("general", MARIONET_MIDDLE), ("T", MARIONET_T_MIDDLE)])
def test_random_marionet_is_calibrated_and_reproducible(kind, middle):
    spec = random_marionet(kind, seed=3)
    assert spec == random_marionet(kind, seed=3)
    assert spec != random_marionet(kind, seed=4)
    robot = Robot.load(spec)
    assert robot.m == 7 and robot.dof == 6
    # the recipe of the bundled robots: u = 0 holds the level platform at the middle
    res = inverse_kinematics(robot, Pose.from_params(6, [*middle, 0.0, 0.0, 0.0]))
    assert res.feasible
    assert np.max(np.abs(res.u)) < 1e-2


def test_random_t_platform_keeps_three_attachment_points():
    robot = Robot.load(random_marionet("T", seed=1))
    assert len({tuple(b) for b in robot.B.round(9)}) == 3


def test_random_marionet_rejects_unknown_kind():
    with pytest.raises(ValueError, match="kind"):
        random_marionet("planar", 0)
