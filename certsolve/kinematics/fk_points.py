"""Point coordinates of the FK systems: the paper's world points, and the platform frame.

Unknowns are the world coordinates of ``k`` chosen platform points ``P_1..P_k`` (or, in the
platform frame, ``P_1`` and the edge vectors ``E_j = P_j - P_1``) and the wire lengths
``ρ_1..ρ_m``; every attachment and the centre of mass are affine combinations of the chosen
points (eq. 8, :mod:`.fk_geometry`).  One builder (:func:`_platform_system`) writes the
physics of both (:mod:`.fk_equations`); the coordinates are its parameter
(:class:`_Points`: moments about the domain centre; :class:`_Frame`: moments about
``P_1``).  Sizes for MARIONET's 7 wires:

* ``general-19``: 4 non-coplanar points (12 coordinates) + 7 ρ: 7 + 6 + 6 equations.  Four
  points with fixed distances also fit the platform's *mirror image*; the signed volume
  ``(P2-P1)·((P3-P1)×(P4-P1))`` must have the sign it has on the platform (a checked
  constraint: an improper pose is never reported), and the redundant equality
  ``signed volume = 6V`` contracts boxes.  In the frame the fourth point is also tied to
  the other three by the redundant ``E_4 = a E_2 + b E_3 + c (E_2 × E_3)``
  (:func:`.fk_equations.fourth_point_constraints`), which holds for every proper pose and
  excludes the mirror ones.
* ``T-16``: the T-platform has only 3 distinct attachment points (9 coordinates + 7 ρ);
  ``almost-planar-13``: 4 wires on a planar platform, 3 points (9 + 4).  A platform whose
  attachments and centre of mass are coplanar is its own mirror image, so no sign is needed.
* ``planar-10``: planar robots (dof 3), 3 points in the plane (6 + 4); the signed area
  fixes the orientation as for ``general-19``.
* ``points``: the paper's 3-point system for a planar platform with more than three
  distinct attachment points; on the T-platform and the almost-planar robot it is the same
  system as ``T-16`` / ``almost-planar-13``, node for node.  It is there for comparison:
  the frame needs 4-5x fewer boxes (τ <= 10 N, u = 0: T-16 6117 vs 1479 boxes,
  almost-planar 24392 vs 4703).
* the frame (``frame``, ``auto``; named ``frame-<paper system>``): a linear change of
  variables of the paper's system (same equations, same count, same solutions) that
  separates translation from rotation; with partial Newton on the translation sub-system
  (:meth:`FrameFormulation.subsystems`) and the orientation split first
  (:meth:`FrameFormulation.bisector`) it needs 5-8 times fewer boxes than the paper's
  variables (see ``benchmarks/fk_bench.py``).

Every platform point lies in the robot's ``domain`` box (the non-chosen attachments through
checked constraints).  Wires sharing an attachment point also get the redundant linear
equation obtained by subtracting their length equations (section III-B of the paper).  A
``reduced`` variant that eliminated ρ (``ρ_i = |A_i - B_i|``, 6-12 unknowns) was removed:
on the bundled robots it never won (τ <= 10 N and 60 N, u as in ``tests/test_fk_frame.py``:
1.6-4.6x the boxes of the paper's system, 15-24x those of the frame, 1.4-3.7x the paper
system's CPU time).
"""

from __future__ import annotations

import itertools
from abc import abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..expr import Constraint, System, const, esum, sqr, var
from ..expr.node import Expr
from ..robot.model import Robot
from ..solver.bisectors import Prioritized
from .fk_equations import (
    absolute_forces_and_moments,
    add0,
    coefficient,
    cross,
    cross0,
    difference,
    eliminating_moments,
    fourth_point_constraints,
    lin,
    number,
    rho_domain,
    sub0,
    tolerance_parameters,
    weight,
    wire_groups,
    wire_weights,
)
from .fk_formulation import FKFormulation
from .fk_geometry import PlatformPoints, exact, exact_det

__all__ = [
    "ALPHA_MAX",
    "ALPHA_MAX_GENERAL",
    "FrameFormulation",
    "PlatformFormulation",
    "PointsFormulation",
]

#: the largest share of the position's width over the orientation's at which the frame
#: bisector still splits the orientation (:class:`.Prioritized` ``alpha``, see
#: :meth:`FrameFormulation.bisector`)
ALPHA_MAX = 0.5
#: the same for general-19, whose orientation is split on E_2 and E_3 only (E_4 auxiliary):
#: each split of them gains more, and the position is worth splitting later (at 60 N, 0.35
#: against 0.5: u~S(2) 174,968 -> 164,109 boxes, u~S(3) 226,492 -> 201,974,
#: random-general-0 3.85M -> 3.21M; T-16 keeps 0.5: 0.35 costs it 17 % more boxes)
ALPHA_MAX_GENERAL = 0.35


# -- the coordinates the physics is written in ----------------------------------------------------


class _Points:
    """Coordinates: the chosen points ``P_1..P_k`` in world coordinates (the paper's systems).

    Moments about the domain centre; every chosen point is a variable bounded by the domain.
    """

    def __init__(self, robot: Robot, Q, L, lG):
        d = robot.dim
        self.robot, self.Q, self.L, self.lG = robot, Q, L, lG
        axes = "xyz"[:d]
        self.P = [[var(f"{a}{j + 1}") for a in axes] for j in range(Q.shape[0])]
        self.B = [[lin(L[i], self.P, c) for c in range(d)] for i in range(robot.m)]
        self.G = [lin(lG, self.P, c) for c in range(d)]
        self.names = [f"{a}{j + 1}" for j in range(Q.shape[0]) for a in axes]
        self.rows = [robot.domain] * Q.shape[0]
        self.bounded = {tuple(np.eye(Q.shape[0])[j]) for j in range(Q.shape[0])}

    def offset(self, i: int, c: int) -> Expr:
        """Component ``c`` of ``B_i - A_i``."""
        return self.B[i][c] - number(self.robot, "A", (i, c))

    def edge_sq(self, a: int, b: int) -> Expr:
        d = self.robot.dim
        return esum(sqr(self.P[a][c] - self.P[b][c]) for c in range(d))

    def edges(self) -> list[list[Expr]]:
        """``E_j = P_j - P_1``, ``j = 2..k``."""
        d = self.robot.dim
        return [[self.P[j][c] - self.P[0][c] for c in range(d)] for j in range(1, len(self.P))]

    def point(self, coefs) -> list[Expr]:
        return [lin(coefs, self.P, c) for c in range(self.robot.dim)]

    def equilibrium(self, w) -> list[Expr]:
        return absolute_forces_and_moments(
            self.robot, self.B, self.G, w, self.robot.domain.mean(axis=1)
        )

    def redundant_moments(self, w, groups, option) -> list[Expr]:
        if not option:
            return []
        return eliminating_moments(self.robot, self.B, self.G, self.L, w, self.P, self.robot.dim)


class _Frame:
    """Coordinates: the reference point ``P_1`` and the edge vectors ``E_j = P_j - P_1``.

    A linear change of variables of :class:`_Points` (same equations, same solutions):
    translation lives in ``P_1`` and rotation in the short ``E_j``; the rigidity equations
    ``|E_j|² = d²`` have no repeated variable, and the moments are taken about ``P_1``,
    whose levers ``B_i - P_1 = Σ l_ij E_j`` are platform-sized (and zero for the wires
    attached at ``P_1``).  ``None`` stands for an exact 0 (no node is built for it).
    """

    def __init__(self, robot: Robot, Q, L, lG):
        d = robot.dim
        k = Q.shape[0]
        self.robot, self.Q, self.L, self.lG = robot, Q, L, lG
        axes = "xyz"[:d]
        self.C = [var(f"{a}1") for a in axes]
        # E[j]: the edge vector to P_{j+1} (E[0], P_1 to itself, is never written)
        self.E: list[list[Expr]] = [[]] + [[var(f"e{a}{j + 1}") for a in axes] for j in range(1, k)]
        self.b = [self.rel(L[i]) for i in range(robot.m)]
        self.g = self.rel(lG)
        self.B = [[add0(self.C[c], self.b[i][c]) for c in range(d)] for i in range(robot.m)]
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
        return add0(self.C[c] - number(self.robot, "A", (i, c)), self.b[i][c])

    def edge_sq(self, a: int, b: int) -> Expr:
        d, E = self.robot.dim, self.E
        if a == 0:
            return esum(sqr(E[b][c]) for c in range(d))
        return esum(sqr(E[a][c] - E[b][c]) for c in range(d))

    def edges(self) -> list[list[Expr]]:
        return self.E[1:]

    def point(self, coefs) -> list[Expr]:
        p = self.rel(coefs)
        return [add0(self.C[c], p[c]) for c in range(self.robot.dim)]

    def moments_about(self, w, pref, skip):
        """Moment of all forces about ``P_1 + rel(pref)``, wires in ``skip`` left out."""
        robot, C, b = self.robot, self.C, self.b
        d = robot.dim
        W = weight(robot)
        p = self.rel(pref)
        comps: list[list[Expr]] = [[] for _ in range(3 if d == 3 else 1)]
        for i in range(robot.m):
            if i in skip:
                continue
            lever = [sub0(b[i][c], p[c]) for c in range(d)]
            arm = [sub0(number(robot, "A", (i, c)) - C[c], p[c]) for c in range(d)]
            for c, mc in enumerate(cross0(lever, arm)):
                if mc is not None:
                    comps[c].append(w[i] * mc)
        if any(v != 0.0 for v in W):
            gl = [sub0(self.g[c], p[c]) for c in range(d)]
            for c, mc in enumerate(cross0(gl, [Expr.wrap(v) for v in W])):
                if mc is not None:
                    comps[c].append(mc)
        return comps

    def equilibrium(self, w) -> list[Expr]:
        """Forces ``Σ w_i ((A_i - P_1) - b_i) + m g``, moments about ``P_1``."""
        robot, C, b = self.robot, self.C, self.b
        W = weight(robot)
        eqs: list[Expr] = []
        for c in range(robot.dim):
            terms = [
                w[i] * sub0(number(robot, "A", (i, c)) - C[c], b[i][c]) for i in range(robot.m)
            ]
            if W[c] != 0.0:
                terms.append(Expr.wrap(W[c]))
            eqs.append(esum(terms))
        k = self.Q.shape[0]
        ref_wires = set(wire_groups(self.L).get(tuple(np.eye(k)[0]), []))
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


# -- the system -------------------------------------------------------------------------------


def _platform_system(
    robot: Robot,
    name: str,
    platform: PlatformPoints,
    coordinates: type[_Points] | type[_Frame],
    redundant_moments: bool | tuple[str, ...],
) -> tuple[System, bool]:
    """The FK system on the chosen platform points (module docstring), in the paper's point
    coordinates (:class:`_Points`) or the platform frame (:class:`_Frame`), and whether the
    fourth-point equalities are among its constraints.

    The physics is written once: lengths, rigidity, equilibrium, the orientation of the
    chosen points, every platform point in the domain, redundant moments and the linear
    differences of wires sharing an attachment.
    """
    d = robot.dim
    Q, L, lG = platform.Q, platform.L, platform.lG
    k = Q.shape[0]
    co = coordinates(robot, Q, L, lG)
    A = robot.A
    exact_anchors = np.all(robot.bounds().exact("A"), axis=1)
    dom = robot.domain

    rho = [var(f"rho{i + 1}") for i in range(robot.m)]
    eqs: list[Expr] = []
    for i in range(robot.m):  # lengths
        eqs.append(esum(sqr(co.offset(i, c)) for c in range(d)) - sqr(rho[i]))
    for a, b in itertools.combinations(range(k), 2):  # rigidity
        eqs.append(co.edge_sq(a, b) - float(np.sum((Q[a] - Q[b]) ** 2)))
    w = wire_weights(robot, rho)
    eqs += co.equilibrium(w)

    constraints: list[Constraint] = []
    fourth: list[Constraint] = []
    if k == d + 1:  # orientation: the signed area / volume of the chosen points keeps its sign
        E = co.edges()
        if d == 3:
            cr = cross(E[1], E[2])
            signed = esum(E[0][c] * cr[c] for c in range(3))
        else:
            signed = E[0][0] * E[1][1] - E[0][1] * E[1][0]
        s0 = float(exact_det(exact(Q[1:] - Q[0])))
        constraints.append(Constraint(signed, s0, s0, redundant=True))
        constraints.append(
            Constraint(signed, 0.0, np.inf) if s0 > 0 else Constraint(signed, -np.inf, 0.0)
        )
        if d == 3 and k == 4:
            fourth = fourth_point_constraints(Q, E[0], E[1], E[2])
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
    groups = wire_groups(L)
    for e in co.redundant_moments(w, groups, redundant_moments):
        constraints.append(Constraint(e, 0.0, 0.0, redundant=True))
    for members in groups.values():
        # wires sharing an attachment: the difference of their length equations is linear
        for a, b in zip(members, members[1:]):
            Aa, Ab = A[a], A[b]
            if exact_anchors[a] and exact_anchors[b]:
                lhs = esum(2.0 * float(Aa[c] - Ab[c]) * co.B[a][c] for c in range(d))
                const_term: float | Expr = float(np.sum(Aa * Aa) - np.sum(Ab * Ab))
            else:  # anchors within tolerances: the same terms, their numbers as intervals
                na = [number(robot, "A", (a, c)) for c in range(d)]
                nb = [number(robot, "A", (b, c)) for c in range(d)]
                lhs = esum(2.0 * (na[c] - nb[c]) * co.B[a][c] for c in range(d))
                const_term = esum(sqr(na[c]) for c in range(d)) - esum(sqr(nb[c]) for c in range(d))
            constraints.append(
                Constraint(sqr(rho[a]) - sqr(rho[b]) + lhs - const_term, 0.0, 0.0, redundant=True)
            )

    names = list(co.names) + [f"rho{i + 1}" for i in range(robot.m)]
    domain = np.vstack(co.rows + [np.zeros((robot.m, 2))])
    lo, hi = rho_domain(robot, np.zeros(robot.m), robot.domain)  # u = 0; per u: search_domain
    domain[k * d :, 0] = lo
    domain[k * d :, 1] = np.maximum(hi, lo)
    params: dict = {f"u{i + 1}": 0.0 for i in range(robot.m)} | tolerance_parameters(robot)
    system = System(names, domain, eqs, constraints, name=name, parameters=params)
    return system, bool(fourth)


# -- the formulations ------------------------------------------------------------------------------


@dataclass(kw_only=True)
class PlatformFormulation(FKFormulation):
    """A formulation on chosen platform points: ``platform`` holds them (``Q``, the affine
    coefficients ``L`` of the attachments and ``lG`` of the centre of mass)."""

    platform: PlatformPoints

    @property
    def Q(self) -> np.ndarray:
        """The chosen points ``(k, d)``, platform frame."""
        return self.platform.Q

    @property
    def L(self) -> np.ndarray:
        """The affine coefficients ``(m, k)`` of the attachments."""
        return self.platform.L

    @property
    def lG(self) -> np.ndarray:
        """The affine coefficients ``(k,)`` of the centre of mass."""
        return self.platform.lG

    @property
    def n_points(self) -> int:
        return self.Q.shape[0]

    def points_from(self, x) -> np.ndarray:
        """The chosen points ``(k, d)`` from a vector of the system's variables."""
        k, d = self.n_points, self.robot.dim
        return np.array(x[: k * d], dtype=float).reshape(k, d)

    def coordinates_of(self, P) -> np.ndarray:
        """The inverse of :meth:`points_from`: the first ``k*d`` variables for points ``P``."""
        return np.array(P, dtype=float).ravel()

    def encode(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """The chosen points' coordinates of the pose: ``P_j = p + R Q_j``."""
        return self.coordinates_of(position + self.Q @ rotation.T)

    def decode(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rigid transform ``P_j = p + R Q_j`` fitted to the chosen points (Kabsch), and
        ``B_i = Σ_j l_ij P_j``."""
        P = self.points_from(x)
        Q = self.Q
        qc = Q.mean(axis=0)
        pc = P.mean(axis=0)
        U, _, Vt = np.linalg.svd((Q - qc).T @ (P - pc))
        D = np.eye(Q.shape[1])
        D[-1, -1] = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
        R = Vt.T @ D @ U.T
        return pc - R @ qc, R, self.L @ P

    @abstractmethod
    def _edges(self) -> list[list[Expr]]:
        """``E_j = P_j - P_1``, ``j = 2..k``, as expressions of the variables."""

    def levers(self) -> tuple[list[Expr], list[list[Expr]]]:
        """``G = P_1 + Σ_{j>=2} lG_j E_j`` and ``B_i - G = Σ_{j>=2} (l_ij - lG_j) E_j`` with
        the edge vectors ``E_j``; the differences of coefficients are outward-rounded
        interval constants, so the enclosures cover the exact ``B_i - G``."""
        robot = self.robot
        d, k = robot.dim, self.n_points
        P1 = [var(f"{a}1") for a in "xyz"[:d]]
        E = self._edges()

        def rel(lo, hi) -> list[Expr]:
            nz = [j for j in range(1, k) if lo[j] != 0.0 or hi[j] != 0.0]
            if not nz:
                return [const(0.0)] * d
            return [esum(coefficient(lo[j], hi[j]) * E[j - 1][c] for j in nz) for c in range(d)]

        G = [P1[c] + g for c, g in enumerate(rel(self.lG, self.lG))]
        return G, [rel(*difference(self.L[i], self.lG)) for i in range(robot.m)]


@dataclass(kw_only=True)
class PointsFormulation(PlatformFormulation):
    """The paper's systems: the chosen points in world coordinates (``x1, y1, z1, x2 ...``),
    moments about the domain centre."""

    kind: ClassVar[str] = "points"

    @classmethod
    def build(cls, robot: Robot, name: str, platform: PlatformPoints) -> PointsFormulation:
        system, _ = _platform_system(robot, name, platform, _Points, True)
        return cls(name=name, robot=robot, system=system, platform=platform)

    def _edges(self) -> list[list[Expr]]:
        axes = "xyz"[: self.robot.dim]
        return [[var(f"{a}{j + 1}") - var(f"{a}1") for a in axes] for j in range(1, self.n_points)]


@dataclass(kw_only=True)
class FrameFormulation(PlatformFormulation):
    """The paper's system in a platform frame: ``P_1`` (``x1, y1, z1``), the edge vectors
    ``E_j = P_j - P_1`` (``ex2, ey2 ...``) and ρ; moments about ``P_1``.

    ``translation``: the lengths and the forces in ``(P_1, ρ)``, a square sub-system well
    conditioned for a whole box of orientations (partial Newton).  In general-19 the fourth
    edge vector is :attr:`determined` by the other two through the fourth-point equalities:
    it is never split (splitting only E_2, E_3 and P_1: general-19 at 60 N u~S(2) 332,650
    -> 174,968 boxes, u~S(3) 304,304 -> 226,492, at 10 N 156,523 -> 130,749;
    random-general-0 at 60 N 3.92M -> 3.85M).
    """

    kind: ClassVar[str] = "frame"

    translation: tuple[list[int], list[int]]

    @classmethod
    def build(cls, robot: Robot, name: str, platform: PlatformPoints) -> FrameFormulation:
        system, fourth = _platform_system(robot, name, platform, _Frame, ("points",))
        d, k, m = robot.dim, platform.Q.shape[0], robot.m
        equations = list(range(m)) + [m + k * (k - 1) // 2 + c for c in range(d)]
        variables = list(range(d)) + list(range(k * d, k * d + m))
        return cls(
            name=name,
            robot=robot,
            system=system,
            platform=platform,
            determined=tuple(range(3 * d, 4 * d)) if fourth else (),
            translation=(equations, variables),
        )

    def points_from(self, x) -> np.ndarray:
        P = super().points_from(x)
        P[1:] = P[0] + P[1:]
        return P

    def coordinates_of(self, P) -> np.ndarray:
        P = np.array(P, dtype=float)
        P[1:] = P[1:] - P[0]
        return P.ravel()

    def _edges(self) -> list[list[Expr]]:
        axes = "xyz"[: self.robot.dim]
        return [[var(f"e{a}{j + 1}") for a in axes] for j in range(1, self.n_points)]

    def subsystems(self) -> list[tuple[list[int], list[int]]]:
        return [self.translation]

    def bisector(self, domain: np.ndarray) -> Any:
        """Orientation (edge vectors) first; the reference point only while it is much
        wider (:class:`.Prioritized`).

        In space, narrow wire-length ranges (low tension limits) pin the platform position
        once its orientation is known: the orientation is split first; wide ranges leave
        the position free, so it is split sooner (measured: T-16 at 10 N / 60 N; a planar
        platform has a single rotation and keeps ``alpha = 0.25``), though never before it
        is twice as wide as the orientation (:data:`ALPHA_MAX`): at 60 N a split of the
        orientation leaves ~0.27 of a surviving box after contraction, one of the position
        ~0.65 (random-general-0; 0.5 instead of 0.75: general-19 u~S(2) and T-16 u=2 at
        60 N, 8 % and 1 % fewer boxes; docs/fk-cost.md).
        """
        names = self.system.variables
        alpha = 0.25
        if self.robot.dim == 3:
            rho = np.array([v.startswith("rho") for v in names])
            width = float(np.mean(domain[rho, 1] - domain[rho, 0])) if rho.any() else 0.0
            cap = ALPHA_MAX_GENERAL if self.determined else ALPHA_MAX
            alpha = float(np.clip(width / 25.0, 0.25, cap))
        return Prioritized(
            [v.startswith("e") for v in names],
            [not v.startswith(("e", "rho")) for v in names],
            alpha=alpha,
        )
