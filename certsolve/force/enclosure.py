"""Interval enclosures of the isotropic-force test over boxes of poses (the proof step).

For a required force ``f_req > 0`` define, for every candidate facet ``k`` of the wrench
zonotope and both signs (:mod:`.isotropic`),

    g_k^± = Σ_l φ(±c_k·h_l) ± c_k·w_ext - f_req ||c_k,f||,
    φ(s)  = max(s τ_l^min, s τ_l^max) = τ_l^max max(s, 0) + τ_l^min min(s, 0).

The index formula is homogeneous of degree 0 in ``c_k``, so ``c_k`` may be the generalised
cross product of the **unnormalised** columns ``ĥ_i = ρ_i h_i = (a_i, b_i × a_i)``, with
``b_i = R B_i``, ``a_i = A_i - p - b_i`` (``b × a = b × (A - p)``); only
``c_k·h_l = (c_k·ĥ_l)/ρ_l`` needs the wire length ``ρ_l``.  Every ``g`` may moreover be
multiplied by one positive constant per ``(box, k)``.  At a pose where ``H`` has full rank:

    f_min ≥ f_req  ⟺  g_k^± ≥ 0 for every k and sign,

(a term with ``c_k,f = 0`` is then the section's non-emptiness condition); and
``f_min < f_req`` as soon as one ``g_k^± < 0``.

:func:`slack_enclosures` encloses every ``g`` over a batch of boxes with outward-rounded
interval arithmetic (:mod:`certsolve.interval`; rotations from interval angles with the
rigorous ``sin``/``cos``; point-matrix products with the a-priori rounding-error bound of
:func:`certsolve.interval.linalg.mr_matmul`).  It also returns

* ``full_rank``: some ``c_k·ĥ_l`` (``l`` not in subset ``k``) excludes 0 over the box: a
  proof that ``rank H = w`` at every pose of the box, required by the equivalence above;
* ``wires_ok``: every ``ρ_l`` is bounded away from 0 (no anchor inside the box).

**Interval robot parameters.**  With ``params`` (a :class:`~certsolve.robot.params.RobotBounds`)
the anchors ``A``, attachments ``B`` and tension limits are interval arrays over a box of
design parameters ``θ`` (one per box of the batch), and every enclosure holds for every
robot of the box *and* every pose of the pose box simultaneously (the design search,
:mod:`.design`).  Each formula below is an identity for every fixed robot.  Point
platforms evaluate it with the robot's intervals in place of its floats (natural interval
arithmetic: measured faster, at equal tightness per second, than a slope form).  Rigid
platforms add the parameters as slope dimensions: the midpoint value encloses the
quantity at the centre pose *and* centre parameters, and the slopes in ``θ`` are exact
derivatives of the affine arrays (:func:`_column_slopes`; ``φ`` with slopes in its tension
limits, :func:`~.meanvalue.phi_mv`), so coordinates moved together by one parameter stay
correlated to first order.

**Interval mass and centre of mass.**  ``params.mass`` and ``params.com`` (a robot with
tolerances) enter only the weight's wrench ``w_g = (m g, (R c) × (m g))``, which is
multilinear in ``(m, c)``, and every ``g`` is affine in ``w_ext``: over the box of ``(m, c)``,
``g`` lies between its least and greatest values at the box's corners (``g(m, c)`` is a
convex combination of them, with the multilinear interpolation weights).  So the slacks are
enclosed for each corner robot -- each an exact weight, in the slope form above -- and the
result is their hull (rigid platforms: the corners are one more axis of the batch of
``c_k·w``, :func:`_weight_mv`; the rest is shared).  A point platform has no centre of mass,
and its ``m g`` is a plain interval product.  An exact weight is one corner, the nominal
one: the same floats as before.

**Point platform (dof 2).**  ``c_j = (a_jy, -a_jx)`` and
``c_j·ĥ_i = -cross(A_j - p, A_i - p) = -(cross(A_j, A_i) + cross(A_i - A_j, p))``, linear in
``p``: its interval is exact up to rounding.

**Rigid platforms (dof 3, 6).**  The natural interval extension of a 5×5 determinant loses
everything to cancellation, so the normals are written in **basis form** (:func:`_rigid`):
with ``w`` columns ``B0`` proven independent over the box and ``Y = ĥ_B0^{-1} ĥ_N``, every
normal is ``λ^T ĥ_B0^{-1}`` with ``λ`` a small wedge of a block of ``Y``, and every
``c·ĥ_l`` is an entry of ``λ`` or ``λ^T Y``.  All quantities are carried in **slope form**
(:mod:`.meanvalue`: value at the box midpoint, range, slopes), starting from the columns
``ĥ(x) ∈ ĥ(mid) + Σ_j J_j(X)(x_j - mid_j)`` (``J`` the interval Jacobian over the box; at a
fixed orientation ``ĥ`` is affine in ``p``), so the final enclosures are tight to first order.
The inverse is proven with ``P ≈ ĥ_B0(mid)^{-1}`` and ``||P ĥ_B0(X) - I||_∞ < 1/2``; the basis
is, per box, the one with the smallest such bound (boxes where none exists stay undecided).
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike

from ..interval import arith, elementary
from ..interval.core import Pair
from ..interval.linalg import mr_from_bounds
from ..interval.rounding import down, up
from ..robot import Robot
from ..robot.params import RobotBounds
from .loads import force_rows
from .meanvalue import MV, Limit, LimitMV, mv_sum, phi_mv, pmatmul, wedge_mv
from .wedge import basis_groups, facet_subsets

__all__ = ["interval_rotation", "slack_enclosures"]

_PI_LO = float(np.nextafter(np.pi, -np.inf))
_PI_HI = float(np.nextafter(np.pi, np.inf))


# -- small interval helpers (pairs of arrays) ---------------------------------------------
def _sum(terms):
    lo, hi = terms[0]
    for tlo, thi in terms[1:]:
        lo, hi = arith.add(lo, hi, tlo, thi)
    return lo, hi


def _sum_up(x):
    """Upper bound of the sum of non-negative ``x`` over the last axis (rounding included)."""
    n = x.shape[-1]
    return up(np.sum(x, axis=-1) * (1.0 + (n + 2) * 2.0**-52))


def _deg_to_rad(lo, hi):
    """Enclosure of ``[lo, hi] · π / 180``."""
    plo, phi = arith.mul(lo, hi, np.full_like(lo, _PI_LO), np.full_like(hi, _PI_HI))
    c = np.full_like(lo, 180.0)
    return arith.div(plo, phi, c, c)


def _const(x, B):
    a = np.full(B, float(x))
    return a, a


def _imat(entries):
    """Interval matrix ``(n, n, B)`` from a nested list of interval pairs."""
    lo = np.stack([np.stack([e[0] for e in row]) for row in entries])
    hi = np.stack([np.stack([e[1] for e in row]) for row in entries])
    return lo, hi


def _imatmul(X, Y):
    """Product of interval matrices ``(n, n, B)``."""
    (xlo, xhi), (ylo, yhi) = X, Y
    n = xlo.shape[0]
    plo, phi = arith.mul(xlo[:, :, None], xhi[:, :, None], ylo[None], yhi[None])  # (i, k, j, B)
    return _sum([(plo[:, k], phi[:, k]) for k in range(n)])


def _rotation_parts(dof: int, alo: np.ndarray, ahi: np.ndarray, derivatives: bool):
    """Enclosures of ``R`` and (optionally) of ``∂R/∂α_j`` per **degree**, over angle boxes.

    ``alo``, ``ahi``: ``(1, B)`` (θ) or ``(3, B)`` (yaw, pitch, roll; ``R = Rz Ry Rx`` as
    :func:`certsolve.robot.geometry.rotation_zyx`).  Returns ``(R, [dR_j])`` as interval
    pairs of shape ``(d, d, B)``.
    """
    B = alo.shape[1]
    rlo, rhi = _deg_to_rad(alo, ahi)
    clo, chi = elementary.cos(rlo, rhi)
    slo, shi = elementary.sin(rlo, rhi)
    c = [(clo[i], chi[i]) for i in range(alo.shape[0])]
    s = [(slo[i], shi[i]) for i in range(alo.shape[0])]
    ns = [arith.neg(*x) for x in s]
    nc = [arith.neg(*x) for x in c]
    zero, one = _const(0.0, B), _const(1.0, B)
    k = arith.div(np.full(B, _PI_LO), np.full(B, _PI_HI), np.full(B, 180.0), np.full(B, 180.0))
    if dof == 3:
        R = _imat([[c[0], ns[0]], [s[0], c[0]]])
        dR = [_imat([[ns[0], nc[0]], [c[0], ns[0]]])] if derivatives else []
    else:
        Rz = _imat([[c[0], ns[0], zero], [s[0], c[0], zero], [zero, zero, one]])
        Ry = _imat([[c[1], zero, s[1]], [zero, one, zero], [ns[1], zero, c[1]]])
        Rx = _imat([[one, zero, zero], [zero, c[2], ns[2]], [zero, s[2], c[2]]])
        R = _imatmul(_imatmul(Rz, Ry), Rx)
        dR = []
        if derivatives:
            dRz = _imat([[ns[0], nc[0], zero], [c[0], ns[0], zero], [zero, zero, zero]])
            dRy = _imat([[ns[1], zero, c[1]], [zero, zero, zero], [nc[1], zero, ns[1]]])
            dRx = _imat([[zero, zero, zero], [zero, ns[2], nc[2]], [zero, c[2], ns[2]]])
            dR = [
                _imatmul(_imatmul(dRz, Ry), Rx),
                _imatmul(_imatmul(Rz, dRy), Rx),
                _imatmul(_imatmul(Rz, Ry), dRx),
            ]
    dR = [arith.mul(lo, hi, k[0], k[1]) for lo, hi in dR]
    return R, dR


def interval_rotation(dof: int, alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """Enclosure ``(Rlo, Rhi)`` ``(d, d, B)`` of the rotations over angle boxes (degrees)."""
    return _rotation_parts(dof, alo, ahi, derivatives=False)[0]


def _matvec_point(R, V):
    """``R v_i`` for interval ``R`` ``(d, d, B)``, point vectors ``V`` ``(m, d)``: ``(m, d, B)``."""
    Rlo, Rhi = R
    d = V.shape[1]
    terms = [
        _scale(Rlo[None, :, c, :], Rhi[None, :, c, :], V[:, c][:, None, None]) for c in range(d)
    ]
    return _sum(terms)


def _matvec(R, V):
    """``R v_i`` for interval ``R`` ``(d, d, B)`` and interval vectors ``V`` ``(m, d, n)`` with
    ``n`` 1 or ``B``: ``(m, d, B)`` (a thin ``V`` shared by the batch uses the point path)."""
    vlo, vhi = V
    if vlo.shape[-1] == 1 and np.array_equal(vlo, vhi):
        return _matvec_point(R, vlo[..., 0])
    Rlo, Rhi = R
    d = vlo.shape[1]
    terms = [
        arith.mul(
            Rlo[None, :, c, :], Rhi[None, :, c, :], vlo[:, c][:, None, :], vhi[:, c][:, None, :]
        )
        for c in range(d)
    ]
    return _sum(terms)


def _cross2(a, b):
    """``a_x b_y - a_y b_x`` on interval vectors with the component axis first."""
    (alo, ahi), (blo, bhi) = a, b
    return arith.sub(
        *arith.mul(alo[0], ahi[0], blo[1], bhi[1]), *arith.mul(alo[1], ahi[1], blo[0], bhi[0])
    )


def _cross3(a, b):
    (alo, ahi), (blo, bhi) = a, b
    comps = [
        arith.sub(
            *arith.mul(alo[i], ahi[i], blo[j], bhi[j]), *arith.mul(alo[j], ahi[j], blo[i], bhi[i])
        )
        for i, j in ((1, 2), (2, 0), (0, 1))
    ]
    return np.stack([c[0] for c in comps]), np.stack([c[1] for c in comps])


def _scale(lo, hi, c):
    """``c · [lo, hi]`` for float ``c`` with ``0 · inf = 0`` (the tension bound 0 is common)."""
    with np.errstate(invalid="ignore"):
        rlo, rhi = arith.scale(lo, hi, c)
    zero = np.broadcast_to(np.asarray(c) == 0, rlo.shape)
    return np.where(zero, 0.0, rlo), np.where(zero, 0.0, rhi)


def _phi(slo, shi, tmin, tmax):
    """Enclosure of ``φ(s) = τmax max(s, 0) + τmin min(s, 0)``; ``τ`` are interval pairs
    (broadcast with ``s``; thin pairs take the point path)."""
    plo, phi = _tscale(np.maximum(slo, 0.0), np.maximum(shi, 0.0), tmax)
    nlo, nhi = _tscale(np.minimum(slo, 0.0), np.minimum(shi, 0.0), tmin)
    return arith.add(plo, phi, nlo, nhi)


def _tscale(lo, hi, t):
    """``[t] · [lo, hi]`` for an interval pair ``t`` (``0 · inf = 0``)."""
    tlo, thi = t
    if tlo is thi or np.array_equal(tlo, thi):
        return _scale(lo, hi, tlo)
    return arith.mul(lo, hi, tlo, thi)


# -- the robot's columns ------------------------------------------------------------------
def _columns(robot: Robot, plo, phi, R, A: Pair, Bp: Pair):
    """Natural enclosures over the box: ``e = A - p``, ``b = R B``, ``a = e - b`` ``(m, d, B)``
    and the unnormalised columns ``ĥ`` ``(w, m, B)`` (dof 3, 6); ``A``, ``Bp`` interval pairs
    ``(m, d, n)``."""
    e = arith.sub(*A, plo[None], phi[None])
    b = _matvec(R, Bp)
    a = arith.sub(*e, *b)
    tr = [(np.moveaxis(x[0], 1, 0), np.moveaxis(x[1], 1, 0)) for x in (e, b, a)]
    et, bt, at = tr
    if robot.dof == 3:
        mlo, mhi = _cross2(bt, et)
        mlo, mhi = mlo[None], mhi[None]
    else:
        mlo, mhi = _cross3(bt, et)
    h = (np.concatenate([at[0], mlo]), np.concatenate([at[1], mhi]))
    return e, b, a, h


def _column_slopes(robot: Robot, e, b, R, dR, prm: RobotBounds) -> list:
    """Interval enclosures ``(w, m, B)`` of ``∂ĥ/∂x_j`` over the box, per axis ``j``.

    Positions: ``∂a/∂p_j = -e_j``, ``∂(b × (A - p))/∂p_j = -b × e_j``; angles:
    ``∂a/∂α = -∂b/∂α``, ``∂(b × (A - p))/∂α = ∂b/∂α × (A - p)``, ``∂b/∂α = (∂R/∂α) B``;
    design parameters (``A``, ``B`` affine in ``θ``): ``∂a/∂θ = ∂A/∂θ - R ∂B/∂θ``,
    ``∂(b × e)/∂θ = (R ∂B/∂θ) × e + b × ∂A/∂θ``.
    """
    d = robot.dim
    w = robot.wrench_dim
    blo, bhi = (np.moveaxis(b[0], 1, 0), np.moveaxis(b[1], 1, 0))  # (d, m, B)
    et = (np.moveaxis(e[0], 1, 0), np.moveaxis(e[1], 1, 0))
    shape = (w,) + blo.shape[1:]
    out = []
    for j in range(d):
        lo = np.zeros(shape)
        hi = np.zeros(shape)
        lo[j] = hi[j] = -1.0
        if d == 2:  # ∂/∂p of b_x (A_y - p_y) - b_y (A_x - p_x) = (b_y, -b_x)
            if j == 0:
                lo[2], hi[2] = blo[1], bhi[1]
            else:
                lo[2], hi[2] = -bhi[0], -blo[0]
        else:  # -b × e_j
            i1, i2 = (j + 1) % 3, (j + 2) % 3
            lo[3 + i1], hi[3 + i1] = -bhi[i2], -blo[i2]
            lo[3 + i2], hi[3 + i2] = blo[i1], bhi[i1]
        out.append((lo, hi))
    for dRj in dR:
        db = _matvec(dRj, prm.B)  # (m, d, B)
        dbt = (np.moveaxis(db[0], 1, 0), np.moveaxis(db[1], 1, 0))
        if d == 2:
            mom = _cross2(dbt, et)
            mom = (mom[0][None], mom[1][None])
        else:
            mom = _cross3(dbt, et)
        nlo, nhi = arith.neg(*dbt)
        out.append((np.concatenate([nlo, mom[0]]), np.concatenate([nhi, mom[1]])))
    cross = _cross2 if d == 2 else _cross3
    for dA, dB in zip(prm.dA, prm.dB):
        if not (np.any(dA) or np.any(dB)):
            out.append((np.zeros(shape), np.zeros(shape)))
            continue
        db = _matvec_point(R, dB)  # (m, d, B)
        dbt = (np.moveaxis(db[0], 1, 0), np.moveaxis(db[1], 1, 0))
        dat = np.moveaxis(dA, 1, 0)[..., None]  # (d, m, 1)
        da = arith.sub(dat, dat, *dbt)
        mom = arith.add(*cross(dbt, et), *cross((blo, bhi), (dat, dat)))
        if d == 2:
            mom = (mom[0][None], mom[1][None])
        lo = np.concatenate([np.broadcast_to(da[0], (d,) + shape[1:]), mom[0]])
        hi = np.concatenate([np.broadcast_to(da[1], (d,) + shape[1:]), mom[1]])
        out.append((lo, hi))
    return out


def _weight_wrench(robot: Robot, B: int, external, prm: RobotBounds):
    """dof 2: enclosure of ``w_ext`` = weight (+ ``external``), shape ``(2, B)``: the
    interval of the mass (``prm.mass``) times ``g``."""
    d = robot.dim
    mlo, mhi = np.full(d, prm.mass[0]), np.full(d, prm.mass[1])
    flo, fhi = arith.mul(mlo, mhi, robot.gravity, robot.gravity)  # weight = mass * g
    wlo = np.broadcast_to(flo[:, None], (d, B))
    whi = np.broadcast_to(fhi[:, None], (d, B))
    if external is not None:
        e = np.asarray(external, dtype=float)[:, None]
        wlo, whi = arith.add(wlo, whi, e, e)
    return wlo, whi


# -- the slacks -----------------------------------------------------------------------------
def slack_enclosures(
    robot: Robot,
    plo: np.ndarray,
    phi: np.ndarray,
    f_req: float,
    external: ArrayLike | None = None,
    alo: np.ndarray | None = None,
    ahi: np.ndarray | None = None,
    rotation: np.ndarray | None = None,
    params: RobotBounds | None = None,
    norms: bool = False,
) -> tuple[np.ndarray, ...]:
    """Enclosures of every ``g_k^±`` over ``B`` boxes (batch last).

    ``plo``, ``phi``: ``(d, B)`` position bounds (cm); ``alo``, ``ahi``: ``(na, B)`` angle
    bounds (degrees; dof 3: θ, dof 6: yaw, pitch, roll) or ``None`` for the fixed
    ``rotation`` (a ``(d, d)`` float matrix, identity if omitted); ``params``: interval
    anchors, attachments and tension limits per box (batch of ``B`` or of 1; default the
    robot's floats).  Returns ``(glo, ghi, full_rank, wires_ok)`` with ``g`` of shape
    ``(2K, B)``, and with ``norms`` a fifth array ``(2K, B)``: an upper bound of
    ``||c_k,f||`` in the same scaling as ``g``, so that at a pose with full rank
    ``f_min ≥ f_req + min_k glo_k / norm_k`` whenever every ``glo_k ≥ 0``.
    """
    prm = RobotBounds.point(robot) if params is None else params
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        if robot.dof == 2:
            out = _point_slacks(robot, f_req, external, prm, *_parts_point(robot, plo, phi, prm))
        else:
            out = _rigid(robot, plo, phi, f_req, external, alo, ahi, rotation, prm)
    return out if norms else out[:4]


def _parts_point(robot: Robot, plo, phi, prm: RobotBounds):
    Alo, Ahi = prm.A  # (m, 2, n), n = 1 or B
    m = robot.m
    subsets = facet_subsets(m, 2)
    j = subsets[:, 0]
    Aj = (Alo[j][:, None], Ahi[j][:, None])  # (K, 1, 2, n)
    Ai = (Alo[None], Ahi[None])  # (1, m, 2, n)
    e = arith.sub(Alo, Ahi, plo[None], phi[None])  # a = A - p: (m, 2, B)
    elo, ehi = e
    rho = arith.sqrt(*_sum([arith.sqr(elo[:, r], ehi[:, r]) for r in range(2)]))

    def comp(x, r):
        return x[0][..., r, :], x[1][..., r, :]

    # c_j · ĥ_i = -cross(a_j, a_i) = -(cross(A_j, A_i) + cross(A_i - A_j, p))
    c1 = arith.sub(
        *arith.mul(*comp(Aj, 0), *comp(Ai, 1)), *arith.mul(*comp(Aj, 1), *comp(Ai, 0))
    )  # (K, m, n)
    dx = arith.sub(*comp(Ai, 0), *comp(Aj, 0))
    dy = arith.sub(*comp(Ai, 1), *comp(Aj, 1))
    t1 = arith.mul(*dx, plo[1], phi[1])
    t2 = arith.mul(*dy, plo[0], phi[0])
    cr = arith.add(*c1, *arith.sub(*t1, *t2))
    D = arith.neg(*cr)  # (K, m, B)
    c = (np.stack([elo[j, 1], -ehi[j, 0]]), np.stack([ehi[j, 1], -elo[j, 0]]))  # (2, K, B)
    cf = (rho[0][j], rho[1][j])  # ||c_j|| = ρ_j
    return subsets, rho, D, c, cf


def _weight_mv(robot: Robot, R, Rmid, dR, nd: int, B: int, external, prm: RobotBounds) -> MV:
    """``w_ext`` ``(w, V, B)`` as a slope triple (it depends on the angles through ``R com``),
    one per corner ``v`` of the box of the mass and the centre of mass
    (:meth:`.RobotBounds.weight_corners`; ``V = 1`` for an exact weight): each is the exact
    robot's triple, ``w_v = (m_v g, (R c_v) × (m_v g))``."""
    d = robot.dim
    masses, coms = prm.weight_corners()  # (V,), (V, d)
    V = masses.shape[0]
    mass = np.broadcast_to(masses, (d, V))
    g = np.broadcast_to(robot.gravity[:, None], (d, V))
    flo, fhi = arith.mul(mass, mass, g, g)  # weight = mass * g
    f = MV.const(
        np.broadcast_to(flo[..., None], (d, V, B)), np.broadcast_to(fhi[..., None], (d, V, B)), nd
    )
    gm = _matvec_point(Rmid, coms)
    gx = _matvec_point(R, coms)
    z = np.zeros((V, d, B))
    gs = [(z, z)] * d + [_matvec_point(dRj, coms) for dRj in dR]
    gs += [(z, z)] * (nd - len(gs))  # the design parameters do not move the weight
    rc = MV(gm, gx, gs).apply(lambda t: np.moveaxis(t, 0, 1))  # (d, V, B)

    def comp(u, i):
        return u.apply(lambda t: t[i])

    if robot.dof == 3:
        mom = comp(rc, 0) * comp(f, 1) - comp(rc, 1) * comp(f, 0)
        moms = [mom]
    else:
        moms = [
            comp(rc, i) * comp(f, j) - comp(rc, j) * comp(f, i) for i, j in ((1, 2), (2, 0), (0, 1))
        ]
    parts = [comp(f, i) for i in range(d)] + moms
    out = MV(
        (np.stack([p.m[0] for p in parts]), np.stack([p.m[1] for p in parts])),
        (np.stack([p.x[0] for p in parts]), np.stack([p.x[1] for p in parts])),
        [
            (np.stack([p.s[j][0] for p in parts]), np.stack([p.s[j][1] for p in parts]))
            for j in range(nd)
        ],
    )
    if external is not None:
        ex = np.broadcast_to(np.asarray(external, dtype=float)[:, None, None], (len(parts), V, B))
        out = out + MV.const(ex, ex, nd)
    return out


def _imatmul_b(X, Y):
    """Interval matrix product ``(B, a, b) @ (B, b, c)`` (natural, outward rounded)."""
    (xlo, xhi), (ylo, yhi) = X, Y
    plo, phi = arith.mul(
        xlo[..., :, :, None], xhi[..., :, :, None], ylo[..., None, :, :], yhi[..., None, :, :]
    )
    return _sum([(plo[..., :, k, :], phi[..., :, k, :]) for k in range(xlo.shape[-1])])


class _BasisInverse:
    """Enclosures of ``G = ĥ_B0(x)^{-1}`` (applied to matrices) over a set of ``x``.

    With ``P ≈ ĥ_B0(mid)^{-1}`` a float matrix and ``E = P ĥ_B0 - I``, ``β = ||E||_∞ < 1``
    gives ``G = (I + F) P`` with ``||F||_∞ ≤ β' = β / (1 - β)``, so for any ``V``:
    ``G V = u + F u`` with ``u = P V`` and ``|(F u)_ij| ≤ β' max_k |u_kj|``.
    """

    def __init__(self, P: np.ndarray, M: Pair) -> None:
        w = P.shape[-1]
        Elo, Ehi = pmatmul(P, M)
        eye = np.eye(w)
        mag = np.maximum(np.abs(up(Ehi - eye)), np.abs(down(Elo - eye)))
        beta = np.max(_sum_up(mag), axis=-1)  # (B,)
        self.ok = beta < 0.5
        with np.errstate(divide="ignore", invalid="ignore"):
            bp = up(beta / down(1.0 - beta))
        self.beta = np.where(self.ok, bp, np.inf)
        self.P = P

    def apply(self, V: Pair) -> Pair:
        ulo, uhi = pmatmul(self.P, V)
        mag = np.max(np.maximum(np.abs(ulo), np.abs(uhi)), axis=-2, keepdims=True)
        with np.errstate(invalid="ignore"):
            rad = up(self.beta[:, None, None] * mag)
        rad = np.where(np.isnan(rad), np.inf, rad)
        return down(ulo - rad), up(uhi + rad)


def _rigid(robot: Robot, plo, phi, f_req, external, alo, ahi, rotation, prm: RobotBounds):
    r"""dof 3 and 6: the basis form of the facets with slope enclosures.

    With a basis ``B0`` of ``w`` columns (nonsingular over the box, the one with the largest
    normalised determinant at the midpoint), the extra columns ``N`` and
    ``Y = ĥ_B0^{-1} ĥ_N`` (``w × e``), the normal of the facet subset ``S`` is, up to the
    factor ``±det ĥ_B0`` (of constant sign over the box),

        c_S = λ^T ĥ_B0^{-1}[F, :],   λ = wedge(Y[F, T]),   F = B0 \ S,  T = S ∩ N,

    (``λ = 1`` if ``T`` is empty) and ``c_S · ĥ_l`` is ``λ_l`` for ``l`` in ``F``,
    ``λ · Y[F, l]`` for ``l`` in ``N \ S``, 0 on ``S``.  Also ``c_S · w = λ · z[F]`` with
    ``z = ĥ_B0^{-1} w_ext``.  Everything is carried in slope form (:mod:`.meanvalue`); the
    slopes of the inverse follow from ``ĥ_B0(x) y(x) = ĥ_N(x)``:
    ``y(x) - y(m) = G(x)[(ĥ_N(x) - ĥ_N(m)) - (ĥ_B0(x) - ĥ_B0(m)) y(m)]``.
    """
    d, B = plo.shape
    m, w, nf = robot.m, robot.wrench_dim, force_rows(robot)
    if alo is not None:
        R, dR = _rotation_parts(robot.dof, alo, ahi, derivatives=True)
        amid = np.minimum(np.maximum(0.5 * alo + 0.5 * ahi, alo), ahi)
        Rmid = _rotation_parts(robot.dof, amid, amid, derivatives=False)[0]
    else:
        Rp = np.eye(d) if rotation is None else np.asarray(rotation, dtype=float)
        Rb = np.broadcast_to(Rp[:, :, None], (d, d, B))
        R, dR, Rmid = (Rb, Rb), [], (Rb, Rb)
    pmid = np.minimum(np.maximum(0.5 * plo + 0.5 * phi, plo), phi)
    radius_rows = [np.maximum(up(phi - pmid), up(pmid - plo))]
    if alo is not None:
        radius_rows.append(np.maximum(up(ahi - amid), up(amid - alo)))
    if prm.k:  # the design parameters are slope dimensions too
        radius_rows.append(np.broadcast_to(prm.radius, (prm.k, B)))
    radii = np.concatenate(radius_rows)  # (nd, B)
    nd = radii.shape[0]

    e, b, _, hx = _columns(robot, plo, phi, R, prm.A, prm.B)
    _, _, _, hm = _columns(robot, pmid, pmid, Rmid, prm.A_mid, prm.B_mid)
    h = MV(hm, hx, _column_slopes(robot, e, b, R, dR, prm))  # (w, m, B)
    if prm.k:  # coordinates moved by one parameter are dependent: the slope range is tighter
        h = h.tighten(radii)
        hx = h.x
    a = h.apply(lambda t: t[:d])
    sq = a.apply(lambda t: t[0]).sqr()
    for r in range(1, d):
        sq = sq + a.take(r).sqr()
    rho = sq.sqrt()  # (m, B)
    rho = rho.tighten(radii)
    wires_ok = np.all(rho.x[0] > 0.0, axis=0)
    wext = _weight_mv(robot, R, Rmid, dR, nd, B, external, prm)  # (w, V, B)

    # basis per box: the one whose inverse is proven with the smallest β over the box
    bases = list(combinations(range(m), w))
    betas = np.full((len(bases), B), np.inf)
    hbx = np.transpose(hx[0], (2, 0, 1)), np.transpose(hx[1], (2, 0, 1))  # (B, w, m)
    hbm = mr_from_bounds(*hm)[0].transpose(2, 0, 1)
    for ib, b0 in enumerate(bases):
        cols = list(b0)
        Mm = hbm[:, :, cols]
        good = np.all(np.isfinite(Mm), axis=(1, 2))
        Mm = np.where(good[:, None, None], Mm, np.eye(w))
        good &= (
            np.abs(
                np.linalg.det(Mm / np.maximum(np.linalg.norm(Mm, axis=1, keepdims=True), 1e-300))
            )
            > 1e-12
        )
        Mm = np.where(good[:, None, None], Mm, np.eye(w))
        inv = _BasisInverse(np.linalg.inv(Mm), (hbx[0][:, :, cols], hbx[1][:, :, cols]))
        betas[ib] = np.where(good & inv.ok, inv.beta, np.inf)
    choice = np.argmin(betas, axis=0)
    found = np.isfinite(np.min(betas, axis=0))

    K = len(facet_subsets(m, w))
    glo = np.full((2 * K, B), -np.inf)
    ghi = np.full((2 * K, B), np.inf)
    nhi = np.full((2 * K, B), np.inf)
    full_rank = np.zeros(B, dtype=bool)
    for ib, b0 in enumerate(bases):
        sel = np.nonzero((choice == ib) & found)[0]
        if sel.size == 0:
            continue
        g_lo, g_hi, n_hi, ok = _rigid_basis(
            robot,
            b0,
            h.take((..., sel)),
            rho.take((..., sel)),
            wext.take((..., sel)),
            radii[:, sel],
            f_req,
            nf,
            prm.take(sel),
        )
        glo[:, sel] = np.where(ok, g_lo, -np.inf)
        ghi[:, sel] = np.where(ok, g_hi, np.inf)
        nhi[:, sel] = n_hi
        full_rank[sel] = ok
    glo = np.where(np.isnan(glo), -np.inf, glo)
    ghi = np.where(np.isnan(ghi), np.inf, ghi)
    nhi = np.where(np.isnan(nhi), np.inf, nhi)
    return glo, ghi, full_rank, wires_ok, nhi


def _rigid_basis(robot: Robot, b0, h: MV, rho: MV, wext: MV, radii, f_req, nf, prm):
    """The slacks of :func:`_rigid` for boxes sharing the basis ``b0``: ``(2K, B')``."""
    m, w = robot.m, robot.wrench_dim
    b0 = tuple(int(i) for i in b0)
    nn = [i for i in range(m) if i not in b0]
    B = radii.shape[1]
    # leading batch for the matrix algebra
    hb = h.apply(lambda t: np.transpose(t[:, list(b0)], (2, 0, 1)))  # (B, w, w)
    hn = h.apply(lambda t: np.transpose(t[:, nn], (2, 0, 1)))  # (B, w, e)
    wv = wext.apply(lambda t: np.transpose(t, (2, 0, 1)))  # (B, w, V)
    Pm = mr_from_bounds(*hb.m)[0]
    P = np.linalg.inv(np.where(np.isfinite(Pm), Pm, 0.0) + 0.0)
    GX = _BasisInverse(P, hb.x)
    Gm = _BasisInverse(P, hb.m)
    ok = GX.ok & Gm.ok & np.all(np.isfinite(P), axis=(1, 2))

    # G(X): start from (I + F) P, then refine twice by its own slope form
    # G(x) - G(m) = -G(x) (ĥ_B(x) - ĥ_B(m)) G(m)
    w_eye = np.broadcast_to(np.eye(w), (B, w, w))
    Gm_full = Gm.apply((w_eye, w_eye))
    GXf = GX.apply((w_eye, w_eye))
    rad3 = radii[:, :, None, None]
    for _ in range(2):
        sG = [arith.neg(*_imatmul_b(GXf, _imatmul_b(sb, Gm_full))) for sb in hb.s]
        GXf = MV(Gm_full, GXf, sG).enclose(rad3)

    def solve(rhs: MV) -> MV:
        """``G(x) v(x)`` in slope form for ``v`` = ``ĥ_N`` or ``w_ext``."""
        vm = Gm.apply(rhs.m)
        vx = GX.apply(rhs.x)
        s = [_imatmul_b(GXf, arith.sub(*sv, *_imatmul_b(sb, vm))) for sv, sb in zip(rhs.s, hb.s)]
        return MV(vm, vx, s)

    y = solve(hn).tighten(rad3)
    z = solve(wv).tighten(rad3)
    gm = (Gm_full[0][..., :nf], Gm_full[1][..., :nf])
    gx = (GXf[0][..., :nf], GXf[1][..., :nf])
    gs = [arith.neg(*_imatmul_b(GXf, _imatmul_b(sb, gm))) for sb in hb.s]
    Gf = MV(gm, gx, gs).tighten(rad3)  # rows of G, force columns: (B, w, nf)
    # batch last again
    y = y.apply(lambda t: np.transpose(t, (1, 2, 0)))  # (w, e, B)
    z = z.apply(lambda t: np.transpose(t, (1, 2, 0)))  # (w, V, B)
    Gf = Gf.apply(lambda t: np.transpose(t, (1, 2, 0)))  # (w, nf, B)
    nd = len(radii)
    gp_lo, gp_hi, gm_lo, gm_hi, n_hi = [], [], [], [], []
    for F, T, Rr in basis_groups(m, w, b0):
        Kt, t = T.shape
        if t == 0:
            one = np.ones((1, Kt, B))
            lam = MV.const(one, one, len(radii))
        else:
            lam = wedge_mv(y.take((F.T[:, None, :], T.T[None, :, :])))
            lam = lam.tighten(radii)
        # c · ĥ_l for l in F (λ) and l in R (λ · Y[F, l])
        cols = [np.array(b0)[F.T]]  # (t+1, Kt) column ids
        qs = [lam / rho.take(cols[0])]
        if Rr.shape[1]:
            YF = y.take((F.T[:, None, :], Rr.T[None, :, :]))
            DR = mv_sum(lam.take(f).take(None) * YF.take(f) for f in range(t + 1))  # (e-t, Kt, B)
            DR = DR.tighten(radii)
            cR = np.array(nn)[Rr.T]
            cols.append(cR)
            qs.append(DR / rho.take(cR))
        pos_terms, neg_terms = [], []
        for q, c in zip(qs, cols):
            tmin = _tau_mv(prm.tau_min, prm.tau_min_mid, prm.dtau_min, c, nd)
            tmax = _tau_mv(prm.tau_max, prm.tau_max_mid, prm.dtau_max, c, nd)
            pp = phi_mv(q, tmin, tmax)
            pm = phi_mv(-q, tmin, tmax)
            for i in range(c.shape[0]):
                pos_terms.append(pp.take(i))
                neg_terms.append(pm.take(i))
        Np, Nm = mv_sum(pos_terms), mv_sum(neg_terms)
        w_terms, f_terms = [], []
        for f in range(t + 1):
            lf = lam.take(f)  # (Kt, B)
            w_terms.append(lf.take((slice(None), None)) * z.take(F[:, f]))
            f_terms.append(lf.take(None) * Gf.take(F[:, f]).apply(lambda a: np.moveaxis(a, 1, 0)))
        cw = mv_sum(w_terms)  # (Kt, V, B): one per corner of the weight's box
        cf = mv_sum(f_terms)  # (nf, Kt, B)
        cf = cf.tighten(radii)
        n2 = cf.apply(lambda a: a[0]).sqr()
        for r in range(1, nf):
            n2 = n2 + cf.take(r).sqr()
        nrm = n2.sqrt()
        n_hi.append(nrm.enclose(radii)[1])
        fr = nrm.scale(float(f_req))
        Np_v, Nm_v, fr_v = (u.take((slice(None), None)) for u in (Np, Nm, fr))
        # g is linear in w_ext, which is multilinear in the mass and the centre of mass: over
        # their box it lies between its values at the corners
        gp = (Np_v + cw - fr_v).enclose(radii)
        gn = (Nm_v - cw - fr_v).enclose(radii)
        gp_lo.append(np.min(gp[0], axis=1))
        gp_hi.append(np.max(gp[1], axis=1))
        gm_lo.append(np.min(gn[0], axis=1))
        gm_hi.append(np.max(gn[1], axis=1))
    glo = np.concatenate(gp_lo + gm_lo)
    ghi = np.concatenate(gp_hi + gm_hi)
    return glo, ghi, np.concatenate(n_hi + n_hi), ok


def _tau_mv(box: Pair, mid: Pair, deriv: np.ndarray, c: np.ndarray, nd: int) -> Limit:
    """Tension limits of the wires ``c`` as a slope triple (an interval pair without design
    parameters): slopes 0 in the pose axes, the exact derivatives in the parameters."""
    cbox = (box[0][c], box[1][c])
    if deriv.shape[0] == 0:
        return cbox
    slopes: list[Pair | None] = [None] * (nd - deriv.shape[0])
    for dt in deriv:
        v = dt[c][..., None]
        slopes.append((v, v) if np.any(v) else None)
    return LimitMV(m=(mid[0][c], mid[1][c]), x=cbox, s=slopes)


def _point_slacks(robot, f_req, external, prm: RobotBounds, subsets, rho, D, c, cf):
    """dof 2: the slacks from the exact linear cross products of :func:`_parts_point`."""
    m, w = robot.m, robot.wrench_dim
    K = subsets.shape[0]
    B = rho[0].shape[1]
    member = np.zeros((K, m), dtype=bool)
    member[np.arange(K)[:, None], subsets] = True
    mem = member[..., None]
    Dlo = np.where(mem, 0.0, D[0])
    Dhi = np.where(mem, 0.0, D[1])
    full_rank = np.any((Dlo > 0.0) | (Dhi < 0.0), axis=(0, 1))
    wires_ok = np.all(rho[0] > 0.0, axis=0)
    qlo, qhi = arith.div(Dlo, Dhi, rho[0][None], rho[1][None])  # c_k · h_l
    qlo = np.where(mem, 0.0, qlo)
    qhi = np.where(mem, 0.0, qhi)
    tmn = prm.tau_min[0][None], prm.tau_min[1][None]  # (1, m, n)
    tmx = prm.tau_max[0][None], prm.tau_max[1][None]
    pp = _phi(qlo, qhi, tmn, tmx)
    pm = _phi(-qhi, -qlo, tmn, tmx)
    Np = _sum([(pp[0][:, i], pp[1][:, i]) for i in range(m)])  # (K, B)
    Nm = _sum([(pm[0][:, i], pm[1][:, i]) for i in range(m)])
    wlo, whi = _weight_wrench(robot, B, external, prm)  # (2, B)
    cw = _sum([arith.mul(c[0][r], c[1][r], wlo[r][None], whi[r][None]) for r in range(w)])
    Np = arith.add(*Np, *cw)
    Nm = arith.sub(*Nm, *cw)
    fr = _scale(cf[0], cf[1], float(f_req))
    gp = arith.sub(*Np, *fr)
    gm = arith.sub(*Nm, *fr)
    glo = np.concatenate([gp[0], gm[0]])
    ghi = np.concatenate([gp[1], gm[1]])
    # NaN can only come from inf - inf (a wire of length ~0): make it the whole line
    glo = np.where(np.isnan(glo), -np.inf, glo)
    ghi = np.where(np.isnan(ghi), np.inf, ghi)
    nhi = np.concatenate([cf[1], cf[1]])
    return glo, ghi, full_rank, wires_ok, np.where(np.isnan(nhi), np.inf, nhi)
