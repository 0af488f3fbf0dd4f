"""The largest centred ellipse (ellipsoid) inside a force polytope: section IV-C of the paper.

Krut et al. mention, besides the isotropic force, "the centred ellipse with the largest
surface included inside the operational force polytope".  Centred here means centred at the
bias point ``x0`` (the origin without load).  With the ellipsoid ``{x0 + L u : |u| ≤ 1}`` and
``M = L L^T``, it lies in ``{n_k · x ≤ d_k}`` iff ``||L^T n_k|| ≤ s_k = d_k - n_k · x0`` for
every ``k``, i.e. ``n_k^T M n_k ≤ s_k²``: constraints **linear** in ``M``.  Maximising the area
(volume) ``∝ sqrt(det M)`` is the concave problem

    max log det M   subject to   n_k^T M n_k ≤ s_k²,   M ≻ 0,

solved here with SLSQP (scipy) from the inscribed ball ``M = r² I``; its optimum is unique.
The semi-axes are the square roots of the eigenvalues of ``M``.  It exists only when the
bias point is strictly inside (``r > 0``).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gamma, pi

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import minimize

from .polytope import ForcePolytope

__all__ = ["CentredEllipsoid", "largest_centred_ellipsoid"]


@dataclass
class CentredEllipsoid:
    centre: np.ndarray  # (n,)
    semi_axes: np.ndarray  # (n,) decreasing
    axes: np.ndarray  # (n, n) unit axes as columns
    measure: float  # area (n = 2) or volume (n = 3)
    converged: bool

    def to_dict(self) -> dict:
        return {
            "centre": [float(t) for t in self.centre],
            "semi_axes": [float(t) for t in self.semi_axes],
            "axes": [[float(t) for t in col] for col in self.axes.T],
            "measure": float(self.measure),
            "converged": bool(self.converged),
        }


def _sym(x: np.ndarray, n: int) -> np.ndarray:
    M = np.zeros((n, n))
    iu = np.triu_indices(n)
    M[iu] = x
    return M + M.T - np.diag(np.diag(M))


def largest_centred_ellipsoid(poly: ForcePolytope, centre: ArrayLike) -> CentredEllipsoid:
    """The largest-area (volume) ellipsoid centred at ``centre`` inside ``poly``."""
    x0 = np.asarray(centre, dtype=float)
    N = poly.normals
    s = poly.offsets - N @ x0
    n = N.shape[1]
    r = float(np.min(s))
    if not r > 0:
        raise ValueError("the centre is not strictly inside the polytope: no centred ellipse")
    iu = np.triu_indices(n)
    # n_k^T M n_k is linear in the upper-triangular entries of M
    coef = np.stack(
        [np.where(i == j, N[:, i] * N[:, j], 2.0 * N[:, i] * N[:, j]) for i, j in zip(*iu)],
        axis=1,
    )
    scale = r * r

    def obj(x):
        sign, logdet = np.linalg.slogdet(_sym(x, n))
        return np.inf if sign <= 0 else -logdet

    def grad(x):
        G = -np.linalg.inv(_sym(x, n))
        return np.where(iu[0] == iu[1], G[iu], 2.0 * G[iu])

    x_start = (np.eye(n) * 0.999)[iu]  # in units of r²
    cons = {
        "type": "ineq",
        "fun": lambda x: (s * s) / scale - coef @ x,
        "jac": lambda x: -coef,
    }
    res = minimize(
        obj,
        x_start,
        jac=grad,
        constraints=[cons],
        method="SLSQP",
        options={"maxiter": 500, "ftol": 1e-12},
    )
    M = _sym(res.x, n) * scale
    w, V = np.linalg.eigh(M)
    order = np.argsort(w)[::-1]
    w, V = np.maximum(w[order], 0.0), V[:, order]
    semi = np.sqrt(w)
    unit_ball = pi ** (n / 2) / gamma(n / 2 + 1)
    return CentredEllipsoid(
        centre=x0,
        semi_axes=semi,
        axes=V,
        measure=float(unit_ball * np.prod(semi)),
        converged=bool(res.success),
    )
