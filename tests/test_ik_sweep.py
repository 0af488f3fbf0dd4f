"""IK continuation sweep (Merlet 2007, Fig. 3): the controls solve the IK equations at every
certified point (checked in mpmath from the robot file, not with the library's geometry),
statuses follow the tension limits, bad ``--sweep`` strings give one-line errors."""

from __future__ import annotations

import json

import mpmath as mp
import numpy as np
import pytest

from certsolve.cli import main
from certsolve.kinematics import inverse_kinematics, with_tau_max
from certsolve.kinematics.ik_sweep import PointStatus, ik_sweep
from certsolve.robot import Robot

PLANAR = "examples/robots/planar.json"
MARIONET = "examples/robots/marionet.json"


def mp_equilibrium(robot: Robot, pose_params, u):
    """Tensions (eq. 6) and the residual ``H τ + w_g`` at 40 digits, from the raw arrays."""
    mp.mp.dps = 40
    A = [[mp.mpf(float(x)) for x in row] for row in robot.A]
    B = [[mp.mpf(float(x)) for x in row] for row in robot.B]
    if robot.dof == 3:
        x, y, th = (mp.mpf(v) for v in pose_params)
        c, s = mp.cos(mp.radians(th)), mp.sin(mp.radians(th))
        R = [[c, -s], [s, c]]
        p = [x, y]
    else:
        x, y, z, yaw, pitch, roll = (mp.mpf(v) for v in pose_params)
        cz, sz = mp.cos(mp.radians(yaw)), mp.sin(mp.radians(yaw))
        cy, sy = mp.cos(mp.radians(pitch)), mp.sin(mp.radians(pitch))
        cx, sx = mp.cos(mp.radians(roll)), mp.sin(mp.radians(roll))
        R = [
            [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
            [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
            [-sy, cy * sx, cy * cx],
        ]
        p = [x, y, z]
    d = len(p)
    force = [mp.mpf(0)] * d
    moment = [mp.mpf(0)] * (1 if d == 2 else 3)
    taus = []
    for i in range(robot.m):
        b = [sum(R[r][c] * B[i][c] for c in range(d)) for r in range(d)]
        ab = [A[i][r] - p[r] - b[r] for r in range(d)]
        rho = mp.sqrt(sum(t * t for t in ab))
        n = [t / rho for t in ab]
        L = rho + mp.mpf(float(robot.V[i])) + mp.mpf(float(robot.K[i])) * mp.mpf(float(u[i]))
        tau = mp.mpf(float(robot.k[i])) * (L - mp.mpf(float(robot.L0[i]))) / L
        taus.append(tau)
        force = [force[r] + tau * n[r] for r in range(d)]
        if d == 2:
            moment[0] += tau * (b[0] * n[1] - b[1] * n[0])
        else:
            cr = [b[1] * n[2] - b[2] * n[1], b[2] * n[0] - b[0] * n[2], b[0] * n[1] - b[1] * n[0]]
            moment = [moment[r] + tau * cr[r] for r in range(3)]
    if robot.dof == 6:  # weight and its moment about the platform origin
        F = [mp.mpf(float(robot.mass)) * mp.mpf(float(g)) for g in robot.gravity]
        cg = [sum(R[r][c] * mp.mpf(float(robot.com[c])) for c in range(3)) for r in range(3)]
        force = [force[r] + F[r] for r in range(3)]
        cr = [cg[1] * F[2] - cg[2] * F[1], cg[2] * F[0] - cg[0] * F[2], cg[0] * F[1] - cg[1] * F[0]]
        moment = [moment[r] + cr[r] for r in range(3)]
    residual = max(abs(t) for t in force + moment)
    return [float(t) for t in taus], float(residual)


@pytest.mark.parametrize(
    "path, pose, tau_max, sweep",
    [
        (PLANAR, [85.0, 65.0, 3.0], 60.0, (1, 0.1, 10.0, 40)),  # the Fig. 3 example
        (PLANAR, [80.0, 55.0, 0.0], 10.0, (2, -10.0, 5.0, 25)),
        (MARIONET, [111.0, 58.0, 107.0, 5.0, -3.0, 2.0], 10.0, (4, -1.0, 1.5, 12)),
    ],
)
def test_certified_points_solve_the_ik_equations(path, pose, tau_max, sweep):
    robot = with_tau_max(Robot.load(path), tau_max)
    joint, start, stop, count = sweep
    res = ik_sweep(robot, pose, joint=joint, start=start, stop=stop, count=count)
    assert res.status == "complete" and len(res.points) == count
    certified = [p for p in res.points if p.status is PointStatus.CERTIFIED]
    assert certified, res.counts
    values = np.linspace(start, stop, count)
    for p, v in zip(res.points, values, strict=True):
        assert p.value == v and (p.u is None or p.u[joint - 1] == v)
    for p in certified:
        taus, residual = mp_equilibrium(robot, pose, p.u)
        assert residual <= 1e-9 * (1.0 + max(abs(t) for t in taus))
        assert np.allclose(taus, p.tau, rtol=0, atol=1e-9)
        assert all(0.0 <= t <= tau_max for t in taus)
        lo, hi = p.enclosure
        assert np.all(lo <= p.u) and np.all(p.u <= hi) and np.all(hi - lo < 1e-8)
        tlo, thi = p.tension_bounds
        assert np.all(tlo <= taus) and np.all(np.array(taus) <= thi)
        assert p.reason == ""


def test_continuation_matches_the_exact_tension_solve():
    """Algorithm 2's linear solve in τ coordinates is an independent route to the same u."""
    robot = with_tau_max(Robot.load(PLANAR), 60.0)
    pose = [85.0, 65.0, 3.0]
    res = ik_sweep(robot, pose, start=0.1, stop=10.0, count=15)
    for p in res.points:
        ref = inverse_kinematics(robot, pose, "alg2", u_fixed=p.value, certify=False)
        assert np.allclose(p.u, ref.u, rtol=0, atol=1e-9)
    # the predictor does its job: later points need no more Newton steps than the first
    its = [p.iterations for p in res.points]
    assert max(its[2:]) <= its[0]
    assert res.points[0].predicted is None and res.points[3].predicted is not None


def test_statuses_across_the_tension_limits():
    """τ_min = 0 is crossed near u_1 = 4.2 cm and τ_max = 10 N near 6.9 cm at this pose."""
    robot = Robot.load(PLANAR)
    pose = [80.0, 55.0, 0.0]
    res = ik_sweep(robot, pose, start=0.1, stop=10.0, count=60)
    seen = set()
    for p in res.points:
        taus, _ = mp_equilibrium(robot, pose, p.u)
        excess = max(max(-t for t in taus), max(t - 10.0 for t in taus))
        if abs(excess) < 1e-6:
            continue
        expected = PointStatus.INFEASIBLE if excess > 0 else PointStatus.CERTIFIED
        assert p.status is expected, (p.value, taus, p.reason)
        if expected is PointStatus.INFEASIBLE:
            assert "tension" in p.reason and p.violations
            worst = max(p.violations, key=lambda v: v.excess)
            assert worst.excess == pytest.approx(excess, abs=1e-7)
        seen.add(expected)
    assert seen == {PointStatus.INFEASIBLE, PointStatus.CERTIFIED}
    statuses = [p.status for p in res.points]
    first = statuses.index(PointStatus.CERTIFIED)
    last = len(statuses) - 1 - statuses[::-1].index(PointStatus.CERTIFIED)
    assert all(s is PointStatus.CERTIFIED for s in statuses[first : last + 1])
    assert 0 < first and last < len(statuses) - 1


def test_progress_can_stop_and_arguments_are_checked():
    calls = []

    def progress(info):
        calls.append(info.points)
        return info.points < 3

    res = ik_sweep(PLANAR, [90, 60, 0], start=0, stop=1, count=10, progress=progress)
    assert res.status == "cancelled" and len(res.points) == 3 and calls == [1, 2, 3]
    with pytest.raises(ValueError, match="count"):
        ik_sweep(PLANAR, [90, 60, 0], start=0, stop=1, count=1)
    with pytest.raises(ValueError, match="joint 5"):
        ik_sweep(PLANAR, [90, 60, 0], joint=5, start=0, stop=1, count=3)
    with pytest.raises(ValueError, match="m = w \\+ 1"):
        ik_sweep("examples/robots/almost-planar.json", [90, 60, -1], start=0, stop=1, count=3)


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_json_and_plot(capsys, tmp_path):
    png = tmp_path / "sweep.png"
    code, out, err = run(
        capsys, "ik", PLANAR, "--pose", "80,55,0", "--sweep", "1=0.1:10:20", "--plot", str(png),
        "--json",
    )  # fmt: skip
    assert code == 0 and err == ""
    d = json.loads(out)
    assert d["joint"] == 1 and len(d["points"]) == 20 and d["plot"] == str(png)
    assert sum(d["counts"].values()) == 20 and d["counts"]["infeasible"] > 0
    assert {p["status"] for p in d["points"]} <= {"certified", "uncertified", "infeasible"}
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, _ = run(capsys, "ik", PLANAR, "--pose", "85,65,3", "--sweep", "3=-1.5:0:4")
    assert code == 0 and "4 certified" in out and "IK sweep of u_3" in out


@pytest.mark.parametrize(
    "sweep, message",
    [
        ("1:0.1:10:8", "expected J=START:STOP:N"),
        ("x=0:1:3", "the wire J must be an integer"),
        ("9=0:1:3", "--sweep J: the robot has wires 1..4"),
        ("1=0:1", "expected J=START:STOP:N"),
        ("1=a:1:3", "expected J=START:STOP:N"),
        ("1=0:1:2.5", "N must be an integer"),
        ("1=0:1:1", "--sweep N: must be greater than or equal to 2"),
        ("1=0:nan:3", "finite"),
    ],
)
def test_cli_bad_sweep(capsys, sweep, message):
    code, out, err = run(capsys, "ik", PLANAR, "--pose", "90,60,0", "--sweep", sweep)
    assert code == 2 and out == ""
    assert err.startswith("error: --sweep") and message in err and err.count("\n") == 1


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--method", "alg2"], "drop --method"),
        (["--tau-fixed", "3"], "--tau-fixed does not apply"),
        (["--timeout", "0"], "--timeout: must be greater than 0"),
    ],
)
def test_cli_sweep_conflicts(capsys, extra, message):
    code, _, err = run(capsys, "ik", PLANAR, "--pose", "90,60,0", "--sweep", "1=0:1:3", *extra)
    assert code == 2 and message in err and "Traceback" not in err
    code, _, err = run(capsys, "ik", PLANAR, "--pose", "90,60,0", "--plot", "x.png")
    assert code == 2 and "--plot goes with --sweep" in err
