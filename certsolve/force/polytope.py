"""The operational force polytope and hyperplane shifting (the default algorithm).

Krut, Company, Pierrot (2004), section III: the admissible joint forces form the box
``τ_min ≤ τ ≤ τ_max`` (eq. 3) and the operational forces are ``f = J_m^T τ`` (eq. 2).  For a
wire robot ``J_m^T`` is the wrench matrix ``H`` (``w × m``, columns ``h_i``), so the
polytope is the zonotope

    W = {H τ : τ_min ≤ τ ≤ τ_max}.

It is described here in two equivalent forms:

* **normal/offset** ``n_k · f ≤ d_k`` with unit normals ``n_k``;
* the paper's form ``m^T v_k ≤ 1`` (eq. 18) with ``v_k = n_k / d_k`` (undefined when the
  facet plane passes through the origin, ``d_k = 0``; eq. (6) excludes that case too).  A
  facet with ``d_k < 0`` has the origin on its outer side: the inequality then reads
  ``m^T v_k ≥ 1`` (the paper's *BorderType2*) and the origin is outside.

**Hyperplane shifting.**  Every facet normal ``c`` of a full-dimensional zonotope is
orthogonal to ``w - 1`` independent generators (:mod:`.wedge`), and the offset of the
supporting hyperplane with normal ``c`` is the support function of the joint box mapped
by ``H``:

    d(c) = max_{τ in box} c · H τ = Σ_i max(c·h_i τ_i^min, c·h_i τ_i^max)
         = (c^T H) τ_mid + |c^T H| τ_rad,

with ``τ_mid``, ``τ_rad`` the centre and half-width of the box.  For each of the
``C(m, w-1)`` subsets both ``+c`` and ``-c`` give a facet; duplicates (several subsets in
the same hyperplane) are merged.  :func:`zonotope_facets` does this for a batch of poses
without Python loops; :func:`hyperplane_shifting` returns the deduplicated polytope of one
pose.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .wedge import facet_subsets, wedge_float

__all__ = [
    "FlatPolytopeError",
    "ForcePolytope",
    "zonotope_facets",
    "zonotope_facets_t",
    "hyperplane_shifting",
    "dedupe_facets",
    "NORMAL_TOL",
]

#: generalised cross products below this (columns of norm ≤ 1) are treated as zero
NORMAL_TOL = 1e-12


class FlatPolytopeError(ValueError):
    """The polytope has no interior (``rank H < w``): no facet description, no ball."""


@dataclass
class ForcePolytope:
    """``{f : normals @ f ≤ offsets}`` in ``dim`` dimensions (``normals`` are unit rows)."""

    normals: np.ndarray  # (r, dim)
    offsets: np.ndarray  # (r,)
    algorithm: str
    vertices: np.ndarray | None = None  # (nv, dim) when known
    space: str = "force"  # "force" (dof 2 or a force section) or "wrench" (dof 3/6 full)
    meta: dict = field(default_factory=dict)

    @property
    def dim(self) -> int:
        return int(self.normals.shape[1]) if self.normals.ndim == 2 else 0

    @property
    def n_facets(self) -> int:
        return int(self.normals.shape[0])

    def paper_vectors(self) -> np.ndarray:
        """``v_k = n_k / d_k`` of eq. (18) (rows of NaN where the plane crosses the origin)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            v = self.normals / self.offsets[:, None]
        v[np.abs(self.offsets) <= 1e-12 * max(1.0, float(np.abs(self.offsets).max()))] = np.nan
        return v

    def signed_distance(self, x: ArrayLike) -> float:
        """``min_k (d_k - n_k·x)``: the inscribed radius about ``x`` (negative if outside)."""
        x = np.asarray(x, dtype=float)
        return float(np.min(self.offsets - self.normals @ x))

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool:
        return self.signed_distance(x) >= -tol

    def to_dict(self) -> dict:
        v = self.paper_vectors()
        facets = []
        for k in range(self.n_facets):
            facets.append(
                {
                    "normal": [float(t) for t in self.normals[k]],
                    "offset": float(self.offsets[k]),
                    "v": None if np.isnan(v[k]).any() else [float(t) for t in v[k]],
                    "type": 1 if self.offsets[k] >= 0 else 2,
                }
            )
        out = {
            "space": self.space,
            "dim": self.dim,
            "algorithm": self.algorithm,
            "n_facets": self.n_facets,
            "facets": facets,
            "origin_inside": bool(np.all(self.offsets >= 0)) if self.n_facets else False,
        }
        if self.vertices is not None:
            out["vertices"] = [[float(t) for t in p] for p in self.vertices]
        out.update(self.meta)
        return out


def _box_mid_rad(tau_min, tau_max):
    tmin = np.asarray(tau_min, dtype=float)
    tmax = np.asarray(tau_max, dtype=float)
    return 0.5 * (tmin + tmax), 0.5 * (tmax - tmin)


def zonotope_facets_t(
    Ht: np.ndarray, tau_min: ArrayLike, tau_max: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Candidate facets in batch-last layout: ``Ht`` is ``(w, m, P)``.

    Returns ``(C, D, d_plus, d_minus)`` of shapes ``(w, K, P)``, ``(K, m, P)``, ``(K, P)``,
    ``(K, P)``; see :func:`zonotope_facets`.
    """
    w, m = Ht.shape[:2]
    mid, rad = _box_mid_rad(tau_min, tau_max)
    subsets = facet_subsets(m, w)  # (K, w-1)
    M = Ht[:, subsets.T]  # (w, w-1, K, P)
    C = wedge_float(M)  # (w, K, P)
    D = C[0][:, None, :] * Ht[0][None, :, :]
    for r in range(1, w):
        D += C[r][:, None, :] * Ht[r][None, :, :]
    lin = np.einsum("kmp,m->kp", D, mid)
    spread = np.einsum("kmp,m->kp", np.abs(D), rad)
    return C, D, spread + lin, spread - lin


def zonotope_facets(
    H: np.ndarray, tau_min: ArrayLike, tau_max: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Candidate facets of ``{H τ}`` for a batch of poses.

    ``H`` has shape ``(P, w, m)``.  Returns ``(C, D, d_plus, d_minus)``: unnormalised normals
    ``C`` ``(P, K, w)`` (one per ``(w-1)``-subset of columns, ``K = C(m, w-1)``), the
    products ``D = C H`` ``(P, K, m)`` (``D[k, i] = c_k · h_i``), and the offsets of the
    supporting hyperplanes with normals ``+c_k`` and ``-c_k``:
    ``d(±c) = ±D τ_mid + |D| τ_rad``.  A zero ``c_k`` (dependent columns) gives a void
    candidate ``0 ≤ d`` with ``d ≥ 0``: callers drop it by its norm.
    """
    H = np.asarray(H, dtype=float)
    C, D, dp, dm = zonotope_facets_t(np.moveaxis(H, 0, -1), tau_min, tau_max)
    return np.moveaxis(C, 0, -1).transpose(1, 0, 2), np.moveaxis(D, -1, 0), dp.T, dm.T


def dedupe_facets(
    normals: np.ndarray, offsets: np.ndarray, tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """Normalise ``n·f ≤ d`` rows to unit normals and merge rows equal within ``tol``.

    The tolerance is relative to the largest offset magnitude (forces of very different
    sizes are then compared at the same relative precision).
    """
    nrm = np.linalg.norm(normals, axis=1)
    keep = nrm > 0
    n = normals[keep] / nrm[keep, None]
    d = offsets[keep] / nrm[keep]
    if n.shape[0] == 0:
        return n, d
    scale = max(1.0, float(np.max(np.abs(d))))
    rows = np.concatenate([n, (d / scale)[:, None]], axis=1)
    _, first = np.unique(np.round(rows / tol), axis=0, return_index=True)
    rows = rows[np.sort(first)]
    # rows split by a rounding boundary: merge the survivors pairwise (few of them)
    chosen: list[np.ndarray] = []
    for r in rows:
        if not any(np.max(np.abs(r - c)) <= 10 * tol for c in chosen):
            chosen.append(r)
    out = np.array(chosen)
    return out[:, :-1], out[:, -1] * scale


def hyperplane_shifting(H: np.ndarray, tau_min: ArrayLike, tau_max: ArrayLike) -> ForcePolytope:
    """The polytope ``{H τ}`` of one pose (``H`` is ``w × m``) by hyperplane shifting.

    Raises ``ValueError`` if ``H`` has rank below ``w`` (the polytope has no interior and no
    facet description of this kind).
    """
    H = np.asarray(H, dtype=float)
    w = H.shape[0]
    C, D, dp, dm = zonotope_facets(H[None], tau_min, tau_max)
    C, D, dp, dm = C[0], D[0], dp[0], dm[0]
    cn = np.linalg.norm(C, axis=1)
    ok = cn > NORMAL_TOL * max(1.0, float(np.abs(H).max()) ** (w - 1))
    if not ok.any() or not np.any(np.abs(D[ok]) > NORMAL_TOL):
        raise FlatPolytopeError(f"the wrench matrix has rank < {w}: the polytope is flat")
    normals = np.concatenate([C[ok], -C[ok]])
    offsets = np.concatenate([dp[ok], dm[ok]])
    n, d = dedupe_facets(normals, offsets)
    return ForcePolytope(
        n, d, algorithm="hyperplane-shifting", space="force" if w == 2 else "wrench"
    )
