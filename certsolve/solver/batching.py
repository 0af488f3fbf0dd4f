"""The adaptive batch size: small rounds first (deep fast), larger while that pays, and no
round past the time limit.

The buffer is a stack: a round takes the last ``k`` boxes, so the search goes down one
bisection level per round on a front of ``k`` boxes.  A leaf (a certified solution) at
depth ``d`` is reached after about ``k d`` boxes, so a small ``k`` finds the first
solutions early.  A round costs about ``o + c k`` seconds (``o``: the round's numpy calls,
``c``: per box), so a large ``k`` processes more boxes per second.  :class:`BatchSizer`
trades the two:

* it **starts** at ``start`` boxes;
* after ``rounds`` full rounds at a size it **doubles** the size (up to ``cap``) while the
  per-box time ``t/k`` fell by at least ``gain`` since the previous size and the next
  round, predicted at ``2 k`` times the per-box time, stays within ``share`` of the
  remaining time limit.  With the model above, doubling from ``k/2`` to ``k`` cuts the
  per-box time from ``2o/k + c`` to ``o/k + c``, by at least ``gain = 1/4`` while
  ``k <= 2 o / c``: the size settles where the round's fixed cost is about half the cost
  of its boxes, at most 1.5 times the best per-box time; once the gain fails, the size
  stays;
* **each round** is cut to the boxes the remaining time fits at ``margin`` times the last
  per-box time (at least one box), so a round does not overrun the limit by its size.  The
  margin (2) is there because the per-box time grows with the batch on large systems
  (Yamamura1-0040, 40 variables: 3.6 ms a box in a round of 256, 7.1 ms in 512, 12 ms in
  494 of larger boxes; a 10 s limit ended after 17.6 s of search, 14.3 s at the last
  per-box time, ~10 s with the margin).

Only the grouping of the boxes changes: every box popped is processed as before, so the
set of certified solutions of a complete search is the same (box counts may differ
slightly, through solutions proven earlier or later and the learnt CID count).  On IBEX's
files certsolve is behind on, small first rounds did not bring solutions earlier
(docs/solver.md), so :meth:`~.branch_and_prune.Solver.default` starts at ``batch_size``
and only the cut to the time left applies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["BatchSizer"]


@dataclass(kw_only=True)
class BatchSizer:
    """The next round's size from the timings of the last ones (see the module docstring).

    ``cap``: the largest size (the step's ``batch_size``); ``start``: the first size;
    ``rounds``: full rounds timed at a size before deciding; ``gain``: the relative fall of
    the per-box time that makes a doubling pay; ``share``: the largest share of the remaining
    time a round may be predicted to take after a doubling; ``margin``: the factor on the
    last per-box time when a round is cut to the time left.
    """

    cap: int
    start: int = 16
    rounds: int = 2
    gain: float = 0.25
    share: float = 0.05
    margin: float = 2.0
    size: int = field(init=False)
    per_box: float | None = field(init=False, default=None)  # seconds a box, last round
    _settled: bool = field(init=False, default=False)
    _previous: float | None = field(init=False, default=None)  # per box at the last size
    _boxes: int = field(init=False, default=0)  # full rounds at this size: boxes, seconds
    _seconds: float = field(init=False, default=0.0)
    _count: int = field(init=False, default=0)

    def __post_init__(self) -> None:
        if not (int(self.cap) >= 1 and int(self.start) >= 1 and int(self.rounds) >= 1):
            raise ValueError("cap, start and rounds must be >= 1")
        if not (0 <= self.gain < 1 and 0 < self.share <= 1 and self.margin >= 1):
            raise ValueError("gain must be in [0, 1), share in (0, 1] and margin >= 1")
        self.size = min(int(self.start), int(self.cap))
        self._settled = self.size >= self.cap

    def next(self, remaining: float | None) -> int:
        """The size of the next round with ``remaining`` seconds left (``None``: no limit):
        the current size, cut to what the remaining time fits at ``margin`` times the last
        per-box time."""
        if remaining is None or not self.per_box:
            return self.size
        fits = math.floor(remaining / (self.margin * self.per_box))
        return max(1, min(self.size, fits))

    def record(self, boxes: int, seconds: float, remaining: float | None) -> None:
        """A round took ``seconds`` on ``boxes`` boxes; ``remaining``: seconds left after it."""
        if boxes <= 0:
            return
        self.per_box = max(seconds, 0.0) / boxes
        if self._settled or boxes < self.size:  # a partial round says little of the size
            return
        self._boxes += boxes
        self._seconds += seconds
        self._count += 1
        if self._count < self.rounds:
            return
        per = self._seconds / self._boxes
        paid = self._previous is None or per <= (1.0 - self.gain) * self._previous
        fits = remaining is None or 2 * self.size * per <= self.share * remaining
        if not paid:
            self._settled = True
        elif fits:
            self._previous = per
            self.size = min(2 * self.size, int(self.cap))
            self._settled = self.size >= self.cap
        self._boxes, self._seconds, self._count = 0, 0.0, 0
