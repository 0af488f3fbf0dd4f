"""Inverse kinematics (Merlet 2007, section II.A): round trips, tension distributions,
violations, Algorithms 1 and 2, all robot kinds.

The forward checks use the robot package's own geometry and elastic model
(:func:`wrench_matrix`, :func:`gravity_wrench`, :func:`certsolve.robot.elastic.tension`),
not the IK's code paths.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics.ik import inverse_kinematics
from certsolve.kinematics.ik_tension import closed_form, distribute_tensions
from certsolve.robot import Pose, Robot, RobotFileError, gravity_wrench, wrench_matrix
from certsolve.robot.elastic import tension
from certsolve.robot.geometry import wire_geometry
from certsolve.robot.statics import max_margin_tensions

CENTRE = {
    "marionet": [111, 58, 107, 0, 0, 0],
    "marionet-t": [115, 60, 118, 0, 0, 0],
    "planar": [90, 60, 0],
}


def load(name):
    return Robot.load(f"examples/robots/{name}.json")


def forward_residual(robot, pose, u):
    """max |H τ(u) + w_g| with ρ from the pose and τ from eq. (6)."""
    rho = wire_geometry(robot, pose.position, pose.rotation)[0][0]
    tau = tension(robot, rho, np.asarray(u))
    H = wrench_matrix(robot, pose.position, pose.rotation)[0]
    wg = gravity_wrench(robot, pose.rotation)[0]
    return float(np.max(np.abs(H @ tau + wg))), tau


def near_centre_poses(name, n, rng, spread=8.0, angle=4.0):
    robot = load(name)
    c = np.array(CENTRE[name], dtype=float)
    out = []
    for _ in range(n):
        if robot.dof == 6:
            d = np.concatenate([rng.uniform(-spread, spread, 3), rng.uniform(-angle, angle, 3)])
        else:
            d = np.concatenate([rng.uniform(-spread, spread, 2), rng.uniform(-angle, angle, 1)])
        out.append(Pose.from_params(robot.dof, list(c + d)))
    return robot, out


# -- round trips -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
@pytest.mark.parametrize("method", ["tension", "alg1", "alg2"])
def test_round_trip_equilibrium(name, method):
    robot, poses = near_centre_poses(name, 5, np.random.default_rng(1))
    for pose in poses:
        res = inverse_kinematics(robot, pose, method)
        assert res.u is not None, res.messages
        r, tau = forward_residual(robot, pose, res.u)
        assert r < 1e-9, (method, r)
        assert np.allclose(tau, res.tau, atol=1e-9)
        if method != "alg2":  # alg2 fixes a mid-range tension, limits may be violated
            assert res.status in ("ok", "boundary"), (res.status, res.messages)
        assert json.loads(json.dumps(res.to_dict(), allow_nan=False))["method"] == method


def test_centre_pose_gives_zero_controls():
    """presets.py calibrates L0 so that the max-margin tensions give u = 0 at the centre."""
    robot = load("marionet")
    res = inverse_kinematics(robot, CENTRE["marionet"], "tension")
    assert res.status == "ok" and res.feasible
    assert np.max(np.abs(res.u)) < 1e-3
    assert res.margin == pytest.approx(3.85, abs=0.01)


# -- tension distributions ---------------------------------------------------------------------
@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar", "krut-3"])
def test_closed_form_agrees_with_lp(name):
    robot = load(name)
    rng = np.random.default_rng(2)
    dom = robot.domain
    checked = 0
    for _ in range(40):
        p = list(rng.uniform(dom[:, 0], dom[:, 1]))
        if robot.dof == 6:
            p += list(rng.uniform(-10, 10, 3))
        elif robot.dof == 3:
            p += [rng.uniform(-20, 20)]
        pose = Pose.from_params(robot.dof, p)
        H = wrench_matrix(robot, pose.position, pose.rotation)[0]
        wg = gravity_wrench(robot, pose.rotation)[0]
        cf = distribute_tensions(H, wg, robot.tau_min, robot.tau_max, mode="closed-form")
        lp = max_margin_tensions(H, wg, robot.tau_min, robot.tau_max)
        assert cf.method == "closed-form"
        assert cf.margin == pytest.approx(lp.margin, abs=1e-7 * (1 + abs(lp.margin)))
        assert np.max(np.abs(H @ cf.tau + wg)) < 1e-9
        # the optimum of the margin is unique on the line: the tensions agree too
        if abs(lp.margin) > 1e-6:
            assert np.max(np.abs(cf.tau - lp.tau)) < 1e-6 * (1 + np.max(np.abs(lp.tau)))
        checked += 1
    assert checked == 40


def test_closed_form_is_the_exact_maximum():
    """Brute force over λ: no point of the line has a larger margin."""
    rng = np.random.default_rng(4)
    for _ in range(50):
        tau_p = rng.normal(size=7) * 3
        v = rng.normal(size=7)
        lo, hi = np.zeros(7), np.full(7, 10.0)
        lam, g, (a, b) = closed_form(tau_p, v, lo, hi)
        grid = np.linspace(lam - 5, lam + 5, 20001)
        tau = tau_p[None] + grid[:, None] * v[None]
        gg = np.min(np.minimum(tau - lo, hi - tau), axis=1)
        assert g >= gg.max() - 1e-12
        assert g == pytest.approx(np.min(np.minimum(tau_p + lam * v - lo, hi - tau_p - lam * v)))
        # admissible λ interval: margin >= 0 exactly inside it
        if a <= b:
            for x in (a, b, 0.5 * (a + b)):
                t = tau_p + x * v
                assert np.all(t >= lo - 1e-9) and np.all(t <= hi + 1e-9)
        else:
            assert g < 0


def test_lp_check_recorded():
    res = inverse_kinematics(load("marionet"), CENTRE["marionet"], "tension", check_lp=True)
    lp = res.details["lp_check"]
    assert lp["margin_difference"] < 1e-9 and lp["max_tau_difference"] < 1e-9


# -- violations and infeasible poses -----------------------------------------------------------
def test_stroke_violations_reported():
    robot = load("marionet")
    pose = [153.3626777419095, 66.80361114472768, 128.81390370240953, -0.103, 1.172, 11.431]
    res = inverse_kinematics(robot, pose, "tension")
    assert res.status == "limits-violated" and not res.feasible
    strokes = {(v.wire, v.bound) for v in res.violations if v.quantity == "u"}
    expected = set()
    for i, u in enumerate(res.u):
        if u > 20:
            expected.add((i + 1, "max"))
        if u < -20:
            expected.add((i + 1, "min"))
    assert strokes == expected and strokes
    for v in res.violations:
        assert v.excess == pytest.approx(abs(v.value - v.limit))
        assert v.excess > 0
    d = res.to_dict()
    assert {"wire", "quantity", "value", "limit"} <= set(d["violations"][0])


def test_infeasible_pose_reported_and_proved():
    robot = load("marionet")
    pose = [111, 58, 107, 0, 20, 0]  # pitched 20°: no tensions in [0, 10] N balance it
    t = inverse_kinematics(robot, pose, "tension")
    assert t.status == "infeasible" and not t.feasible
    assert t.margin < 0
    assert any("no admissible tension" in m for m in t.messages)
    a = inverse_kinematics(robot, pose, "alg1")
    assert a.status == "infeasible" and a.u is None
    assert any(m.startswith("proved") for m in a.messages)


def test_alg2_reports_tension_violations():
    robot = load("marionet")
    res = inverse_kinematics(robot, [111, 58, 107, 10, 5, -3], "alg2")
    assert res.status == "limits-violated"
    assert res.certificate.kind == "unique-in-box"  # the point is still a proven solution
    assert {v.quantity for v in res.violations} == {"tau"}
    over = {i + 1 for i, t in enumerate(res.tau) if t > robot.tau_max[i]}
    assert {v.wire for v in res.violations} == over


# -- Algorithm 2 -------------------------------------------------------------------------------
def test_alg2_fixed_wire_mid_tension():
    robot = load("marionet")
    res = inverse_kinematics(robot, CENTRE["marionet"], "alg2")
    assert res.status == "ok"
    assert res.tau[0] == pytest.approx(5.0, abs=1e-12)  # (τ_min + τ_max) / 2
    assert res.certificate.fixed == {1: res.u[0]}
    other = inverse_kinematics(robot, CENTRE["marionet"], "alg2", fixed_wire=3, tau_fixed=4.0)
    assert other.tau[2] == pytest.approx(4.0, abs=1e-12)
    assert forward_residual(robot, other.pose, other.u)[0] < 1e-9


def test_alg2_newton_matches_tau_solve():
    robot = load("marionet")
    pose = Pose.from_params(6, [105, 60, 100, 3, -2, 1])
    a = inverse_kinematics(robot, pose, "alg2")
    b = inverse_kinematics(robot, pose, "alg2", solve="newton")
    c = inverse_kinematics(robot, pose, "alg2", solve="newton", u_last=a.u + 0.05)
    for r in (b, c):
        assert r.certificate.kind == "unique-in-box"
        assert np.allclose(r.u, a.u, atol=1e-10)
    assert c.details["iterations"] <= b.details["iterations"]


def test_alg2_window_violation():
    robot = load("marionet")
    pose = CENTRE["marionet"]
    u0 = inverse_kinematics(robot, pose, "alg2").u
    far = u0.copy()
    far[3] += 1.0
    res = inverse_kinematics(robot, pose, "alg2", u_last=far, window=0.1)
    assert [(v.wire, v.quantity) for v in res.violations] == [(4, "u-window")]


# -- Algorithm 1 -------------------------------------------------------------------------------
def test_alg1_certified_solution():
    robot = load("marionet")
    pose = Pose.from_params(6, [111, 58, 107, 10, 5, -3])
    res = inverse_kinematics(robot, pose, "alg1")
    assert res.status == "ok" and res.feasible
    cert = res.certificate
    assert cert.kind == "unique-in-box" and len(cert.fixed) == 1
    ((j, val),) = cert.fixed.items()
    assert res.u[j - 1] == val
    elo, ehi = cert.enclosure
    assert np.all(elo <= res.u) and np.all(res.u <= ehi) and np.max(ehi - elo) < 1e-9
    assert res.residual < 1e-9
    assert forward_residual(robot, pose, res.u)[0] < 1e-9
    assert np.all(res.tau >= robot.tau_min) and np.all(res.tau <= robot.tau_max)
    assert np.all(np.abs(res.u) <= 20)


def test_alg1_window_around_last_u():
    robot = load("marionet")
    p0 = np.array(CENTRE["marionet"], dtype=float)
    u_last = inverse_kinematics(robot, p0, "alg1").u
    p1 = p0 + np.array([0.02, -0.01, 0.015, 0.01, 0, 0])  # a small motion
    res = inverse_kinematics(robot, p1, "alg1", u_last=u_last)  # 1 mm window
    assert res.status == "ok"
    assert np.all(np.abs(res.u - u_last) <= 0.05 + 1e-12)
    assert res.details["domain"][0] == pytest.approx([u_last[0] - 0.05, u_last[0] + 0.05])
    # a window far from any solution: proved empty
    res = inverse_kinematics(robot, p1, "alg1", u_last=u_last + 5.0)
    assert res.status == "infeasible"


def test_alg1_consistent_with_tension_first():
    """Admissible tensions within the strokes exist <=> Algorithm 1 certifies a solution;
    no admissible tension at all => Algorithm 1 proves that no control works."""
    for name in ("marionet", "marionet-t"):
        robot = load(name)
        rng = np.random.default_rng(9)
        dom = robot.domain
        seen = set()
        for _ in range(40):
            p = list(rng.uniform(dom[:, 0], dom[:, 1])) + list(rng.uniform(-5, 5, 3))
            t = inverse_kinematics(robot, p, "tension")
            a = inverse_kinematics(robot, p, "alg1")
            seen.add((t.status, a.status))
            if t.status == "ok":
                assert a.status == "ok"
            if t.status == "infeasible":
                assert a.status == "infeasible"
            if a.status == "ok":
                assert a.residual < 1e-9
        assert ("infeasible", "infeasible") in seen


# -- the other robots --------------------------------------------------------------------------
def test_almost_planar_overdetermined():
    robot = load("almost-planar")
    eq = inverse_kinematics(robot, [90, 60, -1, 0, 0, 0], "tension")
    assert eq.status == "ok"  # symmetric pose: an equilibrium (numerically)
    assert eq.residual < 1e-12
    assert any("over-determined" in m for m in eq.messages)
    assert np.allclose(eq.tau, eq.tau[0])
    bad = inverse_kinematics(robot, [100, 60, -1, 0, 0, 0], "tension")
    assert bad.status == "not-equilibrium" and not bad.feasible
    assert bad.residual > 1e-3
    a1 = inverse_kinematics(robot, [100, 60, -1, 0, 0, 0], "alg1")
    assert a1.status == "infeasible"  # proved: no control balances this pose
    for method in ("alg1", "alg2"):
        r = inverse_kinematics(robot, [90, 60, -1, 0, 0, 0], method)
        assert r.status == "uncertified" and r.certificate.kind == "none"
        assert forward_residual(robot, r.pose, r.u)[0] < 1e-9


def test_planar_boundary_all_slack():
    """No gravity in the plane: where the null vector changes sign, only τ = 0 balances."""
    robot = load("planar")
    res = inverse_kinematics(robot, [81.6, 16.1, -5.8], "tension")
    assert res.status == "boundary" and not res.feasible
    assert np.all(res.tau == 0)


def test_krut_tensions_only():
    robot = load("krut-3")
    res = inverse_kinematics(robot, [0, 0], "tension")
    assert res.u is None and res.status == "ok"
    assert any("no elastic model" in m for m in res.messages)
    # Krut's 3-motor robot at the centre: equal tensions, the max-margin one is mid-range
    assert np.allclose(res.tau, 275.0)
    for method in ("alg1", "alg2"):
        with pytest.raises(RobotFileError, match="no elastic wire model"):
            inverse_kinematics(robot, [0, 0], method)


def test_pose_forms_and_errors():
    robot = load("marionet")
    a = inverse_kinematics(robot, "111,58,107,0,0,0", "alg2")
    b = inverse_kinematics(robot, [111, 58, 107], "alg2")
    assert np.array_equal(a.u, b.u)
    with pytest.raises(ValueError, match="spatial pose"):
        inverse_kinematics(robot, [1, 2], "tension")
    with pytest.raises(ValueError, match="method"):
        inverse_kinematics(robot, [111, 58, 107], "alg3")
    with pytest.raises(ValueError, match="finite"):
        inverse_kinematics(robot, Pose(np.array([np.nan, 1.0, 2.0]), np.eye(3)), "alg2")


def test_alg1_window_matches_exact_lambda_interval():
    """Independent decision: on the line τ = τ_p + λ v the window and the tension limits
    are an interval of λ per wire; Algorithm 1 certifies iff their intersection is not empty
    (decided here in floating point, skipping windows within 1e-9 of the edge)."""
    robot = load("marionet")
    pose = Pose.from_params(6, [108, 60, 104, 2, -1, 3])
    H = wrench_matrix(robot, pose.position, pose.rotation)[0]
    wg = gravity_wrench(robot, pose.rotation)[0]
    rho = wire_geometry(robot, pose.position, pose.rotation)[0][0]
    ch = distribute_tensions(H, wg, robot.tau_min, robot.tau_max)
    tp, v = ch.particular, ch.null_vector
    u_star = inverse_kinematics(robot, pose, "alg1").u
    rng = np.random.default_rng(3)
    seen = set()
    for _ in range(80):
        c = u_star + rng.uniform(-0.08, 0.08, 7)
        lo, hi = c - 0.05, c + 0.05
        tlo = np.maximum(tension(robot, rho, lo), robot.tau_min)
        thi = np.minimum(tension(robot, rho, hi), robot.tau_max)
        a, b = (tlo - tp) / v, (thi - tp) / v
        gap = np.min(np.maximum(a, b)) - np.max(np.minimum(a, b))
        res = inverse_kinematics(robot, pose, "alg1", u_last=c, window=0.1)
        if gap > 1e-9:
            assert res.status == "ok"
            assert np.all(res.u >= lo - 1e-12) and np.all(res.u <= hi + 1e-12)
        elif gap < -1e-9:
            assert res.status == "infeasible"
        seen.add(res.status)
    assert seen == {"ok", "infeasible"}


def test_two_dimensional_null_space():
    """8 wires on a 6-dof platform: LP tensions, two parametric / fixed wires."""
    spec = json.loads(Path("examples/robots/marionet.json").read_text())
    w = dict(spec["wires"][3], base=[100.0, 120.0, 180.0], platform=[0.0, 5.0, 10.0])
    rho = np.linalg.norm(np.array(w["base"]) - np.array([111, 58, 107]) - np.array(w["platform"]))
    w["L0"] = round((rho + 100) * (1 - 3 / 383), 3)
    spec["wires"].append(w)
    spec["name"] = "marionet-8"
    robot = Robot.load(spec)
    pose = Pose.from_params(6, [105, 62, 100, 3, -2, 1])
    t = inverse_kinematics(robot, pose, "tension")
    assert t.details["distribution"] == "lp" and t.status == "ok"
    a1 = inverse_kinematics(robot, pose, "alg1")
    assert a1.status == "ok" and len(a1.certificate.fixed) == 2
    a2 = inverse_kinematics(robot, pose, "alg2")
    assert a2.certificate.kind == "unique-in-box" and len(a2.details["fixed_wires"]) == 2
    assert a2.details["fixed_wires"][0] == 1
    for r in (t, a1, a2):
        assert forward_residual(robot, pose, r.u)[0] < 1e-9
    assert inverse_kinematics(robot, [111, 58, 107, 0, 20, 0], "alg1").status == "infeasible"


def test_limit_violations_lists_every_limit_once_in_wire_order():
    """One limit check for tensions, strokes and windows: each value beyond a limit by more
    than the tolerance is listed with its excess; values at the limit are not."""
    from certsolve.kinematics.ik_result import LIMIT_TOL, limit_violations, window_violations

    robot = load("marionet")
    tau = 0.5 * (robot.tau_min + robot.tau_max)
    u = 0.5 * (robot.u_min + robot.u_max)
    assert limit_violations(robot, tau, u) == []
    tau[2] = robot.tau_max[2] + 1.0
    tau[0] = robot.tau_min[0] - 2.0
    tau[4] = robot.tau_max[4] + 0.5 * LIMIT_TOL  # within the tolerance
    u[1] = robot.u_min[1] - 3.0
    u[5] = np.nan
    got = [(v.wire, v.quantity, v.bound, v.excess) for v in limit_violations(robot, tau, u)]
    assert got == [
        (1, "tau", "min", pytest.approx(2.0)),
        (2, "u", "min", pytest.approx(3.0)),
        (3, "tau", "max", pytest.approx(1.0)),
        (6, "u", "max", np.inf),
    ]
    u_last = np.zeros(robot.m)
    moved = np.zeros(robot.m)
    moved[3], moved[0] = 0.2, -0.3
    got = [(v.wire, v.bound) for v in window_violations(moved, u_last, 0.4)]
    assert got == [(1, "min")]  # wire 4 is 0.2 from u_last: on the window's edge


def test_algorithm2_reused_matches_the_one_off_call():
    """``Algorithm2(robot).solve(pose)`` is ``ik_algorithm2`` with the robot and options
    checked once: the same controls, tensions and certificate, pose after pose."""
    from certsolve.inputs import InputError
    from certsolve.kinematics.ik_alg2 import Algorithm2, ik_algorithm2

    robot, poses = near_centre_poses("marionet", 5, np.random.default_rng(11))
    alg2 = Algorithm2(robot, fixed_wire=3, tau_fixed=4.0)
    for pose in poses:
        a = alg2.solve(pose)
        b = ik_algorithm2(robot, pose, fixed_wire=3, tau_fixed=4.0)
        assert a.status == b.status and a.certificate.kind == b.certificate.kind == "unique-in-box"
        assert np.array_equal(a.u, b.u) and np.array_equal(a.tau, b.tau)
        assert np.array_equal(a.certificate.enclosure, b.certificate.enclosure)
    # pose parameters as the other entry points take them; a bad one names the field
    c = alg2.solve(list(CENTRE["marionet"]))
    assert np.array_equal(c.u, ik_algorithm2(robot, c.pose, fixed_wire=3, tau_fixed=4.0).u)
    with pytest.raises(InputError) as exc:
        alg2.solve([111, 58, float("nan"), 0, 0, 0])
    assert exc.value.field.startswith("pose")
    with pytest.raises(ValueError, match="box_radius"):
        Algorithm2(robot, box_radius=0.0)


def test_closed_form_on_a_robot_without_one_more_wire_is_refused_at_distribution():
    """``distribution="closed-form"`` needs ``m = w + 1`` wires: with 5 wires on a planar
    robot (w = 3) the refusal names the option, as the API's 422 and the CLI's error do."""
    from certsolve.inputs import InputError

    spec = json.loads((Path(__file__).parents[1] / "examples/robots/planar.json").read_text())
    spec["wires"].append(dict(spec["wires"][0], base=[5.0, 95.0]))
    robot = Robot.load(spec)
    with pytest.raises(InputError, match="one-dimensional null space") as err:
        inverse_kinematics(robot, [100, 60, 0], method="tension", distribution="closed-form")
    assert err.value.field == "distribution"
    assert inverse_kinematics(robot, [100, 60, 0], method="tension").feasible is not None


def _same_result(a, b):
    assert a.status == b.status and a.certificate.kind == b.certificate.kind
    assert np.array_equal(a.u, b.u) and np.array_equal(a.tau, b.tau)
    for x, y in (
        (a.certificate.box, b.certificate.box),
        (a.certificate.enclosure, b.certificate.enclosure),
    ):
        assert (x is None) == (y is None)
        if x is not None:
            assert np.array_equal(x[0], y[0]) and np.array_equal(x[1], y[1])


@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
@pytest.mark.parametrize("options", [{}, {"fixed_wire": 3, "tau_fixed": 4.0}, {"u_fixed": 0.1}])
def test_algorithm2_planned_wires_match_the_per_pose_split(name, options):
    """``Algorithm2`` works out the fixed and free wires (a slice for a run of wires), the
    fixed wire's eq. 5 constant and the free wires' constants once; a wire given as a list
    takes the per-pose path (pivoted QR completion, index arrays): the same floats."""
    from certsolve.kinematics.ik_alg2 import Algorithm2

    robot, poses = near_centre_poses(name, 4, np.random.default_rng(3))
    wire = options.get("fixed_wire", 1)
    planned = Algorithm2(robot, **options)
    per_pose = Algorithm2(robot, **{**options, "fixed_wire": [wire]})
    assert planned._plan.split is not None and per_pose._plan.split is None
    for pose in poses:
        a, b = planned.solve(pose), per_pose.solve(pose)
        _same_result(a, b)
        assert a.details["fixed_wires"] == [wire]
        assert a.certificate.kind == "unique-in-box"
        lo, hi = a.certificate.enclosure
        assert np.all(lo <= a.u) and np.all(a.u <= hi)


def test_algorithm2_checks_options_once_and_pose_at_solve():
    """Bad options raise in the constructor, naming the option; a ``Pose`` that is not
    finite is refused by ``solve`` with an error at the field ``pose`` (checked only when
    its geometry is undefined, as ``as_pose`` would have)."""
    from certsolve.inputs import InputError
    from certsolve.kinematics.ik_alg2 import Algorithm2

    robot = load("marionet")
    for options, field, words in (
        ({"fixed_wire": 9}, "fixed_wire", "wire 9"),
        ({"tau_fixed": 1e9}, "tau_fixed", "below the wire constant k"),
        ({"u_fixed": float("inf")}, "u_fixed", "fixed controls must be finite"),
    ):
        with pytest.raises(InputError, match=words) as err:
            Algorithm2(robot, **options)
        assert err.value.field == field
    alg2 = Algorithm2(robot)
    good = Pose.from_params(6, CENTRE["marionet"])
    inf_rotation = good.rotation.copy()
    inf_rotation[0, 0] = np.inf
    for bad in (Pose(good.position * np.nan, good.rotation), Pose(good.position, inf_rotation)):
        with pytest.raises(InputError) as exc:
            alg2.solve(bad)
        assert exc.value.field == "pose"
    # a pose of another shape or type goes through as_pose
    with pytest.raises(InputError):
        alg2.solve(Pose(good.position[:2], good.rotation))
    _same_result(alg2.solve(Pose(list(good.position), good.rotation.tolist())), alg2.solve(good))


def test_algorithm2_is_exported():
    import certsolve
    import certsolve.kinematics
    from certsolve.kinematics.ik_alg2 import Algorithm2

    assert certsolve.Algorithm2 is certsolve.kinematics.Algorithm2 is Algorithm2
