"""Intervals as pairs of numpy arrays, and the set operations on them.

An interval array is a pair ``(lo, hi)`` of float64 arrays of the same (broadcastable)
shape; element ``k`` is the closed interval ``[lo[k], hi[k]]``.  A batch of boxes is an
interval array of shape ``(batch, n)``.  Conventions (as in IBEX):

* the **empty** interval is any pair with ``lo > hi`` (canonically ``[+inf, -inf]``);
* unbounded intervals use ``-inf`` / ``+inf`` bounds; ``lo`` is never ``+inf`` and ``hi``
  never ``-inf`` for a non-empty interval;
* no bound is ever NaN in a value produced by this package.

All functions are elementwise and vectorised; none of them loops over elements in Python.
"""

from __future__ import annotations

import numpy as np

from .rounding import up

__all__ = [
    "as_interval",
    "empty_like",
    "is_empty",
    "width",
    "midpoint",
    "radius",
    "magnitude",
    "mignitude",
    "hull",
    "intersect",
    "contains",
    "contains_zero",
    "is_subset",
    "is_interior",
]


def as_interval(lo, hi=None):
    """Build ``(lo, hi)`` float64 arrays; ``hi`` defaults to ``lo`` (degenerate intervals)."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = lo if hi is None else np.asarray(hi, dtype=np.float64)
    lo, hi = np.broadcast_arrays(lo, hi)
    return lo.copy(), hi.copy()


def empty_like(lo):
    """Empty intervals with the shape of ``lo``."""
    return np.full_like(lo, np.inf, dtype=np.float64), np.full_like(lo, -np.inf, dtype=np.float64)


def is_empty(lo, hi):
    """Boolean mask of empty intervals."""
    return lo > hi


def width(lo, hi):
    """Upper bound of ``hi - lo`` (0 for degenerate intervals)."""
    return up(hi - lo)


def midpoint(lo, hi):
    """A float inside ``[lo, hi]`` close to its centre (finite intervals; clamps otherwise).

    ``0.5*lo + 0.5*hi`` cannot overflow; the result is clipped back into the interval so
    that rounding never puts the midpoint outside it.
    """
    with np.errstate(invalid="ignore", over="ignore"):
        m = 0.5 * lo + 0.5 * hi
    m = np.where(np.isnan(m), 0.0, m)  # [-inf, inf]
    m = np.where(np.isinf(m), np.clip(m, -np.finfo(float).max, np.finfo(float).max), m)
    return np.minimum(np.maximum(m, lo), hi)


def radius(lo, hi, mid=None):
    """Upper bound of the distance from ``mid`` (default :func:`midpoint`) to both bounds."""
    if mid is None:
        mid = midpoint(lo, hi)
    return np.maximum(up(hi - mid), up(mid - lo))


def magnitude(lo, hi):
    """``max |x|`` over the interval."""
    return np.maximum(np.abs(lo), np.abs(hi))


def mignitude(lo, hi):
    """``min |x|`` over the interval (0 when it contains 0)."""
    return np.where((lo <= 0) & (hi >= 0), 0.0, np.minimum(np.abs(lo), np.abs(hi)))


def hull(alo, ahi, blo, bhi):
    """Smallest interval containing both (an empty operand is ignored)."""
    return np.minimum(alo, blo), np.maximum(ahi, bhi)


def intersect(alo, ahi, blo, bhi):
    """Intersection; empty where the operands are disjoint (``lo > hi``)."""
    return np.maximum(alo, blo), np.minimum(ahi, bhi)


def contains(lo, hi, x):
    """``x in [lo, hi]`` elementwise."""
    return (lo <= x) & (x <= hi)


def contains_zero(lo, hi):
    return (lo <= 0.0) & (hi >= 0.0)


def is_subset(alo, ahi, blo, bhi):
    """``[a] ⊆ [b]`` elementwise (an empty ``a`` is a subset of anything)."""
    return ((alo >= blo) & (ahi <= bhi)) | (alo > ahi)


def is_interior(alo, ahi, blo, bhi):
    """``[a] ⊂ int([b])``: strictly inside, the condition of the Krawczyk test."""
    return (alo > blo) & (ahi < bhi)
