"""Facet candidates of a zonotope and generalised cross products (float and interval).

The wrench polytope ``W = {H τ : τ_min ≤ τ ≤ τ_max}`` is a zonotope with generators the
columns ``h_1..h_m`` of ``H`` (``w × m``).  When ``W`` is full-dimensional, each facet is
parallel to ``w - 1`` linearly independent generators, so its normal is orthogonal to
them: the **generalised cross product** of those ``w - 1`` columns,

    c_k = (-1)^k det(M without row k),   M = [h_{s_1} ... h_{s_{w-1}}]  (w × (w-1)),

which is orthogonal to every column of ``M`` (expand ``det[M, x]`` along its last column:
``det[M, x] = ± c · x``) and vanishes iff the columns are dependent.  The candidate
subsets are the ``C(m, w-1)`` combinations of columns (hyperplane shifting, Bouchet /
Gouttefarde's method; cost grows with ``C(m, w-1)``).

:func:`wedge_float` computes ``c`` for every subset in a batch by the Laplace recursion
``D_r[S] = Σ_t ±M[S_t, r] D_{r-1}[S - S_t]`` on the minors of the first ``r`` columns (``S``
a sorted set of ``r`` rows), vectorised over poses and subsets (batch axes last, for
contiguous gathers); :func:`certsolve.force.meanvalue.wedge_mv` is its interval (slope)
version, built on the same tables.
"""

from __future__ import annotations

from functools import lru_cache
from itertools import combinations

import numpy as np

__all__ = ["facet_subsets", "basis_groups", "wedge_tables", "wedge_float"]


@lru_cache(maxsize=64)
def facet_subsets(m: int, w: int) -> np.ndarray:
    """All ``(w-1)``-subsets of the ``m`` columns, shape ``(K, w-1)`` (``K = C(m, w-1)``)."""
    if w < 2 or m < w - 1:
        return np.zeros((0, max(w - 1, 0)), dtype=np.int64)
    return np.array(list(combinations(range(m), w - 1)), dtype=np.int64).reshape(-1, w - 1)


@lru_cache(maxsize=16)
def wedge_tables(
    w: int,
) -> tuple[list[tuple[np.ndarray, np.ndarray, np.ndarray]], np.ndarray, np.ndarray]:
    """Index tables of the Laplace recursion for ``w``-vectors, ``w - 1`` columns.

    Returns a list over ``r = 2..w-1`` of ``(rows_r, terms)`` where ``rows_r`` are the sorted
    ``r``-subsets of rows and ``terms`` is a list over ``t`` of ``(row_idx, prev_idx, sign)``
    arrays: ``D_r[j] = Σ_t sign[t, j] * M[row_idx[t, j], r-1] * D_{r-1}[prev_idx[t, j]]``.
    Also returns the final ``(w-1)``-subsets (``w`` of them, row ``k`` left out is subset
    ``w-1-k`` in lexicographic order) and the cofactor signs.
    """
    levels: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    prev: list[tuple[int, ...]] = [(s,) for s in range(w)]
    for r in range(2, w):
        rows = list(combinations(range(w), r))
        pos_prev = {s: i for i, s in enumerate(prev)}
        row_idx = np.empty((r, len(rows)), dtype=np.int64)
        prev_idx = np.empty((r, len(rows)), dtype=np.int64)
        sign = np.empty((r, len(rows)))
        for j, S in enumerate(rows):
            for t in range(r):
                row_idx[t, j] = S[t]
                prev_idx[t, j] = pos_prev[S[:t] + S[t + 1 :]]
                # Laplace along column r (1-based) of the r×r minor: sign (-1)^(t+1+r)
                sign[t, j] = (-1.0) ** (t + 1 + r)
        levels.append((row_idx, prev_idx, sign))
        prev = rows
    final = {s: i for i, s in enumerate(prev)}
    # c_k = (-1)^k det(M without row k)
    order = np.array([final[tuple(x for x in range(w) if x != k)] for k in range(w)])
    csign = np.array([(-1.0) ** k for k in range(w)])
    return levels, order, csign


def wedge_float(M: np.ndarray) -> np.ndarray:
    """Generalised cross products of ``M`` of shape ``(w, w-1, ...)``: ``(w, ...)``.

    The batch axes come **last** so that every gather below moves contiguous blocks.
    """
    w = M.shape[0]
    if w == 2:
        return np.stack([M[1, 0], -M[0, 0]])
    if w == 3:
        a, b = M[:, 0], M[:, 1]
        return np.stack(
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        )
    levels, order, csign = wedge_tables(w)
    extra = (1,) * (M.ndim - 2)
    D = M[:, 0]
    for r, (row_idx, prev_idx, sign) in enumerate(levels, start=1):
        col = M[:, r]
        D = np.sum(sign.reshape(sign.shape + extra) * col[row_idx] * D[prev_idx], axis=0)
    return csign.reshape((w,) + extra) * D[order]


@lru_cache(maxsize=64)
def basis_groups(
    m: int, w: int, b0: tuple[int, ...]
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    r"""Facet subsets relative to a basis ``b0`` of ``w`` columns, grouped by ``t = |S ∩ N|``.

    ``N`` are the other columns.  Used by the basis form of the facets (a normal is
    ``λ^T H_B0^{-1}[F]`` with ``λ`` the generalised cross product of ``Y[F, T]``, ``Y = H_B0^{-1}
    H_N``).

    Returns a list of ``(F, T, R)`` index arrays: positions in ``b0`` of ``F = b0 \ S``
    ``(K_t, t+1)``, positions in ``N`` of ``T = S ∩ N`` ``(K_t, t)`` and of ``R = N \ S``
    ``(K_t, e-t)``.
    """
    nn = [i for i in range(m) if i not in b0]
    groups: dict[int, list] = {}
    for S in combinations(range(m), w - 1):
        Ss = set(S)
        F = [k for k, b in enumerate(b0) if b not in Ss]
        T = [k for k, n in enumerate(nn) if n in Ss]
        R = [k for k, n in enumerate(nn) if n not in Ss]
        groups.setdefault(len(T), []).append((F, T, R))
    out = []
    for t in sorted(groups):
        g = groups[t]
        out.append(
            (
                np.array([x[0] for x in g], dtype=np.int64).reshape(len(g), t + 1),
                np.array([x[1] for x in g], dtype=np.int64).reshape(len(g), t),
                np.array([x[2] for x in g], dtype=np.int64).reshape(len(g), len(nn) - t),
            )
        )
    return out
