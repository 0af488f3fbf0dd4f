"""Rigid platforms (dof 3 and 6): the force section at the required moment, with gravity.

References independent of the code under test:

* linear programs (scipy's HiGHS) for the support function of the section
  ``h(u) = max u·H_f τ  s.t.  H_m τ = μ, τ_min ≤ τ ≤ τ_max``: the index is
  ``min_u h(u) - u·x0`` over unit ``u``, so ``h(u) - u·x0 ≥ f_min`` for every direction and
  equality holds at the limiting facet's normal;
* the wrench feasibility LP of :mod:`certsolve.robot.statics` for the sign.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from certsolve.force import certified_workspace, isotropic_force, isotropic_values
from certsolve.robot import Robot, gravity_wrench, wrench_matrix
from certsolve.robot.geometry import rotation_zyx
from certsolve.robot.statics import max_margin_tensions

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"


def load(name: str) -> Robot:
    return Robot.load(ROBOTS / f"{name}.json")


def support(H, nf, mu, tmin, tmax, u):
    """LP: max u·H_f τ with H_m τ = μ and the box."""
    res = linprog(
        -(u @ H[:nf]),
        A_eq=H[nf:],
        b_eq=mu,
        bounds=list(zip(tmin, tmax)),
        method="highs",
    )
    assert res.status == 0
    return -res.fun


def random_unit(rng, n, k):
    u = rng.normal(size=(k, n))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def sample_poses(robot, rng, n, shrink=0.25):
    lo, hi = robot.domain[:, 0], robot.domain[:, 1]
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * shrink
    return mid + (2 * rng.random((n, robot.dim)) - 1) * half


@pytest.mark.parametrize(
    "name, nf, centre_pose",
    [
        ("marionet", 3, [111.0, 58.0, 107.0]),
        ("marionet-t", 3, [115.0, 60.0, 118.0]),
        ("planar", 2, [90.0, 60.0]),
    ],
)
def test_index_against_lp_support_function(name, nf, centre_pose):
    robot = load(name)
    rng = np.random.default_rng(3)
    poses = [np.array(centre_pose)] + list(sample_poses(robot, rng, 3))
    checked = 0
    for p in poses:
        res = isotropic_force(robot, p)
        if res.status != "inside":
            continue
        checked += 1
        H = wrench_matrix(robot, p, np.eye(robot.dim))[0]
        w = gravity_wrench(robot, np.eye(robot.dim))[0]
        x0, mu = -w[:nf], -w[nf:]
        f = res.isotropic_force
        # equality at the limiting direction (minus the weakest disturbance direction)
        n = -res.weakest_direction
        assert support(H, nf, mu, robot.tau_min, robot.tau_max, n) - n @ x0 == pytest.approx(
            f, rel=1e-7, abs=1e-9
        )
        # upper bound in every sampled direction
        for u in random_unit(rng, nf, 40):
            assert support(H, nf, mu, robot.tau_min, robot.tau_max, u) - u @ x0 >= f - 1e-7
        # the hull of the enumerated slice vertices gives the same radius
        assert res.section_check == pytest.approx(f, rel=1e-7, abs=1e-9)
    assert checked >= 2


def test_gravity_bias_changes_the_index():
    """MARIONET at its middle with a heavier, off-centre platform: the ball is centred at
    -weight and the section taken at the weight's moment; without mass both are 0."""
    spec = load("marionet").spec.model_dump()
    heavy = dict(spec, platform={"mass": 0.5, "center_of_mass": [3.0, 0.0, 5.0]})
    light = dict(spec, platform={"mass": 0.0})
    p = [111.0, 58.0, 107.0]
    rh = isotropic_force(Robot.load(heavy), p)
    rl = isotropic_force(Robot.load(light), p)
    assert np.allclose(rl.centre, 0.0) and np.allclose(rl.required_moment, 0.0)
    assert rh.centre[2] == pytest.approx(0.5 * 9.81)
    # μ = -(CG × m g) with CG = (3, 0, 5) cm and m g = (0, 0, -4.905) N
    assert np.allclose(rh.required_moment, [0.0, -3.0 * 0.5 * 9.81, 0.0])
    assert rh.isotropic_force != pytest.approx(rl.isotropic_force)
    H = wrench_matrix(Robot.load(heavy), p, np.eye(3))[0]
    n = -rh.weakest_direction
    h = support(H, 3, rh.required_moment, np.zeros(7), np.full(7, 10.0), n)
    assert h - n @ rh.centre == pytest.approx(rh.isotropic_force, rel=1e-7)


def test_sign_matches_feasibility_lp():
    robot = load("marionet")
    rng = np.random.default_rng(9)
    P = sample_poses(robot, rng, 80, shrink=1.0)
    f, st = isotropic_values(robot, P)
    checked = 0
    for p, fi in zip(P, f):
        if not np.isfinite(fi) or abs(fi) < 0.02:
            continue
        H = wrench_matrix(robot, p, np.eye(3))[0]
        w = gravity_wrench(robot, np.eye(3))[0]
        lp = max_margin_tensions(H, w, robot.tau_min, robot.tau_max)
        assert (fi >= 0) == lp.feasible, p
        checked += 1
    assert checked > 40


def test_rotated_pose_matches_vectorised_values():
    robot = load("marionet")
    res = isotropic_force(robot, [111.0, 58.0, 107.0, 10.0, -5.0, 3.0])
    R = rotation_zyx(*np.radians([10.0, -5.0, 3.0]))
    f, _ = isotropic_values(robot, np.array([[111.0, 58.0, 107.0]]), R)
    assert f[0] == pytest.approx(res.isotropic_force, rel=1e-12)


def test_almost_planar_is_degenerate():
    robot = load("almost-planar")
    res = isotropic_force(robot, [90.0, 60.0, -2.0])
    assert res.status == "degenerate"
    assert res.isotropic_force in (0.0, None)
    f, st = isotropic_values(robot, np.array([[90.0, 60.0, -2.0], [50.0, 40.0, 3.0]]))
    assert np.all(np.isnan(f)) and np.all(st == 2)
    with pytest.raises(ValueError, match="4 wires"):
        certified_workspace(robot, 0.1, [0, 180, 0, 120, -10, 10], 5.0)


@pytest.mark.parametrize("name", ["marionet", "marionet-t"])
def test_basis_form_equals_cross_product_form(name):
    """The two vectorised evaluations (C(m,5) generalised cross products, or one 6x6 inverse
    per pose) agree on random poses, inside and outside the workspace."""
    from certsolve.force.isotropic import _index_batch, _index_batch_basis

    robot = load(name)
    rng = np.random.default_rng(12)
    P = sample_poses(robot, rng, 3000, shrink=1.0)
    R = rotation_zyx(*rng.uniform(-0.2, 0.2, (3, 3000)))
    H = np.moveaxis(wrench_matrix(robot, P, R), 0, -1)
    w = gravity_wrench(robot, R).T
    a = _index_batch(H, w, robot.tau_min, robot.tau_max, 3)
    b = _index_batch_basis(H, w, robot.tau_min, robot.tau_max, 3)
    assert np.all(a[1] == b[1])
    assert np.allclose(a[0], b[0], rtol=1e-9, atol=1e-11)
    assert (a[0] < 0).any() and (a[0] > 0).any()
