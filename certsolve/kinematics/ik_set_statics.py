"""The statics of a robot set at one pose, and the enclosure of its tensions.

For :mod:`.ik_tolerance`: at a pose ``P``, each robot of the set (anchors ``A``,
attachments ``B``, mass and centre of mass within their intervals) has the statics
``H(P; A, B) τ = -w_g`` (Merlet 2007, eqs. 3-4).  With the tensions ``τ_F`` of some wires
fixed, the others solve the linear system::

    f(τ_S, p) = H_S(p) τ_S + H_F(p) τ_F + w_g = 0,

whose matrix and right-hand side are intervals over the set (:func:`set_statics`: the
geometry in interval arithmetic over the anchors, attachments, mass and centre of mass).
The Krawczyk operator of this linear map, ``K(X) = c - Y f(c, p) + (I - Y H_S)(X - c)``
with ``Y ≈ mid(H_S)^-1`` (the package's kernel, :func:`.krawczyk_image`), encloses the
solution of every robot (:func:`solve_linear_set`): ``α = ||I - Y H_S|| < 1`` proves every
matrix of the set nonsingular (one solution per robot) and that solution within ``c ±
||Y f(c, p)|| / (1 - α)``, which three Krawczyk steps then tighten.

``Y f(c, p)`` is taken in the mean-value form of the FK's set test
(:class:`.fk_tolerance.SetKrawczyk`, here :class:`SetSystem`)::

    Y f(c, p) ∈ Y f(c, p0) + Σ_i (Y G_i) t_i (p_i - p0_i),

``p0`` the middle of the set, ``G_i`` the slopes of wire ``i``'s wrench column in its
anchor and attachment over the set (:func:`_slopes`), ``t_i`` its tension.  Enclosing
``f(c, P)`` entry by entry instead reads a column's six entries, which move together with
its anchor, as independent: on T-16 (±0.05 cm, ±1 % ``k``) the tension bounds were 3.6-9
times the spread of 40 sampled robots; they are 1.1-2.3 times in this form.  A toleranced
mass ``m`` and centre of mass ``c`` enter the same form (:func:`_weight_slopes`):
``w_g = m u(c)``, ``u(c) = (g, (R c) × g)`` affine in ``c``, so ``w_g(m, c) - w_g(m0, c0) =
(m - m0) u(c) + Σ_j (c_j - c0_j) m0 u_j`` exactly, and ``Y w_g`` is ``Y w_g(m0, c0)`` plus
``Σ_q |Y s_q| r_q`` over those slopes, instead of ``Y`` times the interval ``w_g`` (which
reads the force and the moments, moved together by ``m`` and ``c``, as independent).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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

__all__ = ["SetStatics", "SetSystem", "set_statics", "solve_linear_set"]

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
    wg = _weight(robot, R, robot.weight_bounds(), _pair(robot.bounds().com))
    return SetStatics(rho=rho, H=H, wg=wg, n=n, CB=CB)


def _weight(robot: Robot, R: np.ndarray, F: Pair, com: Pair) -> Pair:
    """``w_g = (F, (R c) × F)`` ``(w,)`` over the intervals of the force ``F`` ``(d,)`` and the
    centre of mass ``c`` ``(d,)`` (no moment for a point robot)."""
    force = [(np.atleast_1d(F[0][c]), np.atleast_1d(F[1][c])) for c in range(robot.dim)]
    wg = force
    if robot.dof != 2:
        cg = point_matmul_interval(R, com[0], com[1])
        Fv = (np.asarray(F[0], dtype=float)[None], np.asarray(F[1], dtype=float)[None])
        wg = force + _moments((cg[0][None], cg[1][None]), Fv, robot.dof)
    wgl = np.array([np.ravel(x[0])[0] for x in wg])
    wgh = np.array([np.ravel(x[1])[0] for x in wg])
    return wgl, wgh


def _weight_slopes(robot: Robot, pose: Pose) -> tuple[Pair, tuple[Pair, np.ndarray]] | None:
    """The weight's wrench in the mean-value form over the mass ``m`` and the centre of mass
    ``c`` of the set, None where both are exact.  ``w_g = m u(c)`` with
    ``u(c) = (g, (R c) × g)`` affine in ``c``, so for every ``(m, c)`` of the set, exactly,

        w_g(m, c) - w_g(m0, c0) = (m - m0) u(c) + Σ_j (c_j - c0_j) m0 u_j,
        u_j = (0, (R e_j) × g),

    (``(m0, c0)`` the middle): returns ``w_g(m0, c0)`` and the slopes ``(w, 1 + d)``
    (``u(C)`` over the set's ``c``, then ``m0 u_j``) with their radii ``|m - m0|``,
    ``|c_j - c0_j|`` ``(1 + d,)``."""
    b = robot.bounds()
    mass, com = (np.array([b.mass[0]]), np.array([b.mass[1]])), _pair(b.com)
    if mass[0][0] == mass[1][0] and np.array_equal(*com):
        return None
    R = np.asarray(pose.rotation, dtype=float)
    d, g = robot.dim, robot.gravity
    mids, rads = [], []
    for lo, hi in (mass, com):
        mid = np.clip(midpoint(lo, hi), lo, hi)
        mids.append(mid)
        rads.append(np.maximum(up(hi - mid), up(mid - lo)))
    m0 = np.full(d, mids[0][0])
    F0 = arith.mul(m0, m0, g, g)
    wg0 = _weight(robot, R, F0, (mids[1], mids[1]))
    slopes = [_weight(robot, R, (g, g), com)]  # in m: u(c) over the set's c
    for j in range(d):
        e = np.zeros(d)
        e[j] = 1.0
        lo, hi = _weight(robot, R, F0, (e, e))  # in c_j: m0 u_j (no force)
        lo[:d], hi[:d] = 0.0, 0.0
        slopes.append((lo, hi))
    S = (np.stack([s[0] for s in slopes], axis=1), np.stack([s[1] for s in slopes], axis=1))
    return wg0, (S, np.concatenate(rads))


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
    in the anchors and attachments ``p``, the mass and the centre of mass (``τ_F`` as
    intervals)::

        Y f(x, p) ∈ Y f(x, p0) + Σ_i (Y G_i) t_i (p_i - p0_i) + Σ_q (Y s_q) (q - q0),

    ``p0`` the middle of the set, ``G_i`` :func:`_slopes` over the set, ``t_i`` the tension
    of wire ``i`` (``x_i`` or ``τ_F``): the six entries of a wire's column move together
    with its anchor, which an interval ``H(P)`` alone reads as independent; ``q`` the mass
    and the centre of mass, ``s_q`` the weight's slopes (:func:`_weight_slopes`; none
    where both are exact, and then ``w_g`` is the nominal weight)."""

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
        self.weight: tuple[tuple[np.ndarray, np.ndarray], np.ndarray] | None = None
        weight = _weight_slopes(robot, pose)
        if weight is not None:  # w_g at the middle, and its slopes in the mass and the com
            self.wg, (S, r) = weight
            self.weight = mr_from_bounds(*S), r

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
        if self.weight is not None:  # Σ_q |Y s_q| r_q: the weight's first-order spread
            (sc, sr), r = self.weight
            YS = mr_matmul(Y, None, sc, sr)  # (w, 1 + d)
            gw = 1.0 + 2.0 * gamma(r.shape[0] + 2)
            spread = up(spread + up(((np.abs(YS[0]) + YS[1]) @ r) * gw))
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
