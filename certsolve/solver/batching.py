"""The adaptive batch size: small rounds first (deep fast), larger while that pays, under
a time limit a narrow front until the first solution, and no round past the limit.

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

* **under a time limit**, with ``front`` set, a round takes at most ``1/front`` of the
  boxes the search is expected to process within its limit (``cap`` halved until it fits,
  not below ``least``).  A round pops the lower halves of the last one's bisections, so a
  leaf ``d`` levels down comes after about ``k d`` boxes: the front's *latency*.  A search
  stopped by its limit has certified only what lies under the fronts it finished, so that
  latency must be a small share of its boxes (IBEX's Trigo1-0017 at 1,024 boxes a round:
  the first solution after 7,193 boxes, of ~18,000 in 9 CPU seconds).  The boxes expected
  are those processed so far plus the time left over the per-box time at ``k``, ``o/k +
  c``: ``o`` is the shortest round so far (the first rounds take the one box or the few
  the stack holds), ``c`` the rest of the rounds' time over their boxes.  Cheap boxes or a
  long limit allow ``cap`` (katsura-6 within 10 s: the same 21,205 boxes as without a
  limit), and the front never makes a box cost more than 1.5 times its time at ``cap``
  (``slower``), nor cuts a round below 128 boxes (``least``: at rounds of 32,
  Yamamua1-0024sp processed 4,102 boxes in 9.5 CPU s where it processed 7,731).  A search
  that will not finish within its limit works on a narrower front (Trigo1-0017 within
  10 s: 128), which widens as its boxes add up.  Once the search has certified a
  solution the front is reached: the stack holds the deep boxes of the dive, and wide
  rounds take them (kept narrow, the front lost most of the solutions of IBEX's shallow
  ``-sp`` Trigo1 files: Trigo1-0034sp 85 -> 16, docs/solver.md).

Only the grouping of the boxes changes: every box popped is processed as before, so the
set of certified solutions of a complete search is the same (box counts may differ
slightly, through solutions proven earlier or later and the learnt CID count).  On IBEX's
files certsolve is behind on, small first rounds did not bring solutions earlier
(docs/solver.md), so :meth:`~.branch_and_prune.Solver.default` starts at ``batch_size``;
the cut to the time left and the front (:data:`ANYTIME_FRONT`) apply under a time limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["ANYTIME_FRONT", "BatchSizer"]

#: the front of :meth:`~.branch_and_prune.Solver.default`'s searches under a time limit:
#: until the first solution a round takes at most 1/64 of the boxes expected within the
#: limit (``d`` ~ 7-17 rounds to the first solution on IBEX's files: a latency of 1/9-1/4
#: of the boxes); measured in docs/solver.md, *A narrow front until the first solution*
ANYTIME_FRONT = 64


@dataclass(kw_only=True)
class BatchSizer:
    """The next round's size from the timings of the last ones (see the module docstring).

    ``cap``: the largest size (the step's ``batch_size``); ``start``: the first size;
    ``rounds``: full rounds timed at a size before deciding; ``gain``: the relative fall of
    the per-box time that makes a doubling pay; ``share``: the largest share of the remaining
    time a round may be predicted to take after a doubling; ``margin``: the factor on the
    last per-box time when a round is cut to the time left; ``front``: under a time limit
    and until a solution is certified, a round takes at most ``1/front`` of the boxes
    expected within the limit (``None``: no such cap), and at least ``least`` boxes (where
    the stack holds them: fewer, and the rounds' times no longer tell ``o`` from ``c``;
    on IBEX's Yamamura files, 24-80 variables, rounds of 32-64 boxes processed 30-50 %
    fewer boxes in the same CPU time than rounds of 128-200), and never where a box would
    cost more than ``slower`` times its time at ``cap``.
    """

    cap: int
    start: int = 16
    rounds: int = 2
    gain: float = 0.25
    share: float = 0.05
    margin: float = 2.0
    front: int | None = None
    least: int = 128
    slower: float = 1.5
    size: int = field(init=False)
    per_box: float | None = field(init=False, default=None)  # seconds a box, last round
    _settled: bool = field(init=False, default=False)
    _previous: float | None = field(init=False, default=None)  # per box at the last size
    _boxes: int = field(init=False, default=0)  # full rounds at this size: boxes, seconds
    _seconds: float = field(init=False, default=0.0)
    _count: int = field(init=False, default=0)
    _rounds: int = field(init=False, default=0)  # every round recorded: count, boxes,
    _done: int = field(init=False, default=0)  # seconds, the shortest one's seconds
    _time: float = field(init=False, default=0.0)
    _shortest: float = field(init=False, default=math.inf)

    def __post_init__(self) -> None:
        if not (int(self.cap) >= 1 and int(self.start) >= 1 and int(self.rounds) >= 1):
            raise ValueError("cap, start and rounds must be >= 1")
        if not (0 <= self.gain < 1 and 0 < self.share <= 1 and self.margin >= 1):
            raise ValueError("gain must be in [0, 1), share in (0, 1] and margin >= 1")
        if self.front is not None and not int(self.front) >= 1:
            raise ValueError("front must be >= 1 (or None)")
        if not (int(self.least) >= 1 and self.slower >= 1):
            raise ValueError("least must be >= 1 and slower >= 1")
        self.size = min(int(self.start), int(self.cap))
        self._settled = self.size >= self.cap

    def next(self, remaining: float | None, solutions: int = 0) -> int:
        """The size of the next round with ``remaining`` seconds left (``None``: no limit)
        and ``solutions`` certified so far: the current size, at most the front's share of
        the boxes expected within the limit (``front``, while ``solutions`` is 0), cut to
        what the remaining time fits at ``margin`` times the last per-box time."""
        if remaining is None or not self.per_box:
            return self.size
        size = self.size
        cost = None if self.front is None or solutions else self.cost()
        if cost is not None:
            size = min(size, self._front(remaining, *cost))
        fits = math.floor(remaining / (self.margin * self.per_box))
        return max(1, min(size, fits))

    def cost(self) -> tuple[float, float] | None:
        """``(o, c)``: a round of ``k`` boxes takes about ``o + c k`` seconds; ``o`` is the
        shortest round recorded (the round's numpy calls: the first rounds take one box or a
        few), ``c`` the rest of the rounds' time over their boxes.  ``None`` before two
        rounds."""
        if self._rounds < 2:
            return None
        o = self._shortest
        return o, max(self._time - self._rounds * o, 0.0) / self._done

    def _front(self, remaining: float, o: float, c: float) -> int:
        """The first of ``cap``, ``cap/2``, ``cap/4`` ... with ``front k`` at most the boxes
        expected: those recorded plus ``remaining`` over the per-box time ``o/k + c`` at
        ``k``; not below ``least``, nor where ``o/k + c`` passes ``slower`` times its value
        at ``cap``."""
        assert self.front is not None
        k = int(self.cap)
        dearest = self.slower * (o / k + c)
        while (
            k // 2 >= self.least
            and o / (k // 2) + c <= dearest
            and self.front * k > self._done + remaining / (o / k + c)
        ):
            k //= 2
        return k

    def record(self, boxes: int, seconds: float, remaining: float | None) -> None:
        """A round took ``seconds`` on ``boxes`` boxes; ``remaining``: seconds left after it."""
        if boxes <= 0:
            return
        seconds = max(seconds, 0.0)
        self.per_box = seconds / boxes
        self._rounds += 1
        self._done += boxes
        self._time += seconds
        self._shortest = min(self._shortest, seconds)
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
