"""Forward kinematics of a robot known within tolerances (issue 31, item 2): pose boxes that
hold the equilibrium of every robot of the set, checked against robots drawn from the set
and solved one by one by the nominal FK."""

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.inputs import InputError
from certsolve.kinematics import forward_kinematics
from certsolve.kinematics.fk_solver import FKSolver
from certsolve.kinematics.fk_tolerance import SetKrawczyk, _prove_seeds
from certsolve.robot import Robot
from certsolve.solver.newton import krawczyk, linearize

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
U0 = np.zeros(7)


@pytest.fixture(scope="module")
def t16_tol():
    """The bundled T-16 robot with ±0.05 cm anchors and ±1 % k, and its pose boxes at u = 0
    (τ <= 10 N): about 3 s, shared by the tests below."""
    robot = Robot.load(ROBOTS / "marionet-t-tol.json")
    return robot, forward_kinematics(robot, U0)


def _inside(pose, sample) -> bool:
    """The nominal pose ``sample`` of a robot of the set lies in ``pose``'s bounds."""
    b = pose.bounds
    pts = sample.platform_points
    return bool(
        np.all((pts >= b.platform_points[0]) & (pts <= b.platform_points[1]))
        and np.all((sample.position >= b.position[0]) & (sample.position <= b.position[1]))
        and np.all((sample.rotation >= b.rotation[0]) & (sample.rotation <= b.rotation[1]))
    )


def test_one_unique_pose_box_holds_the_drawn_robots(t16_tol):
    robot, res = t16_tol
    assert res.status == "complete" and not res.undecided
    (pose,) = res.solutions
    assert pose.certificate == "unique" and pose.stability.stability == "stable"
    rng = np.random.default_rng(7)
    for corner in (True, False):
        sample = forward_kinematics(robot.draw(rng, corner=corner), U0)
        assert sample.status == "complete"
        (s,) = sample.solutions
        assert _inside(pose, s)
    # the box is a box of the set, not a point: it is wider than the nominal pose's
    lo, hi = pose.bounds.position
    assert np.all(hi - lo > 0.05) and np.all(hi - lo < 2.0)
    d = res.to_dict()["solutions"][0]
    assert len(d["platform_points_lo"]) == 7 and len(d["rotation_hi"]) == 3


def test_the_set_krawczyk_proves_what_the_plain_one_cannot(t16_tol):
    """The plain Krawczyk test with the numbers as interval constants of f(c) fails on
    every box around the set's poses; the test with ``Y J_p (P - p0)`` proves the box the
    result reports (module docstring of :mod:`certsolve.kinematics.fk_tolerance`)."""
    robot, res = t16_tol
    (pose,) = res.solutions
    fk = FKSolver(robot)
    search = fk.search(U0)
    test = SetKrawczyk(fk.form, U0)
    seed = np.array(forward_kinematics(robot.nominal(), U0).solutions[0].box).mean(axis=1)
    proven, elo, ehi, ulo, uhi = _prove_seeds(test, seed[None])
    assert proven[0]
    assert np.all(test(ulo, uhi)[2])
    assert np.allclose(np.array(pose.box), np.stack([elo[0], ehi[0]], axis=1))
    c, r = 0.5 * (ulo + uhi), 0.5 * (uhi - ulo)
    for f in (0.25, 0.5, 1.0, 2.0):
        assert not krawczyk(linearize(search.solver.csys, c - f * r, c + f * r))[2][0]


def test_zero_tolerance_is_the_nominal_answer():
    data = json.loads((ROBOTS / "marionet-t.json").read_text())
    nominal = forward_kinematics(Robot.load(data), U0)
    data["tolerances"] = [
        {"path": "wires[*].base[*]", "plus_minus": 0.0},
        {"path": "wires[*].k", "relative": 0.0},
    ]
    zero = forward_kinematics(Robot.load(data), U0)
    assert len(zero.solutions) == len(nominal.solutions) == 1
    for a, b in zip(zero.solutions, nominal.solutions, strict=True):
        assert a.box == b.box and a.bounds is None
    assert zero.stats.boxes == nominal.stats.boxes


def test_what_the_set_fk_refuses_names_the_field():
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    robot = Robot.load(data)
    for kwargs, field in (
        ({"formulation": "pose"}, "formulation"),
        ({"stable_only": True}, "stable_only"),
        ({"seed_planar": True}, "seed_planar"),
    ):
        with pytest.raises(InputError) as err:
            forward_kinematics(robot, U0, **kwargs)
        assert err.value.field == field
    data["tolerances"].append({"path": "wires[0].platform[0]", "plus_minus": 0.01})
    with pytest.raises(InputError) as err:
        forward_kinematics(Robot.load(data), U0)
    assert err.value.field == "robot.tolerances"


def test_the_fk_job_checks_the_set_at_submission():
    from certsolve.jobs.kinds.fk import FkParams
    from certsolve.robot.schema import load_robot_spec

    spec = load_robot_spec(ROBOTS / "marionet-t-tol.json")
    FkParams(u=list(U0)).check_robot(spec)
    with pytest.raises(ValueError, match="^formulation: pose does not take tolerances"):
        FkParams(u=list(U0), formulation="pose").check_robot(spec)


@pytest.mark.slow
def test_pose_box_against_the_extreme_robots_and_random_draws(t16_tol):
    """Every pose of 12 random robots and of the 6 robots at the corners that push the
    reference point P_1 furthest along each axis (first-order sensitivities) lies in the
    box.  Tightness (the issue's check): P_1's bounds are no wider than 3 times the spread
    of those robots' P_1 plus 0.01 cm, and every attachment's bounds no wider than 3 times
    the first-order spread of the set (``2 |dB/dp| dp``, which the extreme robots reach
    on P_1) plus 0.01 cm."""
    robot, res = t16_tol
    (pose,) = res.solutions
    fk = FKSolver(robot)
    test = SetKrawczyk(fk.form, U0)
    x = np.array(pose.box).mean(axis=1)
    n = test.n
    _, _, jlo, jhi = test.csys.eval_fj(np.r_[x, test.p0][None], np.r_[x, test.p0][None])
    J = 0.5 * (jlo + jhi)[0]
    S = -np.linalg.solve(J[:n, :n], J[:n, n:])  # dx/dp at the nominal robot
    names = list(test.csys.system.variables[n:])
    rng = np.random.default_rng(3)
    robots = [robot.draw(rng, corner=i % 2 == 0) for i in range(12)]
    for row in range(3):  # x1, y1, z1: the reference point
        for sign in (1.0, -1.0):
            p = np.clip(test.p0 + sign * np.sign(S[row]) * test.dp, test.p_lo, test.p_hi)
            A, k = robot.A.copy(), robot.k.copy()
            for name, v in zip(names, p, strict=True):
                part = name.split("_")
                if part[1] == "A":
                    A[int(part[2]), int(part[3])] = v
                else:
                    k[int(part[2])] = v
            robots.append(robot.realization({"A": A, "k": k}))
    points = []
    for r in robots:
        (s,) = forward_kinematics(r, U0).solutions
        assert _inside(pose, s)
        points.append(s.platform_points)
    lo, hi = pose.bounds.platform_points
    spread_p1 = np.ptp(np.array(points)[:, 0], axis=0)  # wire 1 is attached at P_1
    assert np.all(hi[0] - lo[0] <= 3.0 * spread_p1 + 0.01)
    L = fk.form.platform.L  # B_i = P_1 + sum_j L_ij E_j (frame variables P_1, E_2, E_3)
    SB = np.stack([S[c] + sum(L[:, j, None] * S[3 * j + c] for j in range(1, L.shape[1]))
                   for c in range(3)], axis=-2)  # fmt: skip
    first_order = 2.0 * np.abs(SB) @ test.dp
    assert np.all(hi - lo <= 3.0 * first_order + 0.01)


@pytest.mark.slow
def test_a_set_too_wide_for_one_krawczyk_box_is_proven_by_regularity():
    """At u4..7 = -2 the set's equilibria spread over a region where no single Krawczyk box
    contracts: the pose box is proven by the regularity of J_x over U (at most one per
    robot) and the search of the rest (no robot has an equilibrium on U's boundary), and
    it holds the drawn robots' poses."""
    robot = Robot.load(ROBOTS / "marionet-t-tol.json")
    u = np.array([0, 0, 0, -2, -2, -2, -2.0])
    res = forward_kinematics(robot, u)
    assert res.status == "complete" and not res.undecided
    (pose,) = res.solutions
    assert pose.certificate == "unique"
    assert any("regularity" in n and "1 with an equilibrium" in n for n in res.notes)
    rng = np.random.default_rng(11)
    for corner in (True, False, True):
        (s,) = forward_kinematics(robot.draw(rng, corner=corner), u).solutions
        assert _inside(pose, s)


def test_inline_tolerances_in_a_job_request(tmp_path):
    """A robot given inline with its tolerances is accepted by ``POST /v1/jobs``; a bad one
    is a 422 naming the entry, and an option the set's FK does not take is named too."""
    from fastapi.testclient import TestClient

    from certsolve.api.app import create_app
    from certsolve.jobs import ServiceSettings

    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    app = create_app(ServiceSettings(data_dir=tmp_path, workers=0))
    with TestClient(app, base_url="http://localhost") as c:
        job = {"kind": "fk", "robot": data, "params": {"u": [0.0] * 7}}
        assert c.post("/v1/jobs", json=job).status_code == 202
        bad = json.loads(json.dumps(job))
        bad["robot"]["tolerances"][1] = {"path": "wires[9].k", "relative": 0.01}
        r = c.post("/v1/jobs", json=bad)
        assert r.status_code == 422
        assert r.json()["detail"][0]["field"] == "robot.tolerances.1.path"
        job["params"]["stable_only"] = True
        r = c.post("/v1/jobs", json=job)
        assert r.status_code == 422 and "stable_only" in r.text
