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

**Point platform (dof 2).**  ``c_j = (a_jy, -a_jx)`` and
``c_j·ĥ_i = -cross(A_j - p, A_i - p) = -(cross(A_j, A_i) + cross(A_i - A_j, p))``, linear in
``p``: its interval is exact up to rounding.

**Rigid platforms (dof 3, 6).**  The natural interval extension of a 5×5 determinant loses
everything to cancellation, so the columns are enclosed in **mean-value form**
``ĥ_l(x) ∈ ĥ_l(x_mid) + Σ_j J_lj(X) [-r_j, r_j]`` (``J`` the interval Jacobian over the box
``X``; at fixed orientation ``ĥ`` is affine in ``p`` and this is exact), and **preconditioned**
per facet subset ``S_k`` by a point matrix ``A_k ≈ [M_c | c_c]^{-1}`` built from the midpoint
columns.  Since ``wedge(A M) = det(A) A^{-T} wedge(M)``, with ``T_l = A_k ĥ_l`` and
``c' = wedge(T_S)``:

    c'·T_l = det(A_k) c_k·ĥ_l,   c'·(A_k w) = det(A_k) c_k·w,   A_k^T c' = det(A_k) c_k,

so every ``g`` computed from ``(c', T)`` is ``|det A_k|`` times a true ``g`` (the two signs
swap when ``det A_k < 0``).  ``T_S`` is then close to ``[I; 0]`` and its interval wedge is
tight; ``A_k`` is proven invertible (``||A_k G_k - I||_∞ < 1``, rigorously bounded) or the
subset is left unproven.
"""

from __future__ import annotations

import numpy as np

from ..interval import arith, elementary
from ..interval.linalg import mr_from_bounds, mr_matmul, mr_to_bounds
from ..interval.rounding import up
from ..robot import Robot
from .loads import force_rows
from .meanvalue import MV, phi_mv, pmatmul_mv, wedge_mv
from .wedge import facet_subsets, wedge_float

__all__ = ["interval_rotation", "slack_enclosures"]

_PI_LO = float(np.nextafter(np.pi, -np.inf))
_PI_HI = float(np.nextafter(np.pi, np.inf))


# -- small interval helpers (pairs of arrays) ---------------------------------------------
def _sum(terms):
    lo, hi = terms[0]
    for tlo, thi in terms[1:]:
        lo, hi = arith.add(lo, hi, tlo, thi)
    return lo, hi


def _mul(*fs):
    lo, hi = fs[0]
    for f in fs[1:]:
        lo, hi = arith.mul(lo, hi, *f)
    return lo, hi


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


def interval_rotation(dof: int, alo: np.ndarray, ahi: np.ndarray):
    """Enclosure ``(Rlo, Rhi)`` ``(d, d, B)`` of the rotations over angle boxes (degrees)."""
    return _rotation_parts(dof, alo, ahi, derivatives=False)[0]


def _matvec_point(R, V):
    """``R v_i`` for interval ``R`` ``(d, d, B)`` and point vectors ``V`` ``(m, d)``: ``(m, d, B)``."""
    Rlo, Rhi = R
    d = V.shape[1]
    terms = [
        _scale(Rlo[None, :, c, :], Rhi[None, :, c, :], V[:, c][:, None, None]) for c in range(d)
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
    """Enclosure of ``φ(s) = τmax max(s, 0) + τmin min(s, 0)`` (``τ`` broadcast)."""
    plo, phi = _scale(np.maximum(slo, 0.0), np.maximum(shi, 0.0), tmax)
    nlo, nhi = _scale(np.minimum(slo, 0.0), np.minimum(shi, 0.0), tmin)
    return arith.add(plo, phi, nlo, nhi)


def _mag(lo, hi):
    return np.maximum(np.abs(lo), np.abs(hi))


# -- the robot's columns ------------------------------------------------------------------
def _columns(robot: Robot, plo, phi, R):
    """Natural enclosures over the box: ``e = A - p``, ``b = R B``, ``a = e - b`` ``(m, d, B)``
    and the unnormalised columns ``ĥ`` ``(w, m, B)`` (dof 3, 6)."""
    A = robot.A[:, :, None]
    e = arith.sub(A, A, plo[None], phi[None])
    b = _matvec_point(R, robot.B)
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


def _column_slopes(robot: Robot, e, b, dR) -> list:
    """Interval enclosures ``(w, m, B)`` of ``∂ĥ/∂x_j`` over the box, per axis ``j``.

    Positions: ``∂a/∂p_j = -e_j``, ``∂(b × (A - p))/∂p_j = -b × e_j``; angles:
    ``∂a/∂α = -∂b/∂α``, ``∂(b × (A - p))/∂α = ∂b/∂α × (A - p)``, ``∂b/∂α = (∂R/∂α) B``.
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
        db = _matvec_point(dRj, robot.B)  # (m, d, B)
        dbt = (np.moveaxis(db[0], 1, 0), np.moveaxis(db[1], 1, 0))
        if d == 2:
            mom = _cross2(dbt, et)
            mom = (mom[0][None], mom[1][None])
        else:
            mom = _cross3(dbt, et)
        nlo, nhi = arith.neg(*dbt)
        out.append((np.concatenate([nlo, mom[0]]), np.concatenate([nhi, mom[1]])))
    return out


def _upper_absmatmul(absA, X):
    """Rigorous upper bound of ``|A| @ X`` for non-negative ``X``."""
    c, r = mr_matmul(absA, None, X, None)
    return up(c + r)


def _weight_wrench(robot: Robot, R, B: int, external):
    """Enclosure of ``w_ext`` (weight about the platform origin, plus ``external``): ``(w, B)``."""
    d = robot.dim
    mass = np.full(d, robot.mass)
    flo, fhi = arith.mul(mass, mass, robot.gravity, robot.gravity)  # weight = mass * g
    f = (np.broadcast_to(flo[:, None], (d, B)), np.broadcast_to(fhi[:, None], (d, B)))
    if robot.dof == 2:
        wlo, whi = f
    else:
        glo, ghi = _matvec_point(R, robot.com[None, :])  # (1, d, B)
        g = (glo[0], ghi[0])
        if robot.dof == 3:
            mlo, mhi = _cross2(g, f)
            mlo, mhi = mlo[None], mhi[None]
        else:
            mlo, mhi = _cross3(g, f)
        wlo = np.concatenate([f[0], mlo])
        whi = np.concatenate([f[1], mhi])
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
    external=None,
    alo: np.ndarray | None = None,
    ahi: np.ndarray | None = None,
    rotation: np.ndarray | None = None,
):
    """Enclosures of every ``g_k^±`` over ``B`` boxes (batch last).

    ``plo``, ``phi``: ``(d, B)`` position bounds (cm); ``alo``, ``ahi``: ``(na, B)`` angle
    bounds (degrees; dof 3: θ, dof 6: yaw, pitch, roll) or ``None`` for the fixed
    ``rotation`` (a ``(d, d)`` float matrix, identity if omitted).  Returns
    ``(glo, ghi, full_rank, wires_ok)`` with ``g`` of shape ``(2K, B)``.
    """
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        if robot.dof == 2:
            return _finish(robot, f_req, external, *_parts_point(robot, plo, phi))
        return _rigid(robot, plo, phi, f_req, external, alo, ahi, rotation)


def _parts_point(robot: Robot, plo, phi):
    A = robot.A
    m = robot.m
    subsets = facet_subsets(m, 2)
    j = subsets[:, 0]
    Aj = A[j][:, None, :]  # (K, 1, 2)
    Ai = A[None, :, :]  # (1, m, 2)
    e = arith.sub(A[:, :, None], A[:, :, None], plo[None], phi[None])  # a = A - p: (m, 2, B)
    elo, ehi = e
    rho = arith.sqrt(*_sum([arith.sqr(elo[:, r], ehi[:, r]) for r in range(2)]))
    # c_j · ĥ_i = -cross(a_j, a_i) = -(cross(A_j, A_i) + cross(A_i - A_j, p))
    c1 = arith.sub(
        *arith.mul(Aj[..., 0], Aj[..., 0], Ai[..., 1], Ai[..., 1]),
        *arith.mul(Aj[..., 1], Aj[..., 1], Ai[..., 0], Ai[..., 0]),
    )  # (K, m)
    dx = arith.sub(Ai[..., 0], Ai[..., 0], Aj[..., 0], Aj[..., 0])
    dy = arith.sub(Ai[..., 1], Ai[..., 1], Aj[..., 1], Aj[..., 1])
    t1 = arith.mul(dx[0][..., None], dx[1][..., None], plo[1], phi[1])
    t2 = arith.mul(dy[0][..., None], dy[1][..., None], plo[0], phi[0])
    cr = arith.add(c1[0][..., None], c1[1][..., None], *arith.sub(*t1, *t2))
    D = arith.neg(*cr)  # (K, m, B)
    c = (np.stack([elo[j, 1], -ehi[j, 0]]), np.stack([ehi[j, 1], -elo[j, 0]]))  # (2, K, B)
    cf = (rho[0][j], rho[1][j])  # ||c_j|| = ρ_j
    ok = np.ones((subsets.shape[0], plo.shape[1]), dtype=bool)
    return subsets, rho, D, c, cf, None, None, ok


def _weight_mv(robot: Robot, R, Rmid, dR, nd: int, B: int, external) -> MV:
    """``w_ext`` ``(w, B)`` as a slope triple (it depends on the angles through ``R com``)."""
    d = robot.dim
    mass = np.full(d, robot.mass)
    flo, fhi = arith.mul(mass, mass, robot.gravity, robot.gravity)  # weight = mass * g
    f = MV.const(np.broadcast_to(flo[:, None], (d, B)), np.broadcast_to(fhi[:, None], (d, B)), nd)
    com = robot.com[None, :]
    gm = _matvec_point(Rmid, com)
    gx = _matvec_point(R, com)
    z = np.zeros((1, d, B))
    gs = [(z, z)] * d + [_matvec_point(dRj, com) for dRj in dR]
    g = MV(gm, gx, gs).apply(lambda t: t[0])  # (d, B)

    def comp(u, i):
        return u.apply(lambda t: t[i])

    if robot.dof == 3:
        mom = comp(g, 0) * comp(f, 1) - comp(g, 1) * comp(f, 0)
        moms = [mom]
    else:
        moms = [
            comp(g, i) * comp(f, j) - comp(g, j) * comp(f, i) for i, j in ((1, 2), (2, 0), (0, 1))
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
        ex = np.asarray(external, dtype=float)[:, None]
        out = out + MV.const(np.broadcast_to(ex, (len(ex), B)), np.broadcast_to(ex, (len(ex), B)), nd)
    return out


def _rigid(robot: Robot, plo, phi, f_req, external, alo, ahi, rotation):
    """dof 3 and 6: preconditioned slope enclosures (see the module docstring)."""
    d, B = plo.shape
    m, w, nf = robot.m, robot.wrench_dim, force_rows(robot)
    subsets = facet_subsets(m, w)
    K = subsets.shape[0]
    if alo is not None:
        R, dR = _rotation_parts(robot.dof, alo, ahi, derivatives=True)
        amid = np.minimum(np.maximum(0.5 * alo + 0.5 * ahi, alo), ahi)
        Rmid = _rotation_parts(robot.dof, amid, amid, derivatives=False)[0]
    else:
        Rp = np.eye(d) if rotation is None else np.asarray(rotation, dtype=float)
        Rb = np.broadcast_to(Rp[:, :, None], (d, d, B))
        R, dR, Rmid = (Rb, Rb), [], (Rb, Rb)
    pmid = np.minimum(np.maximum(0.5 * plo + 0.5 * phi, plo), phi)
    radii = [np.maximum(up(phi - pmid), up(pmid - plo))]
    if alo is not None:
        radii.append(np.maximum(up(ahi - amid), up(amid - alo)))
    radii = np.concatenate(radii)  # (nd, B)
    nd = radii.shape[0]

    e, b, _, hx = _columns(robot, plo, phi, R)
    _, _, _, hm = _columns(robot, pmid, pmid, Rmid)
    h = MV(hm, hx, _column_slopes(robot, e, b, dR))  # (w, m, B)
    a = h.apply(lambda t: t[:d])
    sq = a.apply(lambda t: t[0]).sqr()
    for r in range(1, d):
        sq = sq + a.apply(lambda t, r=r: t[r]).sqr()
    rho = sq.sqrt()  # (m, B)
    rho_x = rho.enclose(radii)

    # preconditioners A_k from the midpoint columns; proof that each is invertible
    hc = mr_from_bounds(*hm)[0]  # (w, m, B)
    Mc = hc[:, subsets.T]  # (w, w-1, K, B)
    cc = wedge_float(Mc)  # (w, K, B)
    G = np.concatenate([Mc, cc[:, None]], axis=1)
    G = np.transpose(G, (3, 2, 0, 1))  # (B, K, w, w)
    G = G / np.maximum(np.linalg.norm(G, axis=2, keepdims=True), 1e-300)
    good = np.isfinite(G).all(axis=(2, 3))
    G = np.where(good[..., None, None], G, np.eye(w))
    good &= np.abs(np.linalg.det(G)) > 1e-10
    G = np.where(good[..., None, None], G, np.eye(w))
    Ak = np.linalg.inv(G)
    pc, pr = mr_matmul(Ak, None, G, None)
    resid = up(np.abs(pc - np.eye(w)) + pr)
    ok = (np.max(up(np.sum(resid, axis=3)), axis=2) < 0.5).T  # (K, B)

    T = pmatmul_mv(Ak, h.apply(lambda t: np.transpose(t, (2, 0, 1))[:, None]))  # (B, K, w, m)
    T = T.apply(lambda t: np.transpose(t, (2, 3, 1, 0)))  # (w, m, K, B)
    kk = np.arange(K)[None, :]
    c = wedge_mv(T.apply(lambda t: t[:, subsets.T, kk])).tighten(radii)  # (w, K, B)
    D = None
    for r in range(w):
        term = c.apply(lambda t, r=r: t[r][:, None, :]) * T.apply(
            lambda t, r=r: np.transpose(t[r], (1, 0, 2))
        )
        D = term if D is None else D + term  # (K, m, B)
    member = np.zeros((K, m), dtype=bool)
    member[np.arange(K)[:, None], subsets] = True
    D = D.where(member[..., None], 0.0)
    Dlo, Dhi = D.enclose(radii)
    full_rank = np.any(((Dlo > 0.0) | (Dhi < 0.0)) & ok[:, None, :], axis=(0, 1))
    q = (D / rho.apply(lambda t: t[None])).where(member[..., None], 0.0)
    tmx = robot.tau_max[None, :, None]
    tmn = robot.tau_min[None, :, None]
    pp = phi_mv(q, tmn, tmx)
    pm = phi_mv(-q, tmn, tmx)
    Np = pp.apply(lambda t: t[:, 0])
    Nm = pm.apply(lambda t: t[:, 0])
    for i in range(1, m):
        Np = Np + pp.apply(lambda t, i=i: t[:, i])
        Nm = Nm + pm.apply(lambda t, i=i: t[:, i])
    wext = _weight_mv(robot, R, Rmid, dR, nd, B, external)  # (w, B)
    Aw = pmatmul_mv(Ak, wext.apply(lambda t: t.T[:, None, :, None]))  # (B, K, w, 1)
    Aw = Aw.apply(lambda t: np.transpose(t[..., 0], (2, 1, 0)))  # (w, K, B)
    cw = None
    for r in range(w):
        term = c.apply(lambda t, r=r: t[r]) * Aw.apply(lambda t, r=r: t[r])
        cw = term if cw is None else cw + term
    cT = pmatmul_mv(
        np.swapaxes(Ak, 2, 3), c.apply(lambda t: np.transpose(t, (2, 1, 0))[..., None])
    )  # (B, K, w, 1): A_k^T c'
    cT = cT.apply(lambda t: np.transpose(t[..., 0], (2, 1, 0)))  # (w, K, B)
    n2 = cT.apply(lambda t: t[0]).sqr()
    for r in range(1, nf):
        n2 = n2 + cT.apply(lambda t, r=r: t[r]).sqr()
    cf = n2.sqrt().scale(float(f_req))
    gp = (Np + cw - cf).enclose(radii)
    gm = (Nm - cw - cf).enclose(radii)
    bad = ~ok
    glo = np.concatenate([np.where(bad, -np.inf, gp[0]), np.where(bad, -np.inf, gm[0])])
    ghi = np.concatenate([np.where(bad, np.inf, gp[1]), np.where(bad, np.inf, gm[1])])
    glo = np.where(np.isnan(glo), -np.inf, glo)
    ghi = np.where(np.isnan(ghi), np.inf, ghi)
    wires_ok = np.all(rho_x[0] > 0.0, axis=0)
    return glo, ghi, full_rank, wires_ok


def _finish(robot, f_req, external, subsets, rho, D, c, cf, Ak, w_ext, ok):
    m, w = robot.m, robot.wrench_dim
    K = subsets.shape[0]
    B = rho[0].shape[1]
    member = np.zeros((K, m), dtype=bool)
    member[np.arange(K)[:, None], subsets] = True
    mem = member[..., None]
    Dlo = np.where(mem, 0.0, D[0])
    Dhi = np.where(mem, 0.0, D[1])
    full_rank = np.any(((Dlo > 0.0) | (Dhi < 0.0)) & ok[:, None, :], axis=(0, 1))
    wires_ok = np.all(rho[0] > 0.0, axis=0)
    qlo, qhi = arith.div(Dlo, Dhi, rho[0][None], rho[1][None])  # c_k · h_l
    qlo = np.where(mem, 0.0, qlo)
    qhi = np.where(mem, 0.0, qhi)
    tmx = robot.tau_max[None, :, None]
    tmn = robot.tau_min[None, :, None]
    pp = _phi(qlo, qhi, tmn, tmx)
    pm = _phi(-qhi, -qlo, tmn, tmx)
    Np = _sum([(pp[0][:, i], pp[1][:, i]) for i in range(m)])  # (K, B)
    Nm = _sum([(pm[0][:, i], pm[1][:, i]) for i in range(m)])
    if robot.dof == 2:
        wlo, whi = _weight_wrench(robot, None, B, external)  # (2, B)
        cw = _sum(
            [arith.mul(c[0][r], c[1][r], wlo[r][None], whi[r][None]) for r in range(w)]
        )
    else:
        wlo, whi = w_ext
        if external is not None:
            ex = np.asarray(external, dtype=float)[:, None]
            wlo, whi = arith.add(wlo, whi, ex, ex)
        wc, wr = mr_from_bounds(wlo, whi)  # (w, B)
        awc, awr = mr_matmul(Ak, None, wc.T[:, None, :, None], wr.T[:, None, :, None])
        awlo, awhi = mr_to_bounds(awc[..., 0], awr[..., 0])  # (B, K, w)
        cw = _sum(
            [arith.mul(c[0][r], c[1][r], awlo[..., r].T, awhi[..., r].T) for r in range(w)]
        )
    Np = arith.add(*Np, *cw)
    Nm = arith.sub(*Nm, *cw)
    fr = _scale(cf[0], cf[1], float(f_req))
    gp = arith.sub(*Np, *fr)
    gm = arith.sub(*Nm, *fr)
    bad = ~ok  # unproven preconditioner: this subset decides nothing
    glo = np.concatenate([np.where(bad, -np.inf, gp[0]), np.where(bad, -np.inf, gm[0])])
    ghi = np.concatenate([np.where(bad, np.inf, gp[1]), np.where(bad, np.inf, gm[1])])
    # NaN can only come from inf - inf (a wire of length ~0): make it the whole line
    glo = np.where(np.isnan(glo), -np.inf, glo)
    ghi = np.where(np.isnan(ghi), np.inf, ghi)
    return glo, ghi, full_rank, wires_ok
