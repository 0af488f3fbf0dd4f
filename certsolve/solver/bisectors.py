"""Bisectors: choose a variable and a split point for each box (IBEX ``Bsc``).

:class:`SmearSumRelative` (IBEX's ``SmearSumRelative``, the ``ibexsolve`` default) scores
variable ``j`` by ``Σ_i |J_ij| w_j / Σ_k |J_ik| w_k`` -- how much of each equation's
variation over the box comes from ``x_j`` -- and splits the best one.
:class:`LargestFirst` splits the widest variable.  Both split at ``lo + ratio * w`` with
``ratio = 0.45`` by default, off-centre so that a solution lying exactly at the centre of a
symmetric domain does not land on a bisection face.  Variables narrower than ``eps`` are
never chosen, nor variables outside an optional mask (IBEX's "auxiliary" variables:
quantities determined by the others, like the wire lengths of forward kinematics, which
contraction narrows as the others shrink).

Split points and widths come from :mod:`certsolve.interval.core` (:func:`split_point`,
:func:`splittable_width`): an unbounded interval is split at a finite point, and an interval
with no float strictly inside is never chosen.
"""

from __future__ import annotations

import numpy as np

from ..interval.core import split_point, splittable_width
from ..interval.reductions import max_last, to_front

__all__ = ["SmearSumRelative", "LargestFirst", "Prioritized", "split"]


def split(lo, hi, var, ratio: float):
    """Split box ``k`` along ``var[k]``; returns the two halves as ``(lo, hi)`` pairs."""
    rows = np.arange(lo.shape[0])
    m = split_point(lo[rows, var], hi[rows, var], ratio)
    lo1, hi1 = lo.copy(), hi.copy()
    lo2, hi2 = lo.copy(), hi.copy()
    hi1[rows, var] = m
    lo2[rows, var] = m
    return (lo1, hi1), (lo2, hi2)


class LargestFirst:
    def __init__(self, ratio: float = 0.45):
        self.ratio = ratio

    def choose(self, lo, hi, jlo=None, jhi=None, eps: float = 0.0, mask=None) -> np.ndarray:
        w = splittable_width(lo, hi)
        if mask is not None:
            w = np.where(mask, w, -1.0)
        return np.argmax(w, axis=1)


def smear_scores(lo, hi, jlo, jhi, eps: float = 0.0, mask=None) -> np.ndarray:
    """Smear-sum-relative score of every variable ``(B, n)``; -1 where not allowed.

    ``score_j = Σ_i |J_ij| w_j / Σ_k |J_ik| w_k``: how much of each equation's variation
    over the box comes from ``x_j`` (IBEX ``SmearSumRelative``).
    """
    w = splittable_width(lo, hi)
    with np.errstate(all="ignore"):
        mag = np.maximum(np.abs(jlo), np.abs(jhi))  # (B, n, n)
        smear = mag * w[:, None, :]
        rows = np.sum(smear, axis=2, keepdims=True)
        rel = np.where(rows > 0, smear / rows, 0.0)
        score = np.sum(to_front(rel, 1), axis=0)  # = np.sum(rel, axis=1), faster
    score = np.where(np.isfinite(score), score, 0.0)
    allowed = w > eps if mask is None else (w > eps) & mask
    return np.where(allowed, score, -1.0)


class SmearSumRelative:
    def __init__(self, ratio: float = 0.45):
        self.ratio = ratio

    def choose(self, lo, hi, jlo, jhi, eps: float = 0.0, mask=None) -> np.ndarray:
        """Variable to split per box; ``mask`` (n,) restricts the choice (default: all)."""
        w = splittable_width(lo, hi)
        allowed = w > eps if mask is None else (w > eps) & mask
        score = smear_scores(lo, hi, jlo, jhi, eps, mask)
        best = np.argmax(score, axis=1)
        # no information (all zero, or infinite Jacobian): widest allowed variable
        stuck = max_last(score) <= 0.0
        if np.any(stuck):
            wa = np.where(allowed[stuck], w[stuck], -1.0)
            best[stuck] = np.argmax(wa, axis=1)
        return best


class Prioritized:
    """Split ``primary`` variables (by smear) unless a ``secondary`` one is much wider.

    A secondary variable wider than ``1/alpha`` times the widest primary one is split
    (the widest such); otherwise :class:`SmearSumRelative` chooses among the primary
    variables.  Forward kinematics in a platform frame: the orientation (edge vectors) is
    primary, the reference point secondary -- given the orientation, partial Newton on the
    force balance fixes the position, so it needs splitting only while it is wide.
    """

    def __init__(self, primary, secondary, alpha: float = 0.25, ratio: float = 0.45):
        self.primary = np.asarray(primary, dtype=bool)
        self.secondary = np.asarray(secondary, dtype=bool)
        self.alpha = float(alpha)
        self.ratio = ratio
        self._smear = SmearSumRelative(ratio)

    def choose(self, lo, hi, jlo, jhi, eps: float = 0.0, mask=None) -> np.ndarray:
        w = splittable_width(lo, hi)
        prim = self.primary if mask is None else self.primary & mask
        sec = self.secondary if mask is None else self.secondary & mask
        best = self._smear.choose(lo, hi, jlo, jhi, eps, prim)
        wp = max_last(np.where(prim & (w > eps), w, 0.0))
        ws = np.where(sec & (w > eps), w, -1.0)
        js = np.argmax(ws, axis=1)
        big = self.alpha * ws[np.arange(w.shape[0]), js] > wp
        best = np.where(big, js, best)
        return best
