"""The position's Newton step over a box of orientations (:mod:`.fk_position`): its enclosures
hold the force balance and its Jacobian computed independently, it keeps every equilibrium,
it refutes boxes off the force balance, and a search with it finds the same poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.kinematics.fk_position import PositionNewton, norm_bounds, unit_vector_bounds
from certsolve.robot import Robot
from certsolve.robot.elastic import tension
from certsolve.solver import SearchStatus

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
REAL_POSE = [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]


def _forces_numpy(fk: FKSolver, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``Σ τ_i (A_i - B_i) / ρ_i + W`` at points ``x`` ``(N, n)`` of the frame's variables,
    from the robot's numbers and :func:`.tension` alone (``ρ_i = |B_i - A_i|``)."""
    robot, form = fk.robot, fk.form
    d, k = robot.dim, form.L.shape[1]
    P1 = x[:, :d]
    E = x[:, d : k * d].reshape(-1, k - 1, d)
    B = P1[:, None, :] + np.einsum("ij,njc->nic", form.L[:, 1:], E)
    arm = robot.A[None] - B
    rho = np.linalg.norm(arm, axis=2)
    tau = tension(robot, rho, u)
    return np.einsum("ni,nic->nc", tau / rho, arm) + robot.weight_bounds()[0]


def _jacobian_fd(fk: FKSolver, x: np.ndarray, u: np.ndarray, h: float = 1e-5) -> np.ndarray:
    d = fk.robot.dim
    J = np.empty((x.shape[0], d, d))
    for c in range(d):
        step = np.zeros(x.shape[1])
        step[c] = h
        J[:, :, c] = (_forces_numpy(fk, x + step, u) - _forces_numpy(fk, x - step, u)) / (2 * h)
    return J


@pytest.fixture(scope="module")
def t16():
    """T-16 at 60 N, u from IK at a real pose, and the full answer's equilibria."""
    base = Robot.load(ROBOTS / "marionet-t.json")
    robot = with_tau_max(base, 60.0)
    u = inverse_kinematics(base, REAL_POSE, method="alg2").u
    fk = FKSolver(robot, seed_minima=False)
    csys = fk.csys.with_parameters(fk.form.parameters_for(u))
    # the equilibria nearest the pose u was computed from: seeded search, a few boxes
    res = fk.solve(u, max_solutions=1, boxes=fk.seeded_boxes(u, fk.search_box(u))[0])
    assert res.solutions
    return fk, csys, u, np.array([np.mean(s.box, axis=1) for s in res.solutions])


def test_direction_and_length_bounds_hold_and_are_tight():
    rng = np.random.default_rng(3)
    c = rng.uniform(-50, 50, (200, 3))
    r = rng.uniform(0.01, 20, (200, 3))
    lo, hi = c - r, c + r
    nlo, nhi = unit_vector_bounds(lo, hi)
    signed = ~np.any((lo <= 0) & (hi >= 0), axis=1)  # no component changes sign
    pts = rng.uniform(lo[:, None], hi[:, None], (200, 500, 3))
    n = pts / np.linalg.norm(pts, axis=2, keepdims=True)
    ok = ~np.isnan(nlo).any(axis=1)
    assert ok.sum() > 150
    assert np.all(n[ok] >= nlo[ok, None]) and np.all(n[ok] <= nhi[ok, None])
    rlo, rhi = norm_bounds(lo, hi)
    norms = np.linalg.norm(pts, axis=2)
    assert np.all(norms >= rlo[:, None]) and np.all(norms <= rhi[:, None])
    # where no component changes sign, the bounds are reached at vertices (up to rounding)
    corners = np.stack(np.meshgrid(*[[0, 1]] * 3, indexing="ij"), -1).reshape(-1, 3)
    v = np.where(corners[None], hi[:, None], lo[:, None])
    nv = v / np.linalg.norm(v, axis=2, keepdims=True)
    assert signed.sum() > 50
    gap = np.maximum(nv.min(1) - nlo, nhi - nv.max(1))[signed]
    assert np.all(gap <= 1e-14)
    # a box holding the origin has no direction bounds
    nlo0, _ = unit_vector_bounds(np.full((1, 3), -1.0), np.full((1, 3), 1.0))
    assert np.isnan(nlo0).all()


def test_enclosures_hold_the_forces_and_their_jacobian(t16):
    fk, csys, u, sols = t16
    F = fk.forces
    rng = np.random.default_rng(0)
    x0 = sols[0]
    pose = np.arange(x0.size) < F.edges.max() + 1
    for half in (0.05, 1.0, 8.0):
        r = np.where(pose, rng.uniform(0.2, 1.0, x0.size) * half, 0.0)
        off = rng.uniform(-0.5, 0.5, x0.size) * r
        lo, hi = (x0 + off - r)[None], (x0 + off + r)[None]
        c, flo, fhi, jlo, jhi, ok = F.enclose(lo, hi, csys.param_lo, csys.param_hi)
        assert ok.all()
        pts = rng.uniform(lo, hi, (300, x0.size))
        J = _jacobian_fd(fk, pts, u)
        assert np.all(J >= jlo - 1e-6) and np.all(J <= jhi + 1e-6)
        at_c = pts.copy()
        at_c[:, F.position] = c
        g = _forces_numpy(fk, at_c, u)
        assert np.all(g >= flo - 1e-9) and np.all(g <= fhi + 1e-9)
    # at an equilibrium the force balance is 0, and its enclosure holds it
    _, flo, fhi, *_ = F.enclose(sols[:1], sols[:1], csys.param_lo, csys.param_hi)
    assert np.all(flo <= 0.0) and np.all(fhi >= 0.0)


def test_step_keeps_every_equilibrium_and_refutes_boxes_off_the_balance(t16):
    fk, csys, u, sols = t16
    step = PositionNewton(fk.forces, csys)
    pos = fk.forces.position
    rng = np.random.default_rng(1)
    n = sols.shape[1]
    pose = np.zeros(n, dtype=bool)
    pose[: fk.forces.edges.max() + 1] = True
    # boxes of many widths holding an equilibrium, which is anywhere in them: kept, and
    # the equilibrium (its pose and its wire lengths) stays in the narrowed box
    x = np.repeat(sols, 400, axis=0)
    r = np.where(pose, 10.0 ** rng.uniform(-3, 1, x.shape), 1e-6)
    lo = x - r * rng.uniform(0.0, 1.0, x.shape)
    hi = x + r * rng.uniform(0.0, 1.0, x.shape)
    nlo, nhi, empty = step.contract(lo, hi)
    assert not empty.any()
    assert np.all((nlo <= x) & (x <= nhi))
    assert np.any(nhi[:, pos] - nlo[:, pos] < 0.5 * (hi - lo)[:, pos])  # it does narrow
    # the orientation of the equilibrium, the position 5 cm off: no force balance there
    lo, hi = sols[:1].copy(), sols[:1].copy()
    lo[0, pos] += 4.5
    hi[0, pos] += 5.5
    assert step.contract(lo, hi)[2].all()


def test_needs_the_platform_frame():
    robot = Robot.load(ROBOTS / "marionet-t.json")
    with pytest.raises(ValueError, match="^formulation: "):
        FKSolver(robot, "pose", position_newton=True)


@pytest.mark.parametrize(
    ("name", "tau", "pose"),
    [
        ("planar", 60.0, [90.0, 60.0, 0.0]),
        ("marionet-t", 10.0, REAL_POSE),
        pytest.param("marionet-t", 10.0, None, marks=pytest.mark.slow),
        pytest.param("marionet", 10.0, None, marks=pytest.mark.slow),
    ],
)
def test_search_finds_the_same_poses(name, tau, pose):
    base = Robot.load(ROBOTS / f"{name}.json")
    robot = with_tau_max(base, tau)
    u = np.zeros(robot.m) if pose is None else inverse_kinematics(base, pose, method="alg2").u
    plain = FKSolver(robot).solve(u)
    newton = FKSolver(robot, position_newton=True).solve(u)
    assert plain.status == newton.status == SearchStatus.COMPLETE
    assert plain.solutions

    def key(res):
        return sorted(tuple(np.round(s.platform_points.ravel(), 5)) for s in res.solutions)

    assert key(newton) == key(plain)
    assert newton.stats.boxes <= plain.stats.boxes


def test_a_robot_with_tolerances_is_refused_by_name():
    """The step's interval path (the robot's numbers as intervals) is not tested: refused."""
    import json
    from pathlib import Path

    from certsolve.inputs import InputError
    from certsolve.kinematics import FKSolver
    from certsolve.robot import Robot

    spec = json.loads((Path(__file__).parents[1] / "examples/robots/marionet-t.json").read_text())
    spec["tolerances"] = [{"path": "wires[*].k", "relative": 0.01}]
    with pytest.raises(InputError) as err:
        FKSolver(Robot.load(spec), position_newton=True, prepare_search=False)
    assert err.value.field == "position_newton"


def test_off_by_default_and_named_in_the_fingerprint():
    """The step is part of the search's fingerprint (a checkpoint of a search with it is
    not resumed without it), with its ``max_turn``."""
    robot = Robot.load(ROBOTS / "marionet-t.json")
    u = np.zeros(robot.m)
    on = FKSolver(robot, position_newton=True, prepare_search=False)
    assert "PositionNewton(max_turn=10.0)" in on.search(u).solver.fingerprint()
    off = FKSolver(robot, prepare_search=False)
    assert not off.position_newton
    assert "PositionNewton" not in off.search(u).solver.fingerprint()


def test_boxes_turning_more_than_max_turn_are_left_alone(t16):
    fk, csys, u, sols = t16
    pos, edges = fk.forces.position, fk.forces.edges
    # the orientation of the equilibrium, the position 5 cm off: refuted (test above) unless
    # the edge vectors are wider than max_turn
    lo, hi = np.repeat(sols[:1], 2, axis=0), np.repeat(sols[:1], 2, axis=0)
    lo[:, pos] += 4.5
    hi[:, pos] += 5.5
    hi[1, edges[0, 0]] += 0.02
    step = PositionNewton(fk.forces, csys, max_turn=0.01)
    nlo, nhi, empty = step.contract(lo, hi)
    assert empty.tolist() == [True, False]
    assert np.array_equal(nlo[1], lo[1]) and np.array_equal(nhi[1], hi[1])
