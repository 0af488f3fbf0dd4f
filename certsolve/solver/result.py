"""Solver results as plain data that serialise to JSON.

A :class:`SolveResult` answers "where are the solutions of the system in the domain?":

* ``solutions``: boxes each proven (Krawczyk) to contain exactly one solution, inside the
  domain and satisfying every constraint.  ``box`` is a tight *existence* box; the
  solution is also the only one in the larger ``unicity_box``.
* ``undecided``: boxes that may contain solutions but could not be decided -- narrower
  than ``eps`` without a proof (singular or tangent solutions, reason ``"eps"``), a proven
  solution whose box straddles the domain boundary (``"boundary"``), or one whose extra
  constraints could not be decided (``"constraint"``).
* ``pending``: boxes not explored because a limit (time, boxes, solutions) or the caller
  stopped the search.

Undecided and pending boxes are listed as *hulls* with the number of boxes each contains
(:mod:`.summary`): touching undecided boxes of the same reason are merged, and at most
``max_undecided`` hulls are listed (``undecided_dropped`` counts the boxes of the others);
pending boxes are merged by runs of the search stack into at most ``max_pending`` hulls
(``pending_boxes``), which together contain every pending box.  ``undecided_total`` and
``pending_total`` count the boxes themselves.

``status`` is a :class:`~.search.SearchStatus`: ``"complete"`` means nothing is pending and
no undecided box was left out of the listing: every solution of the system in the domain
lies in a solution box or a listed undecided hull; ``"truncated"``: nothing is pending but
some undecided boxes are only counted (``undecided_dropped``); otherwise it names what
stopped the search (``"timeout"``, ``"max_boxes"``, ``"max_solutions"``, ``"cancelled"``).
Nothing is ever silently dropped.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from .search import SearchStats, SearchStatus
from .summary import summarize

__all__ = ["Certificate", "Solution", "Undecided", "Stats", "SolveResult"]


def _box_list(lo: np.ndarray, hi: np.ndarray) -> list[list[float]]:
    return [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]


class Certificate(StrEnum):
    """What a solution box is proven to hold.

    ``unique``: exactly one solution of the system (Krawczyk on the system).
    ``square-subsystem-certified`` (over-determined systems): exactly one solution of a
    square subsystem, and the other equations' enclosures over the box contain 0 -- they
    are satisfied within their enclosure, not proven (:mod:`.nonsquare`).
    ``parametric`` (under-determined systems): for every value of the ``parameters`` in
    the box, exactly one value of the other variables in the box solves the system (a box
    of the paving of the solution set; its unicity box is the box itself).
    """

    UNIQUE = "unique"
    SQUARE_SUBSYSTEM = "square-subsystem-certified"
    PARAMETRIC = "parametric"


@dataclass
class Solution:
    lo: np.ndarray  # existence box: exactly one solution inside (see certificate)
    hi: np.ndarray
    ulo: np.ndarray  # unicity box: that solution is the only one in it
    uhi: np.ndarray
    certificate: Certificate = Certificate.UNIQUE
    verified: bool | None = None  # independent mpmath re-proof (None: not run)
    parameters: list[str] | None = None  # the parameters of a parametric box

    @property
    def midpoint(self) -> np.ndarray:
        return 0.5 * self.lo + 0.5 * self.hi

    @property
    def box(self) -> list[list[float]]:
        return _box_list(self.lo, self.hi)

    def to_dict(self) -> dict:
        out = {
            "box": self.box,
            "midpoint": [float(v) for v in self.midpoint],
            "unicity_box": _box_list(self.ulo, self.uhi),
            "certificate": str(self.certificate),
            "verified": self.verified,
        }
        if self.parameters is not None:
            out["parameters"] = list(self.parameters)
        return out


@dataclass
class Undecided:
    lo: np.ndarray
    hi: np.ndarray
    reason: str  # "eps" | "boundary" | "constraint"
    boxes: int = 1  # undecided boxes of the search in this hull

    @property
    def box(self) -> list[list[float]]:
        return _box_list(self.lo, self.hi)

    def to_dict(self) -> dict:
        return {"box": self.box, "reason": self.reason, "boxes": self.boxes}


@dataclass
class Stats:
    boxes: int = 0  # boxes contracted
    rounds: int = 0  # batches processed
    bisections: int = 0
    certified: int = 0  # Krawczyk proofs (before removing duplicates)
    duplicates: int = 0
    started: int = 0  # solutions first proven from a Newton-starts phase (.starts)
    max_pending: int = 0
    time: float = 0.0  # wall seconds
    cpu: float = 0.0  # CPU seconds, this process and every worker task
    executor: str = "serial"  # "serial" | "processes" | "dask"
    workers: int = 1
    tasks: int = 0  # worker tasks run
    resubmitted: int = 0  # task slices handed out again after a lost worker
    stopped_by: str | None = None  # the status when not complete (older name)
    resumed: int = 0  # times the search was restored from a checkpoint
    resumed_boxes: int = 0  # boxes already processed at the last restore

    @classmethod
    def of(cls, search: SearchStats, step: Stats, status: SearchStatus) -> Stats:
        """The driver's counters and the solver step's, in one record."""
        return cls(
            boxes=search.boxes,
            rounds=search.batches,
            bisections=step.bisections,
            certified=step.certified,
            duplicates=step.duplicates,
            started=step.started,
            max_pending=search.max_pending,
            time=search.time,
            cpu=search.cpu,
            executor=search.executor,
            workers=search.workers,
            tasks=search.tasks,
            resubmitted=search.resubmitted,
            stopped_by=None if status == SearchStatus.COMPLETE else str(status),
            resumed=search.resumed,
            resumed_boxes=search.resumed_boxes,
        )

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class SolveResult:
    variables: list[str]
    status: SearchStatus
    solutions: list[Solution] = field(default_factory=list)
    undecided: list[Undecided] = field(default_factory=list)
    pending_lo: np.ndarray | None = None  # hulls of the pending boxes
    pending_hi: np.ndarray | None = None
    stats: Stats = field(default_factory=Stats)
    eps: float = 0.0
    undecided_total: int = 0  # undecided boxes of the search (hulls listed hold some of them)
    undecided_dropped: int = 0  # undecided boxes in no listed hull (then not complete)
    pending_boxes: np.ndarray | None = None  # pending boxes in each listed hull
    pending_total: int = 0  # pending boxes of the search

    @classmethod
    def of_search(
        cls,
        run: Any,
        *,
        variables: list[str],
        solutions: list[Solution],
        undecided: list[tuple[np.ndarray, np.ndarray, str]],
        stats: Stats,
        eps: float,
        max_undecided: int,
        max_pending: int,
    ) -> SolveResult:
        """The result of a finished search ``run`` (:class:`~.search.SearchRun`): its
        ``undecided`` boxes ``(lo, hi, reason)`` and its pending boxes (the buffer)
        summarised (:func:`.summary.summarize`); ``stats``: the step's counters."""
        plo, phi = run.state.stack.snapshot()
        summ = summarize(undecided, plo, phi, max_undecided=max_undecided, max_pending=max_pending)
        status = run.status
        if status == SearchStatus.COMPLETE and summ.undecided_dropped:
            status = SearchStatus.TRUNCATED  # nothing pending, but not every box is listed
        return cls(
            variables=list(variables),
            status=status,
            solutions=solutions,
            undecided=[Undecided(a, b, r, k) for a, b, r, k in summ.undecided],
            pending_lo=summ.pending_lo,
            pending_hi=summ.pending_hi,
            stats=Stats.of(run.stats, stats, run.status),
            eps=eps,
            undecided_total=summ.undecided_total,
            undecided_dropped=summ.undecided_dropped,
            pending_boxes=summ.pending_boxes,
            pending_total=summ.pending_total,
        )

    @classmethod
    def unexplored(
        cls,
        *,
        variables: list[str],
        domain: np.ndarray,
        status: SearchStatus,
        eps: float,
        time: float,
        cpu: float,
    ) -> SolveResult:
        """The result of a search stopped before its first box (a time limit passed while
        the system was being compiled): no solution, nothing undecided, the whole
        ``domain`` ``(n, 2)`` pending -- all that is known, as a stopped search reports it;
        ``time`` and ``cpu``: the seconds spent."""
        return cls(
            variables=list(variables),
            status=status,
            pending_lo=domain[None, :, 0].copy(),
            pending_hi=domain[None, :, 1].copy(),
            stats=Stats(time=time, cpu=cpu, stopped_by=str(status)),
            eps=eps,
            pending_boxes=np.array([1]),
            pending_total=1,
        )

    @property
    def pending(self) -> list[list[list[float]]]:
        if self.pending_lo is None or self.pending_hi is None:
            return []
        return [_box_list(a, b) for a, b in zip(self.pending_lo, self.pending_hi, strict=True)]

    def to_dict(self) -> dict:
        return {
            "status": str(self.status),
            "variables": list(self.variables),
            "solutions": [s.to_dict() for s in self.solutions],
            "undecided": [u.to_dict() for u in self.undecided],
            "pending": self.pending,
            "undecided_total": self.undecided_total,
            "undecided_dropped": self.undecided_dropped,
            "pending_total": self.pending_total,
            "pending_boxes": [] if self.pending_boxes is None else self.pending_boxes.tolist(),
            "stats": self.stats.to_dict(),
            "eps": self.eps,
        }
