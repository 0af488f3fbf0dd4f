"""Seeds from the energy's local minima: found in floats, searched first, same answer."""

import numpy as np
import pytest

from certsolve import Pose, Robot, forward_kinematics, inverse_kinematics
from certsolve.kinematics.energy_minima import _Energy, energy_minima, start_orientations
from certsolve.kinematics.fk_solver import FKSolver, with_tau_max
from certsolve.robot.geometry import rotation_zyx

ROBOTS = "examples/robots"
POSE = (111.0, 58.0, 107.0, 0.0, 0.0, 0.0)


def robot_and_u(name, pose=POSE, tau_max=None):
    robot = Robot.load(f"{ROBOTS}/{name}.json")
    res = inverse_kinematics(robot, Pose.from_params(6, pose), method="tension")
    assert res.feasible
    return with_tau_max(robot, tau_max), np.asarray(res.u, dtype=float)


def test_start_orientations_are_rotations():
    R = start_orientations(20)
    assert np.allclose(R[0], np.eye(3))
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    # spread: no two of them the same
    d = np.linalg.norm((R[:, None] - R[None]).reshape(20, 20, -1), axis=2)
    assert np.min(d + 10 * np.eye(20)) > 0.1


@pytest.mark.parametrize("name", ["marionet", "marionet-t"])
def test_gradient_is_the_derivative_of_the_energy(name):
    robot, u = robot_and_u(name)
    en = _Energy(robot, u)
    rng = np.random.default_rng(1)
    p = np.array(POSE[:3]) + rng.uniform(-3, 3, (4, 3))
    R = np.array([rotation_zyx(*a) for a in rng.uniform(-0.3, 0.3, (4, 3))])
    g = en.gradient(p, R)
    h = 1e-3
    for j in range(6):  # central differences of U along p and small world rotations
        e = np.zeros((4, 6))
        e[:, j] = h
        fd = (en.value(*en.moved(p, R, e)) - en.value(*en.moved(p, R, -e))) / (2 * h)
        assert np.allclose(fd, g[:, j], rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("name", ["marionet", "marionet-t"])
def test_the_pose_u_was_computed_from_is_a_minimum(name):
    """u from inverse kinematics at a pose: that pose is an equilibrium, and the robot's
    stable one; the descent finds it."""
    robot, u = robot_and_u(name, tau_max=60.0)
    minima = energy_minima(robot, u)
    assert minima and all(m.eig_min > 0 for m in minima)
    target = Robot.load(f"{ROBOTS}/{name}.json")
    pts = Pose.from_params(6, POSE).position + target.B @ rotation_zyx(*POSE[3:]).T
    found = [np.max(np.abs(m.position + robot.B @ m.rotation.T - pts)) < 1e-5 for m in minima]
    assert any(found)


def test_pose_box_encodes_the_pose():
    robot, u = robot_and_u("marionet")
    fk = FKSolver(robot)
    dom = fk.search_box(u)
    R = rotation_zyx(0.1, -0.2, 0.3)
    p = np.array([100.0, 60.0, 100.0])
    box = fk.form.pose_box(p, R, 0.5, dom)
    assert box is not None
    lo, hi = box
    c = 0.5 * (lo + hi)
    pos, R2, _ = fk.form.decode(c)
    assert np.allclose(pos, p, atol=1e-5) and np.allclose(R2, R, atol=1e-6)
    assert np.all(hi[: 3 * fk.form.n_points] - lo[: 3 * fk.form.n_points] <= 1.0 + 1e-9)


@pytest.mark.parametrize("name", ["marionet-t", pytest.param("marionet", marks=pytest.mark.slow)])
def test_seeded_search_gives_the_same_answer(name):
    robot, u = robot_and_u(name)  # the file's own 10 N limit: both searches complete
    plain = forward_kinematics(robot, u, seed_minima=False, timeout=300)
    seeded = forward_kinematics(robot, u, timeout=300)
    assert plain.status == seeded.status == "complete"
    assert seeded.seeding["method"] == "energy minima" and seeded.seeding["seed_boxes"] >= 1
    assert plain.seeding is None
    a = sorted(tuple(np.round(s.platform_points.ravel(), 6)) for s in plain.solutions)
    b = sorted(tuple(np.round(s.platform_points.ravel(), 6)) for s in seeded.solutions)
    assert len(a) == len(b) and np.allclose(a, b, atol=1e-6)


def test_the_stable_pose_comes_first_at_60_newtons():
    """general-19 at tau <= 60 N, u of a real pose: the first certified pose is the one the
    robot is in, proven stable, long before the search could finish."""
    robot, u = robot_and_u("marionet", tau_max=60.0)
    res = forward_kinematics(robot, u, max_solutions=1, stable_only=True)
    assert res.status == "max_solutions" and len(res.solutions) == 1
    pose = res.solutions[0]
    assert np.allclose(pose.position, POSE[:3], atol=1e-6)
    assert pose.stability.stability == "stable"
    assert any("another stable pose is not excluded" in n for n in res.notes)
