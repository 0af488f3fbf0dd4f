"""The platform's affine frame for the FK systems, in exact rationals (Merlet 2007, eq. 8).

Every attachment ``B_i`` and the centre of mass ``G`` are affine combinations of ``k``
chosen platform points: ``B_i = Σ_j l_ij P_j`` with ``Σ_j l_ij = 1``.  Which points are
chosen (the largest simplex), the coefficients ``l_ij`` and the signed volume of the chosen
points are computed here in exact rationals from the robot file's floats and rounded to
nearest once, so the systems written from them are the same on every CPU whichever BLAS
kernel numpy loads.  Nothing here builds an expression: :func:`platform_points` is also the
cheap geometric precondition of the point formulations (:func:`.fk_systems.check_formulation`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..expr.polynomial import gauss_jordan
from ..robot.model import Robot

__all__ = [
    "PlatformPoints",
    "affine_coordinates",
    "choose_points",
    "exact",
    "exact_det",
    "exact_least_squares",
    "is_coplanar",
    "papers_system",
    "planar_platform",
    "platform_points",
]


def exact(a) -> list[list[Fraction]]:
    """A float matrix (or vector, as one row) in exact rationals: every float is one."""
    return [[Fraction(float(x)) for x in row] for row in np.atleast_2d(np.asarray(a, dtype=float))]


def _matmul(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
    return [[sum((x * y for x, y in zip(row, col)), Fraction(0)) for col in zip(*b)] for row in a]


def exact_det(rows: list[list[Fraction]]) -> Fraction:
    """Exact determinant (Laplace expansion along the first row; 2x2 and 3x3 here)."""
    if not rows:
        return Fraction(1)
    minors = ([r[:j] + r[j + 1 :] for r in rows[1:]] for j in range(len(rows)))
    return sum(
        ((-1) ** j * rows[0][j] * exact_det(m) for j, m in enumerate(minors) if rows[0][j]),
        Fraction(0),
    )


def exact_least_squares(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
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


def affine_coordinates(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
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
    M = exact(np.vstack([Q.T, np.ones((1, k))]))  # (d+1, k)
    rhs = exact(np.vstack([X.T, np.ones((1, X.shape[0]))]))
    coef = exact_least_squares(M, rhs)
    resid = max(abs(r - s) for rr, sr in zip(_matmul(M, coef), rhs) for r, s in zip(rr, sr))
    if resid > Fraction(1e-9) * (1 + Fraction(float(np.max(np.abs(X))))):
        raise ValueError("a platform point is not an affine combination of the chosen points")
    out = _rounded(coef).T
    out[np.abs(out) < 1e-14] = 0.0
    return out


def snap_rows(L: np.ndarray, robot: Robot) -> np.ndarray:
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


def choose_points(points: np.ndarray, k: int) -> list[int]:
    """The ``k`` points spanning the largest simplex (best conditioned affine frame).

    The squared volumes (Gram determinants of the edges ``E``; ``det(E)²``, the same
    number, when there are as many edges as dimensions) are compared exactly: a symmetric
    platform has equal simplices, and a float determinant would pick among them by rounding
    noise."""
    best, best_vol = None, Fraction(-1)
    for combo in itertools.combinations(range(points.shape[0]), k):
        P = points[list(combo)]
        E = exact(P[1:] - P[0]) if k > 1 else []
        if not E:
            vol = Fraction(0)
        elif len(E) == len(E[0]):
            vol = exact_det(E) ** 2
        else:
            vol = exact_det(_matmul(E, [list(c) for c in zip(*E)]))
        if vol > best_vol:  # exact: of equal simplices (a symmetric platform) the first
            best, best_vol = list(combo), vol
    if best is None or best_vol <= 1e-12:
        raise ValueError(f"the platform has no {k} affinely independent attachment points")
    return best


def is_coplanar(points: np.ndarray) -> bool:
    if points.shape[0] <= 3:
        return True
    E = points[1:] - points[0]
    s = np.linalg.svd(E, compute_uv=False)
    return bool(s[-1] <= 1e-9 * max(1.0, s[0])) if s.size >= 3 else True


@dataclass(kw_only=True, frozen=True)
class PlatformPoints:
    """The affine frame of a point formulation.

    ``chosen``: indices of the chosen points among the robot's distinct attachment points
    (:meth:`.Robot.attachment_groups`), the reference point ``P_1`` first; ``Q`` ``(k, d)``:
    those points in the platform frame; ``L`` ``(m, k)``: the affine coefficients of every
    attachment (rows of wires sharing a point bitwise equal); ``lG`` ``(k,)``: those of the
    centre of mass.
    """

    chosen: list[int]
    Q: np.ndarray
    L: np.ndarray
    lG: np.ndarray


def platform_points(robot: Robot, name: str, k: int, *, frame: bool = False) -> PlatformPoints:
    """The ``k`` chosen points of ``robot`` and the affine coefficients on them (eq. 8).

    ``frame``: the reference point ``P_1`` is the chosen point that carries the most wires
    (the platform frame's origin).  ``ValueError`` when the robot has fewer than ``k``
    distinct attachment points or they are not affinely independent.
    """
    pts, gidx = robot.attachment_groups()
    if k > pts.shape[0]:
        raise ValueError(
            f"{name} needs {k} distinct attachment points, the robot has {pts.shape[0]}"
        )
    sel = choose_points(pts, k)
    if frame:  # the reference point P_1 carries the most wires
        counts = [int(np.sum(gidx == j)) for j in sel]
        r0 = int(np.argmax(counts))
        sel = [sel[r0]] + [s for i, s in enumerate(sel) if i != r0]
    Q = pts[sel]
    L = snap_rows(affine_coordinates(Q, robot.B), robot)
    lG = affine_coordinates(Q, robot.com[None])[0]
    return PlatformPoints(chosen=[int(i) for i in sel], Q=Q, L=L, lG=lG)


def planar_platform(robot: Robot) -> bool:
    """Attachments and centre of mass coplanar (the platform is its own mirror image)."""
    pts, _ = robot.attachment_groups()
    return is_coplanar(np.vstack([pts, robot.com[None]]))


def papers_system(robot: Robot) -> str:
    """The paper's system for this robot (``auto`` and ``frame`` use it in the platform
    frame): ``planar-10`` (dof 3), ``almost-planar-13`` (4 wires on a planar platform),
    ``T-16`` (3 distinct points on a planar platform), ``points`` (a planar platform with
    more), ``general-19`` (the rest)."""
    if robot.dof == 2:
        raise ValueError(
            "point robots (dof 2) have no rigid platform: forward kinematics of the "
            "elastic model needs dof 3 or 6"
        )
    if robot.dof == 3:
        return "planar-10"
    pts, _ = robot.attachment_groups()
    if planar_platform(robot) and pts.shape[0] >= 3:
        if robot.m == 4:
            return "almost-planar-13"
        if pts.shape[0] == 3:
            return "T-16"
        return "points"
    return "general-19"
