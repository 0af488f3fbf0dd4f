"""Forward-kinematics equation systems of Merlet (2007), built from a robot description.

Unknowns are world coordinates of ``k`` platform points ``P_1..P_k`` and the wire lengths
``ρ_1..ρ_m``; the control vector ``u`` enters as *parameters* (:func:`certsolve.expr.param`)
so one compiled system serves every ``u``.  Every attachment and the centre of mass are
affine combinations of the chosen points (eq. 8): ``B_i = Σ_j l_ij P_j`` with ``Σ_j l_ij = 1``.

Equations (all formulations):

* length, one per wire: ``|A_i - B_i|² - ρ_i² = 0``;
* rigidity: ``|P_a - P_b|² - d_ab² = 0`` for every pair of chosen points;
* equilibrium (eq. 3), with ``w_i = τ_i / ρ_i`` and ``τ_i = k(1 - L0 / (ρ_i + V + K u_i))``
  (eqs. 1-2): forces ``Σ_i w_i (A_i - B_i) + m g = 0`` and moments about the domain centre
  ``O``: ``Σ_i w_i (B_i - O) × (A_i - O) + (G - O) × m g = 0`` (``(B - O) × (B - O) = 0``
  makes the moment linear in the points).

Formulations (sizes for MARIONET's 7 wires):

* ``general-19``: 4 non-coplanar points (12 coordinates) + 7 ρ: 7 + 6 + 6 equations.  Four
  points with fixed distances also fit the platform's *mirror image*; the signed volume
  ``(P2-P1)·((P3-P1)×(P4-P1))`` must have the sign it has on the platform (a checked
  constraint: an improper pose is never reported), and the redundant equality
  ``signed volume = 6V`` contracts boxes.  In the ``frame`` formulation the fourth point
  is also tied to the other three by the redundant ``E_4 = a E_2 + b E_3 + c (E_2 × E_3)``
  (the coefficients of the platform's own ``e_4`` in the basis ``e_2, e_3, e_2 × e_3``),
  which holds for every proper pose and excludes the mirror ones.
* ``T-16``: the T-platform has only 3 distinct attachment points (9 coordinates + 7 ρ);
  ``almost-planar-13``: 4 wires on a planar platform, 3 points (9 + 4).  A platform whose
  attachments and centre of mass are coplanar is its own mirror image, so no sign is needed.
* ``planar-10``: planar robots (dof 3), 3 points in the plane (6 + 4); the signed area
  fixes the orientation as for ``general-19``.
* ``frame`` (the default, ``auto``): the paper's system for this robot in a *platform
  frame*: the reference point ``P_1`` and the edge vectors ``E_j = P_j - P_1`` instead of
  the points, moments about ``P_1``.  A linear change of variables (same equations, same
  count, same solutions, named ``frame-<paper system>``) that separates translation from
  rotation; with partial Newton on the translation sub-system it needs 5-8 times fewer
  boxes than the paper's variables (see ``benchmarks/fk_bench.py``).
* ``pose``: position and Z-Y-X Euler angles of the platform + ρ (6 + m unknowns), the
  classical parameterisation, for comparison.
* ``points``: the paper's 3-point system for a planar platform (attachments and centre of
  mass coplanar) with more than three distinct attachment points, which is what ``auto``
  puts in the platform frame for such a robot; on the T-platform and the almost-planar
  robot it is the same system as ``T-16`` / ``almost-planar-13``, node for node.  It is
  there for comparison: ``frame`` needs 4-5x fewer boxes (τ <= 10 N, u = 0: T-16 6117 vs
  1479 boxes, almost-planar 24392 vs 4703).

One builder (:func:`_platform_formulation`) writes the physics of every point formulation
once; the coordinates are its parameter (:class:`_Points`: the paper's world coordinates,
moments about the domain centre; :class:`_Frame`: ``P_1`` and edge vectors, moments about
``P_1``).  A ``reduced`` variant that eliminated ρ (``ρ_i = |A_i - B_i|``, 6-12 unknowns)
was removed: on the bundled robots it never won (τ <= 10 N and 60 N, u as in
``tests/test_fk_frame.py``: 1.6-4.6x the boxes of the paper's system, 15-24x those of
``frame``, 1.4-3.7x the paper system's CPU time).

Search domain: every platform point lies in the robot's ``domain`` box (the non-chosen
attachments through checked constraints), and ``ρ_i`` in the range allowed by the tension
limits through eq. (7), intersected with the distances from ``A_i`` to that box.  Wires
sharing an attachment point also get the redundant linear equation obtained by subtracting
their length equations (section III-B of the paper).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from ..expr import Constraint, System, const, cos, esum, param, sin, sqr, var
from ..expr.node import Expr
from ..expr.polynomial import gauss_jordan
from ..robot.geometry import rotation_2d, rotation_zyx
from ..robot.model import Robot

__all__ = ["FKFormulation", "build_formulation", "FORMULATIONS", "choose_formulation"]

FORMULATIONS = (
    "auto",
    "general-19",
    "T-16",
    "almost-planar-13",
    "planar-10",
    "points",
    "frame",
    "pose",
)


@dataclass
class FKFormulation:
    """A forward-kinematics system and how to read a robot pose back from its solutions."""

    name: str
    robot: Robot
    system: System
    kind: str  # "points" | "frame" | "pose"
    Q: np.ndarray | None = None  # (k, d) chosen points, platform frame
    L: np.ndarray | None = None  # (m, k) affine coefficients of the attachments
    lG: np.ndarray | None = None  # (k,) affine coefficients of the centre of mass
    info: dict = field(default_factory=dict)
    # kind "frame": the first k*d variables are P_1 and the edge vectors P_j - P_1

    def points_from(self, x) -> np.ndarray:
        """The chosen points ``(k, d)`` from a vector of the system's variables."""
        k, d = self.n_points, self.robot.dim
        P = np.array(x[: k * d], dtype=float).reshape(k, d)
        if self.kind == "frame":
            P[1:] = P[0] + P[1:]
        return P

    def coordinates_of(self, P) -> np.ndarray:
        """The inverse of :meth:`points_from`: the first ``k*d`` variables for points ``P``."""
        P = np.array(P, dtype=float)
        if self.kind == "frame":
            P[1:] = P[1:] - P[0]
        return P.ravel()

    @property
    def n_points(self) -> int:
        return 0 if self.Q is None else self.Q.shape[0]

    def parameters_for(self, u) -> dict[str, float]:
        u = np.asarray(u, dtype=float)
        return {f"u{i + 1}": float(v) for i, v in enumerate(u)}


# -- helpers ----------------------------------------------------------------------------------


def _exact(a) -> list[list[Fraction]]:
    """A float matrix (or vector, as one row) in exact rationals: every float is one."""
    return [[Fraction(float(x)) for x in row] for row in np.atleast_2d(np.asarray(a, dtype=float))]


def _matmul(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
    return [[sum((x * y for x, y in zip(row, col)), Fraction(0)) for col in zip(*b)] for row in a]


def _det(rows: list[list[Fraction]]) -> Fraction:
    """Exact determinant (Laplace expansion along the first row; 2x2 and 3x3 here)."""
    if not rows:
        return Fraction(1)
    minors = ([r[:j] + r[j + 1 :] for r in rows[1:]] for j in range(len(rows)))
    return sum(
        ((-1) ** j * rows[0][j] * _det(m) for j, m in enumerate(minors) if rows[0][j]), Fraction(0)
    )


def _least_squares(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
    """The exact least-squares solution ``X`` of ``a X = b`` (``a`` of full column rank):
    the normal equations ``aᵀa X = aᵀb`` by Gauss-Jordan in rationals.  It is the solution
    itself when ``a X = b`` has one."""
    at = [list(col) for col in zip(*a)]
    n = len(at)
    rows = [p + q for p, q in zip(_matmul(at, a), _matmul(at, b), strict=True)]
    if gauss_jordan(rows, n) < n:
        raise ValueError("the chosen platform points are not affinely independent")
    return [row[n:] for row in rows]


def _rounded(q: list[list[Fraction]]) -> np.ndarray:
    """Exact rationals rounded to the nearest floats (``float(Fraction)`` rounds correctly)."""
    return np.array([[float(x) for x in row] for row in q])


def _affine_coordinates(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Coefficients ``l`` with ``X_i = Σ_j l_ij Q_j``, ``Σ_j l_ij = 1`` (exact fit required).

    Solved in exact rationals from the float coordinates and rounded to nearest, so the
    coefficients -- and which of them are 0 or 1, which decides the terms and nodes the
    builders write -- are the same on every CPU.  A least-squares solve with LAPACK left
    BLAS-kernel noise in them (``1 - 2e-16`` on one kernel, ``1 + 4e-16`` on another; a
    product by exactly 1 or a shared constant folds in the graph): the planar robot's
    system had 316 nodes with OpenBLAS's Haswell kernel and 330 with its SkylakeX one.  A
    platform whose points are exact affine combinations of the chosen ones (every bundled
    robot) gets its exact coefficients.
    """
    k = Q.shape[0]
    M = _exact(np.vstack([Q.T, np.ones((1, k))]))  # (d+1, k)
    rhs = _exact(np.vstack([X.T, np.ones((1, X.shape[0]))]))
    coef = _least_squares(M, rhs)
    resid = max(abs(r - s) for rr, sr in zip(_matmul(M, coef), rhs) for r, s in zip(rr, sr))
    if resid > Fraction(1e-9) * (1 + Fraction(float(np.max(np.abs(X))))):
        raise ValueError("a platform point is not an affine combination of the chosen points")
    out = _rounded(coef).T
    out[np.abs(out) < 1e-14] = 0.0
    return out


def _snap_rows(L: np.ndarray, robot: Robot) -> np.ndarray:
    """Make the affine coefficients of wires sharing an attachment bitwise identical.

    Redundant equations drop the wires attached at a point (zero lever) or subtract the
    length equations of two such wires; they are exact consequences of the system only if
    those wires have exactly the same coefficients.  Rows within 1e-12 of a unit vector
    become that unit vector (the attachment *is* a chosen point).
    """
    L = L.copy()
    k = L.shape[1]
    for i in range(L.shape[0]):
        j = int(np.argmax(np.abs(L[i])))
        if np.max(np.abs(L[i] - np.eye(k)[j])) <= 1e-12:
            L[i] = np.eye(k)[j]
    _, gidx = robot.attachment_groups()
    for g in np.unique(gidx):
        members = np.flatnonzero(gidx == g)
        L[members] = L[members[0]]
    return L


def _choose_points(points: np.ndarray, k: int) -> list[int]:
    """The ``k`` points spanning the largest simplex (best conditioned affine frame).

    The squared volumes (Gram determinants of the edges) are compared exactly: a
    symmetric platform has equal simplices, and a float determinant would pick among them
    by rounding noise."""
    best, best_vol = None, Fraction(-1)
    for combo in itertools.combinations(range(points.shape[0]), k):
        P = points[list(combo)]
        E = _exact(P[1:] - P[0]) if k > 1 else []
        vol = _det(_matmul(E, [list(c) for c in zip(*E)])) if E else Fraction(0)
        if vol > best_vol:  # exact: of equal simplices (a symmetric platform) the first
            best, best_vol = list(combo), vol
    if best is None or best_vol <= 1e-12:
        raise ValueError(f"the platform has no {k} affinely independent attachment points")
    return best


def _is_coplanar(points: np.ndarray) -> bool:
    if points.shape[0] <= 3:
        return True
    E = points[1:] - points[0]
    s = np.linalg.svd(E, compute_uv=False)
    return bool(s[-1] <= 1e-9 * max(1.0, s[0])) if s.size >= 3 else True


def choose_formulation(robot: Robot) -> str:
    """The paper's system for this robot (``auto`` uses it in the platform frame)."""
    if robot.dof == 2:
        raise ValueError(
            "point robots (dof 2) have no rigid platform: forward kinematics of the "
            "elastic model needs dof 3 or 6"
        )
    if robot.dof == 3:
        return "planar-10"
    pts, _ = robot.attachment_groups()
    allpts = np.vstack([pts, robot.com[None]])
    if _is_coplanar(allpts) and pts.shape[0] >= 3:
        if robot.m == 4:
            return "almost-planar-13"
        if pts.shape[0] == 3:
            return "T-16"
        return "points"
    return "general-19"


def _rho_domain(robot: Robot, u: np.ndarray, domain: np.ndarray):
    """Per-wire [ρ_min, ρ_max]: tension limits through eq. (7), intersected with geometry."""
    c = robot.V + robot.K * u
    lo_t = robot.k * robot.L0 / (robot.k - robot.tau_min) - c
    hi_t = robot.k * robot.L0 / (robot.k - robot.tau_max) - c
    near = np.clip(robot.A, domain[:, 0], domain[:, 1])
    dmin = np.linalg.norm(robot.A - near, axis=1)
    far = np.where(
        np.abs(robot.A - domain[:, 0]) > np.abs(robot.A - domain[:, 1]), domain[:, 0], domain[:, 1]
    )
    dmax = np.linalg.norm(robot.A - far, axis=1)
    lo = np.maximum(np.maximum(lo_t, dmin), 0.0)
    hi = np.minimum(hi_t, dmax)
    return lo, hi


def _wire_weights(robot: Robot, rho: list[Expr]) -> list[Expr]:
    """``w_i = τ_i / ρ_i`` with ``τ_i = k (1 - L0 / (ρ_i + V + K u_i))`` (eqs. 1, 2)."""
    out = []
    for i in range(robot.m):
        c = robot.V[i] + robot.K[i] * param(f"u{i + 1}")
        tau = robot.k[i] * (1.0 - robot.L0[i] / (rho[i] + c))
        out.append(tau / rho[i])
    return out


def _fourth_point_constraints(Q, E2, E3, E4) -> list[Constraint]:
    """``E_4 = a E_2 + b E_3 + c (E_2 × E_3)``: the fourth chosen point from the other three.

    ``(a, b, c)`` are the coordinates of the platform's ``e_4 = Q_4 - Q_1`` in the basis
    ``e_2, e_3, e_2 × e_3``; a proper rotation maps ``e_2 × e_3`` to ``E_2 × E_3``, so the
    three equalities hold at every proper pose (redundant: contraction only) and fail at
    the mirror ones.  On general-19 at τ <= 60 N they cut the boxes by 1.6x.
    """
    e = _exact(Q[1:] - Q[0])
    basis = [list(col) for col in zip(e[0], e[1], _cross(e[0], e[1]))]
    a, b, c = (float(v[0]) for v in _least_squares(basis, [[x] for x in e[2]]))
    cr = _cross(E2, E3)
    return [
        Constraint(
            E4[i] - float(a) * E2[i] - float(b) * E3[i] - float(c) * cr[i], 0.0, 0.0, redundant=True
        )
        for i in range(3)
    ]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


# sparse arithmetic on expressions: None stands for an exact 0 (no node is built for it)
def _add0(x, y):
    return x if y is None else (y if x is None else x + y)


def _sub0(x, y):
    if x is None:
        return None if y is None else -y
    return x if y is None else x - y


def _mul0(x, y):
    return None if x is None or y is None else x * y


def _cross0(a, b):
    """``a × b`` (3 components, or the scalar in the plane as one) with None as 0."""
    if len(a) == 3:
        return [
            _sub0(_mul0(a[1], b[2]), _mul0(a[2], b[1])),
            _sub0(_mul0(a[2], b[0]), _mul0(a[0], b[2])),
            _sub0(_mul0(a[0], b[1]), _mul0(a[1], b[0])),
        ]
    return [_sub0(_mul0(a[0], b[1]), _mul0(a[1], b[0]))]


def _lin(coefs: np.ndarray, P: list[list[Expr]], c: int) -> Expr:
    """``Σ_j coefs_j P_j[c]`` (a single point when coefs is a unit vector)."""
    nz = np.flatnonzero(coefs)
    if len(nz) == 1 and coefs[nz[0]] == 1.0:
        return P[nz[0]][c]
    return esum(float(coefs[j]) * P[j][c] for j in nz)


# -- redundant moments of the point formulations ----------------------------------------------


def _eliminating_moments(robot, B, G, L, w, P, d):
    """Redundant equilibrium equations that eliminate wires (statics, section III).

    The moment of all forces about a platform point ``B_p`` has no term for the wires
    attached at ``p``; about the line through two attachment points ``B_p, B_q`` it has
    no term for the wires attached at either.  Fewer wide tension terms make these
    equations much sharper for HC4 than the six equilibrium equations alone.
    Returns a list of expressions (each = 0 at every equilibrium).
    """
    W = [float(v) for v in robot.weight]
    groups = _wire_groups(L)
    keys = list(groups)
    out = []

    def moment_about(pt, skip):
        comps = [[] for _ in range(3 if d == 3 else 1)]
        for i in range(robot.m):
            if i in skip:
                continue
            r = [B[i][c] - pt[c] for c in range(d)]
            a = [float(robot.A[i, c]) - pt[c] for c in range(d)]
            if d == 3:
                m = _cross(r, a)
                for c in range(3):
                    comps[c].append(w[i] * m[c])
            else:
                comps[0].append(w[i] * (r[0] * a[1] - r[1] * a[0]))
        if any(v != 0.0 for v in W):
            g = [G[c] - pt[c] for c in range(d)]
            mg = _cross(g, W) if d == 3 else [g[0] * W[1] - g[1] * W[0]]
            for c in range(len(comps)):
                comps[c].append(mg[c])
        return comps

    for kp in keys:
        p_idx = groups[kp]
        pt = B[p_idx[0]]
        comps = moment_about(pt, set(p_idx))
        out.extend(esum(c) for c in comps if c)
        if d != 3:
            continue
        for kq in keys:
            if kq <= kp:
                continue
            q_idx = groups[kq]
            e = [B[q_idx[0]][c] - pt[c] for c in range(3)]
            comps2 = moment_about(pt, set(p_idx) | set(q_idx))
            terms = [esum(comps2[c]) * e[c] for c in range(3) if comps2[c]]
            if terms:
                out.append(esum(terms))
    return out


def _absolute_forces_and_moments(robot: Robot, B, G, w, O) -> list[Expr]:
    """Equilibrium (eq. 3) with platform points in world coordinates, moments about ``O``.

    Forces ``Σ_i w_i (A_i - B_i) + m g``; moments ``Σ_i w_i (B_i - O) × (A_i - O) + (G - O)
    × m g`` (one component in the plane).  Shared by the point and pose parameterisations.
    """
    d = robot.dim
    W = robot.weight
    eqs: list[Expr] = []
    for c in range(d):  # forces
        terms = [w[i] * (float(robot.A[i, c]) - B[i][c]) for i in range(robot.m)]
        if W[c] != 0.0:
            terms.append(const(float(W[c])))
        eqs.append(esum(terms))
    rel = [[B[i][c] - float(O[c]) for c in range(d)] for i in range(robot.m)]
    arel = robot.A - O
    if d == 3:
        mom_terms: list[list[Expr]] = [[] for _ in range(3)]
        for i in range(robot.m):
            m_i = _cross(rel[i], [float(v) for v in arel[i]])
            for c in range(3):
                mom_terms[c].append(w[i] * m_i[c])
        if np.any(W != 0.0):
            mg = _cross([G[c] - float(O[c]) for c in range(3)], [float(v) for v in W])
            for c in range(3):
                mom_terms[c].append(mg[c])
        eqs.extend(esum(t) for t in mom_terms)
    else:
        terms = [
            w[i] * (rel[i][0] * float(arel[i, 1]) - rel[i][1] * float(arel[i, 0]))
            for i in range(robot.m)
        ]
        eqs.append(esum(terms))
    return eqs


class _Points:
    """Coordinates: the chosen points ``P_1..P_k`` in world coordinates (the paper's systems).

    Moments about the domain centre; every chosen point is a variable bounded by the domain.
    """

    kind = "points"

    def __init__(self, robot: Robot, Q, L, lG):
        d = robot.dim
        self.robot, self.Q, self.L, self.lG = robot, Q, L, lG
        axes = "xyz"[:d]
        self.P = [[var(f"{a}{j + 1}") for a in axes] for j in range(Q.shape[0])]
        self.B = [[_lin(L[i], self.P, c) for c in range(d)] for i in range(robot.m)]
        self.G = [_lin(lG, self.P, c) for c in range(d)]
        self.names = [f"{a}{j + 1}" for j in range(Q.shape[0]) for a in axes]
        self.rows = [robot.domain] * Q.shape[0]
        self.bounded = {tuple(np.eye(Q.shape[0])[j]) for j in range(Q.shape[0])}

    def offset(self, i: int, c: int) -> Expr:
        """Component ``c`` of ``B_i - A_i``."""
        return self.B[i][c] - float(self.robot.A[i, c])

    def edge_sq(self, a: int, b: int) -> Expr:
        d = self.robot.dim
        return esum(sqr(self.P[a][c] - self.P[b][c]) for c in range(d))

    def edges(self) -> list[list[Expr]]:
        """``E_j = P_j - P_1``, ``j = 2..k``."""
        d = self.robot.dim
        return [[self.P[j][c] - self.P[0][c] for c in range(d)] for j in range(1, len(self.P))]

    def point(self, coefs) -> list[Expr]:
        return [_lin(coefs, self.P, c) for c in range(self.robot.dim)]

    def equilibrium(self, w) -> list[Expr]:
        return _absolute_forces_and_moments(
            self.robot, self.B, self.G, w, self.robot.domain.mean(axis=1)
        )

    def redundant_moments(self, w, groups, option) -> list[Expr]:
        if not option:
            return []
        return _eliminating_moments(self.robot, self.B, self.G, self.L, w, self.P, self.robot.dim)


class _Frame:
    """Coordinates: the reference point ``P_1`` and the edge vectors ``E_j = P_j - P_1``.

    A linear change of variables of :class:`_Points` (same equations, same solutions):
    translation lives in ``P_1`` and rotation in the short ``E_j``; the rigidity equations
    ``|E_j|² = d²`` have no repeated variable, and the moments are taken about ``P_1``,
    whose levers ``B_i - P_1 = Σ l_ij E_j`` are platform-sized (and zero for the wires
    attached at ``P_1``).  ``None`` stands for an exact 0 (no node is built for it).
    """

    kind = "frame"

    def __init__(self, robot: Robot, Q, L, lG):
        d = robot.dim
        k = Q.shape[0]
        self.robot, self.Q, self.L, self.lG = robot, Q, L, lG
        axes = "xyz"[:d]
        self.C = [var(f"{a}1") for a in axes]
        self.E = [None] + [[var(f"e{a}{j + 1}") for a in axes] for j in range(1, k)]
        self.b = [self.rel(L[i]) for i in range(robot.m)]
        self.g = self.rel(lG)
        self.B = [[_add0(self.C[c], self.b[i][c]) for c in range(d)] for i in range(robot.m)]
        self.names = [f"{a}1" for a in axes]
        dom = robot.domain
        self.rows = [dom]
        for j in range(1, k):
            self.names += [f"e{a}{j + 1}" for a in axes]
            dj = float(np.sqrt(np.sum((Q[j] - Q[0]) ** 2)))
            span = dom[:, 1] - dom[:, 0]
            # |E_j| = d_j bounds each component; widened so that a solution with an edge
            # parallel to an axis is not on the boundary of the search box
            r = np.minimum(1.0625 * dj + 1e-3, span)
            self.rows.append(np.stack([-r, r], axis=1))
        self.bounded = {tuple(np.eye(k)[0])}

    def rel(self, coefs):
        """``Σ_j coefs_j P_j - P_1`` (affine coefs) as ``Σ_{j>=2} coefs_j E_j``; None = 0."""
        k, E = self.Q.shape[0], self.E
        nz = [j for j in range(1, k) if abs(coefs[j]) > 1e-14]
        out = []
        for c in range(self.robot.dim):
            if not nz:
                out.append(None)
            elif len(nz) == 1 and coefs[nz[0]] == 1.0:
                out.append(E[nz[0]][c])
            else:
                out.append(esum(float(coefs[j]) * E[j][c] for j in nz))
        return out

    def offset(self, i: int, c: int) -> Expr:
        """Component ``c`` of ``B_i - A_i = (P_1 - A_i) + b_i``."""
        return _add0(self.C[c] - float(self.robot.A[i, c]), self.b[i][c])

    def edge_sq(self, a: int, b: int) -> Expr:
        d, E = self.robot.dim, self.E
        if a == 0:
            return esum(sqr(E[b][c]) for c in range(d))
        return esum(sqr(E[a][c] - E[b][c]) for c in range(d))

    def edges(self) -> list[list[Expr]]:
        return self.E[1:]

    def point(self, coefs) -> list[Expr]:
        p = self.rel(coefs)
        return [_add0(self.C[c], p[c]) for c in range(self.robot.dim)]

    def moments_about(self, w, pref, skip):
        """Moment of all forces about ``P_1 + rel(pref)``, wires in ``skip`` left out."""
        robot, C, b = self.robot, self.C, self.b
        d = robot.dim
        W = [float(v) for v in robot.weight]
        p = self.rel(pref)
        comps: list[list[Expr]] = [[] for _ in range(3 if d == 3 else 1)]
        for i in range(robot.m):
            if i in skip:
                continue
            lever = [_sub0(b[i][c], p[c]) for c in range(d)]
            arm = [_sub0(float(robot.A[i, c]) - C[c], p[c]) for c in range(d)]
            for c, mc in enumerate(_cross0(lever, arm)):
                if mc is not None:
                    comps[c].append(w[i] * mc)
        if any(v != 0.0 for v in W):
            gl = [_sub0(self.g[c], p[c]) for c in range(d)]
            for c, mc in enumerate(_cross0(gl, [const(v) for v in W])):
                if mc is not None:
                    comps[c].append(mc)
        return comps

    def equilibrium(self, w) -> list[Expr]:
        """Forces ``Σ w_i ((A_i - P_1) - b_i) + m g``, moments about ``P_1``."""
        robot, C, b = self.robot, self.C, self.b
        W = [float(v) for v in robot.weight]
        eqs: list[Expr] = []
        for c in range(robot.dim):
            terms = [w[i] * _sub0(float(robot.A[i, c]) - C[c], b[i][c]) for i in range(robot.m)]
            if W[c] != 0.0:
                terms.append(const(W[c]))
            eqs.append(esum(terms))
        k = self.Q.shape[0]
        ref_wires = set(_wire_groups(self.L).get(tuple(np.eye(k)[0]), []))
        for comp in self.moments_about(w, np.eye(k)[0], ref_wires):
            eqs.append(esum(comp) if comp else const(0.0))
        return eqs

    def redundant_moments(self, w, groups, option) -> list[Expr]:
        """Moments about other attachment points (``"points"``, when they drop at least a
        quarter of the wires: one wire of seven was measured useless) and about lines
        through two of them (``"lines"``)."""
        if option is True:
            option = ("points", "lines")
        if not option:
            return []
        robot, k = self.robot, self.Q.shape[0]
        ref_key = tuple(np.eye(k)[0])
        keys = list(groups)
        out: list[Expr] = []
        for kp in keys:
            if kp != ref_key and "points" in option and 4 * len(groups[kp]) >= robot.m:
                for comp in self.moments_about(w, np.array(kp), set(groups[kp])):
                    if comp:
                        out.append(esum(comp))
            if robot.dim != 3 or "lines" not in option:
                continue
            for kq in keys:
                if kq <= kp:
                    continue
                skip = set(groups[kp]) | set(groups[kq])
                comps = self.moments_about(w, np.array(kp), skip)
                ax = self.rel(np.array(kq) - np.array(kp) + np.eye(k)[0])
                terms = [esum(comps[c]) * ax[c] for c in range(3) if comps[c] and ax[c] is not None]
                if terms:
                    out.append(esum(terms))
        return out


def _wire_groups(L: np.ndarray) -> dict[tuple, list[int]]:
    """Wires by attachment point (rows are snapped: equal rows <=> same point)."""
    groups: dict[tuple, list[int]] = {}
    for i in range(L.shape[0]):
        groups.setdefault(tuple(L[i]), []).append(i)
    return groups


def _platform_formulation(
    robot: Robot,
    name: str,
    k: int,
    *,
    frame: bool = False,
    redundant_moments: bool | tuple[str, ...] = True,
) -> FKFormulation:
    """The FK system on ``k`` chosen platform points (module docstring), in the paper's point
    coordinates (:class:`_Points`) or the platform frame (:class:`_Frame`, ``frame=True``).

    The physics is written once: lengths, rigidity, equilibrium, the orientation of the
    chosen points, every platform point in the domain, redundant moments and the linear
    differences of wires sharing an attachment.
    """
    robot.require_elastic("forward kinematics")
    d = robot.dim
    pts, gidx = robot.attachment_groups()
    if k > pts.shape[0]:
        raise ValueError(
            f"{name} needs {k} distinct attachment points, the robot has {pts.shape[0]}"
        )
    sel = _choose_points(pts, k)
    if frame:  # the reference point P_1 carries the most wires
        counts = [int(np.sum(gidx == j)) for j in sel]
        r0 = int(np.argmax(counts))
        sel = [sel[r0]] + [s for i, s in enumerate(sel) if i != r0]
    Q = pts[sel]
    L = _snap_rows(_affine_coordinates(Q, robot.B), robot)
    lG = _affine_coordinates(Q, robot.com[None])[0]
    co: _Points | _Frame = (_Frame if frame else _Points)(robot, Q, L, lG)
    A = robot.A
    dom = robot.domain

    rho = [var(f"rho{i + 1}") for i in range(robot.m)]
    eqs: list[Expr] = []
    for i in range(robot.m):  # lengths
        eqs.append(esum(sqr(co.offset(i, c)) for c in range(d)) - sqr(rho[i]))
    for a, b in itertools.combinations(range(k), 2):  # rigidity
        eqs.append(co.edge_sq(a, b) - float(np.sum((Q[a] - Q[b]) ** 2)))
    w = _wire_weights(robot, rho)
    eqs += co.equilibrium(w)

    constraints: list[Constraint] = []
    fourth: list[Constraint] = []
    if k == d + 1:  # orientation: the signed area / volume of the chosen points keeps its sign
        E = co.edges()
        if d == 3:
            cr = _cross(E[1], E[2])
            signed = esum(E[0][c] * cr[c] for c in range(3))
        else:
            signed = E[0][0] * E[1][1] - E[0][1] * E[1][0]
        s0 = float(_det(_exact(Q[1:] - Q[0])))
        constraints.append(Constraint(signed, s0, s0, redundant=True))
        constraints.append(
            Constraint(signed, 0.0, np.inf) if s0 > 0 else Constraint(signed, -np.inf, 0.0)
        )
        if d == 3 and k == 4:
            fourth = _fourth_point_constraints(Q, E[0], E[1], E[2])
            constraints += fourth
    # every platform point (chosen points, attachments, centre of mass) inside the domain
    extra = [np.eye(k)[j] for j in range(1, k)] + [L[i] for i in range(robot.m)] + [lG]
    seen = set(co.bounded)
    for coefs in extra:
        key = tuple(coefs)
        if key in seen:
            continue
        seen.add(key)
        p = co.point(coefs)
        for c in range(d):
            constraints.append(Constraint(p[c], float(dom[c, 0]), float(dom[c, 1])))
    groups = _wire_groups(L)
    for e in co.redundant_moments(w, groups, redundant_moments):
        constraints.append(Constraint(e, 0.0, 0.0, redundant=True))
    for members in groups.values():
        # wires sharing an attachment: the difference of their length equations is linear
        for a, b in zip(members, members[1:]):
            Aa, Ab = A[a], A[b]
            lhs = esum(2.0 * float(Aa[c] - Ab[c]) * co.B[a][c] for c in range(d))
            const_term = float(np.sum(Aa * Aa) - np.sum(Ab * Ab))
            constraints.append(
                Constraint(sqr(rho[a]) - sqr(rho[b]) + lhs - const_term, 0.0, 0.0, redundant=True)
            )

    names = list(co.names) + [f"rho{i + 1}" for i in range(robot.m)]
    rows = np.vstack(co.rows + [np.zeros((robot.m, 2))])
    domain = _with_rho(rows, robot, np.zeros(robot.m), d, k)
    system = _system(robot, names, domain, eqs, constraints, name)
    info: dict = {"points": [int(i) for i in sel]}
    if frame and fourth:
        # E_4 follows E_2 and E_3 through the fourth-point equalities: not split (see FKSolver)
        info["determined"] = list(range(3 * d, 4 * d))
    if frame:
        # lengths + forces in (P_1, ρ): a square sub-system, well conditioned for a whole
        # box of orientations (partial Newton, see FKSolver)
        info["translation"] = {
            "equations": list(range(robot.m)) + [robot.m + k * (k - 1) // 2 + c for c in range(d)],
            "variables": list(range(d)) + list(range(k * d, k * d + robot.m)),
        }
    return FKFormulation(name, robot, system, co.kind, Q=Q, L=L, lG=lG, info=info)


def _system(robot: Robot, names, domain, eqs, constraints, name: str) -> System:
    """The FK system; the control ``u`` enters as parameters ``u1..um`` (set per solve)."""
    params = {f"u{i + 1}": 0.0 for i in range(robot.m)}
    return System(names, domain, eqs, constraints, name=name, parameters=params)


def _with_rho(domain, robot, u, d, k):
    lo, hi = _rho_domain(robot, np.asarray(u, dtype=float), robot.domain)
    out = domain.copy()
    out[k * d :, 0] = lo
    out[k * d :, 1] = np.maximum(hi, lo)  # an empty range is handled by the caller
    return out


def search_domain(form: FKFormulation, u) -> tuple[np.ndarray, bool]:
    """The FK search box for control ``u`` and whether it is non-empty."""
    robot = form.robot
    u = np.asarray(u, dtype=float)
    lo, hi = _rho_domain(robot, u, robot.domain)
    dom = form.system.domain.copy()
    if not any(v.startswith("rho") for v in form.system.variables):
        return dom, bool(np.all(lo <= hi))
    nr = robot.m
    dom[-nr:, 0] = lo
    dom[-nr:, 1] = np.maximum(hi, lo)
    return dom, bool(np.all(lo <= hi))


# -- pose-parameter formulation ------------------------------------------------------------------


def _pose_formulation(robot: Robot) -> FKFormulation:
    robot.require_elastic("forward kinematics")
    d = robot.dim
    rho = [var(f"rho{i + 1}") for i in range(robot.m)]
    dom = robot.domain
    if d == 3:
        p = [var("x"), var("y"), var("z")]
        ang = [var("yaw"), var("pitch"), var("roll")]
        cz, sz, cy, sy, cx, sx = (
            cos(ang[0]),
            sin(ang[0]),
            cos(ang[1]),
            sin(ang[1]),
            cos(ang[2]),
            sin(ang[2]),
        )
        R = [
            [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
            [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
            [-sy, cy * sx, cy * cx],
        ]
        names = ["x", "y", "z", "yaw", "pitch", "roll"]
        ang_dom = [[-np.pi, np.pi], [-np.pi / 2, np.pi / 2], [-np.pi, np.pi]]
    else:
        p = [var("x"), var("y")]
        th = var("theta")
        R = [[cos(th), -sin(th)], [sin(th), cos(th)]]
        names = ["x", "y", "theta"]
        ang_dom = [[-np.pi, np.pi]]

    def world(b):
        return [
            p[r] + esum(float(b[c]) * R[r][c] for c in range(d) if b[c] != 0.0)
            if np.any(b != 0)
            else p[r]
            for r in range(d)
        ]

    B = [world(robot.B[i]) for i in range(robot.m)]
    G = world(robot.com)
    eqs = [
        esum(sqr(B[i][c] - float(robot.A[i, c])) for c in range(d)) - sqr(rho[i])
        for i in range(robot.m)
    ]
    w = _wire_weights(robot, rho)
    eqs += _absolute_forces_and_moments(robot, B, G, w, dom.mean(axis=1))
    constraints = []
    for i in range(robot.m):
        for c in range(d):
            constraints.append(Constraint(B[i][c], float(dom[c, 0]), float(dom[c, 1])))
    names = names + [f"rho{i + 1}" for i in range(robot.m)]
    domain = np.vstack([dom, np.array(ang_dom), np.zeros((robot.m, 2))])
    lo, hi = _rho_domain(robot, np.zeros(robot.m), dom)  # set per u by search_domain
    domain[-robot.m :, 0] = lo
    domain[-robot.m :, 1] = np.maximum(hi, lo)
    system = _system(robot, names, domain, eqs, constraints, "pose")
    return FKFormulation("pose", robot, system, "pose")


def build_formulation(robot: Robot, name: str = "auto") -> FKFormulation:
    """Build the named formulation (``auto``: the paper's system for this robot, in the
    platform frame)."""
    if name not in FORMULATIONS:
        raise ValueError(f"unknown formulation {name!r}; choose from {', '.join(FORMULATIONS)}")
    if name == "auto":
        name = "frame"
    if name == "pose":
        return _pose_formulation(robot)
    if name == "frame":
        base = choose_formulation(robot)
        k = 4 if base == "general-19" else 3
        return _platform_formulation(
            robot, f"frame-{base}", k, frame=True, redundant_moments=("points",)
        )
    if name == "planar-10":
        if robot.dof != 3:
            raise ValueError("planar-10 is for planar robots (dof 3)")
        return _platform_formulation(robot, name, 3)
    if robot.dof != 6:
        raise ValueError(f"{name} is for spatial robots (dof 6)")
    if name == "general-19":
        return _platform_formulation(robot, name, 4)
    pts, _ = robot.attachment_groups()
    if not _is_coplanar(np.vstack([pts, robot.com[None]])):
        raise ValueError(
            f"{name} needs a planar platform (attachments and centre of mass "
            "coplanar); use general-19"
        )
    return _platform_formulation(robot, name, 3)


def rotation_from_points(form: FKFormulation, P: np.ndarray):
    """Rigid transform ``P_j = p + R Q_j`` fitted to the chosen points (Kabsch)."""
    Q = form.Q
    qc = Q.mean(axis=0)
    pc = P.mean(axis=0)
    Hm = (Q - qc).T @ (P - pc)
    U, _, Vt = np.linalg.svd(Hm)
    D = np.eye(Q.shape[1])
    D[-1, -1] = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ D @ U.T
    return pc - R @ qc, R


def pose_from_angles(form: FKFormulation, x: np.ndarray):
    d = form.robot.dim
    if d == 3:
        return x[:3].copy(), rotation_zyx(x[3], x[4], x[5])
    return x[:2].copy(), rotation_2d(x[2])
