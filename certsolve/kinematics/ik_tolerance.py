"""Inverse kinematics of a robot known within tolerances: control intervals for every robot.

A robot file with ``tolerances`` (:mod:`certsolve.robot.tolerance`) describes a *set* of
robots.  At a pose ``P`` (the position and the float rotation matrix, as every IK
certificate reads it), each robot ``r`` of the set has its own statics (Merlet 2007,
eqs. 3-4)::

    H(P; A, B) τ = -w_g(mass, com),

``w`` equations in ``m >= w`` tensions, and its own controls from eq. 5.  No single control
vector holds the pose for every robot (each robot with the same ``u`` has its own
equilibrium: forward kinematics gives the set's pose box); the answer is a **control
interval per wire** holding every robot's control, for one tension *distribution* that
every robot follows:

``method="tension"``
    ``m - w`` wires (the last ones of a pivoted QR of the nominal ``H``: the others are the
    best-conditioned basis) are held at fixed tensions ``τ_F``, the same for every robot:
    first the nominal robot's max-margin tensions (:mod:`.ik_tension`, the ``tension``
    method's answer, so a set of one robot gives the nominal answer); when that does not
    prove every limit, with one fixed wire, the value of ``τ_F`` with the largest proven
    margin: a batch of 32 values across its tension range, then two finer batches around
    the best.
``method="alg2"``
    Algorithm 2's fixed wire(s) at one fixed *control* ``u_F`` (``u_fixed``, or eq. 5 on
    the nominal robot from ``tau_fixed``, default the middle of the range, as
    :func:`.ik_algorithm2`): the same control for every robot, whose tension ``τ_F``
    (eq. 6) is then an interval over the set.

The free wires' tensions solve the linear system ``f(τ_S, p) = H_S(p) τ_S + H_F(p) τ_F +
w_g = 0``, whose matrix and right-hand side are intervals over the set (:func:`set_statics`:
the geometry in interval arithmetic over the anchors, attachments, mass and centre of
mass).  The Krawczyk operator of this linear map, ``K(X) = c - Y f(c, p) + (I - Y H_S)(X -
c)`` with ``Y ≈ mid(H_S)^-1`` (the package's kernel, :func:`.krawczyk_image`), encloses the
solution of every robot: ``α = ||I - Y H_S|| < 1`` proves every matrix of the set
nonsingular (one solution per robot) and that solution within ``c ± ||Y f(c, p)|| / (1 -
α)``, which three Krawczyk steps then tighten.  ``Y f(c, p)`` is taken in the mean-value
form of the FK's set test (:class:`SetSystem`): ``Y f(c, p0) + Σ_i (Y G_i) t_i (p_i -
p0_i)`` with ``G_i`` the slopes of wire ``i``'s wrench column in its anchor and
attachment.  Enclosing ``f(c, P)`` entry by entry instead loses that a column's six
entries move together with its anchor: on T-16 (±0.05 cm, ±1 % ``k``) the tension bounds
were 3.6-9 times the spread of 40 sampled robots, they are 1.1-2.3 times now (the
controls 1.1-2.0 times, ``k`` entering them directly).

The controls follow from eq. 2 and eq. 1 solved for the length, each number once::

    L_i = L0_i / (1 - τ_i / k_i),     u_i = (L_i - ρ_i - V_i) / K_i,

in interval arithmetic over ``τ``, ``k``, ``L0``, ``V``, ``K`` and ``ρ`` (the control is
undefined where ``τ_i`` may reach ``k_i``).  **What is proven**: for every robot of the
set, the distribution has exactly one tension vector, inside the reported tension
bounds, and the control of each wire that gives it lies in its interval; ``ok`` means
every tension bound lies within ``[τ_min, τ_max]`` and every control interval within the
stroke.  A bound that fails is reported per wire (:class:`.Violation`) with the worst
case of the enclosure -- an upper bound of the set's worst case: the violation is certain
(for the nominal robot) only where ``details["set"]["nominal_tau"]`` violates it too.  The
result's ``u`` is the middle of the intervals: one control vector to send, which proves
nothing about the pose of a robot of the set.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..inputs import InputError
from ..interval import arith
from ..interval.core import Pair, midpoint
from ..interval.linalg import (
    gamma,
    krawczyk_image,
    krawczyk_magnitude,
    mr_from_bounds,
    mr_matmul,
    mr_to_bounds,
    point_matmul_interval,
)
from ..interval.rounding import down, up
from ..robot.geometry import Pose
from ..robot.model import Robot
from .ik_alg2 import Alg2Options, _fix_controls, _fixed_wires
from .ik_enclose import enclose_pose, is_elastic
from .ik_inputs import check_pose, require_elastic, search_window
from .ik_result import (
    LIMIT_TOL,
    Certificate,
    IKResult,
    IKStatus,
    Violation,
    limit_violations,
    window_violations,
)
from .ik_tension import distribute_tensions

__all__ = [
    "SetStatics",
    "SetSystem",
    "check_tolerant_ik",
    "set_statics",
    "solve_linear_set",
    "tolerant_inverse_kinematics",
]

#: values of a single fixed tension tried, across its range, when the nominal one fails
GRID = 32
#: rounds of that grid, each around the best value of the last
ROUNDS = 3
#: Krawczyk steps that tighten the linear enclosure
_STEPS = 3


@dataclass(kw_only=True, frozen=True)
class SetStatics:
    """The statics of every robot of the set at one pose, as intervals (rounded outward):
    ``rho`` ``(m,)`` wire lengths, ``H`` ``(w, m)`` the wrench matrix (column ``i``:
    ``(n_i, CB_i × n_i)``, eq. 4), ``wg`` ``(w,)`` the weight's wrench about the platform
    origin."""

    rho: Pair
    H: Pair
    wg: Pair
    n: Pair  # (m, d) unit vectors B -> A
    CB: Pair  # (m, d) attachments about the platform origin, world axes


def _cross(a: Pair, b: Pair, i: int, j: int) -> Pair:
    """``a_i b_j - a_j b_i`` over the last axis of interval arrays."""
    p = arith.mul(a[0][..., i], a[1][..., i], b[0][..., j], b[1][..., j])
    q = arith.mul(a[0][..., j], a[1][..., j], b[0][..., i], b[1][..., i])
    return arith.sub(p[0], p[1], q[0], q[1])


def _moments(CB: Pair, n: Pair, dof: int) -> list[Pair]:
    """The rows of ``CB × n`` (one row in the plane, none for a point robot)."""
    if dof == 2:
        return []
    if dof == 3:
        return [_cross(CB, n, 0, 1)]
    return [_cross(CB, n, 1, 2), _cross(CB, n, 2, 0), _cross(CB, n, 0, 1)]


def set_statics(robot: Robot, pose: Pose) -> SetStatics:
    """:class:`SetStatics` at ``pose`` over every robot of ``robot``'s set: ``CB = R B``,
    ``AB = A - p - CB``, ``ρ = |AB|``, ``n = AB / ρ``, the moments ``CB × n``, and
    ``w_g = (F, (R com) × F)`` with ``F = mass g``, each in interval arithmetic over the
    numbers' intervals (:meth:`.Robot.bounds`).  Raises :class:`~certsolve.inputs.InputError`
    (``pose``) where a wire length of the set may be 0."""
    b = robot.bounds()
    return _statics(robot, pose, _pair(b.A), _pair(b.B))


def _pair(t) -> Pair:
    return np.asarray(t[0], dtype=float), np.asarray(t[1], dtype=float)


def _statics(robot: Robot, pose: Pose, A: Pair, B: Pair) -> SetStatics:
    """:func:`set_statics` with the anchors ``A`` and attachments ``B`` given (the mass and
    the centre of mass: the set's)."""
    R = np.asarray(pose.rotation, dtype=float)
    p = np.asarray(pose.position, dtype=float)
    cb_lo, cb_hi = point_matmul_interval(R, B[0].T, B[1].T)
    CB = (cb_lo.T, cb_hi.T)  # (m, d)
    a = arith.sub(A[0], A[1], p, p)
    AB = arith.sub(a[0], a[1], CB[0], CB[1])
    sq = arith.sqr(*AB)
    rho2 = (sq[0][:, 0], sq[1][:, 0])
    for c in range(1, robot.dim):
        rho2 = arith.add(rho2[0], rho2[1], sq[0][:, c], sq[1][:, c])
    rho = arith.sqrt(*rho2)
    if not np.all(rho[0] > 0.0):
        bad = int(np.argmax(~(rho[0] > 0.0))) + 1
        raise InputError("pose", f"wire {bad}: a robot of the set may have its length 0 here")
    n = arith.div_nonzero(AB[0], AB[1], rho[0][:, None], rho[1][:, None])
    rows = [(n[0][:, c], n[1][:, c]) for c in range(robot.dim)] + _moments(CB, n, robot.dof)
    H = (np.array([r[0] for r in rows]), np.array([r[1] for r in rows]))
    F = robot.weight_bounds()
    force = [(np.atleast_1d(F[0][c]), np.atleast_1d(F[1][c])) for c in range(robot.dim)]
    wg = force
    if robot.dof != 2:
        clo, chi = _pair(robot.bounds().com)
        cg = point_matmul_interval(R, clo, chi)
        Fv = (np.asarray(F[0], dtype=float)[None], np.asarray(F[1], dtype=float)[None])
        wg = force + _moments((cg[0][None], cg[1][None]), Fv, robot.dof)
    wgl = np.array([np.ravel(x[0])[0] for x in wg])
    wgh = np.array([np.ravel(x[1])[0] for x in wg])
    return SetStatics(rho=rho, H=H, wg=(wgl, wgh), n=n, CB=CB)


def _imatmul(a: Pair, b: Pair) -> Pair:
    """Interval matrix product ``(..., p, k) @ (..., k, q)``, rounded outward."""
    lo, hi = arith.mul(
        a[0][..., :, :, None], a[1][..., :, :, None], b[0][..., None, :, :], b[1][..., None, :, :]
    )
    out = (lo[..., 0, :], hi[..., 0, :])
    for j in range(1, lo.shape[-2]):
        out = arith.add(out[0], out[1], lo[..., j, :], hi[..., j, :])
    return out


def _skew(v: Pair) -> Pair:
    """``[v]×`` ``(m, 3, 3)``: ``[v]× x = v × x``."""
    z = np.zeros_like(v[0][:, 0])
    out = []
    for t, s in ((v[0], v[1]), (v[1], v[0])):  # lo from lo and -hi, hi from hi and -lo
        out.append(
            np.stack(
                [
                    np.stack([z, -s[:, 2], t[:, 1]], axis=-1),
                    np.stack([t[:, 2], z, -s[:, 0]], axis=-1),
                    np.stack([-s[:, 1], t[:, 0], z], axis=-1),
                ],
                axis=-2,
            )
        )
    return out[0], out[1]


def _slopes(robot: Robot, pose: Pose, st: SetStatics) -> Pair:
    """``G`` ``(m, w, 2d)``: the derivatives of each wire's wrench column ``H_i`` in its
    anchor ``A_i`` and attachment ``B_i``, enclosed over the set: with ``D = (I - n nᵀ)/ρ``,
    ``∂n/∂A = D``, ``∂n/∂B = -D R``, ``∂(CB × n)/∂A = [CB]× D`` and ``∂(CB × n)/∂B =
    -[n]× R - [CB]× D R`` (in the plane the cross product's row, ``(-CB_y, CB_x)`` and
    ``(n_y, -n_x)``)."""
    m, d = st.n[0].shape
    R = np.asarray(pose.rotation, dtype=float)
    Rp = (np.broadcast_to(R, (m, d, d)), np.broadcast_to(R, (m, d, d)))
    n = (st.n[0][:, :, None], st.n[1][:, :, None])
    nT = (st.n[0][:, None, :], st.n[1][:, None, :])
    nn = arith.mul(n[0], n[1], nT[0], nT[1])
    eye = np.broadcast_to(np.eye(d), (m, d, d))
    D = arith.sub(eye, eye, nn[0], nn[1])
    r = (st.rho[0][:, None, None], st.rho[1][:, None, None])
    D = arith.div_nonzero(D[0], D[1], r[0], r[1])
    DR = _imatmul(D, Rp)
    dA, dB = [D], [arith.neg(*DR)]
    if robot.dof == 6:
        cx, nx = _skew(st.CB), _skew(st.n)
        a = _imatmul(cx, D)
        b1, b2 = _imatmul(nx, Rp), _imatmul(cx, DR)
        dA.append(a)
        dB.append(arith.neg(*arith.add(b1[0], b1[1], b2[0], b2[1])))
    elif robot.dof == 3:
        cb, nv = st.CB, st.n
        c_row = (
            np.stack([-cb[1][:, 1], cb[0][:, 0]], -1)[:, None],
            np.stack([-cb[0][:, 1], cb[1][:, 0]], -1)[:, None],
        )
        n_row = (
            np.stack([nv[0][:, 1], -nv[1][:, 0]], -1)[:, None],
            np.stack([nv[1][:, 1], -nv[0][:, 0]], -1)[:, None],
        )
        a = _imatmul(c_row, D)
        b1, b2 = _imatmul(n_row, Rp), _imatmul(c_row, DR)
        dA.append(a)
        dB.append(arith.sub(b1[0], b1[1], b2[0], b2[1]))
    GA = (np.concatenate([x[0] for x in dA], axis=1), np.concatenate([x[1] for x in dA], axis=1))
    GB = (np.concatenate([x[0] for x in dB], axis=1), np.concatenate([x[1] for x in dB], axis=1))
    return np.concatenate([GA[0], GB[0]], axis=2), np.concatenate([GA[1], GB[1]], axis=2)


class SetSystem:
    """The free wires' statics of every robot of the set, for a batch of fixed tensions:
    ``f(x, p) = H_S(p) x + H_F(p) τ_F + w_g``, linear in ``x = τ_S``, with its
    preconditioned residual in the mean-value form of :class:`.fk_tolerance.SetKrawczyk`
    in the anchors and attachments ``p`` (the mass, the centre of mass and ``τ_F`` as
    intervals)::

        Y f(x, p) ∈ Y f(x, p0) + Σ_i (Y G_i) t_i (p_i - p0_i),

    ``p0`` the middle of the set, ``G_i`` :func:`_slopes` over the set, ``t_i`` the tension
    of wire ``i`` (``x_i`` or ``τ_F``): the six entries of a wire's column move together
    with its anchor, which an interval ``H(P)`` alone reads as independent."""

    def __init__(self, robot: Robot, pose: Pose, st: SetStatics, F: np.ndarray, tauF: Pair):
        m = st.H[0].shape[1]
        self.F, self.S = F, np.setdiff1d(np.arange(m), F)
        self.tauF = tauF
        self.H = (st.H[0][:, self.S], st.H[1][:, self.S])
        self.Hc, self.Hr = mr_from_bounds(*self.H)
        b = robot.bounds()
        mids, rads = [], []
        for t in (_pair(b.A), _pair(b.B)):
            mid = np.clip(midpoint(*t), t[0], t[1])
            mids.append((mid, mid))
            rads.append(np.maximum(up(t[1] - mid), up(mid - t[0])))
        self.at_mid = _statics(robot, pose, mids[0], mids[1])
        self.radius = np.concatenate(rads, axis=1)  # (m, 2d): |p_i - p0_i|
        self.G = mr_from_bounds(*_slopes(robot, pose, st))  # (m, w, 2d)
        self.wg = st.wg

    def preconditioned(self, Y: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``Y f(x, p)`` over the set, midpoint-radius ``(C, w)``, for ``x`` ``(C, w)``."""
        H0 = self.at_mid.H
        S, F = self.S, self.F
        hc, hr = mr_from_bounds(H0[0][:, S], H0[1][:, S])
        t = mr_matmul(hc, hr, x[..., None], None)
        f = mr_to_bounds(t[0][..., 0], t[1][..., 0])
        f = arith.add(f[0], f[1], self.wg[0], self.wg[1])
        for k, j in enumerate(F):
            h = arith.mul(
                H0[0][:, j], H0[1][:, j], self.tauF[0][:, k : k + 1], self.tauF[1][:, k : k + 1]
            )
            f = arith.add(f[0], f[1], h[0], h[1])
        fc, fr = mr_from_bounds(*f)
        bc, br = mr_matmul(Y, None, fc[..., None], fr[..., None])
        # Σ_i |Y G_i| r_i |t_i|: the anchors' and attachments' first-order spread
        YG = mr_matmul(Y, None, self.G[0], self.G[1])  # (m, w, 2d)
        g = 1.0 + 2.0 * gamma(self.radius.shape[1] + 2)  # the products' rounding
        q = up(((np.abs(YG[0]) + YG[1]) @ self.radius[..., None])[..., 0] * g).T  # (w, m)
        mag_t = np.empty((x.shape[0], q.shape[1]))
        mag_t[:, S] = np.abs(x)
        mag_t[:, F] = np.maximum(np.abs(self.tauF[0]), np.abs(self.tauF[1]))
        spread = up((mag_t @ q.T) * (1.0 + 2.0 * gamma(q.shape[1] + 2)))
        return bc[..., 0], up(br[..., 0] + spread)


def solve_linear_set(system: SetSystem, C: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bounds ``(lo, hi)`` ``(C, w)`` of the free wires' tensions of every robot of the set
    for each of the ``C`` fixed tensions of ``system``, and the mask of the rows where they
    are proven (module docstring: ``α = ||I - Y H_S|| < 1``, then Krawczyk steps,
    :func:`.krawczyk_image`, with :meth:`SetSystem.preconditioned`)."""
    Hc, Hr = system.Hc, system.Hr
    w = Hc.shape[0]
    with np.errstate(all="ignore"):
        Y = np.linalg.inv(Hc) if np.all(np.isfinite(Hc)) else np.full((w, w), np.nan)
        Mc, Mr = mr_matmul(Y, None, Hc, Hr)
        mag = krawczyk_magnitude(Mc, Mr)
        alpha = float(up(np.max(np.sum(mag, axis=-1)) * (1.0 + 2.0 * gamma(w + 2))))
        c = np.zeros((C, w))
        bc, br = system.preconditioned(Y, c)
        c = -bc  # one Newton step from 0: the linear system's float solution
        bc, br = system.preconditioned(Y, c)
        beta = up(np.max(np.abs(bc) + br, axis=-1) / down(1.0 - alpha))
        r = up(beta * (1.0 + 2.0**-20))[:, None] + 1e-300
        lo, hi = down(c - r), up(c + r)
        proven = (alpha < 1.0) & np.isfinite(beta) & np.all(np.isfinite(Y))
        for _ in range(_STEPS):
            c = midpoint(lo, hi)
            bc, br = system.preconditioned(Y, c)
            klo, khi, _ = krawczyk_image(c, lo, hi, mag, bc, br)
            ok = np.isfinite(klo) & np.isfinite(khi)
            lo, hi = np.where(ok, np.fmax(lo, klo), lo), np.where(ok, np.fmin(hi, khi), hi)
    lo = np.where(proven[:, None], lo, -np.inf)
    hi = np.where(proven[:, None], hi, np.inf)
    return lo, hi, proven


def _elastic(robot: Robot, idx: np.ndarray | slice = slice(None)) -> dict[str, Pair]:
    """The intervals of ``k``, ``K``, ``V``, ``L0`` of the wires ``idx`` over the set."""
    b = robot.bounds()
    out = {}
    for name in ("k", "K", "V", "L0"):
        lo, hi = getattr(b, name)
        out[name] = (np.asarray(lo, dtype=float)[idx], np.asarray(hi, dtype=float)[idx])
    return out


def _tension_of_control(robot: Robot, st: SetStatics, F: np.ndarray, uF: np.ndarray) -> Pair:
    """Eq. 6 over the set for the wires ``F`` at the controls ``uF``: ``L = ρ + V + K u``,
    ``τ = k (1 - L0 / L)``, as a batch of one ``(1, |F|)``."""
    e = _elastic(robot, F)
    Ku = arith.scale(e["K"][0], e["K"][1], uF)
    L = arith.add(st.rho[0][F], st.rho[1][F], e["V"][0], e["V"][1])
    L = arith.add(L[0], L[1], Ku[0], Ku[1])
    if not np.all(L[0] > 0.0):
        raise InputError("u_fixed", "a wire length of the set may reach 0 with this control")
    q = arith.div_nonzero(e["L0"][0], e["L0"][1], L[0], L[1])
    one = np.ones_like(q[0])
    s = arith.sub(one, one, q[0], q[1])
    tl, th = arith.mul(e["k"][0], e["k"][1], s[0], s[1])
    return tl[None], th[None]


def _controls(robot: Robot, tau: Pair, rho: Pair) -> Pair:
    """Controls over the set from tensions (eq. 2, eq. 1 for ``L``; module docstring), NaN
    where ``τ`` may reach ``k``."""
    e = _elastic(robot)
    q = arith.div_nonzero(tau[0], tau[1], e["k"][0], e["k"][1])
    one = np.ones_like(q[0])
    s = arith.sub(one, one, q[0], q[1])
    defined = s[0] > 0.0
    L = arith.div_nonzero(e["L0"][0], e["L0"][1], np.where(defined, s[0], 1.0), s[1])
    d = arith.sub(L[0], L[1], rho[0], rho[1])
    d = arith.sub(d[0], d[1], e["V"][0], e["V"][1])
    u = arith.div_nonzero(d[0], d[1], e["K"][0], e["K"][1])
    return np.where(defined, u[0], np.nan), np.where(defined, u[1], np.nan)


def _interval_violations(robot: Robot, lo, hi) -> list[Violation]:
    """The worst cases of ``limit_violations``: an upper limit against the upper bounds, a
    lower limit against the lower bounds (``lo``, ``hi``: ``(τ, u)`` pairs, ``u`` may be
    None)."""
    above = [v for v in limit_violations(robot, *hi) if v.bound == "max"]
    below = [v for v in limit_violations(robot, *lo) if v.bound == "min"]
    return sorted(above + below, key=lambda v: (v.wire, v.quantity))


def _margin(robot: Robot, tlo: np.ndarray, thi: np.ndarray) -> np.ndarray:
    """Proven smallest distance of the tensions to their limits, ``(C,)`` (N, rounded down)."""
    return np.min(
        np.minimum(down(tlo - robot.tau_min), down(robot.tau_max - thi)), axis=-1, initial=np.inf
    )


def check_tolerant_ik(
    robot: Robot, method: str, solve: str = "tau", pose: Pose | None = None
) -> None:
    """What the IK of a set does not take, refused naming the field
    (:class:`~certsolve.inputs.InputError`): Algorithm 1 (a search for one robot's
    controls), ``solve="newton"`` (the set's statics are linear in the tensions), a robot
    with fewer wires than equilibrium equations (a pose is an equilibrium of chosen robots
    only, not of a set), and with ``pose``, a wire whose length may be 0 for a robot of the
    set (:func:`set_statics`)."""
    if method not in ("tension", "alg2"):
        raise InputError(
            "method", f"{method} is not available for a robot with tolerances; use tension or alg2"
        )
    if solve != "tau":
        raise InputError("solve", "a robot with tolerances is solved in the tensions (tau)")
    if robot.m < robot.wrench_dim:
        raise InputError(
            "robot.tolerances",
            f"{robot.wrench_dim} equilibrium equations for {robot.m} tensions: the pose is "
            "an equilibrium of chosen robots only, not of a set",
        )
    if pose is not None:
        set_statics(robot, pose)


def _tensions(robot: Robot, pose: Pose, st: SetStatics, F: np.ndarray, tauF: Pair):
    """For a batch of fixed tensions ``τ_F`` ``(C, |F|)`` (intervals): bounds ``(C, m)`` of
    every wire's tension over the set, the mask of the proven rows, and their proven margins
    (``-inf`` where not proven)."""
    m = st.H[0].shape[1]
    C = tauF[0].shape[0]
    system = SetSystem(robot, pose, st, F, tauF)
    xlo, xhi, proven = solve_linear_set(system, C)
    tlo, thi = np.empty((C, m)), np.empty((C, m))
    tlo[:, F], thi[:, F] = tauF
    tlo[:, system.S], thi[:, system.S] = xlo, xhi
    return tlo, thi, proven, np.where(proven, _margin(robot, tlo, thi), -np.inf)


def _verdict(
    nominal: Robot,
    ok: bool,
    tau: tuple[np.ndarray, np.ndarray],
    u: tuple[np.ndarray | None, np.ndarray | None],
    tau_n: np.ndarray,
    messages: list[str],
) -> tuple[IKStatus, list[Violation]]:
    """The status and the worst-case violations of the set's bounds (``messages`` gets
    each tension violation with the nominal robot's value: certain where it violates too)."""
    if not ok:
        messages.append(
            "the set's statics could not be enclosed: the free wires' wrench matrix may be "
            "singular for a robot of the set"
        )
        return IKStatus.UNCERTIFIED, []
    (tlo, thi), (ulo, uhi) = tau, u
    violations = _interval_violations(nominal, (tlo, ulo), (thi, uhi))
    for v in violations:
        if v.quantity == "tau":
            nv = float(tau_n[v.wire - 1])
            certain = nv > v.limit + LIMIT_TOL if v.bound == "max" else nv < v.limit - LIMIT_TOL
            messages.append(
                f"wire {v.wire}: the set's worst case is at most {v.excess:.4g} N "
                f"{'above' if v.bound == 'max' else 'below'} the limit; the nominal robot has "
                f"{nv:.6g} N ({'violated' if certain else 'within'})"
            )
    if ulo is not None and not np.all(np.isfinite(ulo)):
        bad = [int(i) + 1 for i in np.flatnonzero(~np.isfinite(ulo))]
        messages.append(
            f"no control: the tension of wires {bad} may reach k for a robot of the set"
        )
        return IKStatus.NO_SOLUTION, violations
    return (IKStatus.LIMITS_VIOLATED if violations else IKStatus.OK), violations


def tolerant_inverse_kinematics(
    robot: Robot,
    pose: Pose,
    method: str = "tension",
    *,
    distribution: str = "auto",
    check_lp: bool = False,
    fixed_wire: int = 1,
    tau_fixed: float | None = None,
    u_fixed: float | None = None,
    solve: str = "tau",
    u_last: np.ndarray | None = None,
    window: float | None = None,
) -> IKResult:
    """Control intervals holding ``pose`` for every robot of ``robot``'s set, with the tension
    bounds of the distribution and what fails (module docstring).  ``method``: ``"tension"``
    (options ``distribution``, ``check_lp`` of the nominal distribution) or ``"alg2"``
    (``fixed_wire``, ``tau_fixed``, ``u_fixed``; ``u_last`` and ``window``: controls
    that may leave the window are reported).  ``alg1`` and ``solve="newton"`` are refused
    (:class:`~certsolve.inputs.InputError`): the set's statics are solved in the tensions."""
    t0 = time.perf_counter()
    check_tolerant_ik(robot, method, solve)
    nominal = robot.nominal()
    elastic = is_elastic(nominal)
    if method == "alg2" and not elastic:
        require_elastic(nominal, "alg2")
    enc = enclose_pose(nominal, pose.position, pose.rotation)
    check_pose(pose, enc)
    H0, wg0 = enc.H, enc.wg
    w, m = H0.shape
    st = set_statics(robot, pose)
    messages: list[str] = []
    details: dict = {}
    if method == "tension":
        ch = distribute_tensions(
            H0, wg0, nominal.tau_min, nominal.tau_max, mode=distribution, check_lp=check_lp
        )
        messages += ch.notes
        if ch.lp_check is not None:
            details["lp_check"] = ch.lp_check
        _, _, piv = scipy.linalg.qr(H0, pivoting=True)
        F = np.sort(piv[w:])
        tau_nom = np.where(np.isfinite(ch.tau), ch.tau, 0.5 * (nominal.tau_min + nominal.tau_max))
        cand = tau_nom[F][None]
        tauF: Pair = (cand, cand)
        fixed_u: dict[int, float] = {}
    else:
        if u_last is not None:
            _, _, u_last = search_window(nominal, u_last, window)
        F = np.array(_fixed_wires(H0, fixed_wire, m - w), dtype=np.int64)
        opts = Alg2Options(fixed_wire=fixed_wire, tau_fixed=tau_fixed, u_fixed=u_fixed)
        u0, _ = _fix_controls(nominal, enc, F, opts)
        uF = u0[F]
        fixed_u = {int(j) + 1: float(v) for j, v in zip(F, uF, strict=True)}
        tauF = _tension_of_control(robot, st, F, uF)
    S = np.setdiff1d(np.arange(m), F)
    tlo, thi, proven, margins = _tensions(robot, pose, st, F, tauF)
    C = tlo.shape[0]
    if method == "tension" and F.size == 1 and not margins[0] >= 0.0:
        j = int(F[0])
        best = (float(margins[0]), tlo[0], thi[0], bool(proven[0]))
        t_lo, t_hi = float(nominal.tau_min[j]), float(nominal.tau_max[j])
        for _ in range(ROUNDS):  # a grid across the range, then finer around the best
            grid = np.linspace(t_lo, t_hi, GRID)[:, None]
            glo, ghi, gok, gm = _tensions(robot, pose, st, F, (grid, grid))
            C += GRID
            k = int(np.argmax(gm))
            if gm[k] > best[0]:
                best = (float(gm[k]), glo[k], ghi[k], bool(gok[k]))
            step = (t_hi - t_lo) / (GRID - 1)
            t = float(best[1][j])
            t_lo = max(t - step, float(nominal.tau_min[j]))
            t_hi = min(t + step, float(nominal.tau_max[j]))
        if best[1][j] != tlo[0, j]:
            messages.append(
                f"the nominal robot's max-margin tension of wire {j + 1} does not hold the "
                f"limits for the whole set; fixed at {float(best[1][j]):.6g} N instead (the "
                f"largest proven margin of {C - 1} values across its range)"
            )
        margin, tlo, thi, ok = best
    else:
        tlo, thi, ok, margin = tlo[0], thi[0], bool(proven[0]), float(margins[0])
    # the nominal robot under the same distribution, for the certainty of a violation
    with np.errstate(all="ignore"):
        if method == "tension":
            tnF = tlo[F]
        else:
            L0n = enc.W[F] + nominal.K[F] * uF
            tnF = nominal.k[F] * (L0n - nominal.L0[F]) / L0n
        tau_n = np.empty(m)
        tau_n[F] = tnF
        tau_n[S] = np.linalg.solve(H0[:, S], -(wg0 + H0[:, F] @ tnF))
    ulo = uhi = None
    if elastic and ok:
        ulo, uhi = _controls(robot, (tlo, thi), st.rho)
        if method == "alg2":
            ulo[F] = uhi[F] = uF
    fixed_what = "tension" if method == "tension" else "control"
    fixed_vals = tlo[F] if method == "tension" else uF
    fixed_text = ", ".join(
        f"{'tau' if method == 'tension' else 'u'}_{int(j) + 1} = {float(v):.6g}"
        for j, v in zip(F, fixed_vals, strict=True)
    )
    details["set"] = {
        "fixed": fixed_what,
        "fixed_wires": [int(j) + 1 for j in F],
        "fixed_values": [float(v) for v in fixed_vals],
        "tau_lo": tlo,
        "tau_hi": thi,
        "u_lo": ulo,
        "u_hi": uhi,
        "margin_lo": margin,
        "nominal_tau": tau_n,
        "candidates": C,
    }
    status, violations = _verdict(nominal, ok, (tlo, thi), (ulo, uhi), tau_n, messages)
    if ok and ulo is not None and uhi is not None and u_last is not None and window is not None:
        violations += [v for v in window_violations(uhi, u_last, window) if v.bound == "max"]
        violations += [v for v in window_violations(ulo, u_last, window) if v.bound == "min"]
        if status == IKStatus.OK and violations:
            status = IKStatus.LIMITS_VIOLATED
    u = None
    if ulo is not None and uhi is not None and status != IKStatus.NO_SOLUTION:
        u = midpoint(ulo, uhi)
    cert = Certificate(
        kind="every-robot" if ok else "none",
        statement=(
            f"with {fixed_text} for every robot of the set, each robot has exactly one "
            "tension vector solving its statics, within details.set tau_lo..tau_hi, and its "
            "controls lie in 'enclosure'"
        )
        if ok
        else "floating-point result, not certified",
        enclosure=None if u is None or ulo is None or uhi is None else (ulo, uhi),
        fixed=fixed_u,
    )
    messages.append(
        "robot with tolerances: u is the middle of the control intervals (certificate."
        "enclosure); each robot of the set needs its own control within them, and u itself "
        "proves nothing about a robot's pose (forward kinematics with u gives the set's pose box)"
    )
    return IKResult(
        robot=robot.name,
        dof=robot.dof,
        method=method,
        pose=pose,
        status=status,
        feasible=status == IKStatus.OK,
        u=u,
        tau=midpoint(tlo, thi) if ok else None,
        rho=enc.rho,
        margin=margin if ok else None,
        residual=None,
        violations=violations,
        certificate=cert,
        messages=messages,
        details=details,
        time=time.perf_counter() - t0,
    )
