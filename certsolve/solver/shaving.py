"""Constructive interval disjunction (CID, IBEX ``CtcCID``/``ACID``), batched.

For a box ``X`` and a variable ``j``, cut ``X_j`` into ``s`` slices, contract every slice
with an inner contractor (HC4), and replace ``X`` by the hull of the contracted slices.
Every solution in ``X`` lies in some slice, is kept by that slice's contraction, hence is
in the hull: the operation is sound whenever the inner contractor is.  If every slice is
proven empty, so is ``X``.  Unlike bisection, the pieces are merged back, so the number of
boxes does not grow; unlike 3B shaving, the hull also narrows the *other* variables.

All boxes of a batch, each with its own variable, are sliced at once: one inner call on
``B × s`` boxes per variable round.

:class:`Shave` is the pipeline's part (:mod:`.batch` protocol): CID on the variable the
bisector chose for each box, then on more variables by decreasing smear score, as many as
a fixed count or the count :class:`AdaptiveCount` learns (IBEX's ACID).
"""

from __future__ import annotations

import math
import time
from dataclasses import KW_ONLY, dataclass

import numpy as np

from ..interval.core import cut_points
from ..interval.reductions import any_last
from .batch import BISECTION_GAIN, Batch, log_volume_ratio
from .bisectors import smear_scores

__all__ = ["CID", "AdaptiveCount", "Shave", "check_count"]


class CID:
    """Slice ``var[k]`` of box ``k`` into ``slices`` pieces; hull of the contracted pieces."""

    def __init__(self, inner, slices: int = 4):
        if slices < 2:
            raise ValueError("CID needs at least 2 slices")
        self.inner = inner
        self.slices = int(slices)

    def contract(self, lo, hi, var):
        """Returns ``(lo, hi, empty)`` for boxes ``(B, n)`` and variables ``var`` ``(B,)``."""
        B, n = lo.shape
        s = self.slices
        if B == 0:
            return lo.copy(), hi.copy(), np.zeros(0, dtype=bool)
        rows = np.arange(B)
        cuts = cut_points(lo[rows, var], hi[rows, var], s)  # (B, s+1), finite inside
        slo = np.repeat(lo, s, axis=0)
        shi = np.repeat(hi, s, axis=0)
        r2 = np.arange(B * s)
        v2 = np.repeat(var, s)
        # consecutive slices share their cut points: together they cover [a, b]
        slo[r2, v2] = cuts[:, :-1].ravel()
        shi[r2, v2] = cuts[:, 1:].ravel()
        clo, chi, cemp = self.inner(slo, shi)
        clo = clo.reshape(B, s, n)
        chi = chi.reshape(B, s, n)
        cemp = cemp.reshape(B, s)
        alive = ~cemp
        empty = ~np.any(alive, axis=1)
        big = np.where(alive[:, :, None], clo, np.inf)
        small = np.where(alive[:, :, None], chi, -np.inf)
        nlo = np.fmax(lo, np.min(big, axis=1))
        nhi = np.fmin(hi, np.max(small, axis=1))
        nlo = np.where(empty[:, None], lo, nlo)
        nhi = np.where(empty[:, None], hi, nhi)
        return nlo, nhi, empty


@dataclass
class AdaptiveCount:
    """How many variables to shave before a bisection, learnt as IBEX's ACID does.

    The search alternates use and learning, counted in boxes: the last ``learn`` boxes of
    every ``cycle`` shave more variables (by decreasing smear score) -- all of them in the
    first learning phase, then twice the last learnt count (``double``; else all) -- and each
    records how many rounds it needed: the position of its last round that shrank its volume
    by at least ``ratio``.  At the end of a phase, the mean of those counts (rounded up, at
    least 1) becomes the count every other box uses.  It only chooses *how much* sound
    contraction to apply, never what is kept.

    Before the first phase ends the count is ``start`` (1: the chosen variable only).  IBEX
    learns on the first boxes; here those come in tiny batches (1, 2, 4 ... boxes at the
    root), where each round of CID is a few numpy calls for almost nothing: learning there
    cost small systems up to 1.6x their time (brown-5-vector, 153 boxes: 0.32 -> 0.50 s),
    and a search of fewer than ``cycle - learn`` boxes now never pays for learning.

    ``first=True`` (the solver's default since issue 30, :class:`Shave` ``learn_first``) is
    IBEX's order again: the ``learn`` boxes that *open* each cycle learn, so the first
    ``learn`` boxes of a search shave every variable and the count is learnt from box
    ``learn`` on.  A search where shaving all the variables pays converges near the root
    (IBEX's Trigexp1-020: 110 -> 34 boxes, 0.56 -> 0.34 s; BroydenBanded-014 334 -> 28
    boxes, 0.55 -> 0.22 s); small searches where it does not pay the learning (Katsura-12,
    98 boxes: 0.29 -> 0.52 s).  Measured in ``docs/solver.md`` (*Contraction strength beside
    ibexsolve*).

    Counted in boxes, not in calls: a call is a whole batch, and with batches of up to 1024
    boxes most searches make fewer than 50 calls; learning in the first 5 calls of 50 meant
    learning on the first few dozen boxes near the root only, once.  Now every batch holds
    about ``learn / cycle`` of learning boxes, spread over the search.

    Plain data: the learnt state belongs to a search (the solver keeps it in its search
    state), so a checkpoint saves it with the search and a worker task starts from the count
    its search has learnt.
    """

    n: int
    _: KW_ONLY
    cycle: int = 1000
    learn: int = 50
    ratio: float = 0.1
    double: bool = True  #: later learning phases shave twice the learnt count, not all
    start: int = 1  #: the count until the first learning phase ends
    #: the learning boxes open each cycle (IBEX: the first 50 calls of every 1000), not
    #: close it
    first: bool = False
    count: int = -1  #: the count in use (-1: ``start``)
    boxes: int = 0  #: boxes seen so far
    phases: int = 0  #: learning phases ended
    needed_sum: int = 0  #: sum of the rounds the boxes of this learning phase needed
    needed_boxes: int = 0  #: boxes of this learning phase

    def __post_init__(self) -> None:
        if not 0 < self.learn <= self.cycle:
            raise ValueError("need 0 < learn <= cycle")
        if self.count < 0:
            self.count = min(int(self.start), int(self.n))

    @property
    def threshold(self) -> float:
        """Log-volume change of a useful round."""
        return float(np.log1p(-self.ratio))

    def plan(self, boxes: int) -> tuple[np.ndarray, np.ndarray]:
        """For the next ``boxes`` boxes: how many variables each shaves, and which learn."""
        at = (self.boxes + np.arange(boxes)) % self.cycle
        learns = at < self.learn if self.first else at >= self.cycle - self.learn
        more = self.n if self.phases == 0 or not self.double else min(self.n, 2 * self.count)
        return np.where(learns, more, self.count), learns

    def done(self, needed: np.ndarray, boxes: int) -> None:
        """After :meth:`plan` ``(boxes)``: ``needed`` are the rounds the learning boxes
        needed, in order."""
        self.needed_sum += int(np.sum(needed))
        self.needed_boxes += int(needed.size)
        self.boxes += int(boxes)
        end = self.learn if self.first else self.cycle  # where a phase ends in its cycle
        ended = (self.boxes - end) // self.cycle + 1 if self.boxes >= end else 0
        if ended > self.phases:
            self.phases = ended
            if self.needed_boxes:
                self.count = max(1, math.ceil(self.needed_sum / self.needed_boxes))
            self.needed_sum = self.needed_boxes = 0


def check_count(count: int | str | None) -> None:
    """``count`` is a number >= 1, ``None`` (all the variables) or ``"auto"``."""
    if count not in (None, "auto") and not int(count) >= 1:
        raise ValueError("cid_vars must be >= 1, None (all variables) or 'auto'")


class Shave:
    """CID before bisection (IBEX ``CtcCID`` / ACID), a part of the pipeline.

    For each box with a variable to split (:meth:`.Batch.choice`), :class:`CID` with
    ``slices`` slices contracted by ``inner`` (HC4) on that variable, then on up to
    ``count - 1`` other variables by decreasing smear score over the box (from the round's
    Jacobian; variables the bisector may split, with a positive score).  ``count``: a
    number; ``None``: all the variables; ``"auto"``: the count the search learns
    (:class:`AdaptiveCount`; its state is the search's, ``batch.acid``, created by
    :meth:`learner`).  Boxes narrower than ``eps`` are left alone (they are reported as
    undecided).  Wrapped in a :class:`.pipeline.FixPoint`, a box CID shrank as much as a
    bisection goes round again instead of being split.

    ``count="auto"`` against 1 (batches of 1024, one process, CPU s, with the affine
    relaxation): on IBEX's benchmarks up to 8x fewer boxes and half the time or less on
    the hard files (Brent-10 141,814 -> 17,998 boxes, 22.1 -> 11.8 s; transistor 216,437
    -> 60,385 boxes, 27.3 -> 13.2 s; Discrete-Integral-6 118,067 -> 18,463 boxes, 7.8 ->
    2.2 s), but 1.07-1.25x the time on medium systems (katsura-6 22,121 -> 21,680 boxes,
    2.09 -> 2.27 s; eco-7 0.81 -> 1.12 s, 0.91 -> 1.0 s since the extra variables of small
    batches are shaved side by side; Eco9 2.8 -> 3.3 s); searches of fewer than ~950 boxes
    never learn, so cost the same.  ``None`` against 1: 2-9x fewer boxes, 1.3-2x the CPU
    time on ``examples/systems``.
    """

    def __init__(
        self,
        inner,
        slices: int = 4,
        count: int | str | None = "auto",
        *,
        n: int,
        learn_first: bool = True,
    ):
        check_count(count)
        #: the contractor of each slice (``contract(lo, hi) -> (lo, hi, empty)``)
        self.inner = inner
        self.cid = CID(inner.contract, slices)
        self.n = int(n)
        #: learn the count (``"auto"``)
        self.auto = count == "auto"
        #: ``"auto"`` learns on the first boxes of each cycle, as IBEX's ACID does
        #: (:attr:`AdaptiveCount.first`)
        self.learn_first = bool(learn_first)
        #: variables CID contracts (chosen first, then by smear score) when not learning
        self.count = self.n if count in (None, "auto") else min(int(count), self.n)
        #: a batch that plans at most this many (box, extra variable) CID calls shaves them
        #: side by side in one call (:meth:`_side_by_side`), else one variable after the
        #: other.  Measured against always one after the other (CPU s, one worker, median
        #: of 5 runs interleaved): Brent-8 5.56 -> 3.90, Brent-10 13.5 -> 10.2, eco-7 1.15
        #: -> 0.98, transistor 15.3 -> 15.1, Caprasse 0.61 -> 0.59; Discrete-Integral-6
        #: 2.36 -> 2.46, katsura-6 2.49 -> 2.55; the others within 2 %.  Side by side on
        #: every batch (no limit) loses on the large ones (Katsura-14, Brent-8, 1 run).
        self.stacked_pairs = 512
        #: a batch of at most this many boxes (a chain's front, a box converging alone) is
        #: shaved side by side again, up to :attr:`sweeps` times in all, each box while its
        #: last sweep shrank it as much as a bisection (:meth:`_side_by_side`)
        self.sweep_rows = 2
        self.sweeps = 4

    def learner(self) -> AdaptiveCount | None:
        """A fresh learnt state for a search (``count="auto"``), else ``None``."""
        return AdaptiveCount(self.n, first=self.learn_first) if self.auto else None

    def describe(self) -> str:
        count = ("auto-first" if self.learn_first else "auto") if self.auto else self.count
        inner = getattr(self.inner, "describe", lambda: type(self.inner).__name__)()
        return f"Shave({inner}, slices={self.cid.slices}, count={count})"

    def apply(self, batch: Batch) -> None:
        var = batch.choice()
        rows = var >= 0
        if not np.any(rows):
            return
        if rows.all():
            lo, hi, v = batch.lo, batch.hi, var
            jlo, jhi = batch.jacobian()
        else:
            lo, hi, v = batch.lo[rows], batch.hi[rows], var[rows]
            jlo, jhi = batch.jacobian(rows)
        clo, chi, cemp = self.contract(
            lo, hi, jlo, jhi, v, batch.acid, eps=batch.eps, mask=batch.mask, deadline=batch.deadline
        )
        batch.with_rows(rows, clo, chi, cemp)

    def contract(
        self,
        lo,
        hi,
        jlo,
        jhi,
        var,
        acid: AdaptiveCount | None = None,
        *,
        eps=0.0,
        mask=None,
        deadline: float | None = None,
    ):
        """CID on ``var`` then on up to ``count - 1`` other variables of each box (or the
        count ``acid`` has learnt, more for its learning boxes; this call updates it), by
        decreasing smear score over the box (``jlo, jhi``: its Jacobian enclosure).

        Each round is one batched CID call on the boxes that still have a variable to
        contract; every call is sound (:class:`CID`), so is the sequence.  A small batch
        shaves its extra variables side by side instead (:meth:`_side_by_side`,
        :attr:`stacked_pairs`).  A box proven empty stays empty.  Returns ``(lo, hi,
        empty)``.

        ``deadline`` (a :func:`time.monotonic` value): past it, no further variable is
        shaved.  On a large system one call can be long: ``Yamamua1-0600sp`` (601
        variables), whose learning boxes shave every variable, took 35 s in one call, and a
        10 s limit ran 31 s (``docs/ibex-benchs.md``).
        """
        clo, chi, cemp = self.cid.contract(lo, hi, var)
        B = lo.shape[0]
        if acid is None:
            limit, learns = np.full(B, self.count), np.zeros(B, dtype=bool)
        else:
            limit, learns = acid.plan(B)
        needed = np.ones(B, dtype=np.int64)  # recorded for the learning boxes only
        extra = int(np.max(limit, initial=1)) - 1
        if extra > 0:
            rows = np.arange(B)
            score = smear_scores(lo, hi, jlo, jhi, eps, mask)
            score[rows, var] = -1.0
            order = np.argsort(-score, axis=1, kind="stable")[:, :extra]
            useful = np.take_along_axis(score, order, axis=1) > 0.0
            useful &= np.arange(order.shape[1]) < (limit - 1)[:, None]
            if np.count_nonzero(useful) <= self.stacked_pairs:
                self._side_by_side(clo, chi, cemp, order, useful, learns, needed, acid)
            else:
                for k in range(order.shape[1]):
                    act = np.flatnonzero(useful[:, k] & ~cemp)
                    if act.size == 0:
                        break  # scores are sorted: no box has a k-th (or later) variable
                    if deadline is not None and time.monotonic() > deadline:
                        break  # the search's limit: what is shaved so far is kept
                    nlo, nhi, emp = self.cid.contract(clo[act], chi[act], order[act, k])
                    if acid is not None:
                        shrank = _learnt(acid, learns[act], clo[act], chi[act], nlo, nhi, emp)
                        needed[act[shrank]] = k + 2  # the chosen variable, then k + 1 others
                    clo[act], chi[act] = nlo, nhi
                    cemp[act] |= emp
        if acid is not None:
            acid.done(needed[learns], B)
        return clo, chi, cemp

    def _side_by_side(self, clo, chi, cemp, order, useful, learns, needed, acid) -> None:
        """The extra variables of :meth:`contract` side by side: one CID call on a copy of
        each box per variable, the results intersected (in place).

        Each copy's CID keeps every solution of the box, so their intersection does too, and
        an empty one (or an empty intersection) proves the box empty.  The sequence shaves
        each variable of an already shaved box, so it contracts more per box; side by side
        costs one call instead of one per variable, which wins when the batch is small (a
        numpy call costs nearly the same for 50 rows as for 500).  ACID learns from each
        variable's gain over the same starting box (the first sweep).

        A batch of at most :attr:`sweep_rows` boxes is swept again (up to :attr:`sweeps`),
        each box while its last sweep shrank its volume at least as much as a bisection
        (:data:`~.batch.BISECTION_GAIN`): on a chain (a tridiagonal or banded system) a sweep
        moves the bounds a link or two along it, and a box converging alone to a solution
        goes round the search loop once per sweep otherwise.  Measured on IBEX's files
        (``docs/solver.md``, *A small batch swept again*): Trigexp2-13sp 57 -> 2 boxes,
        BroydenTri-0030 384 -> 120, Trigexp1-100 96 -> 27; Bratu-0030 523 -> 735 (its first
        rounds are of one or two boxes too).  Swept again at every batch size, the wide
        searches lost more (CountercurrentReactors2-8 no longer completed in 10 s).
        """
        sweeps = self.sweeps if clo.shape[0] <= self.sweep_rows else 1
        for sweep in range(1, sweeps + 1):
            box, col = np.nonzero(useful & ~cemp[:, None])
            if box.size == 0:
                return
            if sweep < sweeps:  # the gain decides the next sweep
                lo0, hi0 = clo.copy(), chi.copy()
            nlo, nhi, emp = self.cid.contract(clo[box], chi[box], order[box, col])
            if acid is not None:
                shrank = _learnt(acid, learns[box], clo[box], chi[box], nlo, nhi, emp)
                np.maximum.at(needed, box[shrank], col[shrank] + 2)
            np.maximum.at(clo, box, nlo)
            np.minimum.at(chi, box, nhi)
            np.logical_or.at(cemp, box, emp)
            cemp |= any_last(clo > chi)
            if sweep == sweeps:
                return
            # again on the boxes this sweep shrank as much as a bisection, learning no more
            useful = useful & (log_volume_ratio(lo0, hi0, clo, chi) < BISECTION_GAIN)[:, None]
            learns, acid = np.zeros_like(learns), None


def _learnt(acid: AdaptiveCount, learns, lo, hi, nlo, nhi, empty) -> np.ndarray:
    """The learning boxes a CID call contracted enough to count for ACID: proven empty, or
    their log-volume dropped below ``acid.threshold``."""
    return learns & (empty | (log_volume_ratio(lo, hi, nlo, nhi) < acid.threshold))
