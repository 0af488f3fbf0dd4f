"""Bounded summaries of what a search leaves: undecided and pending boxes as hulls with counts.

A search may end with a million boxes it could not decide (a curve of singular solutions, a
pole) or could not explore (a time limit).  A result lists them as *hulls* -- each hull
contains the boxes it stands for, so listing hulls instead of boxes loses no solution -- with
the number of boxes each one holds, and at most a fixed number of them:

* :func:`merge_touching` replaces groups of boxes that touch or overlap (closed boxes with a
  common point, found among neighbours in a sweep along one axis, grouped by connected
  components) by their hulls, in rounds: a hull that touches another box or hull is merged
  in the next round.  Vectorised: ``O(N log N)`` numpy work per round for ``N`` boxes;
  greedy (a few touching hulls may stay apart).
* :func:`chunk_hulls` cuts the search stack into at most ``k`` runs of consecutive boxes and
  lists the hull of each (the stack is depth-first, so neighbours in it are neighbours in the
  search tree).  Cost: one ``reduceat`` pass over the stack, no Python loop over boxes.
* :func:`summarize` builds the undecided and pending parts of a
  :class:`~.result.SolveResult` with both: undecided boxes are merged (only boxes of the same
  reason), and listed up to ``max_undecided`` hulls -- past it the largest clusters are kept,
  the number of boxes left out is reported and the status cannot be ``complete``; pending
  boxes are merged by chunks into at most ``max_pending`` hulls, none left out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["merge_touching", "chunk_hulls", "summarize", "Summary", "MAX_LISTED"]

#: default cap on listed undecided hulls and on listed pending hulls
MAX_LISTED = 1000

_OFFSETS = 8  # sweep neighbours compared per box and round


def _sweep_axis(lo: np.ndarray, hi: np.ndarray) -> int:
    """The axis along which the boxes overlap least: spread of positions over typical width
    (estimated on a sample of at most 4096 boxes)."""
    step = max(1, lo.shape[0] // 4096)
    lo, hi = lo[::step], hi[::step]
    with np.errstate(all="ignore"):
        mid = np.clip(0.5 * lo + 0.5 * hi, -1e300, 1e300)
        spread = np.max(mid, axis=0) - np.min(mid, axis=0)
        width = _median_of_columns(np.clip(hi - lo, 0.0, 1e300))
        score = spread / (width + 1e-300)
    score = np.where(np.isfinite(score), score, 0.0)
    return int(np.argmax(score))


def _median_of_columns(a: np.ndarray) -> np.ndarray:
    """``np.median(a, axis=0)``, the same floats (the middle of each sorted column, or the
    mean ``(x + y) / 2`` of its two middle values; NaN in a column holding one), without
    the import of ``numpy.ma`` that ``np.median`` makes on its first call (~5 ms)."""
    s = np.sort(a, axis=0)
    k = a.shape[0]
    mid = s[k // 2] if k % 2 else (s[k // 2 - 1] + s[k // 2]) / 2
    return np.where(np.isnan(s[-1]), np.nan, mid)


def _components(i: np.ndarray, j: np.ndarray, N: int) -> tuple[int, np.ndarray]:
    """The connected components of the undirected graph on ``N`` nodes with the edges
    ``(i[e], j[e])``: their number and each node's label, ``0 ..`` in the order of their
    smallest node (the labels of ``scipy.sparse.csgraph.connected_components``, without
    its import: ~0.12 s of CPU).

    Each node points to a node of its component with an index no larger (at first itself);
    a round hooks, for every edge, the larger of its two ends' roots onto the smaller, then
    follows the pointers to their roots (pointer jumping, ``O(log N)`` gathers).  Rounds
    stop when no root moves: then every edge joins two nodes of one root, and a root only
    ever points along edges, so the roots are the components' smallest nodes.
    """
    root = np.arange(N)
    while True:
        ri, rj = root[i], root[j]
        low = np.minimum(ri, rj)
        hooked = root.copy()
        np.minimum.at(hooked, ri, low)
        np.minimum.at(hooked, rj, low)
        while True:  # pointer jumping: every node to its root
            up = hooked[hooked]
            if np.array_equal(up, hooked):
                break
            hooked = up
        if np.array_equal(hooked, root):
            break
        root = hooked
    is_root = root == np.arange(N)
    rank = np.cumsum(is_root) - 1  # a root's label: the roots before it
    return int(rank[-1]) + 1, rank[root]


def _touching_pairs(lo: np.ndarray, hi: np.ndarray):
    """Touching pairs ``(i, j)`` among boxes at most ``_OFFSETS`` apart in sweep order (sorted
    by the lower bound on :func:`_sweep_axis`); returns the sort order and the pairs."""
    N = lo.shape[0]
    ax = _sweep_axis(lo, hi)
    order = np.argsort(lo[:, ax], kind="stable")
    slo, shi = lo.T[:, order], hi.T[:, order]  # (n, N): one contiguous row per axis
    pi, pj = [], []
    active = np.arange(N - 1)
    for k in range(1, _OFFSETS + 1):
        active = active[active + k < N]
        j = active + k
        near = slo[ax, j] <= shi[ax, active]  # sorted by lo: the next ones are further away
        active, j = active[near], j[near]
        if active.size == 0:
            break
        a, b = active, j
        for d in range(lo.shape[1]):  # axis by axis: most candidates fail early
            if d == ax:
                continue
            keep = (slo[d, b] <= shi[d, a]) & (slo[d, a] <= shi[d, b])
            a, b = a[keep], b[keep]
        pi.append(a)
        pj.append(b)
    if not pi:
        return order, np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    return order, np.concatenate(pi), np.concatenate(pj)


def _group_hulls(lo, hi, counts, labels, ngroups):
    perm = np.argsort(labels, kind="stable")
    sl = labels[perm]
    starts = np.flatnonzero(np.r_[True, sl[1:] != sl[:-1]])
    assert starts.size == ngroups
    return (
        np.minimum.reduceat(lo[perm], starts, axis=0),
        np.maximum.reduceat(hi[perm], starts, axis=0),
        np.add.reduceat(counts[perm], starts),
    )


def merge_touching(lo, hi, counts=None, max_rounds: int = 12):
    """Hulls of groups of touching boxes: ``(lo, hi, counts)``, largest groups first.

    Greedy: each round merges the connected groups of touching pairs (of boxes, then of
    hulls) found among sweep neighbours, and rounds go on while they merge at least 1% of
    the hulls; a few touching hulls may stay apart.  ``counts`` (default 1 each) are the
    numbers of boxes each input already stands for; every input box lies in the hull it is
    counted in.
    """
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    counts = np.ones(lo.shape[0], dtype=np.int64) if counts is None else np.asarray(counts)
    for _ in range(max_rounds):
        N = lo.shape[0]
        if N < 2:
            break
        order, i, j = _touching_pairs(lo, hi)
        if i.size == 0:
            break
        ngroups, labels = _components(i, j, N)
        lo, hi, counts = _group_hulls(lo[order], hi[order], counts[order], labels, ngroups)
        if ngroups > 0.99 * N:
            break
    first = np.argsort(-counts, kind="stable")
    return lo[first], hi[first], counts[first]


def chunk_hulls(lo, hi, max_listed: int):
    """At most ``max_listed`` hulls of runs of consecutive boxes: ``(lo, hi, counts)``."""
    N = lo.shape[0]
    if N <= max_listed:
        return lo.copy(), hi.copy(), np.ones(N, dtype=np.int64)
    starts = (np.arange(max_listed, dtype=np.int64) * N) // max_listed
    return (
        np.minimum.reduceat(lo, starts, axis=0),
        np.maximum.reduceat(hi, starts, axis=0),
        np.diff(np.r_[starts, N]),
    )


@dataclass(kw_only=True)
class Summary:
    """Undecided and pending parts of a result (see the module docstring)."""

    undecided: list  # [(lo, hi, reason, boxes)] hulls listed, largest clusters first
    undecided_total: int  # undecided boxes found by the search
    undecided_dropped: int  # of those, boxes in no listed hull
    pending_lo: np.ndarray  # (k, n) hulls of the boxes left by a limit
    pending_hi: np.ndarray
    pending_boxes: np.ndarray  # (k,) boxes in each hull
    pending_total: int


def summarize(
    undecided: list,
    pending_lo: np.ndarray,
    pending_hi: np.ndarray,
    *,
    max_undecided: int = MAX_LISTED,
    max_pending: int = MAX_LISTED,
) -> Summary:
    """``undecided`` is a list of ``(lo, hi, reason)``; pending boxes are ``(N, n)`` arrays."""
    if max_undecided < 0 or max_pending < 1:
        raise ValueError("max_undecided must be >= 0 and max_pending >= 1")
    n = pending_lo.shape[1]
    hulls = []
    reasons = sorted({r for _, _, r in undecided})
    for reason in reasons:
        rows = [(a, b) for a, b, r in undecided if r == reason]
        ulo = np.array([a for a, _ in rows], dtype=np.float64).reshape(-1, n)
        uhi = np.array([b for _, b in rows], dtype=np.float64).reshape(-1, n)
        mlo, mhi, cnt = merge_touching(ulo, uhi)
        hulls += [(mlo[k], mhi[k], reason, int(cnt[k])) for k in range(cnt.size)]
    hulls.sort(key=lambda h: -h[3])  # stable: reasons in order within equal counts
    listed = hulls[:max_undecided]
    plo, phi, pcnt = chunk_hulls(pending_lo, pending_hi, max_pending)
    return Summary(
        undecided=listed,
        undecided_total=len(undecided),
        undecided_dropped=sum(h[3] for h in hulls[max_undecided:]),
        pending_lo=plo,
        pending_hi=phi,
        pending_boxes=pcnt,
        pending_total=int(pending_lo.shape[0]),
    )
