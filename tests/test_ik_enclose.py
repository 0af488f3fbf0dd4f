"""The rigorous enclosures behind the IK certificates, checked against mpmath at 60 digits.

For random poses and controls, the exact value of every quantity (computed by mpmath from
the exact binary inputs) must lie within the floating-point value ± its error bound; the
Krawczyk tests must agree with the solver's :func:`krawczyk`, prove boxes that contain
the exact solution and fail on boxes that exclude it.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from certsolve.kinematics.ik import inverse_kinematics
from certsolve.kinematics.ik_enclose import (
    SquareSystem,
    dtension_range,
    enclose_pose,
    jacobian_mr,
    krawczyk_mr,
    residual_mr,
    tension_mr,
)
from certsolve.robot import Pose, Robot
from certsolve.solver.newton import krawczyk, linearization_from_bounds

mp = mpmath.mp
ROBOTS = ["marionet", "marionet-t", "almost-planar", "planar", "krut-4"]


def load(name):
    return Robot.load(f"examples/robots/{name}.json")


def random_pose(robot, rng):
    dom = robot.domain
    p = rng.uniform(dom[:, 0] + 10, dom[:, 1] - 10)
    if robot.dof == 6:
        return Pose.from_params(6, list(p) + list(rng.uniform(-40, 40, 3)))
    if robot.dof == 3:
        return Pose.from_params(3, list(p) + [rng.uniform(-40, 40)])
    return Pose.from_params(2, list(p))


def M(x):
    return mpmath.mpf(float(x))


def exact_geometry(robot, pose):
    """ρ, H (w × m) and w_g in mpmath from the exact float inputs."""
    d = robot.dim
    R = [[M(pose.rotation[i, j]) for j in range(d)] for i in range(d)]
    p = [M(x) for x in pose.position]
    rho, cols = [], []
    for i in range(robot.m):
        c = [mp.fsum(R[a][b] * M(robot.B[i, b]) for b in range(d)) for a in range(d)]
        ab = [M(robot.A[i, a]) - p[a] - c[a] for a in range(d)]
        r = mp.sqrt(mp.fsum(x * x for x in ab))
        n = [x / r for x in ab]
        if robot.dof == 6:
            mom = [c[1] * n[2] - c[2] * n[1], c[2] * n[0] - c[0] * n[2], c[0] * n[1] - c[1] * n[0]]
        elif robot.dof == 3:
            mom = [c[0] * n[1] - c[1] * n[0]]
        else:
            mom = []
        rho.append(r)
        cols.append(n + mom)
    H = [[cols[i][k] for i in range(robot.m)] for k in range(len(cols[0]))]
    F = [M(robot.mass) * M(g) for g in robot.gravity]
    cg = [mp.fsum(R[a][b] * M(robot.com[b]) for b in range(d)) for a in range(d)]
    if robot.dof == 6:
        wm = [cg[1] * F[2] - cg[2] * F[1], cg[2] * F[0] - cg[0] * F[2], cg[0] * F[1] - cg[1] * F[0]]
    elif robot.dof == 3:
        wm = [cg[0] * F[1] - cg[1] * F[0]]
    else:
        wm = []
    return rho, H, F + wm


def exact_tension(robot, rho, i, u):
    L = rho[i] + M(robot.V[i]) + M(robot.K[i]) * M(u)
    return M(robot.k[i]) * (L - M(robot.L0[i])) / L


def within(x_float, err, exact) -> bool:
    return abs(M(x_float) - exact) <= M(err)


@pytest.mark.parametrize("name", ROBOTS)
def test_geometry_enclosure(name):
    mp.dps = 60
    robot = load(name)
    rng = np.random.default_rng(7)
    for _ in range(6):
        pose = random_pose(robot, rng)
        enc = enclose_pose(robot, pose.position, pose.rotation)
        assert enc.valid
        rho, H, wg = exact_geometry(robot, pose)
        for i in range(robot.m):
            assert within(enc.rho[i], enc.rho_err[i], rho[i])
            if robot.is_elastic:
                assert within(enc.W[i], enc.W_err[i], rho[i] + M(robot.V[i]))
            for k in range(len(H)):
                assert within(enc.H[k, i], enc.H_err[k, i], H[k][i]), (k, i)
        for k in range(len(wg)):
            assert within(enc.wg[k], enc.wg_err[k], wg[k])
        # the bounds are tight enough to be useful
        assert np.max(enc.H_err) < 1e-12


@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
def test_tension_residual_and_derivative_enclosures(name):
    mp.dps = 60
    robot = load(name)
    rng = np.random.default_rng(11)
    for _ in range(4):
        pose = random_pose(robot, rng)
        enc = enclose_pose(robot, pose.position, pose.rotation)
        rho, H, wg = exact_geometry(robot, pose)
        u = rng.uniform(-20, 20, (3, robot.m))
        tau, etau = tension_mr(robot, enc, u)
        f, ef = residual_mr(enc, tau, etau)
        sq = SquareSystem(robot, enc, np.arange(1, robot.m))
        tau2, f2, ef2 = sq.residual(u)
        lo = u - rng.uniform(0, 0.5, u.shape)
        dc, dr = dtension_range(robot, enc, lo, u)
        for b in range(u.shape[0]):
            tex = [exact_tension(robot, rho, i, u[b, i]) for i in range(robot.m)]
            for i in range(robot.m):
                assert within(tau[b, i], etau[b, i], tex[i])
                # dτ/du at the ends of [lo, u] lies in the derivative enclosure
                for x in (lo[b, i], u[b, i]):
                    L = rho[i] + M(robot.V[i]) + M(robot.K[i]) * M(x)
                    d = M(robot.k[i]) * M(robot.L0[i]) * M(robot.K[i]) / (L * L)
                    assert within(dc[b, i], dr[b, i], d)
            for k in range(len(H)):
                fex = mp.fsum(H[k][i] * tex[i] for i in range(robot.m)) + wg[k]
                assert within(f[b, k], ef[b, k], fex)
                assert within(f2[b, k], ef2[b, k], fex)


def exact_alg2_solution(robot, pose, u_fixed, fixed):
    """u_S solving H τ(u) + w_g = 0 with u_fixed on wire `fixed`, by mpmath at 60 digits."""
    rho, H, wg = exact_geometry(robot, pose)
    free = [i for i in range(robot.m) if i != fixed]
    tf = exact_tension(robot, rho, fixed, u_fixed)
    A = mpmath.matrix([[H[k][i] for i in free] for k in range(len(H))])
    b = mpmath.matrix([-(wg[k] + H[k][fixed] * tf) for k in range(len(H))])
    t = mpmath.lu_solve(A, b)
    out = []
    for j, i in enumerate(free):
        k, K, V, L0 = (M(x) for x in (robot.k[i], robot.K[i], robot.V[i], robot.L0[i]))
        out.append(k * L0 / (K * (k - t[j])) - (rho[i] + V) / K)
    return free, out


@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
def test_alg2_certificate_contains_exact_solution(name):
    mp.dps = 60
    robot = load(name)
    rng = np.random.default_rng(3)
    for _ in range(4):
        pose = random_pose(robot, rng)
        res = inverse_kinematics(robot, pose, "alg2")
        assert res.certificate.kind == "unique-in-box"
        (blo, bhi), (elo, ehi) = res.certificate.box, res.certificate.enclosure
        free, uex = exact_alg2_solution(robot, pose, res.u[0], 0)
        assert blo[0] == bhi[0] == res.u[0] == elo[0] == ehi[0]
        for j, i in enumerate(free):
            assert M(elo[i]) <= uex[j] <= M(ehi[i])
            assert blo[i] <= elo[i] <= ehi[i] <= bhi[i]
        # the unicity box is the 1 µm box of the options, the enclosure is tight
        assert np.all(bhi[1:] - blo[1:] > 1.9e-4)
        assert np.all(ehi - elo < 1e-8)


def _krawczyk_inputs(robot, enc, S, u, rad):
    """f and J enclosures for the generic tests (u: (1, m))."""
    xlo, xhi = np.nextafter(u[:, S] - rad, -np.inf), np.nextafter(u[:, S] + rad, np.inf)
    tau, etau = tension_mr(robot, enc, u)
    fc, fr = residual_mr(enc, tau, etau)
    flo, fhi = np.nextafter(fc - fr, -np.inf), np.nextafter(fc + fr, np.inf)
    full_lo, full_hi = u.copy(), u.copy()
    full_lo[:, S], full_hi[:, S] = xlo, xhi
    dc, dr = dtension_range(robot, enc, full_lo, full_hi)
    Jc, Jr = jacobian_mr(enc, S, dc[:, S], dr[:, S])
    return xlo, xhi, fc, fr, flo, fhi, Jc, Jr


@pytest.mark.parametrize("name", ["marionet", "marionet-t", "planar"])
def test_krawczyk_variants_agree_and_fail_off_solution(name):
    robot = load(name)
    rng = np.random.default_rng(5)
    S = np.arange(1, robot.m)
    for _ in range(4):
        pose = random_pose(robot, rng)
        res = inverse_kinematics(robot, pose, "alg2")
        enc = enclose_pose(robot, pose.position, pose.rotation)
        sq = SquareSystem(robot, enc, S)
        for shift, expect in ((0.0, True), (3.0, False), (-2.5, False)):
            rad = 1e-4
            u = res.u[None].copy()
            u[0, 3] += shift * rad  # shifted boxes exclude the (unique) solution
            xlo, xhi, fc, fr, flo, fhi, Jc, Jr = _krawczyk_inputs(robot, enc, S, u, rad)
            a = sq.krawczyk(u, np.full((1, S.size), rad))[4][0]
            b = krawczyk_mr(u[:, S], xlo, xhi, fc, fr, Jc, Jr)[2][0]
            lin = linearization_from_bounds(
                xlo,
                xhi,
                u[:, S],
                flo,
                fhi,
                np.nextafter(Jc - Jr, -np.inf),
                np.nextafter(Jc + Jr, np.inf),
            )
            c = krawczyk(lin)[2][0]
            assert a == b == c == expect, (shift, a, b, c)


def test_structured_krawczyk_image_no_wider_than_generic():
    """The structured operator bounds |I - YJ| through τ' directly: never looser."""
    robot = load("marionet")
    pose = Pose.from_params(6, [111, 58, 107, 5, -3, 2])
    res = inverse_kinematics(robot, pose, "alg2")
    enc = enclose_pose(robot, pose.position, pose.rotation)
    S = np.arange(1, 7)
    u = res.u[None]
    xlo, xhi, fc, fr, flo, fhi, Jc, Jr = _krawczyk_inputs(robot, enc, S, u, 1e-4)
    klo1, khi1, p1 = krawczyk_mr(u[:, S], xlo, xhi, fc, fr, Jc, Jr)
    out = SquareSystem(robot, enc, S).krawczyk(u, np.full((1, 6), 1e-4))
    klo2, khi2, p2 = out[2], out[3], out[4]
    assert p1[0] and p2[0]
    w1 = khi1 - klo1
    w2 = khi2 - klo2
    assert np.all(w2 <= 1.5 * w1)
