"""Force polytope and maximum isotropic force of the planar point robots (Krut et al. 2004).

Expected values come from closed forms (the 3-motor robot at the centre: a regular hexagon
of side 450 N, inradius 225·√3), from scipy's convex hull of the 2^m mapped box vertices,
from brute-force minimisation of the support function over directions, and from the
max-margin linear program of :mod:`certsolve.robot.statics` -- never from the code under
test.
"""

from math import sqrt
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from certsolve.force import (
    ForcePolytope,
    hyperplane_shifting,
    isotropic_force,
    krut_polytope,
    largest_centred_ellipsoid,
)
from certsolve.force.krut import box_vertices
from certsolve.robot import Pose, Robot, wrench_matrix
from certsolve.robot.statics import max_margin_tensions

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"


def load(name: str) -> Robot:
    return Robot.load(ROBOTS / f"{name}.json")


def random_positions(rng, n, radius=95.0):
    r = radius * np.sqrt(rng.random(n))
    t = 2 * np.pi * rng.random(n)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def same_facets(a: ForcePolytope, b: ForcePolytope, tol=1e-7) -> bool:
    if a.n_facets != b.n_facets:
        return False
    scale = max(1.0, float(np.abs(a.offsets).max()))
    ra = np.c_[a.normals, a.offsets / scale]
    rb = np.c_[b.normals, b.offsets / scale]
    return all(np.min(np.max(np.abs(rb - r), axis=1)) < tol for r in ra)


def hull_facets(H, tmin, tmax):
    """Facets of conv{H τ : τ a box vertex} with scipy (merged coplanar simplices)."""
    pts = box_vertices(tmin, tmax) @ H.T
    hull = ConvexHull(pts)
    eq = hull.equations
    rows = np.unique(np.round(np.c_[eq[:, :-1], -eq[:, -1] / 1e3], 9), axis=0)
    return ForcePolytope(rows[:, :-1], rows[:, -1] * 1e3, "qhull")


def brute_force_radius(H, tmin, tmax, centre, n_dir=20000):
    """min over unit u of (support of {H τ} in u) - u·centre, dense directions + refinement."""
    theta = np.linspace(0, 2 * np.pi, n_dir, endpoint=False)

    def value(th):
        u = np.stack([np.cos(th), np.sin(th)], axis=-1)
        s = u @ H  # (k, m)
        return np.sum(np.maximum(s * tmin, s * tmax), axis=-1) - u @ centre

    v = value(theta)
    k = int(np.argmin(v))
    fine = np.linspace(theta[k] - 2 * np.pi / n_dir, theta[k] + 2 * np.pi / n_dir, 20001)
    return float(np.min(value(fine)))


def test_krut3_centre_closed_form():
    robot = load("krut-3")
    expected = 225.0 * sqrt(3.0)  # regular hexagon of side 450 N
    for algorithm in ("shifting", "krut"):
        res = isotropic_force(robot, Pose.from_params(2, [0.0, 0.0]), algorithm=algorithm)
        assert res.status == "inside"
        assert abs(res.isotropic_force - expected) <= 1e-9 * expected
        # eq. (19): f_min = min 1/||v_k||
        v = res.polytope.paper_vectors()
        assert abs(1.0 / np.max(np.linalg.norm(v, axis=1)) - expected) <= 1e-9 * expected
        assert res.polytope.n_facets == 6


@pytest.mark.parametrize("name", ["krut-3", "krut-4", "krut-5", "krut-6"])
def test_two_algorithms_and_qhull_agree(name):
    robot = load(name)
    rng = np.random.default_rng(len(name) + robot.m)
    P = np.concatenate([np.zeros((1, 2)), random_positions(rng, 12, 120.0)])
    for p in P:
        H = wrench_matrix(robot, p, np.eye(2))[0]
        a = hyperplane_shifting(H, robot.tau_min, robot.tau_max)
        b = krut_polytope(H, robot.tau_min, robot.tau_max)
        c = hull_facets(H, robot.tau_min, robot.tau_max)
        assert same_facets(a, b), p
        assert same_facets(a, c), p


@pytest.mark.parametrize("name", ["krut-3", "krut-5"])
def test_paper_form_and_vertices(name):
    robot = load(name)
    rng = np.random.default_rng(7)
    for p in random_positions(rng, 8, 60.0):
        H = wrench_matrix(robot, p, np.eye(2))[0]
        poly = krut_polytope(H, robot.tau_min, robot.tau_max)
        pts = box_vertices(robot.tau_min, robot.tau_max) @ H.T
        v = poly.paper_vectors()
        inside = poly.offsets > 0
        # eq. (18): m^T v_k <= 1 for every point of the polytope (type-1 facets)
        assert np.all(pts @ v[inside].T <= 1.0 + 1e-9)
        # every facet supports at least two vertices (an edge)
        touch = np.abs(pts @ poly.normals.T - poly.offsets) <= 1e-7 * np.abs(poly.offsets).max()
        assert np.all(touch.sum(axis=0) >= 2)
        assert poly.meta["krut"]["origin_inside"] == bool(np.all(poly.offsets >= 0))


@pytest.mark.parametrize("name", ["krut-3", "krut-4", "krut-6"])
def test_isotropic_force_matches_brute_force(name):
    robot = load(name)
    rng = np.random.default_rng(11)
    for p in random_positions(rng, 6, 70.0):
        res = isotropic_force(robot, p)
        H = wrench_matrix(robot, p, np.eye(2))[0]
        ref = brute_force_radius(H, robot.tau_min, robot.tau_max, np.zeros(2))
        if res.isotropic_force >= 0:
            assert abs(res.isotropic_force - ref) <= 1e-6 * max(1.0, abs(ref))
        else:  # outside: the direction minimum is ≤ the facet value, and both are negative
            assert ref <= res.isotropic_force + 1e-6 * abs(ref) and ref < 0


@pytest.mark.parametrize("name", ["krut-3", "krut-5"])
def test_outside_flag_matches_tension_lp(name):
    robot = load(name)
    rng = np.random.default_rng(5)
    checked = 0
    for p in random_positions(rng, 60, 110.0):
        res = isotropic_force(robot, p)
        if abs(res.isotropic_force) < 1.0:
            continue  # too close to the workspace boundary for the LP's tolerance
        H = wrench_matrix(robot, p, np.eye(2))[0]
        lp = max_margin_tensions(H, np.zeros(2), robot.tau_min, robot.tau_max)
        assert (res.status == "inside") == lp.feasible, p
        checked += 1
    assert checked > 30


def test_pose_outside_is_negative_and_flagged():
    robot = load("krut-3")
    res = isotropic_force(robot, [95.0, 0.0])
    assert res.isotropic_force < 0 and res.status == "outside" and not res.inside
    assert res.to_dict()["polytope"]["origin_inside"] is False


def test_external_force_shifts_the_ball():
    """With a constant external force w the ball is centred at -w: for the symmetric
    hexagon at the centre, an external force of 100 N along +x leaves 225√3 - 100·(distance
    ratio) -- checked against the brute-force support function about -w."""
    robot = load("krut-3")
    w = np.array([100.0, 30.0])
    res = isotropic_force(robot, [0.0, 0.0], external=w)
    H = wrench_matrix(robot, np.zeros(2), np.eye(2))[0]
    ref = brute_force_radius(H, robot.tau_min, robot.tau_max, -w)
    assert abs(res.isotropic_force - ref) <= 1e-6 * ref
    assert res.isotropic_force < 225 * sqrt(3)


def test_largest_centred_ellipse_closed_forms():
    box = ForcePolytope(
        np.array([[1, 0], [-1, 0], [0, 1], [0, -1.0]]), np.array([3, 3, 1, 1.0]), "t"
    )
    e = largest_centred_ellipsoid(box, [0.0, 0.0])
    assert np.allclose(e.semi_axes, [3.0, 1.0], rtol=1e-6)
    # regular hexagon (symmetric): the ellipse is the inscribed circle
    res = isotropic_force(load("krut-3"), [0.0, 0.0], ellipse=True)
    assert np.allclose(res.ellipse.semi_axes, [225 * sqrt(3)] * 2, rtol=1e-6)


def test_to_dict_is_json_ready():
    import json

    res = isotropic_force(load("krut-4"), [10.0, 5.0], ellipse=True)
    d = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert d["isotropic_force"] == pytest.approx(res.isotropic_force)
    assert len(d["polytope"]["facets"]) == res.polytope.n_facets


def test_krut_refuses_huge_problems():
    robot = load("marionet")
    with pytest.raises(ValueError, match="linear systems"):
        isotropic_force(robot, [111.0, 58.0, 107.0], algorithm="krut")
