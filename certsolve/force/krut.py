"""The six steps of Krut, Company, Pierrot (2004), section III: a reference algorithm.

For ``f = J_m^T τ`` with ``J_m^T = H = U S V^T`` (eq. 4, numpy's ``U, S, Vt``):

1. the ``2^m`` vertices of the joint box (eq. 3): bit ``i`` of ``l - 1`` chooses
   ``τ_i^max`` (1) or ``τ_i^min`` (0) (eq. 7);
2. their coordinates in the SVD joint base, ``τ_s = V^T τ`` (eq. 8);
3. their projection on the range of ``J_m^T``, ``τ_r = P τ_s`` (eq. 9: the first ``n``
   coordinates);
4. for every choice of ``n`` distinct projected vertices, the hyperplane ``p^T u_k = 1``
   through them (eqs. 10-14): ``u_k = T_k^{-1} [1 … 1]^T`` when ``det T_k ≠ 0``.  When
   ``T_k`` is singular but the ``n`` points are affinely independent, their hyperplane
   passes through the origin (the case the paper says "the final algorithm takes into
   account"); it is kept as ``n_r · p = 0`` with ``n_r`` the generalised cross product of
   the differences ``p_j - p_1``;
5. the frontier test (15): a hyperplane is a facet iff all projected vertices lie on one
   side (*BorderType1*: all ``≤ 1``; *BorderType2*: all ``≥ 1``).  The origin is inside iff
   every facet is of type 1;
6. mapping into the operational space.  Since ``f_s = S' τ_r``, a point with
   ``τ_r^T u_k = 1`` satisfies ``f_s^T (S'^{-1} u_k) = 1``, so ``v_k = S'^{-1} u_k`` in the
   SVD operational base and ``v_k ← U v_k`` in the canonical base.  (The paper's eq. (17)
   prints ``v_k = S' u_k``, copied from the velocity paper [1] where the map goes the other
   way; for forces it is the inverse of ``S'``.  The test against hyperplane shifting
   checks this.)

The cost is ``C(2^m, n)`` linear systems: fine for the planar robots (``C(64, 2) = 2016``
for 6 motors), impossible for MARIONET (``C(128, 6) ≈ 5·10^9``); :func:`krut_polytope`
refuses beyond ``max_combinations``.
"""

from __future__ import annotations

from itertools import combinations
from math import comb

import numpy as np
from numpy.typing import ArrayLike

from .polytope import FlatPolytopeError, ForcePolytope, dedupe_facets
from .wedge import wedge_float

__all__ = ["krut_polytope", "box_vertices"]


def box_vertices(tau_min: ArrayLike, tau_max: ArrayLike) -> np.ndarray:
    """Step 1 (eq. 7): the ``2^m`` vertices, row ``l - 1`` from the bits of ``l - 1``."""
    tmin = np.asarray(tau_min, dtype=float)
    tmax = np.asarray(tau_max, dtype=float)
    m = tmin.size
    bits = (np.arange(2**m)[:, None] >> np.arange(m)[None, :]) & 1
    return np.where(bits == 1, tmax, tmin)


def krut_polytope(
    H: np.ndarray,
    tau_min: ArrayLike,
    tau_max: ArrayLike,
    max_combinations: int = 1_000_000,
    tol: float = 1e-9,
) -> ForcePolytope:
    """Operational force polytope of one pose by the paper's six steps (see module doc)."""
    H = np.asarray(H, dtype=float)
    n, m = H.shape
    n_comb = comb(2**m, n)
    if n_comb > max_combinations:
        raise ValueError(
            f"Krut's algorithm needs C(2^{m}, {n}) = {n_comb} linear systems "
            f"(limit {max_combinations}); use hyperplane shifting"
        )
    if m < n:  # (found by the service's schemathesis run: the SVD below needs m >= n)
        raise FlatPolytopeError(f"{m} wires span fewer than {n} directions: the polytope is flat")
    U, S, Vt = np.linalg.svd(H)
    if S[-1] <= 1e-12 * S[0]:
        raise FlatPolytopeError(f"the wrench matrix has rank < {n}: the polytope is flat")
    verts = box_vertices(tau_min, tau_max)  # step 1
    tau_s = verts @ Vt.T  # step 2, eq. (8)
    tau_r = tau_s[:, :n]  # step 3, eq. (9)
    scale = max(1.0, float(np.abs(tau_r).max()))
    idx = np.fromiter(
        (i for c in combinations(range(len(tau_r)), n) for i in c), dtype=np.int64
    ).reshape(-1, n)
    T = tau_r[idx]  # (q, n, n): eq. (13)
    det = np.linalg.det(T / scale)
    cramer = np.abs(det) > 1e-12
    u = np.linalg.solve(T[cramer], np.ones((int(cramer.sum()), n, 1)))[..., 0]  # eq. (14)
    # singular systems: hyperplane through the origin when the points are affinely independent
    Ts = T[~cramer]
    diffs = np.swapaxes(Ts[:, 1:, :] - Ts[:, :1, :], 1, 2)  # (q', n, n-1)
    nr = wedge_float(np.moveaxis(diffs, 0, -1)).T if n >= 2 else np.ones((len(Ts), 1))
    nn = np.linalg.norm(nr, axis=1)
    good = nn > 1e-12 * scale ** (n - 1)
    nr = nr[good] / nn[good, None]
    through = np.abs(np.einsum("kj,kj->k", nr, Ts[good][:, 0, :])) <= tol * scale
    nr = nr[through]

    # step 5, eq. (15): all projected vertices on one side
    val = u @ tau_r.T  # (q, 2^m)
    type1 = np.all(val <= 1.0 + tol, axis=1)
    type2 = np.all(val >= 1.0 - tol, axis=1) & ~type1
    val0 = nr @ tau_r.T
    side_neg = np.all(val0 <= tol * scale, axis=1)
    side_pos = np.all(val0 >= -tol * scale, axis=1) & ~side_neg
    # step 6, eq. (17) corrected: v = U S'^{-1} u
    v1 = (u[type1] / S) @ U.T
    v2 = (u[type2] / S) @ U.T
    z = (np.concatenate([nr[side_neg], -nr[side_pos]]) / S) @ U.T
    normals = np.concatenate([v1, -v2, z])
    offsets = np.concatenate([np.ones(len(v1)), -np.ones(len(v2)), np.zeros(len(z))])
    nrm, off = dedupe_facets(normals, offsets)
    poly = ForcePolytope(
        nrm,
        off,
        algorithm="krut2004",
        space="force" if n == 2 else "wrench",
        meta={
            "krut": {
                "combinations": int(len(idx)),
                "cramer_systems": int(cramer.sum()),
                "frontiers": int(type1.sum() + type2.sum() + side_neg.sum() + side_pos.sum()),
                "origin_inside": bool(not type2.any() and not side_pos.any()),
            }
        },
    )
    return poly
