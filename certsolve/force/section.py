"""The force section of the wrench polytope, exactly, by vertex enumeration and a hull.

For rigid platforms (dof 3 and 6) the wrench ``H τ`` has force rows ``H_f`` (2 or 3) and
moment rows ``H_m`` (1 or 3).  The forces the wires can produce while the moment equals a
given ``μ`` form the polytope

    F(μ) = {H_f τ : τ_min ≤ τ ≤ τ_max, H_m τ = μ},

the section of ``W = {H τ}`` by the plane ``moment = μ``.  It is the image under ``H_f`` of
the slice ``Q = {τ in box : H_m τ = μ}`` of the joint box, whose vertices are *basic*
points: ``m - k`` coordinates at a bound and the ``k = rows(H_m)`` others solving
``H_m τ = μ`` (a vertex of a polytope ``{A τ = b, l ≤ τ ≤ u}`` has at least ``m - k`` active
bounds).  :func:`slice_vertices` enumerates every basis (``C(m, k)`` choices times
``2^(m-k)`` bound patterns: 560 linear solves for MARIONET) in one batched solve; the force
section is then the convex hull of ``H_f`` of those vertices (``scipy.spatial.ConvexHull``,
Qhull), with coplanar hull simplices merged into facets.

This is independent of the facet formula used for the index (:mod:`.isotropic`): both are
exact descriptions of the same polytope, and the tests check they agree.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull, QhullError

from .krut import box_vertices
from .polytope import FlatPolytopeError, ForcePolytope, dedupe_facets

__all__ = ["slice_vertices", "hull_polytope", "force_section"]


def slice_vertices(
    A: ArrayLike, b: ArrayLike, tau_min: ArrayLike, tau_max: ArrayLike, tol: float = 1e-9
) -> np.ndarray:
    """Vertices of ``{τ : A τ = b, τ_min ≤ τ ≤ τ_max}`` (``A`` is ``k × m``), possibly repeated.

    With ``k = 0`` these are the ``2^m`` box vertices.  Returns ``(nv, m)`` (empty if the
    slice is empty).
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    b = np.atleast_1d(np.asarray(b, dtype=float))
    tmin = np.asarray(tau_min, dtype=float)
    tmax = np.asarray(tau_max, dtype=float)
    k, m = A.shape
    if k == 0:
        return box_vertices(tmin, tmax)
    span = float(np.max(tmax - tmin)) if m else 1.0
    out = []
    for subset in combinations(range(m), k):
        basic = list(subset)
        non = [i for i in range(m) if i not in basic]
        Ab = A[:, basic]
        if abs(np.linalg.det(Ab)) <= 1e-12 * max(1.0, float(np.abs(Ab).max())) ** k:
            continue
        tn = box_vertices(tmin[non], tmax[non])  # (2^(m-k), m-k)
        rhs = b[None, :] - tn @ A[:, non].T
        tb = np.linalg.solve(Ab, rhs.T).T  # (2^(m-k), k)
        ok = np.all((tb >= tmin[basic] - tol * span) & (tb <= tmax[basic] + tol * span), axis=1)
        if not ok.any():
            continue
        tau = np.empty((int(ok.sum()), m))
        tau[:, non] = tn[ok]
        tau[:, basic] = np.clip(tb[ok], tmin[basic], tmax[basic])
        out.append(tau)
    return np.concatenate(out) if out else np.zeros((0, m))


def hull_polytope(points: np.ndarray, algorithm: str) -> ForcePolytope:
    """Facets of the convex hull of ``points`` (raises ``ValueError`` if it is flat)."""
    pts = np.asarray(points, dtype=float)
    dim = pts.shape[1]
    if len(pts) <= dim:
        raise FlatPolytopeError("the polytope is flat (too few vertices)")
    scale = max(1.0, float(np.abs(pts).max()))
    pts_u = np.unique(np.round(pts / (1e-12 * scale)) * (1e-12 * scale), axis=0)
    try:
        hull = ConvexHull(pts_u)
    except QhullError:
        raise FlatPolytopeError("the polytope is flat (no interior)") from None
    eq = hull.equations  # n·x + e ≤ 0
    normals, offsets = dedupe_facets(eq[:, :-1], -eq[:, -1], tol=1e-9)
    return ForcePolytope(normals, offsets, algorithm=algorithm, vertices=pts_u[hull.vertices])


def force_section(
    H: np.ndarray, tau_min: ArrayLike, tau_max: ArrayLike, moment: ArrayLike, n_force: int
) -> ForcePolytope:
    """``F(μ)`` above for one pose: force rows ``H[:n_force]``, moment rows the others."""
    H = np.asarray(H, dtype=float)
    Hf, Hm = H[:n_force], H[n_force:]
    verts = slice_vertices(Hm, moment, tau_min, tau_max)
    if len(verts) == 0:
        raise ValueError("the required moment cannot be produced: the section is empty")
    poly = hull_polytope(verts @ Hf.T, algorithm="vertex-enumeration+qhull")
    poly.meta = {"slice_vertices": int(len(verts))}
    return poly
