"""What the search driver (:mod:`.search`) and its checkpoints (:mod:`.checkpoint`) share.

The driver saves itself through a checkpoint, and a checkpoint reads a running search and
restores a step's state: each needs a *view* of the other, not the other module.  The
views are here, below both, with the plain data they exchange:

* :class:`Step` -- what the driver needs from a search (start, process, tally, and for
  workers and checkpoints known / found / merge);
* :class:`SearchStats` -- the driver's counters, saved in a checkpoint and restored;
* :class:`Tally` -- a step's counts of what its state holds;
* :class:`RunningSearch` -- what a checkpoint reads from a search to save it;
* :class:`Saver` -- what the driver asks of a checkpoint (begin, tick, write).

So :mod:`.search` and :mod:`.checkpoint` each import this module and neither imports the
other (``tests/test_layers.py`` checks it, ``TYPE_CHECKING`` imports included).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

import numpy as np

__all__ = ["RunningSearch", "Saver", "SearchStats", "Step", "Tally"]


@dataclass(kw_only=True)
class Tally:
    """A step's counts of what its state holds (for limits and progress)."""

    solutions: int  # what max_solutions counts
    undecided: int = 0
    extra: dict[str, float] = field(default_factory=dict)


class Step(Protocol):
    """What the driver needs from a search.  The step's *state* must have a ``stack``
    (:class:`~.buffer.BoxStack`: ``push``, ``pop_hinted``, ``snapshot``, ``hints``, ``len``);
    the rest of it is the step's business.

    Executors with workers also use :meth:`known`, :meth:`found` and :meth:`merge`, and
    the step and its state must pickle.
    """

    @property
    def batch_size(self) -> int:
        """Boxes per batch."""
        ...

    def start(self, known: Any = None) -> Any:
        """A new state with an empty stack, seeded with ``known`` (see :meth:`known`)."""

    def process(
        self, lo: np.ndarray, hi: np.ndarray, state: Any, *, deadline: float | None = None
    ) -> None:
        """Process a batch ``(B, n)``: record results in ``state``, push what remains of the
        boxes on ``state.stack``.  Whatever is neither pushed nor recorded is proven empty.

        ``deadline``: a :func:`time.monotonic` value (the search's time limit) past which
        the step may cut its work on the batch short, pushing the boxes as far as it got
        (sound: contracting less keeps every solution), so that one long round does not
        outlast the limit by much.

        ``hints`` (keyword, only when the buffer holds some): the boxes' hints
        (:mod:`.buffer`).  A buffer holds hints only if the step's own parts left some, so
        a step that leaves none need not accept the keyword."""

    def tally(self, state: Any) -> Tally: ...

    def known(self, state: Any) -> Any:
        """What a task must know from ``state`` (small, picklable; ``None`` if nothing)."""

    def found(self, state: Any) -> Any:
        """What ``state`` recorded since :meth:`start` (picklable), for :meth:`merge`."""

    def merge(self, state: Any, found: Any) -> None:
        """Add a task's :meth:`found` to ``state``."""


@dataclass(kw_only=True)
class SearchStats:
    """Counters of one search (steps add their own in their state)."""

    executor: str = "serial"  # "serial" | "processes" | "dask"
    workers: int = 1
    boxes: int = 0  # boxes processed by the step
    batches: int = 0
    tasks: int = 0  # worker tasks finished
    resubmitted: int = 0  # task slices handed out again after a worker was lost
    max_pending: int = 0
    time: float = 0.0  # wall seconds
    cpu: float = 0.0  # CPU seconds: this process plus every task
    resumed: int = 0  # times the search was restored from a checkpoint (.checkpoint)
    resumed_boxes: int = 0  # boxes already processed at the last restore

    def to_dict(self) -> dict:
        return asdict(self)


class RunningSearch(Protocol):
    """A search as a checkpoint reads it (:class:`.search.Search` is one)."""

    step: Step
    state: Any

    def pending_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the pending boxes (the buffer and the slices handed out)."""
        ...

    def pending_hints(self) -> np.ndarray | None:
        """Their hints (:mod:`.buffer`), in the same order, or ``None``."""
        ...

    def counters(self) -> SearchStats:
        """The counters as they are now."""
        ...


class Saver(Protocol):
    """A checkpoint as the driver uses it (:class:`.checkpoint.Checkpoint` is one)."""

    def begin(self, step: Step, lo: Any, hi: Any) -> tuple[Any, SearchStats] | None:
        """Fingerprint the search; the restored ``(state, counters)`` if one is stored."""
        ...

    def tick(self, search: RunningSearch) -> None:
        """Save if it is time to."""
        ...

    def write(self, search: RunningSearch) -> None:
        """Save now."""
        ...
