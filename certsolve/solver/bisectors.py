"""Bisectors: choose a variable and a split point for each box (IBEX ``Bsc``).

:class:`SmearSumRelative` (IBEX's ``SmearSumRelative``, the ``ibexsolve`` default) scores
variable ``j`` by ``Σ_i |J_ij| w_j / Σ_k |J_ik| w_k`` -- how much of each equation's
variation over the box comes from ``x_j`` -- and splits the best one.
:class:`SmearCurvatureMix` (the :class:`~.branch_and_prune.Solver`'s default) splits two
boxes in three by that score and the third by the *curvature* score
``Σ_i w(J_ij) w_j / Σ_k |J_ik| w_k``, the share of each equation's variation that interval
Newton cannot absorb (see :func:`curvature_scores`).
Where the Jacobian gives no information, the variable widest relative to the domain is split.
:class:`LargestFirst` splits the widest variable.  All split at ``lo + ratio * w`` with
``ratio = 0.45`` by default, off-centre so that a solution lying exactly at the centre of a
symmetric domain does not land on a bisection face.  A :class:`SmearCurvatureMix` with
``at_zero`` (``Solver.default``'s, unless ``split_at_zero=False``: for the variables that
multiply others) splits an interval that holds 0 well inside at 0 instead (:func:`split`):
each half then has a sign, which a product over it is tight for.  Variables narrower than
``eps`` are never chosen, nor variables outside an optional mask (IBEX's "auxiliary" variables:
quantities determined by the others, like the wire lengths of forward kinematics, which
contraction narrows as the others shrink).  :class:`SmearCurvatureMix` also leaves out, while
another variable scores, a variable whose impact on the equations (:func:`smear_impact`) and
width relative to the domain are both far below the box's largest (:func:`_best`,
``narrow``): the relative smear of an equation whose variables are all tiny gives them a
share as large as that of an equation still wide.

Split points and widths come from :mod:`certsolve.interval.core` (:func:`split_point`,
:func:`splittable_width`): an unbounded interval is split at a finite point, and an interval
with no float strictly inside is never chosen.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..interval.core import split_point, splittable_width
from ..interval.reductions import max_last, to_front

__all__ = [
    "SmearSumRelative",
    "SmearCurvatureMix",
    "LargestFirst",
    "Prioritized",
    "box_coin",
    "curvature_scores",
    "domain_scale",
    "smear_impact",
    "smear_scores",
    "split",
]


#: :class:`SmearCurvatureMix` ``narrow``: a variable below this share of the box's largest,
#: both in impact (:func:`smear_impact`) and in width relative to the domain, is not split
#: while another one scores (:func:`_best`)
NARROW_SPLIT = 1e-3


#: :func:`split` ``at_zero``: 0 is the split point when it lies at least this fraction of
#: the width inside the interval
ZERO_MARGIN = 0.05


def split(lo, hi, var, ratio: float, *, at_zero: Any = False):
    """Split box ``k`` along ``var[k]``; returns the two halves as ``(lo, hi)`` pairs.

    At ``lo + ratio * w`` (:func:`~certsolve.interval.core.split_point`); with ``at_zero``
    (``True``, or an ``(n,)`` mask of the variables it applies to), at 0 where the interval
    holds 0 at least ``ZERO_MARGIN`` of its width inside (a *sign split*: every half has a
    sign in that variable, and a product with it is as tight as interval arithmetic gets).
    A solution with a zero coordinate then lies on the face of both halves; the certifier's
    inflated proof (:class:`.pipeline.Inflate`) proves it across the face, and its unicity
    box prunes the other half.

    Measured on IBEX's benchmark files (``docs/solver.md``, *The split point*): for the
    variables that multiply others it finds the first solutions of Eco10, Redeco10 and
    CountercurrentReactors2-12 to -28 in 10 s; on every variable it also cost Yamamura's and
    Trigo1's (cubes and sines of single variables, where a sign buys nothing); Katsura's
    solutions with zero coordinates land on faces, whose boxes then converge in a tail of
    small rounds (katsura-6: 42 -> 83 rounds; 50 since the fixpoints leave such narrow
    variables out, :func:`.batch.progress_gain`).  ``Solver.default`` splits its variables
    that multiply others so, unless ``split_at_zero=False``.
    """
    rows = np.arange(lo.shape[0])
    a, b = lo[rows, var], hi[rows, var]
    m = split_point(a, b, ratio)
    if np.ndim(at_zero) or at_zero:
        with np.errstate(invalid="ignore", over="ignore"):
            margin = ZERO_MARGIN * (b - a)  # inf for an unbounded interval: cut as before
            inside = (a + margin < 0.0) & (0.0 < b - margin)
        if np.ndim(at_zero):
            inside &= np.asarray(at_zero, dtype=bool)[var]
        m = np.where(inside, 0.0, m)
    lo1, hi1 = lo.copy(), hi.copy()
    lo2, hi2 = lo.copy(), hi.copy()
    hi1[rows, var] = m
    lo2[rows, var] = m
    return (lo1, hi1), (lo2, hi2)


class LargestFirst:
    def __init__(self, ratio: float = 0.45):
        self.ratio = ratio

    def choose(
        self, lo, hi, jlo=None, jhi=None, eps: float = 0.0, mask=None, scale=None
    ) -> np.ndarray:
        """The widest variable (absolute widths: ``scale`` is accepted and ignored)."""
        w = splittable_width(lo, hi)
        if mask is not None:
            w = np.where(mask, w, -1.0)
        return np.argmax(w, axis=1)


def smear_scores(lo, hi, jlo, jhi, eps: float = 0.0, mask=None) -> np.ndarray:
    """Smear-sum-relative score of every variable ``(B, n)``; -1 where not allowed.

    ``score_j = Σ_i |J_ij| w_j / Σ_k |J_ik| w_k``: how much of each equation's variation
    over the box comes from ``x_j`` (IBEX ``SmearSumRelative``).
    """
    return _relative_scores(lo, hi, jlo, jhi, eps, mask, curvature=False)


def curvature_scores(lo, hi, jlo, jhi, eps: float = 0.0, mask=None) -> np.ndarray:
    """Curvature score of every variable ``(B, n)``; -1 where not allowed.

    ``score_j = Σ_i (J̄_ij - J̲_ij) w_j / Σ_k |J_ik| w_k``: the part of each equation's
    variation that comes from the *width* of ``x_j``'s Jacobian entries, relative to the
    equation's smear.  Interval Newton contracts a box by a factor of about
    ``|Y| w(J) w(X)`` (``Y`` its preconditioner), so this is the part it cannot absorb; it is
    0 for a variable entering every equation linearly, and for a bilinear term ``x_a x_b``
    both ``x_a`` and ``x_b`` get ``w_a w_b``: a variable multiplying many others (an
    eigenvalue ``λ`` in ``(A + λ B + λ² C) x = 0``) collects a term from each of them.
    """
    return _relative_scores(lo, hi, jlo, jhi, eps, mask, curvature=True)


def smear_impact(lo, hi, jlo, jhi) -> np.ndarray:
    """``(B, n)``: ``max_i |J_ij| w_j``, the largest variation ``x_j`` alone can cause in one
    equation over the box (IBEX's ``SmearMax`` score); unlike a width, it does not depend on
    the variable's unit."""
    w = splittable_width(lo, hi)
    with np.errstate(all="ignore"):
        mag = np.maximum(np.abs(jlo), np.abs(jhi))
        return np.max(mag * w[:, None, :], axis=1, initial=0.0)


def _relative_scores(lo, hi, jlo, jhi, eps, mask, curvature: bool) -> np.ndarray:
    w = splittable_width(lo, hi)
    with np.errstate(all="ignore"):
        mag = np.maximum(np.abs(jlo), np.abs(jhi))  # (B, n, n)
        smear = mag * w[:, None, :]
        rows = np.sum(smear, axis=2, keepdims=True)
        part = (jhi - jlo) * w[:, None, :] if curvature else smear
        rel = np.where(rows > 0, part / rows, 0.0)
        score = np.sum(to_front(rel, 1), axis=0)  # = np.sum(rel, axis=1), faster
    score = np.where(np.isfinite(score), score, 0.0)
    allowed = w > eps if mask is None else (w > eps) & mask
    return np.where(allowed, score, -1.0)


def _best(score, lo, hi, scale=None, narrow: float = 0.0, impact=None) -> np.ndarray:
    """The best-scoring variable per box; where no score is positive (all zero, or an infinite
    Jacobian) the widest allowed one (score >= 0: the scores are -1 exactly where a variable is
    not allowed), its width divided by ``scale`` (``(n,)``, the widths of the search domain)
    when given.

    ``narrow`` > 0: an allowed variable below ``narrow`` times the box's largest, in impact
    (``impact``, :func:`smear_impact`; its width when not given) and (with ``scale``) in
    width relative to the domain, scores 0.
    Smear-sum-relative scores are shares of each equation's variation: an equation whose
    variables have all been narrowed to ~1e-7 still hands them a whole share.  On IBEX's
    Trigo1-0010sp (``x_i`` in ``[0, 2π]``, ``x_i`` and ``SE`` in equation ``i``), six such
    equations kept ``SE`` being split from 5e-7 down to 1e-8, doubling the boxes every round,
    while ``x_7`` stayed 0.18 wide around two of its roots: 5,069 boxes, 127-191 with the
    rule (``docs/solver.md``, *Variables already narrow*).  Both must be small, so that a
    variable whose unit makes all its widths small (a domain of ``[0, 1e-6]`` beside ``[0,
    1e3]``) is still split.  The impact, not the width: an eigenvalue ``λ`` 1-2,500 wide that
    multiplies ``x_j`` in ``[-1e8, 1e8]`` beside products 1e9 wide (IBEX's Geneig-icse) is far
    narrower than the widest, yet it moves the equations as much as they do; left out by
    width, Geneig, Geneigbis and Geneig-icse no longer completed (4,864 boxes -> 110k in
    160 s on Geneig-icse, ``docs/solver.md``, *The narrow rule compares impacts*).

    Widths relative to the domain make that choice unit-free: on IBEX's AOL-legentil (two
    angles in ``[0, π/2]``, a multiplier ``z`` in ``[-1e8, 1e8]``, and poles where every
    Jacobian entry is infinite) the absolute width split ``z`` alone, forever (a million
    boxes in 60 s), where splitting each variable in turn proves in 27 boxes that there is no
    solution.
    """
    if narrow > 0.0:
        score = np.where(_negligible(score, lo, hi, scale, narrow, impact), 0.0, score)
    best = np.argmax(score, axis=1)
    stuck = max_last(score) <= 0.0
    if np.any(stuck):
        w = splittable_width(lo[stuck], hi[stuck])
        if scale is not None:
            w = w / scale
        best[stuck] = np.argmax(np.where(score[stuck] >= 0.0, w, -1.0), axis=1)
    return best


def _negligible(score, lo, hi, scale, narrow: float, impact=None) -> np.ndarray:
    """``(B, n)``: allowed variables below ``narrow`` times the box's largest allowed finite
    value of each measure: the variable's ``impact`` (:func:`smear_impact`) when given, else
    its width; and, with ``scale``, its width relative to the domain."""
    allowed = score >= 0.0
    w = splittable_width(lo, hi)
    sizes = [w if impact is None else impact]
    if scale is not None:
        sizes.append(w / scale)
    out = allowed
    for size in sizes:
        finite = allowed & np.isfinite(size)  # an unbounded one sets no scale, is never narrow
        out = out & (size < narrow * max_last(np.where(finite, size, 0.0))[:, None])
    return out


def domain_scale(domain) -> np.ndarray:
    """``(n,)`` widths of a domain ``(n, 2)`` for :func:`_best`: 1 where the width is not
    finite and positive (an unbounded variable then keeps its infinite width)."""
    w = domain[:, 1] - domain[:, 0]
    return np.where(np.isfinite(w) & (w > 0.0), w, 1.0)


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


def box_coin(lo, hi, share: float = 0.5) -> np.ndarray:
    """A pseudo-random ``(B,)`` bool per box, True for about ``share`` of the boxes.

    A hash of the bounds' bits (multiply by the 64-bit golden ratio, xor over the
    variables, multiply again; the top 53 bits as a fraction): the same box always draws the
    same coin, whatever batch or worker it is processed in, and the two halves of a split
    draw independent-looking ones.
    """
    with np.errstate(over="ignore"):
        lb = np.ascontiguousarray(lo, dtype=np.float64).view(np.uint64)
        hb = np.ascontiguousarray(hi, dtype=np.float64).view(np.uint64)
        h = np.bitwise_xor.reduce(lb * _GOLDEN + hb, axis=1) * _GOLDEN
    return (h >> np.uint64(11)).astype(np.float64) < share * 2.0**53


class SmearSumRelative:
    def __init__(self, ratio: float = 0.45):
        self.ratio = ratio

    def choose(self, lo, hi, jlo, jhi, eps: float = 0.0, mask=None, scale=None) -> np.ndarray:
        """Variable to split per box; ``mask`` (n,) restricts the choice (default: all);
        ``scale`` (n,) the domain widths, for boxes without information (:func:`_best`)."""
        return _best(smear_scores(lo, hi, jlo, jhi, eps, mask), lo, hi, scale)


class SmearCurvatureMix:
    """Split a ``share`` of the boxes (drawn by :func:`box_coin`) by :func:`curvature_scores`,
    the others by :func:`smear_scores`.

    Smear alone splits the variables that move the equations most, and can leave a variable
    that multiplies many others too wide for Newton ever to converge: on IBEX's Geneig-icse
    (a quadratic eigenvalue problem, ``x_j λ`` and ``x_j λ²`` as auxiliary variables) the
    wide ``x_j`` keep being split while ``λ`` stays ~0.3 wide: 110k boxes in 60 s found 5 of
    its 10 solutions.  Curvature alone splits ``λ`` and ``λ²`` down to 1e-6 and below and
    stalls where the ``x_j`` are still symmetric about 0 (the midpoint Jacobian is singular
    there, Newton has no preconditioner).  Mixed: 10 solutions in ~6.5k boxes with a third
    by curvature (~4k with half), and within ±10 % of smear's boxes on the other systems
    measured (``benchmarks/solver_bench.py --bisector mix,smear``).  The coin is a hash of
    the box, so a search is reproducible and does not depend on batch sizes or workers.
    """

    def __init__(
        self,
        share: float = 1 / 3,
        ratio: float = 0.45,
        *,
        at_zero: Any = False,
        narrow: float = NARROW_SPLIT,
    ):
        self.share = float(share)
        self.ratio = ratio
        #: variables below this share of the box's largest impact and relative width are
        #: left out (:func:`_best`)
        self.narrow = float(narrow)
        #: split an interval holding 0 at 0 (:func:`split`): ``True``, ``False`` or an
        #: ``(n,)`` mask of the variables (``Solver.default``'s: those that multiply
        #: others, :attr:`~certsolve.expr.compiled.CompiledSystem.coupled`)
        self.at_zero = np.array(at_zero, dtype=bool) if np.ndim(at_zero) else bool(at_zero)

    def choose(self, lo, hi, jlo, jhi, eps: float = 0.0, mask=None, scale=None) -> np.ndarray:
        score = smear_scores(lo, hi, jlo, jhi, eps, mask)
        rows = np.flatnonzero(box_coin(lo, hi, self.share))
        if rows.size:
            curv = curvature_scores(lo[rows], hi[rows], jlo[rows], jhi[rows], eps, mask)
            linear = max_last(curv) <= 0.0  # no curvature left: smear decides
            score[rows[~linear]] = curv[~linear]
        impact = smear_impact(lo, hi, jlo, jhi) if self.narrow > 0.0 else None
        return _best(score, lo, hi, scale, self.narrow, impact)


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

    def choose(self, lo, hi, jlo, jhi, eps: float = 0.0, mask=None, scale=None) -> np.ndarray:
        w = splittable_width(lo, hi)
        prim = self.primary if mask is None else self.primary & mask
        sec = self.secondary if mask is None else self.secondary & mask
        best = self._smear.choose(lo, hi, jlo, jhi, eps, prim, scale)
        wp = max_last(np.where(prim & (w > eps), w, 0.0))
        ws = np.where(sec & (w > eps), w, -1.0)
        js = np.argmax(ws, axis=1)
        big = self.alpha * ws[np.arange(w.shape[0]), js] > wp
        best = np.where(big, js, best)
        return best
