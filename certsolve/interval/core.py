"""Intervals as pairs of numpy arrays, and the set operations on them.

An interval array is a pair ``(lo, hi)`` of float64 arrays of the same (broadcastable)
shape; element ``k`` is the closed interval ``[lo[k], hi[k]]``.  A batch of boxes is an
interval array of shape ``(batch, n)``.  Conventions (as in IBEX):

* the **empty** interval is any pair with ``lo > hi`` (canonically ``[+inf, -inf]``);
* unbounded intervals use ``-inf`` / ``+inf`` bounds; ``lo`` is never ``+inf`` and ``hi``
  never ``-inf`` for a non-empty interval;
* no bound is ever NaN in a value produced by this package.

Points chosen inside intervals (:func:`midpoint`, :func:`split_point`, :func:`cut_points`) are
always finite floats, also for unbounded intervals: ``(-inf, inf)`` is cut at 0 and
``[a, inf)`` at ``a + 2.5 max(|a|, 1)`` (mirrored for ``(-inf, b]``), so that repeated
bisection of a half-line moves outward geometrically (about x3.5 per split; the largest float
is reached after ~600 splits) instead of jumping to ``±1.8e308`` as a float midpoint would.
``[max_float, inf)`` (and its mirror) has no float inside: :func:`splittable_width` is 0 there.

All functions are elementwise and vectorised; none of them loops over elements in Python.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .rounding import up

__all__ = [
    "Pair",
    "Quad",
    "as_interval",
    "empty_like",
    "is_empty",
    "width",
    "midpoint",
    "split_point",
    "cut_points",
    "splittable_width",
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

Pair = tuple[np.ndarray, np.ndarray]
"""An interval array as its bounds ``(lo, hi)``."""
Quad = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""Two interval arrays ``(xlo, xhi, ylo, yhi)``: the operands a backward projection narrows."""


def as_interval(lo: ArrayLike, hi: ArrayLike | None = None) -> Pair:
    """Build ``(lo, hi)`` float64 arrays; ``hi`` defaults to ``lo`` (degenerate intervals)."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = lo if hi is None else np.asarray(hi, dtype=np.float64)
    lo, hi = np.broadcast_arrays(lo, hi)
    return lo.copy(), hi.copy()


def empty_like(lo: np.ndarray) -> Pair:
    """Empty intervals with the shape of ``lo``."""
    return np.full_like(lo, np.inf, dtype=np.float64), np.full_like(lo, -np.inf, dtype=np.float64)


def is_empty(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Boolean mask of empty intervals."""
    return lo > hi


def width(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Upper bound of ``hi - lo`` (0 for degenerate intervals)."""
    return up(hi - lo)


_MAX = float(np.finfo(np.float64).max)
_GROWTH = 2.5  # [a, inf) is cut at a + _GROWTH * max(|a|, 1)


def _unbounded_point(lo, hi):
    """A finite point of each interval with an infinite bound (see the module docstring)."""
    with np.errstate(invalid="ignore", over="ignore"):
        up_pt = lo + _GROWTH * np.maximum(np.abs(lo), 1.0)  # [lo, inf)
        down_pt = hi - _GROWTH * np.maximum(np.abs(hi), 1.0)  # (-inf, hi]
    m = np.where(np.isinf(hi), up_pt, down_pt)
    m = np.where(np.isinf(lo) & np.isinf(hi), 0.0, m)
    return np.clip(m, -_MAX, _MAX)


def split_point(lo: ArrayLike, hi: ArrayLike, ratio: float = 0.5) -> np.ndarray:
    """A finite float in ``[lo, hi]``: ``lo + ratio (hi - lo)`` for bounded intervals (without
    overflow when ``hi - lo`` does), the unbounded rule of the module docstring otherwise."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        w = hi - lo
        m = lo + ratio * w
        if not np.all(np.isfinite(w)):
            m = np.where(np.isfinite(w), m, (1.0 - ratio) * lo + ratio * hi)
    return _finish(m, lo, hi)


def _finish(m, lo, hi):
    """Unbounded intervals get their finite point; every point is clamped into its interval."""
    unbounded = np.isinf(lo) | np.isinf(hi)
    if np.any(unbounded):
        m = np.where(unbounded, _unbounded_point(lo, hi), m)
    return np.minimum(np.maximum(m, lo), hi)


def midpoint(lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """A finite float inside ``[lo, hi]`` close to its centre (``0.5 lo + 0.5 hi``, which
    cannot overflow; the unbounded rule of the module docstring for infinite bounds)."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        m = 0.5 * lo + 0.5 * hi
    return _finish(m, lo, hi)


def cut_points(lo: ArrayLike, hi: ArrayLike, slices: int) -> np.ndarray:
    """``slices + 1`` non-decreasing cut points of each interval, from ``lo`` to ``hi``.

    Bounded intervals are cut evenly; an unbounded one at its :func:`split_point` only (the
    other cuts repeat it: degenerate slices are harmless, the slices still cover the interval).
    Returns an array of shape ``lo.shape + (slices + 1,)``.
    """
    lo = np.asarray(lo, dtype=np.float64)[..., None]
    hi = np.asarray(hi, dtype=np.float64)[..., None]
    t = np.arange(slices + 1) / slices
    with np.errstate(invalid="ignore", over="ignore"):
        w = hi - lo
        cuts = lo + w * t
        if not np.all(np.isfinite(w)):
            cuts = np.where(np.isfinite(w), cuts, lo * (1.0 - t) + hi * t)
    unbounded = np.isinf(lo) | np.isinf(hi)
    if np.any(unbounded):
        cuts = np.where(unbounded, split_point(lo, hi), cuts)
    cuts = np.minimum(np.maximum(cuts, lo), hi)
    cuts[..., 0] = lo[..., 0]
    cuts[..., -1] = hi[..., 0]
    return cuts


def splittable_width(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``hi - lo``, or 0 where no float lies strictly inside (the interval cannot be split)."""
    with np.errstate(invalid="ignore", over="ignore"):
        w = hi - lo
    m = split_point(lo, hi)
    return np.where((m > lo) & (m < hi), w, 0.0)


def radius(lo: np.ndarray, hi: np.ndarray, mid: np.ndarray | None = None) -> np.ndarray:
    """Upper bound of the distance from ``mid`` (default :func:`midpoint`) to both bounds."""
    if mid is None:
        mid = midpoint(lo, hi)
    return np.maximum(up(hi - mid), up(mid - lo))


def magnitude(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``max |x|`` over the interval."""
    return np.maximum(np.abs(lo), np.abs(hi))


def mignitude(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``min |x|`` over the interval (0 when it contains 0)."""
    return np.where((lo <= 0) & (hi >= 0), 0.0, np.minimum(np.abs(lo), np.abs(hi)))


def hull(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    """Smallest interval containing both (an empty operand is ignored)."""
    return np.minimum(alo, blo), np.maximum(ahi, bhi)


def intersect(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    """Intersection; empty where the operands are disjoint (``lo > hi``)."""
    return np.maximum(alo, blo), np.minimum(ahi, bhi)


def contains(lo: np.ndarray, hi: np.ndarray, x: np.ndarray | float) -> np.ndarray:
    """``x in [lo, hi]`` elementwise."""
    return (lo <= x) & (x <= hi)


def contains_zero(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return (lo <= 0.0) & (hi >= 0.0)


def is_subset(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> np.ndarray:
    """``[a] ⊆ [b]`` elementwise (an empty ``a`` is a subset of anything)."""
    return ((alo >= blo) & (ahi <= bhi)) | (alo > ahi)


def is_interior(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> np.ndarray:
    """``[a] ⊂ int([b])``: strictly inside, the condition of the Krawczyk test."""
    return (alo > blo) & (ahi < bhi)
