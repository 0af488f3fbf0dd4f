"""Trajectories (certsolve.track_trajectory): a smooth path against an independent Newton
continuation, a wire driven to zero tension, a fold of the equilibria.

The reference is written here: the platform's static equilibrium in pose coordinates
(forces and moments of the wires, eq. 6, and of the weight), solved by float Newton with
a central-difference Jacobian, continued from row to row.  It shares no code with the
solver's formulations (chosen platform points, wire lengths as variables).
"""

import json

import numpy as np
import pytest

import certsolve
from certsolve.inputs import InputError
from certsolve.kinematics.trajectory import LostReason, TrajectoryFollower, TrajectoryStatus
from certsolve.robot.geometry import rotation_zyx

ROBOTS = "examples/robots"


def rotation(dof, q):
    if dof == 6:
        return rotation_zyx(*np.radians(q[3:6]))
    c, s = np.cos(np.radians(q[2])), np.sin(np.radians(q[2]))
    return np.array([[c, -s], [s, c]])


def cross(a, b):
    if a.shape[-1] == 3:
        return np.cross(a, b)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def equilibrium(robot, q, u):
    """Net force and moment on the platform at pose parameters ``q`` (cm, degrees)."""
    d = robot.dim
    R = rotation(robot.dof, q)
    p = q[:d]
    B = p + robot.B @ R.T
    diff = robot.A - B
    rho = np.linalg.norm(diff, axis=1)
    tau = robot.k * (1.0 - robot.L0 / (rho + robot.V + robot.K * u))
    f = (tau / rho)[:, None] * diff
    W = robot.weight
    force = f.sum(axis=0) + W
    moment = cross(B - p, f).sum(axis=0) + cross(R @ robot.com, W)
    return np.concatenate([force, np.atleast_1d(moment)])


def tensions(robot, q, u):
    R = rotation(robot.dof, q)
    rho = np.linalg.norm(robot.A - (q[: robot.dim] + robot.B @ R.T), axis=1)
    return robot.k * (1.0 - robot.L0 / (rho + robot.V + robot.K * u))


def newton(robot, q, u, tol=1e-11):
    """Float Newton on :func:`equilibrium` (central differences); None if it fails."""
    q = np.array(q, dtype=float)
    for _ in range(30):
        f = equilibrium(robot, q, u)
        J = np.empty((q.size, q.size))
        for j in range(q.size):
            e = np.zeros(q.size)
            e[j] = 1e-6
            J[:, j] = (equilibrium(robot, q + e, u) - equilibrium(robot, q - e, u)) / 2e-6
        step = np.linalg.solve(J, f)
        q = q - step
        if np.max(np.abs(step)) < tol:
            return q, J
    return None


def continuation(robot, start, controls):
    """The reference branch: Newton from the previous row's pose (None once it fails)."""
    q = np.asarray(start, dtype=float)
    out = []
    for u in controls:
        got = newton(robot, q, u)
        if got is None:
            break
        q = got[0]
        out.append(got)
    return out


def start_of(robot, pose):
    return np.asarray(certsolve.inverse_kinematics(robot, pose).u, dtype=float)


@pytest.mark.parametrize(
    "name, pose",
    [("planar", [90.0, 60.0, 0.0]), ("marionet-t", [115.0, 60.0, 118.0, 0.0, 0.0, 0.0])],
)
def test_a_smooth_path_matches_an_independent_continuation(name, pose):
    robot = certsolve.load_robot(f"{ROBOTS}/{name}.json")
    u0 = start_of(robot, pose)
    t = np.linspace(0.0, 1.0, 60)[:, None]
    phase = np.arange(robot.m)[None, :]
    controls = u0 + 0.8 * np.sin(2 * np.pi * t + phase) * t  # a few mm of motion
    res = certsolve.track_trajectory(robot, controls, pose)
    assert res.status == TrajectoryStatus.COMPLETE, res.reason
    assert res.lost_at is None
    assert [s.index for s in res.steps] == list(range(len(controls)))
    assert all(s.certified for s in res.steps)
    assert all(s.joined for s in res.steps[1:]) and res.steps[0].joined is None
    ref = continuation(robot, pose, controls)
    assert len(ref) == len(controls)
    tracker = certsolve.Tracker(robot)
    moved = 0.0
    for step, (q, _) in zip(res.steps, ref, strict=True):
        d = robot.dim
        R = rotation(robot.dof, q)
        points = q[:d] + robot.B @ R.T
        assert np.allclose(step.pose.platform_points, points, atol=1e-7, rtol=0)
        assert np.allclose(step.pose.tau, tensions(robot, q, step.u), atol=1e-7, rtol=0)
        # the reference equilibrium lies in the certified box (chosen points, lengths)
        x = tracker.initial_point(certsolve.Pose(q[:d], R))
        box = np.array(step.pose.box)
        slack = 1e-8 * (1.0 + np.abs(x))
        assert np.all((box[:, 0] - slack <= x) & (x <= box[:, 1] + slack))
        moved = max(moved, float(np.max(np.abs(points - ref[0][0][:d]))))
    assert moved > 0.1  # the path is not a standstill


def test_a_wire_driven_to_zero_tension_is_lost_at_the_right_step():
    robot = certsolve.load_robot(f"{ROBOTS}/marionet-t.json")
    pose = [115.0, 60.0, 118.0, 0.0, 0.0, 0.0]
    u0 = start_of(robot, pose)
    controls = u0 - 0.05 * np.arange(200)[:, None] * np.eye(robot.m)[3]  # shorten wire 4
    res = certsolve.track_trajectory(robot, controls, pose)
    assert res.status == TrajectoryStatus.LOST
    assert res.lost_reason == LostReason.TENSION
    assert "wire 4" in res.reason and "minimum 0 N" in res.reason
    k = res.lost_at
    assert [s.index for s in res.steps] == list(range(k + 1))
    assert all(s.certified for s in res.steps[:k]) and not res.steps[k].certified
    ref = continuation(robot, pose, controls[: k + 40])
    tau4 = np.array([tensions(robot, q, u)[3] for (q, _), u in zip(ref, controls, strict=False)])
    # certified steps have wire 4 taut; the reference goes slack within a few steps after
    assert np.all(tau4[:k] > 0.0)
    assert tau4[k] < 0.25  # the step's box reaches zero tension
    slack = int(np.argmax(tau4 < 0.0))
    assert tau4[slack] < 0.0 and k <= slack <= k + 5


def test_a_fold_is_never_crossed_silently():
    """An imperfect pitchfork of the planar robot's rotation (tension limits widened so
    that the equations alone decide): with all controls equal and low, the platform has
    two rotated equilibria; a small asymmetry makes the one turned against it end in a
    fold as the controls rise (its rotational stiffness -- the smallest eigenvalue of
    -J -- goes to 0, and it meets the unstable middle branch).  A plain Newton
    continuation jumps to the other side there.  The follower must stop before the fold,
    every step it certified on the reference branch."""
    data = json.load(open(f"{ROBOTS}/planar.json"))
    for w in data["wires"]:
        w["tau"] = [-50.0, 50.0]  # compressed wires allowed: no tension limit on the way
    robot = certsolve.Robot.load(data)
    bias = 0.1 * np.array([1.0, -1.0, 1.0, -1.0])
    cs = np.arange(-3.0, 0.0, 0.01)
    ref = continuation(robot, [90.0, 60.0, -30.0], cs[:, None] + bias)
    assert len(ref) == len(cs)
    theta = np.array([q[2] for q, _ in ref])
    stiff = np.array([np.linalg.eigvalsh(-0.5 * (J + J.T)).min() for _, J in ref])
    i = int(np.argmax(np.diff(theta))) + 1  # the plain continuation jumps here
    assert theta[i - 1] < 0.0 < theta[i], "the reference must cross the fold"
    assert stiff[i - 1] < 0.1 * stiff[0]  # the branch's stiffness vanishing: a fold
    c_fold = cs[i]  # the branch ends between cs[i - 1] and cs[i]
    rows = np.linspace(cs[i - 40], c_fold + 0.2, 60)
    res = certsolve.track_trajectory(robot, rows[:, None] + bias, ref[i - 40][0])
    assert res.status == TrajectoryStatus.LOST
    assert res.lost_reason in (
        LostReason.SINGULAR,
        LostReason.CERTIFICATE,
        LostReason.LINK,
        LostReason.NEWTON,
    )
    certified = [st for st in res.steps if st.certified]
    assert len(certified) == res.lost_at > 5
    assert rows[res.lost_at - 1] < c_fold
    # every certified step is on the reference branch (turned against the bias)
    again = continuation(robot, ref[i - 40][0], [st.u for st in certified])
    assert len(again) == len(certified)
    for st, (q, _) in zip(certified, again, strict=True):
        assert q[2] < 0.0
        R = rotation(3, q)
        assert np.allclose(st.pose.platform_points, q[:2] + robot.B @ R.T, atol=1e-7, rtol=0)


def test_the_follower_is_reused_and_the_result_is_plain_data():
    robot = certsolve.load_robot(f"{ROBOTS}/planar.json")
    pose = [90.0, 60.0, 0.0]
    u0 = start_of(robot, pose)
    controls = u0 + 0.01 * np.arange(10)[:, None]
    follower = TrajectoryFollower(robot)
    a = follower.follow(controls, certsolve.Pose.from_params(3, pose))
    b = follower.follow(controls, certsolve.Pose.from_params(3, pose))
    assert a.to_dict()["steps"] == b.to_dict()["steps"]
    d = json.loads(json.dumps(a.to_dict()))
    assert d["status"] == "complete" and d["lost_at"] is None
    assert set(d["steps"][0]) >= {
        "index", "u", "certified", "pose", "platform_points", "tensions", "box", "joined",
    }  # fmt: skip


def test_bad_inputs_name_the_field():
    robot = certsolve.load_robot(f"{ROBOTS}/planar.json")
    u = [0.0] * 4
    with pytest.raises(InputError) as e:
        certsolve.track_trajectory(robot, [u, u, [0.0] * 3], [90, 60, 0])
    assert e.value.field == "controls.2"
    with pytest.raises(InputError) as e:
        certsolve.track_trajectory(robot, [u], [90, 60, 0], half_width=-1)
    assert e.value.field == "half_width"
    with pytest.raises(InputError) as e:
        certsolve.track_trajectory(robot, [], [90, 60, 0])
    assert e.value.field == "controls"
    with pytest.raises(InputError) as e:
        certsolve.track_trajectory(robot, [u], [90, 60, float("nan")])
    assert e.value.field.startswith("start")


def test_tracker_is_exported_and_matches_track():
    robot = certsolve.load_robot(f"{ROBOTS}/planar.json")
    u = start_of(robot, [90.0, 60.0, 0.0])
    tracker = certsolve.Tracker(robot)
    a = tracker.step(u, [90.0, 60.0, 0.0], half_width=0.1)
    b = certsolve.track(robot, u, [90.0, 60.0, 0.0], half_width=0.1)
    assert a.certified and b.certified
    assert np.allclose(a.pose.position, b.pose.position, atol=1e-12)


def test_the_tension_enclosure_holds_every_tension_of_the_lengths():
    from certsolve.kinematics.trajectory import tension_enclosure

    robot = certsolve.load_robot(f"{ROBOTS}/marionet.json")
    rng = np.random.default_rng(3)
    for _ in range(20):
        a = rng.uniform(50.0, 250.0, robot.m)
        b = a + rng.uniform(0.0, 1.0, robot.m)
        u = rng.uniform(-20.0, 20.0, robot.m)
        lo, hi = tension_enclosure(robot, a, b, u)
        for rho in np.linspace(a, b, 7):
            tau = robot.k * (1.0 - robot.L0 / (rho + robot.V + robot.K * u))
            assert np.all((lo <= tau) & (tau <= hi))
        # and it is tight: its ends are the tensions at the ends
        ta = robot.k * (1.0 - robot.L0 / (a + robot.V + robot.K * u))
        assert np.allclose(lo, ta, rtol=1e-12, atol=1e-9)


def test_a_robot_with_tolerances_is_refused_by_name():
    """Tracking follows one robot's branch: a set of robots is refused, naming the field,
    in Python, on the command line and at a job's submission (not tracked as nominal)."""
    from certsolve.cli import main
    from certsolve.inputs import InputError
    from certsolve.jobs.kinds.trajectory import TrajectoryParams
    from certsolve.kinematics.tracking import Tracker
    from certsolve.robot.model import Robot
    from certsolve.robot.schema import load_robot_spec

    path = "examples/robots/marionet-t-tol.json"
    with pytest.raises(InputError) as e:
        Tracker(Robot.load(path))
    assert e.value.field == "robot.tolerances"
    assert main(["fk", path, "--u", "0,0,0,0,0,0,0", "--near", "115,60,118"]) == 2
    params = TrajectoryParams(controls=[[0.0] * 7], start=[115, 60, 118])
    with pytest.raises(ValueError, match="robot.tolerances"):
        params.check_robot(load_robot_spec(path))
