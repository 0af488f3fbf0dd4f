"""Constructive interval disjunction (CID, IBEX ``CtcCID``/``ACID``), batched.

For a box ``X`` and a variable ``j``, cut ``X_j`` into ``s`` slices, contract every slice
with an inner contractor (HC4), and replace ``X`` by the hull of the contracted slices.
Every solution in ``X`` lies in some slice, is kept by that slice's contraction, hence is
in the hull: the operation is sound whenever the inner contractor is.  If every slice is
proven empty, so is ``X``.  Unlike bisection, the pieces are merged back, so the number of
boxes does not grow; unlike 3B shaving, the hull also narrows the *other* variables.

All boxes of a batch, each with its own variable, are sliced at once: one inner call on
``B × s`` boxes per variable round.
"""

from __future__ import annotations

import math
from dataclasses import KW_ONLY, dataclass

import numpy as np

from ..interval.core import cut_points

__all__ = ["CID", "AdaptiveCount"]


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
        learns = (self.boxes + np.arange(boxes)) % self.cycle >= self.cycle - self.learn
        more = self.n if self.phases == 0 or not self.double else min(self.n, 2 * self.count)
        return np.where(learns, more, self.count), learns

    def done(self, needed: np.ndarray, boxes: int) -> None:
        """After :meth:`plan` ``(boxes)``: ``needed`` are the rounds the learning boxes
        needed, in order."""
        self.needed_sum += int(np.sum(needed))
        self.needed_boxes += int(needed.size)
        self.boxes += int(boxes)
        ended = self.boxes // self.cycle
        if ended > self.phases:
            self.phases = ended
            if self.needed_boxes:
                self.count = max(1, math.ceil(self.needed_sum / self.needed_boxes))
            self.needed_sum = self.needed_boxes = 0
