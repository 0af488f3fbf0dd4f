"""Forward kinematics: round trips with inverse kinematics, mirror rejection, tension and
stroke limits, planar seeding, certified tracking.

Expected poses come from inverse kinematics (an independent code path: tensions by LP or
closed form, then eq. 5), never from the forward solver itself.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from certsolve.kinematics import (
    FKSolver,
    Tracker,
    forward_kinematics,
    inverse_kinematics,
    with_tau_max,
)
from certsolve.robot import Pose, Robot, platform_points
from certsolve.solver import ProcessExecutor
from certsolve.solver.certify import boxes_minus

ROBOTS = "examples/robots"


def load(name):
    return Robot.load(f"{ROBOTS}/{name}.json")


def ik_u(robot, pose):
    res = inverse_kinematics(robot, pose, method="tension")
    assert res.feasible, res.to_dict()
    return np.asarray(res.u, dtype=float)


def matching(result, robot, pose, tol=1e-6):
    """Solutions whose platform points are within ``tol`` cm of the pose's points."""
    target = platform_points(robot, pose.position, pose.rotation)[0]
    return [s for s in result.solutions if np.max(np.abs(s.platform_points - target)) <= tol]


def local_boxes(fk, robot, pose, radius, u):
    """The FK search box for ``u`` restricted to chosen points within ``radius`` cm of the
    pose."""
    form = fk.form
    c = form.coordinates_of(pose.position + form.Q @ pose.rotation.T)
    dom = fk.search_box(u)
    lo, hi = dom[:, 0].copy(), dom[:, 1].copy()
    k = c.size
    lo[:k] = np.maximum(lo[:k], c - radius)
    hi[:k] = np.minimum(hi[:k], c + radius)
    return lo[None], hi[None]


# -- round trips ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "params, formulation",
    [
        ((90, 60, 0), "auto"),
        ((75, 52, 0), "auto"),
        ((80, 55, 3), "auto"),
        ((100, 62, -3), "auto"),
        ((90, 60, 0), "planar-10"),
        ((100, 62, -3), "planar-10"),
    ],
)
def test_planar10_round_trip_full_domain(params, formulation):
    robot = load("planar")
    pose = Pose.from_params(3, params)
    u = ik_u(robot, pose)
    res = forward_kinematics(robot, u, formulation=formulation, timeout=120)
    assert res.formulation == ("frame-planar-10" if formulation == "auto" else "planar-10")
    assert res.status == "complete"
    assert len(matching(res, robot, pose)) == 1
    for s in res.solutions:
        assert s.certificate == "unique"


def test_t16_round_trip_full_domain():
    robot = load("marionet-t")
    pose = Pose.from_params(6, (112, 58, 115, 4, -3, 2))
    u = ik_u(robot, pose)
    res = forward_kinematics(robot, u, timeout=300)
    assert res.formulation == "frame-T-16"
    assert res.status == "complete"
    assert len(matching(res, robot, pose)) == 1


@pytest.mark.slow
def test_general19_round_trip_full_domain():
    robot = load("marionet")
    pose = Pose.from_params(6, (108, 60, 104, 5, 3, -4))
    u = ik_u(robot, pose)
    res = forward_kinematics(robot, u, timeout=1200)
    assert res.formulation == "frame-general-19"
    assert res.status == "complete"
    assert len(matching(res, robot, pose)) == 1


@pytest.mark.parametrize(
    "name, params, formulation, radius",
    [
        ("marionet", (111, 58, 107, 0, 0, 0), "general-19", 0.5),
        ("marionet", (108, 60, 104, 5, 3, -4), "general-19", 0.5),
        ("marionet", (108, 60, 104, 5, 3, -4), "auto", 0.5),
        ("marionet-t", (116, 61, 119, -5, 2, 3), "T-16", 2.0),
        ("marionet-t", (116, 61, 119, -5, 2, 3), "auto", 2.0),
        ("planar", (70, 45, 5), "planar-10", 2.0),
    ],
)
def test_round_trip_in_a_local_box(name, params, formulation, radius):
    """IK -> u -> FK searched in a box around the pose: the pose is certified there."""
    robot = load(name)
    pose = Pose.from_params(robot.dof, params)
    u = ik_u(robot, pose)
    fk = FKSolver(robot, formulation)
    res = fk.solve(u, boxes=local_boxes(fk, robot, pose, radius, u), timeout=120)
    assert res.status == "complete"
    assert len(matching(res, robot, pose)) == 1


def test_almost_planar13_fk_then_ik_round_trip():
    """4 wires cannot hold a generic 6-D pose: go FK -> pose -> IK and compare the controls."""
    robot = load("almost-planar")
    u = np.array([0.3, -0.2, 0.25, -0.1])
    fk = FKSolver(robot)
    assert fk.formulation == "frame-almost-planar-13"
    guess = Pose.from_params(6, (90, 60, -1, 0, 0, 0))
    res = fk.solve(u, boxes=local_boxes(fk, robot, guess, 4.0, u), timeout=120)
    assert res.status == "complete" and len(res.solutions) == 1
    s = res.solutions[0]
    back = inverse_kinematics(robot, Pose(s.position, s.rotation), method="tension")
    assert np.allclose(back.u, u, atol=1e-6)
    assert np.allclose(back.tau, s.tau, atol=1e-6)


# -- mirror images ----------------------------------------------------------------------------


def _mirrored(robot: Robot) -> Robot:
    data = robot.spec.model_dump()
    for w in data["wires"]:
        w["platform"][2] = -w["platform"][2]
    com = data["platform"]["center_of_mass"]
    com[2] = -com[2]
    data["name"] = robot.name + "-mirror"
    return Robot.load(data)


def test_general19_never_reports_a_mirror_image():
    """The mirrored platform fits the original robot's world points with the same wire
    lengths and forces -- a solution of all 19 equations -- but only as an improper
    (reflected) pose, which must be rejected; the original robot finds it."""
    robot = load("marionet")
    mirror = _mirrored(robot)
    pose = Pose.from_params(6, (111, 58, 107, 0, 0, 0))
    u = ik_u(robot, pose)
    fk = FKSolver(robot, "general-19")
    box = local_boxes(fk, robot, pose, 0.5, u)
    found = fk.solve(u, boxes=box, timeout=120)
    assert found.status == "complete"
    assert len(matching(found, robot, pose)) == 1

    fkm = FKSolver(mirror, "general-19")
    # same world points: the chosen points of the mirror robot sit where the original's are
    assert np.allclose(fkm.form.L, fk.form.L)
    res = fkm.solve(u, boxes=box, timeout=120)
    assert res.status == "complete"
    assert res.solutions == []
    assert all(und.reason != "eps" for und in res.undecided)


# -- limits -----------------------------------------------------------------------------------


def test_solutions_respect_tension_limits():
    """Raising tau_max only adds poses: the tau <= 10 poses are exactly the tau <= 60 poses
    whose tensions stay within 10 N, and every reported tension is within its limits."""
    robot = load("planar")
    u = np.array([0.8, 1.8, -2.5, -3.6])
    r60 = forward_kinematics(robot, u, tau_max=60.0, timeout=120)
    r10 = forward_kinematics(robot, u, tau_max=10.0, timeout=120)
    assert r60.status == r10.status == "complete"
    for res, tmax in ((r60, 60.0), (r10, 10.0)):
        for s in res.solutions:
            assert np.all(s.tau >= -1e-9) and np.all(s.tau <= tmax + 1e-9)
    within = [s for s in r60.solutions if np.max(s.tau) <= 10.0]
    assert len(r60.solutions) > len(within)  # some equilibrium needs more than 10 N
    assert len(r10.solutions) == len(within)
    for s in r10.solutions:
        assert any(np.allclose(s.platform_points, t.platform_points, atol=1e-6) for t in within)


def test_stroke_violations_are_reported():
    robot = load("planar")
    res = forward_kinematics(robot, [25.0, 0.0, 0.0, -21.0], timeout=60)
    notes = " ".join(res.notes)
    assert "u1 = 25" in notes and "u4 = -21" in notes


def test_tau_max_override_changes_only_tension_limits():
    robot = load("marionet-t")
    r = with_tau_max(robot, 60.0)
    assert np.all(r.tau_max == 60.0) and np.all(r.tau_min == robot.tau_min)
    assert np.array_equal(r.A, robot.A) and np.array_equal(r.L0, robot.L0)


# -- planar seeding ---------------------------------------------------------------------------


def test_seed_subtraction_covers_the_domain_exactly():
    rng = np.random.default_rng(0)
    lo, hi = np.zeros(5), np.ones(5) * 10
    seeds = []
    for _ in range(3):
        a = rng.uniform(0, 8, 5)
        seeds.append((a, a + rng.uniform(0.5, 3, 5)))
    pieces = list(zip(*boxes_minus(lo, hi, [s[0] for s in seeds], [s[1] for s in seeds])))
    pts = rng.uniform(0, 10, (20000, 5))
    covered = np.zeros(len(pts), dtype=bool)
    for a, b in list(seeds) + pieces:
        covered |= np.all((pts >= a) & (pts <= b), axis=1)
    assert covered.all()
    for plo, phi in pieces:  # pieces never enter a seed's interior
        for a, b in seeds:
            assert not np.all(np.maximum(plo, a) < np.minimum(phi, b))


@pytest.mark.slow
def test_seeded_search_equals_the_plain_search():
    robot = load("almost-planar")
    u = np.zeros(4)
    plain = forward_kinematics(robot, u, timeout=600)
    seeded = forward_kinematics(robot, u, seed_planar=True, timeout=600)
    assert plain.status == seeded.status == "complete"
    assert len(plain.solutions) == len(seeded.solutions)
    assert seeded.seeding["rest_of_domain_searched"]
    only = forward_kinematics(robot, u, seed_planar=True, seeded_only=True, timeout=600)
    assert only.status == "cancelled" and not only.seeding["rest_of_domain_searched"]
    assert only.pending  # the rest of the domain, not searched
    # the seeded search on worker processes, with --verify: the same poses, re-proven
    par = forward_kinematics(
        robot, u, seed_planar=True, timeout=600, verify=True, executor=ProcessExecutor(2, warmup=0)
    )
    assert par.status == "complete" and par.stats.executor == "processes"
    assert len(par.solutions) == len(plain.solutions)
    assert all(s.verified for s in par.solutions)


# -- tracking ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
def test_tracking_certifies_the_ik_pose(name):
    robot = load(name)
    start = {
        "marionet": (111, 58, 107, 0, 0, 0),
        "marionet-t": (115, 60, 118, 0, 0, 0),
        "planar": (90, 60, 0),
    }[name]
    tr = Tracker(robot)
    rng = np.random.default_rng(1)
    prev = Pose.from_params(robot.dof, start)
    params = np.array(start, dtype=float)
    for _ in range(5):
        params = params + rng.normal(0, 0.03, params.size)
        pose = Pose.from_params(robot.dof, params)
        res = tr.step(ik_u(robot, pose), prev)
        assert res.certified, res.message
        assert res.half_width == pytest.approx(0.1)
        target = platform_points(robot, pose.position, pose.rotation)[0]
        assert np.max(np.abs(res.pose.platform_points - target)) < 1e-7
        prev = res.pose


def test_tracking_never_certifies_a_non_solution():
    """Started far from any equilibrium, a step either fails or certifies a true solution."""
    robot = load("planar")
    pose = Pose.from_params(3, (90, 60, 0))
    u = ik_u(robot, pose)
    tr = Tracker(robot)
    res = tr.step(u, Pose.from_params(3, (40, 30, 60)))
    if res.certified:
        back = inverse_kinematics(robot, Pose(res.pose.position, res.pose.rotation))
        assert np.allclose(back.u, u, atol=1e-6)


def test_cli_fk_json_and_errors():
    cmd = [
        sys.executable,
        "-m",
        "certsolve.cli",
        "fk",
        f"{ROBOTS}/planar.json",
        "--u",
        "0.5,0.5,0.5,0.5",
        "--json",
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["status"] == "complete" and len(data["solutions"]) == 1
    sol = data["solutions"][0]
    for key in ("position", "rotation", "euler", "platform_points", "rho", "tau", "certificate"):
        assert key in sol
    bad = subprocess.run(cmd[:5] + ["--u", "1,2"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2
    assert "--u: expected 4 values (one per wire), got 2" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_solve_searches_the_box_for_u_and_leaves_the_system_alone():
    """The search domain depends on ``u`` (eq. 7); it is passed to the search, and so are
    the parameter values: the compiled system's own domain and parameters (shared by every
    solve) stay as built."""
    robot = with_tau_max(load("planar"), 60.0)
    u = np.array([0.8, 1.8, -2.5, -3.6])
    fk = FKSolver(robot)
    built = fk.csys.system.domain.copy()
    params = dict(fk.csys.system.parameters), fk.csys.param_lo.copy(), fk.csys.param_hi.copy()
    box = fk.search_box(u)
    assert not np.array_equal(box, built)  # otherwise this test proves nothing
    search = fk.search(u)
    assert search.solver.csys.param_lo.tolist() == u.tolist()
    assert np.array_equal(search.solver.domain, box)
    res = fk.solve(u)
    assert np.array_equal(fk.csys.system.domain, built)
    assert fk.csys.system.parameters == params[0]
    assert np.array_equal(fk.csys.param_lo, params[1])
    assert np.array_equal(fk.csys.param_hi, params[2])
    assert res.status == "complete" and len(res.solutions) == 2
    for s in res.solutions:
        lo, hi = np.array(s.box).T
        assert np.all(lo >= box[:, 0]) and np.all(hi <= box[:, 1])
