"""Stability verdicts of FK poses against an independent finite-difference Hessian.

The reference is written here from the robot file alone, with numpy: the potential energy
``U = Σ k_i (L_i - L0_i ln L_i) - m g·G`` (``L_i = |B_i - A_i| + V_i + K_i u_i``) of the
platform moved by ``δp`` and turned by ``exp([δω]×)`` about its centre of mass, and its
Hessian by central differences.  ``u`` comes from IK Algorithm 2 at a pose, so that pose is
an equilibrium: the robot is there, and it must come out ``stable``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, forward_kinematics, with_tau_max
from certsolve.kinematics.fk_pose import PoseFormulation
from certsolve.kinematics.fk_systems import build_formulation
from certsolve.kinematics.stability import (
    EnergyHessian,
    Stability,
    classify,
    not_positive_definite,
)
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"


def _rotvec(w) -> np.ndarray:
    th = float(np.linalg.norm(w))
    K = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    if th == 0.0:
        return np.eye(3)
    return np.eye(3) + np.sin(th) / th * K + (1.0 - np.cos(th)) / th**2 * K @ K


def _energy(data, u, G, R) -> float:
    com = np.array(data["platform"].get("center_of_mass") or [0.0] * len(G))
    U = 0.0
    for i, w in enumerate(data["wires"]):
        B = G + R @ (np.array(w["platform"], dtype=float) - com)
        L = np.linalg.norm(B - np.array(w["base"], dtype=float)) + w["V"] + w["K"] * u[i]
        U += w["k"] * (L - w["L0"] * np.log(L))
    g = np.array(data.get("gravity") or [0.0] * len(G))
    return float(U - data["platform"]["mass"] * g @ G)


def fd_hessian(data, u, G, R, h: float = 2e-3) -> np.ndarray:
    """Central differences of ``U`` in (translation of G, rotation about G), at ``δ = 0``."""
    d = len(G)
    s = 3 if d == 2 else 6

    def f(q):
        if d == 2:
            c, sn = np.cos(q[2]), np.sin(q[2])
            Rq = np.array([[c, -sn], [sn, c]]) @ R
        else:
            Rq = _rotvec(q[3:]) @ R
        return _energy(data, u, G + q[:d], Rq)

    H = np.zeros((s, s))
    E = np.eye(s) * h
    for a in range(s):
        for b in range(s):
            H[a, b] = (f(E[a] + E[b]) - f(E[a] - E[b]) - f(E[b] - E[a]) + f(-E[a] - E[b])) / (
                4 * h * h
            )
    return 0.5 * (H + H.T)


def load(name):
    data = json.loads((ROBOTS / f"{name}.json").read_text())
    return data, Robot.load(data)


def check_poses(data, robot, res, u, pose_from):
    """Every verdict agrees with the FD Hessian; the pose u came from is found and stable."""
    assert res.solutions
    found = False
    for s in res.solutions:
        G = s.position + s.rotation @ robot.com
        fd = np.linalg.eigvalsh(fd_hessian(data, u, G, s.rotation))[0]
        v = s.stability
        tol = 1e-4 * abs(fd) + 1e-3
        assert v.eig_lo - tol <= fd <= v.eig_hi + tol
        assert v.eig_lo <= v.eig_hi
        if v.stability == Stability.STABLE:
            assert fd > 0.0
        elif v.stability == Stability.UNSTABLE:
            assert fd < 0.0
        d = robot.dim
        at = np.allclose(s.position, pose_from[:d], atol=1e-6)
        if at and np.allclose(s.euler_deg, pose_from[d:], atol=1e-6):
            found = True
            assert v.stability == Stability.STABLE
    assert found


@pytest.mark.parametrize(
    ("name", "pose", "tau"),
    [
        ("planar", [90.0, 60.0, 0.0], None),
        ("planar", [90.0, 60.0, 0.0], 60.0),  # a stable and an unstable pose
        ("marionet-t", [111.0, 58.0, 107.0, 0.0, 0.0, 0.0], None),
    ],
)
def test_verdicts_agree_with_finite_differences(name, pose, tau):
    data, robot = load(name)
    u = inverse_kinematics(robot, pose, method="alg2").u
    res = forward_kinematics(robot, u, tau_max=tau)
    check_poses(data, robot, res, u, pose)
    kinds = {s.stability.stability for s in res.solutions}
    assert Stability.UNDECIDED not in kinds
    if tau == 60.0:
        assert kinds == {Stability.STABLE, Stability.UNSTABLE}


@pytest.mark.slow
def test_general19_pose_of_the_robot_is_stable():
    data, robot = load("marionet")
    pose = [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]
    u = inverse_kinematics(robot, pose, method="alg2").u
    check_poses(data, robot, forward_kinematics(robot, u), u, pose)


def _pose_box(form, position, R, u, half: float):
    """A box of ``form``'s variables around the pose (points and lengths ± ``half``)."""
    robot = form.robot
    if isinstance(form, PoseFormulation):
        yaw = np.arctan2(R[1, 0], R[0, 0])
        pitch = -np.arcsin(R[2, 0])
        roll = np.arctan2(R[2, 1], R[2, 2])
        x = np.concatenate([position, [yaw, pitch, roll]])
        B = position + robot.B @ R.T
    else:
        P = position + form.Q @ R.T
        x = form.coordinates_of(P)
        B = form.L @ P
    x = np.concatenate([x, np.linalg.norm(B - robot.A, axis=1)])
    return x - half, x + half


@pytest.mark.parametrize("formulation", ["frame", "general-19", "pose"])
def test_hessian_encloses_finite_differences_away_from_equilibria(formulation):
    """At any pose (not an equilibrium) the enclosure holds the FD Hessian of the same chart,
    entry by entry, in every formulation."""
    data, robot = load("marionet")
    form = build_formulation(robot, formulation)
    eh = EnergyHessian(form)
    rng = np.random.default_rng(7)
    for _ in range(3):
        position = np.array([111.0, 58.0, 107.0]) + rng.uniform(-5, 5, 3)
        R = _rotvec(rng.uniform(-0.3, 0.3, 3))
        u = rng.uniform(-1.0, 1.0, robot.m)
        lo, hi = _pose_box(form, position, R, u, 1e-9)
        Hlo, Hhi = eh.enclose(lo[None], hi[None], u)
        G = position + R @ robot.com
        H = fd_hessian(data, u, G, R)
        tol = 1e-4 * np.max(np.abs(H)) + 1e-3
        assert np.all(Hlo[0] - tol <= H) and np.all(H <= Hhi[0] + tol)
        assert np.max(Hhi - Hlo) < 1e-6 * np.max(np.abs(H))


def test_classify_against_numpy_eigenvalues():
    """Thin random symmetric interval matrices: the verdict matches numpy's smallest
    eigenvalue, which the enclosure holds; wide ones stay undecided."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(200, 6, 6))
    A = A + A.transpose(0, 2, 1) + rng.uniform(-3, 6, size=(200, 1, 1)) * np.eye(6)
    lam = np.linalg.eigvalsh(A)[:, 0]
    r = 1e-9
    status, lo, hi = classify(A - r, A + r)
    assert np.all(lo <= lam + 1e-9) and np.all(lam - 1e-9 <= hi)
    margin = np.abs(lam) > 1e-6
    for s, v in zip(np.array(status)[margin], lam[margin], strict=True):
        assert s == (Stability.STABLE if v > 0 else Stability.UNSTABLE)
    # wide boxes: every member of [H] is one possible Hessian
    status, lo, hi = classify(A - 50.0, A + 50.0)
    assert set(status) == {Stability.UNDECIDED}
    assert np.all(lo <= lam) and np.all(lam <= hi)


def test_not_positive_definite_is_sound():
    """A box marked 'not PD' holds no positive definite symmetric matrix (sampled), and the
    clearly indefinite thin ones are marked."""
    rng = np.random.default_rng(5)
    A = rng.normal(size=(300, 6, 6))
    A = A + A.transpose(0, 2, 1) + rng.uniform(-2, 8, size=(300, 1, 1)) * np.eye(6)
    rad = rng.uniform(0.0, 0.5, size=(300, 6, 6))
    rad = 0.5 * (rad + rad.transpose(0, 2, 1))
    mark = not_positive_definite(A - rad, A + rad)
    for k in np.flatnonzero(mark):
        for _ in range(20):
            E = rng.uniform(-1, 1, size=(6, 6)) * rad[k]
            M = A[k] + 0.5 * (E + E.T)
            assert np.linalg.eigvalsh(M)[0] < 0.0
    lam = np.linalg.eigvalsh(A)[:, 0]
    thin = not_positive_definite(A - 1e-12, A + 1e-12)
    assert np.all(thin == (lam < 0.0))


def test_pose_to_dict_and_cli_show_the_verdict(tmp_path, capsys):
    from certsolve.cli import main

    robot = Robot.load(ROBOTS / "planar.json")
    u = inverse_kinematics(robot, [90.0, 60.0, 0.0], method="alg2").u
    res = FKSolver(with_tau_max(robot, 60.0)).solve(u)
    d = res.to_dict()["solutions"]
    assert sorted(s["stability"] for s in d) == ["stable", "unstable"]
    for s, p in zip(d, res.solutions, strict=True):
        assert s["eig_min"] == [p.stability.eig_lo, p.stability.eig_hi]
    args = ["fk", str(ROBOTS / "planar.json"), "--u", ",".join(map(str, u)), "--tau-max", "60"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert out.count("stability: stable") == 1 and out.count("stability: unstable") == 1
    assert main([*args, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert sorted(s["stability"] for s in got["solutions"]) == ["stable", "unstable"]


def test_tracking_step_carries_the_verdict():
    from certsolve.kinematics.tracking import Tracker

    robot = Robot.load(ROBOTS / "marionet-t.json")
    pose = [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]
    u = inverse_kinematics(robot, pose, method="alg2").u
    near = forward_kinematics(robot, u).solutions[0]
    step = Tracker(robot, stability=True).step(u, near)
    assert step.certified
    assert step.pose.stability.stability == Stability.STABLE
    assert step.to_dict()["pose"]["stability"] == "stable"
    assert Tracker(robot).step(u, near).pose.stability.stability == Stability.UNDECIDED
