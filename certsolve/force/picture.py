"""The force picture at one pose (Krut et al. 2004, Fig. 4), as plain geometry.

:func:`force_picture` turns an :class:`~.isotropic.IsotropicForceResult` into what a figure
draws, so that the numbers can be tested without looking at pixels:

* the **force polytope** as a polygon: the operational force polytope ``{H τ}`` (dof 2) or
  the force section ``F(μ)`` at the moment required by the load (dof 3);
* the **largest isotropic circle**: centre the bias point ``x0 = -w_ext,f`` (the
  gravity-shifted centre; the origin without load) and radius the maximum isotropic force;
* the **largest centred ellipse** (section IV-C) when it was computed;
* the origin (zero force), to show the gravity shift.

A spatial robot (dof 6) has a 3-D section ``F(μ)``, a ball and an ellipsoid: the picture
holds their **three sections through the centre** by the planes ``f_x = x0_x``,
``f_y = x0_y`` and ``f_z = x0_z``.  A plane through the centre cuts the ball in a great
circle of the same radius and the ellipsoid ``{x0 + v : vᵀ M⁻¹ v ≤ 1}`` in the ellipse
``{v : v_abᵀ (M⁻¹)_ab v_ab ≤ 1}``.

Polygons are intersections of half-planes ``n · f ≤ d`` (the polytope's facets, restricted
to the plane), computed with Qhull from a Chebyshev centre (a linear program), with their
vertices in counter-clockwise order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection, QhullError

from .isotropic import IsotropicForceResult

__all__ = ["PicturePanel", "ForcePicture", "force_picture", "halfplane_polygon"]

_AXES = ("f_x", "f_y", "f_z")


@dataclass(kw_only=True)
class PicturePanel:
    """One 2-D view: coordinates ``axes`` (N); for dof 6, the section ``plane``."""

    axes: tuple[str, str]
    plane: str | None  # e.g. "f_z = 0.1962 N" (dof 6), None for planar robots
    polygon: np.ndarray | None  # (k, 2) vertices, counter-clockwise; None: empty or flat
    centre: np.ndarray  # (2,) the bias point x0 in these coordinates
    radius: float | None  # isotropic circle radius (N); None when no circle fits
    ellipse: np.ndarray | None  # (n, 2) points on the ellipse (closed curve)
    ellipse_semi_axes: np.ndarray | None  # (2,) semi-axes of this ellipse (N)
    origin: np.ndarray  # (2,) zero force in these coordinates

    def to_dict(self) -> dict:
        def lst(a):
            return None if a is None else np.asarray(a, dtype=float).tolist()

        return {
            "axes": list(self.axes),
            "plane": self.plane,
            "polygon": lst(self.polygon),
            "centre": lst(self.centre),
            "radius": self.radius,
            "ellipse_semi_axes": lst(self.ellipse_semi_axes),
            "origin": lst(self.origin),
        }


@dataclass(kw_only=True)
class ForcePicture:
    """Everything :func:`~.plots.plot_force_picture` draws (module docstring)."""

    robot: str
    dof: int
    pose: list[float]
    isotropic_force: float | None
    status: str
    centre: np.ndarray  # (nf,) bias point x0 = -w_ext,f
    ellipse_semi_axes: np.ndarray | None  # (nf,) of the full ellipse/ellipsoid
    n_facets: int | None
    panels: list[PicturePanel]
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "dof": self.dof,
            "pose": [float(v) for v in self.pose],
            "isotropic_force": self.isotropic_force,
            "status": self.status,
            "centre": [float(v) for v in self.centre],
            "ellipse_semi_axes": (
                None if self.ellipse_semi_axes is None else self.ellipse_semi_axes.tolist()
            ),
            "n_facets": self.n_facets,
            "panels": [p.to_dict() for p in self.panels],
            "notes": list(self.notes),
        }


def halfplane_polygon(normals: ArrayLike, offsets: ArrayLike) -> np.ndarray | None:
    """Vertices (counter-clockwise) of ``{x ∈ R² : normals @ x ≤ offsets}``.

    ``None`` when the region is empty, flat or unbounded.
    """
    N = np.asarray(normals, dtype=float)
    d = np.asarray(offsets, dtype=float)
    norm = np.linalg.norm(N, axis=1)
    keep = norm > 1e-12 * max(1.0, float(norm.max(initial=0.0)))
    N, d, norm = N[keep], d[keep], norm[keep]
    if len(N) < 3:
        return None
    # Chebyshev centre: max r subject to N x + r |N_k| <= d
    lp = linprog(
        [0.0, 0.0, -1.0],
        A_ub=np.hstack([N, norm[:, None]]),
        b_ub=d,
        bounds=[(None, None), (None, None), (0.0, None)],
        method="highs",
    )
    if lp.status != 0:
        return None
    x, r = lp.x[:2], lp.x[2]
    if not r > 1e-9 * max(1.0, float(np.abs(d).max())):
        return None
    try:
        hs = HalfspaceIntersection(np.hstack([N, -d[:, None]]), x)
    except QhullError:
        return None
    pts = hs.intersections
    ang = np.arctan2(pts[:, 1] - x[1], pts[:, 0] - x[0])
    pts = pts[np.argsort(ang)]
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9 * (1.0 + np.abs(pts[1:]).max())
    return pts[keep]


def _ellipse_points(Q: np.ndarray, centre: np.ndarray, n: int = 181):
    """Points of ``{centre + v : vᵀ Q v = 1}`` and its semi-axes (Q 2x2 positive definite)."""
    w, V = np.linalg.eigh(Q)
    semi = 1.0 / np.sqrt(w)
    t = np.linspace(0.0, 2.0 * np.pi, n)
    pts = centre[None, :] + (np.stack([np.cos(t), np.sin(t)], axis=1) * semi) @ V.T
    order = np.argsort(semi)[::-1]
    return pts, semi[order]


def force_picture(res: IsotropicForceResult) -> ForcePicture:
    """The geometry of the Fig. 4 picture at the pose of ``res`` (module docstring).

    ``res`` comes from :func:`~.isotropic.isotropic_force` (with ``ellipse=True`` for the
    ellipse); the polytope is its force polytope (dof 2) or force section (dof 3, 6).
    """
    poly = res.polytope
    nf = len(res.centre)
    x0 = np.asarray(res.centre, dtype=float)
    notes = list(res.notes)
    r = res.isotropic_force
    radius = float(r) if r is not None and np.isfinite(r) and r > 0 else None
    if poly is None:
        notes.append("no force polytope at this pose: nothing to draw but the centre")
    Minv = None
    if res.ellipse is not None:
        e = res.ellipse
        Minv = e.axes @ np.diag(1.0 / e.semi_axes**2) @ e.axes.T
    panels = []
    planes = [(0, 1, None)] if nf == 2 else [(0, 1, 2), (0, 2, 1), (1, 2, 0)]
    for a, b, k in planes:
        polygon = None
        if poly is not None:
            N = poly.normals
            d = poly.offsets
            if k is not None:  # restrict to the plane f_k = x0_k
                d = d - N[:, k] * x0[k]
            polygon = halfplane_polygon(N[:, [a, b]], d)
        ell = semi = None
        if Minv is not None:
            ell, semi = _ellipse_points(Minv[np.ix_([a, b], [a, b])], x0[[a, b]])
        panels.append(
            PicturePanel(
                axes=(_AXES[a], _AXES[b]),
                plane=None if k is None else f"{_AXES[k]} = {x0[k]:.4g} N",
                polygon=polygon,
                centre=x0[[a, b]],
                radius=radius,
                ellipse=ell,
                ellipse_semi_axes=semi,
                origin=np.zeros(2),
            )
        )
    return ForcePicture(
        robot=res.robot,
        dof=res.dof,
        pose=list(res.pose),
        isotropic_force=r,
        status=res.status,
        centre=x0,
        ellipse_semi_axes=None if res.ellipse is None else np.asarray(res.ellipse.semi_axes),
        n_facets=None if poly is None else poly.n_facets,
        panels=panels,
        notes=notes,
    )
