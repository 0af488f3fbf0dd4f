"""The physics of the FK systems (Merlet 2007, eqs. 1-8), written once for every coordinate kind.

* wire lengths: ``|A_i - B_i|² - ρ_i² = 0``, one per wire; ``ρ_i`` ranges over the lengths
  the tension limits allow through eq. (7) (:func:`rho_domain`);
* tensions: ``w_i = τ_i / ρ_i`` with ``τ_i = k (1 - L0 / (ρ_i + V + K u_i))`` (eqs. 1, 2;
  :func:`wire_weights`), the control ``u`` entering as the parameters ``u1..um``;
* equilibrium (eq. 3): forces ``Σ_i w_i (A_i - B_i) + m g = 0`` and moments about a point
  ``O``: ``Σ_i w_i (B_i - O) × (A_i - O) + (G - O) × m g = 0``
  (:func:`absolute_forces_and_moments`; ``(B - O) × (B - O) = 0`` makes the moment linear
  in the points);
* redundant equilibrium equations that eliminate wires: moments about an attachment point
  or a line through two (:func:`eliminating_moments`, section III of the paper);
* the fourth chosen point of general-19 tied to the other three
  (:func:`fourth_point_constraints`).

The coordinates in which these are written (the paper's points, a platform frame, a pose)
are in :mod:`.fk_points` and :mod:`.fk_pose`.  ``None`` stands for an exact 0 in the
sparse helpers (no node is built for it).
"""

from __future__ import annotations

import numpy as np

from ..expr import Constraint, const, esum, param
from ..expr.node import Expr
from ..interval.rounding import down, up
from ..robot.model import Robot
from .fk_geometry import exact, exact_least_squares

__all__ = [
    "absolute_forces_and_moments",
    "coefficient",
    "add0",
    "cross",
    "cross0",
    "difference",
    "eliminating_moments",
    "fourth_point_constraints",
    "lin",
    "mul0",
    "number",
    "rho_domain",
    "tolerance_parameters",
    "sub0",
    "wire_groups",
    "weight",
    "wire_weights",
]


def rho_domain(robot: Robot, u: np.ndarray, domain: np.ndarray):
    """Per-wire [ρ_min, ρ_max]: tension limits through eq. (7), intersected with geometry,
    over every robot of the set (:meth:`.Robot.bounds`; the nominal numbers without
    tolerances).

    ``ρ(τ) = k L0 / (k - τ) - V - K u`` is monotone in each number (increasing in ``L0``,
    decreasing in ``V``, in ``K`` as ``-u``, in ``k`` as ``-τ``), so its range over the set
    is at the corners chosen by those signs; the distance from the anchor box to the domain
    box is bounded per axis.
    """
    b = robot.bounds()

    def length(tau, low: bool):
        """ρ at the corner where it is lowest (``low``) or highest."""

        def pick(pair, lower_when):  # the end of ``pair`` that lowers ρ where the mask says
            return np.where(lower_when == low, pair[0], pair[1])

        k = pick(b.k, tau < 0)
        L0 = pick(b.L0, True)
        V = pick(b.V, False)
        K = pick(b.K, u < 0)
        return k * L0 / (k - tau) - (V + K * u)

    lo_t = length(robot.tau_min, True)
    hi_t = length(robot.tau_max, False)
    (alo, ahi), dlo, dhi = b.A, domain[:, 0], domain[:, 1]
    dmin = np.linalg.norm(np.maximum(np.maximum(dlo - ahi, alo - dhi), 0.0), axis=1)
    far = np.maximum(
        np.maximum(np.abs(alo - dlo), np.abs(alo - dhi)),
        np.maximum(np.abs(ahi - dlo), np.abs(ahi - dhi)),
    )
    dmax = np.linalg.norm(far, axis=1)
    lo = np.maximum(np.maximum(lo_t, dmin), 0.0)
    hi = np.minimum(hi_t, dmax)
    return lo, hi


def number(robot: Robot, name: str, index: tuple[int, ...]) -> float | Expr:
    """A number of the robot as the FK systems write it: the float where it is exact, the
    parameter ``tol_<name>_<index>`` where it is known within a tolerance
    (:meth:`.Robot.bounds`; its interval is the parameter's value,
    :func:`tolerance_parameters`), so a robot without tolerances gives the same graph as
    its floats, and a proof can treat the toleranced numbers apart (:mod:`.fk_tolerance`)."""
    lo, hi = (float(a[index]) for a in getattr(robot.bounds(), name))
    return lo if lo == hi else param("_".join(["tol", name, *map(str, index)]))


def weight(robot: Robot) -> list[float | Expr]:
    """The weight ``m g`` (N) per axis, as :func:`number` writes numbers (an exact 0 on an
    axis without gravity; the parameter ``tol_W_<axis>`` where the mass is toleranced)."""
    lo, hi = robot.weight_bounds()
    return [float(a) if a == b else param(f"tol_W_{c}") for c, (a, b) in enumerate(zip(lo, hi))]


def tolerance_parameters(robot: Robot) -> dict[str, tuple[float, float]]:
    """The interval of every parameter :func:`number` and :func:`weight` write, by name
    (empty for a robot without tolerances)."""
    b = robot.bounds()
    out: dict[str, tuple[float, float]] = {}
    for name in ("A", "k", "K", "V", "L0"):
        lo, hi = getattr(b, name)
        for index in zip(*np.nonzero(~b.exact(name))):
            key = "_".join(["tol", name, *(str(int(i)) for i in index)])
            out[key] = (float(lo[index]), float(hi[index]))
    wlo, whi = robot.weight_bounds()
    for c in np.flatnonzero(wlo != whi):
        out[f"tol_W_{c}"] = (float(wlo[c]), float(whi[c]))
    return out


def wire_weights(robot: Robot, rho: list[Expr]) -> list[Expr]:
    """``w_i = τ_i / ρ_i`` with ``τ_i = k (1 - L0 / (ρ_i + V + K u_i))`` (eqs. 1, 2)."""
    out = []
    for i in range(robot.m):
        c = number(robot, "V", (i,)) + number(robot, "K", (i,)) * param(f"u{i + 1}")
        tau = number(robot, "k", (i,)) * (1.0 - number(robot, "L0", (i,)) / (rho[i] + c))
        out.append(tau / rho[i])
    return out


def fourth_point_constraints(Q, E2, E3, E4) -> list[Constraint]:
    """``E_4 = a E_2 + b E_3 + c (E_2 × E_3)``: the fourth chosen point from the other three.

    ``(a, b, c)`` are the coordinates of the platform's ``e_4 = Q_4 - Q_1`` in the basis
    ``e_2, e_3, e_2 × e_3``; a proper rotation maps ``e_2 × e_3`` to ``E_2 × E_3``, so the
    three equalities hold at every proper pose (redundant: contraction only) and fail at
    the mirror ones.  On general-19 at τ <= 60 N they cut the boxes by 1.6x.
    """
    e = exact(Q[1:] - Q[0])
    basis = [list(col) for col in zip(e[0], e[1], cross(e[0], e[1]))]
    a, b, c = (float(v[0]) for v in exact_least_squares(basis, [[x] for x in e[2]]))
    cr = cross(E2, E3)
    return [
        Constraint(
            E4[i] - float(a) * E2[i] - float(b) * E3[i] - float(c) * cr[i], 0.0, 0.0, redundant=True
        )
        for i in range(3)
    ]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


# sparse arithmetic on expressions: None stands for an exact 0 (no node is built for it)
def add0(x, y):
    return x if y is None else (y if x is None else x + y)


def sub0(x, y):
    if x is None:
        return None if y is None else -y
    return x if y is None else x - y


def mul0(x, y):
    return None if x is None or y is None else x * y


def cross0(a, b):
    """``a × b`` (3 components, or the scalar in the plane as one) with None as 0."""
    if len(a) == 3:
        return [
            sub0(mul0(a[1], b[2]), mul0(a[2], b[1])),
            sub0(mul0(a[2], b[0]), mul0(a[0], b[2])),
            sub0(mul0(a[0], b[1]), mul0(a[1], b[0])),
        ]
    return [sub0(mul0(a[0], b[1]), mul0(a[1], b[0]))]


def lin(coefs: np.ndarray, P: list[list[Expr]], c: int) -> Expr:
    """``Σ_j coefs_j P_j[c]`` (a single point when coefs is a unit vector)."""
    nz = np.flatnonzero(coefs)
    if len(nz) == 1 and coefs[nz[0]] == 1.0:
        return P[nz[0]][c]
    return esum(float(coefs[j]) * P[j][c] for j in nz)


# -- redundant moments of the point formulations ----------------------------------------------


def eliminating_moments(robot, B, G, L, w, P, d):
    """Redundant equilibrium equations that eliminate wires (statics, section III).

    The moment of all forces about a platform point ``B_p`` has no term for the wires
    attached at ``p``; about the line through two attachment points ``B_p, B_q`` it has
    no term for the wires attached at either.  Fewer wide tension terms make these
    equations much sharper for HC4 than the six equilibrium equations alone.
    Returns a list of expressions (each = 0 at every equilibrium).
    """
    W = weight(robot)
    groups = wire_groups(L)
    keys = list(groups)
    out = []

    def moment_about(pt, skip):
        comps = [[] for _ in range(3 if d == 3 else 1)]
        for i in range(robot.m):
            if i in skip:
                continue
            r = [B[i][c] - pt[c] for c in range(d)]
            a = [number(robot, "A", (i, c)) - pt[c] for c in range(d)]
            if d == 3:
                m = cross(r, a)
                for c in range(3):
                    comps[c].append(w[i] * m[c])
            else:
                comps[0].append(w[i] * (r[0] * a[1] - r[1] * a[0]))
        if any(v != 0.0 for v in W):
            g = [G[c] - pt[c] for c in range(d)]
            mg = cross(g, W) if d == 3 else [g[0] * W[1] - g[1] * W[0]]
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


def absolute_forces_and_moments(robot: Robot, B, G, w, O) -> list[Expr]:
    """Equilibrium (eq. 3) with platform points in world coordinates, moments about ``O``.

    Forces ``Σ_i w_i (A_i - B_i) + m g``; moments ``Σ_i w_i (B_i - O) × (A_i - O) + (G - O)
    × m g`` (one component in the plane).  Shared by the point and pose parameterisations.
    """
    d = robot.dim
    W = weight(robot)
    eqs: list[Expr] = []
    for c in range(d):  # forces
        terms = [w[i] * (number(robot, "A", (i, c)) - B[i][c]) for i in range(robot.m)]
        if W[c] != 0.0:
            terms.append(Expr.wrap(W[c]))
        eqs.append(esum(terms))
    rel = [[B[i][c] - float(O[c]) for c in range(d)] for i in range(robot.m)]
    arel = [[number(robot, "A", (i, c)) - float(O[c]) for c in range(d)] for i in range(robot.m)]
    if d == 3:
        mom_terms: list[list[Expr]] = [[] for _ in range(3)]
        for i in range(robot.m):
            m_i = cross(rel[i], arel[i])
            for c in range(3):
                mom_terms[c].append(w[i] * m_i[c])
        if any(v != 0.0 for v in W):
            mg = cross([G[c] - float(O[c]) for c in range(3)], W)
            for c in range(3):
                mom_terms[c].append(mg[c])
        eqs.extend(esum(t) for t in mom_terms)
    else:
        terms = [w[i] * (rel[i][0] * arel[i][1] - rel[i][1] * arel[i][0]) for i in range(robot.m)]
        eqs.append(esum(terms))
    return eqs


def wire_groups(L: np.ndarray) -> dict[tuple, list[int]]:
    """Wires by attachment point (rows are snapped: equal rows <=> same point)."""
    groups: dict[tuple, list[int]] = {}
    for i in range(L.shape[0]):
        groups.setdefault(tuple(L[i]), []).append(i)
    return groups


def difference(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of ``a - b``: one float where the difference is surely exact (``a == b``, or
    one of them 0), else rounded outward."""
    d = a - b
    surely = (a == b) | (a == 0.0) | (b == 0.0)
    return np.where(surely, d, down(d)), np.where(surely, d, up(d))


def coefficient(lo: float, hi: float) -> Expr:
    """The constant ``[lo, hi]`` (a point when ``lo == hi``)."""
    return const(float(lo)) if lo == hi else const(float(lo), float(hi))
