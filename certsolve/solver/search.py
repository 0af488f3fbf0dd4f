"""The search driver: one batched loop over a box buffer for every branch-and-prune search.

The solver, the forward kinematics, the certified workspace paving and the IK enclosure
search differ only in what they do to a batch of boxes.  That is a *step*
(:class:`Step`); everything around it is here, written once:

* the **buffer**: the step's state holds a :class:`~.buffer.BoxStack`; a batch is the last
  ``step.batch_size`` boxes (depth-first at the batch level), or as many as a
  :class:`~.batching.BatchSizer` chooses (small first rounds, larger while that pays);
* the **limits** (:class:`Limits`): wall time, processed boxes, and certified results
  ("solutions": whatever the step certifies -- solutions, inside boxes, an IK point);
* **cancellation**: a progress callback returning ``False``, or a ``cancel`` event
  (anything with ``is_set()``, e.g. :class:`threading.Event`) set by another thread;
* **progress**: one :class:`Progress` record after every batch (serial) or task (workers);
* one **status** (:class:`SearchStatus`): ``complete`` when nothing is pending, else why the
  search stopped;
* **checkpoints** (optional, :mod:`.checkpoint`): the search saved at intervals and when it
  stops, and resumed from the last save.

The guarantee the driver keeps: a box taken from the buffer is either given to the step,
which accounts for all of it (proven empty, recorded in its state, or pushed back as smaller
boxes), or it comes back to the buffer.  When the search stops, the pending boxes and the
step's records together cover the initial boxes: nothing is dropped by the driver.

*Executors* decide where batches run: :class:`SerialExecutor` (here, the default),
local processes and Dask (:mod:`.executors`).  Executors that use workers send *tasks*
(:func:`run_task`): a slice of the buffer, what is already known (e.g. certified solutions,
so that workers do not prove them again) and per-task limits; a task runs the same batch
loop on its own small buffer and returns what it found and the boxes it did not finish.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .batching import BatchSizer
from .buffer import stacked_hints
from .protocol import Saver, SearchStats, Step, Tally

__all__ = [
    "Executor",
    "Limits",
    "Listing",
    "Progress",
    "Search",
    "SearchRun",
    "SearchStats",
    "SearchStatus",
    "SerialExecutor",
    "Step",
    "Tally",
    "TaskResult",
    "run_search",
    "run_task",
]


class SearchStatus(StrEnum):
    """How a search ended: ``complete`` means nothing is pending, the limits name the limit
    (or the caller) that stopped it with boxes left to explore; ``truncated`` (a result
    status, never a stop) means nothing is pending but the answer lists only part of its
    undecided boxes (the others are counted)."""

    COMPLETE = "complete"
    TRUNCATED = "truncated"
    TIMEOUT = "timeout"
    MAX_BOXES = "max_boxes"
    MAX_SOLUTIONS = "max_solutions"
    CANCELLED = "cancelled"


@dataclass(kw_only=True, frozen=True)
class Limits:
    """When to stop early (``None``: no limit).

    ``timeout``: wall seconds; ``max_boxes``: boxes processed by the step; ``max_solutions``:
    results the step certifies (:attr:`Tally.solutions`).  Limits are checked between
    batches, so a search may overshoot by one batch (one task per worker with workers;
    the solver's batch may end with a phase of Newton starts, :mod:`.starts`);
    a :class:`~.batching.BatchSizer` cuts a batch to what the remaining time fits.
    """

    timeout: float | None = None
    max_boxes: int | None = None
    max_solutions: int | None = None

    def __post_init__(self) -> None:
        if self.timeout is not None and not self.timeout >= 0:
            raise ValueError("timeout must be >= 0 (seconds)")
        for name in ("max_boxes", "max_solutions"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or int(v) != v or v < 0):
                raise ValueError(f"{name} must be an integer >= 0")


@dataclass
class Progress:
    """What a progress callback receives after each batch (serial) or task (workers).

    ``solutions`` and ``undecided`` are the step's counts (:class:`Tally`); ``extra`` holds
    the step's own figures (the paving's ``inside`` / ``outside`` / ``inside_share`` ...).
    ``found``: what the step certified since the previous report, as the step lists it
    (the solver: :class:`~.result.Solution` records), so a caller can stream solutions as
    they are proven; empty for steps that do not list theirs (:class:`Listing`).
    """

    boxes: int  # processed so far
    pending: int  # in the buffer or handed out to workers
    solutions: int
    undecided: int
    elapsed: float  # wall seconds
    tasks: int = 0  # worker tasks finished
    extra: dict[str, float] = field(default_factory=dict)
    found: list[Any] = field(default_factory=list)


@runtime_checkable
class Listing(Protocol):
    """A step that lists what it certified, for :attr:`Progress.found`."""

    def listed(self, state: Any, start: int) -> tuple[list[Any], int]:
        """The results recorded in ``state`` from position ``start`` on, and the position
        after them (the next call's ``start``)."""
        ...


@dataclass(kw_only=True)
class SearchRun:
    """The end of a search: its status, the step's state (records, and the pending boxes
    in ``state.stack``) and the counters."""

    status: SearchStatus
    state: Any
    stats: SearchStats

    @property
    def pending(self) -> int:
        return len(self.state.stack)


ProgressCallback = Callable[[Progress], bool | None]


class Search:
    """One search in progress: the step and its state, limits, callbacks and counters.

    Executors drive it: :meth:`run_serial` processes batches here; :meth:`take`,
    :meth:`give_back` and :meth:`absorb` hand slices of the buffer to workers and take their
    results back.  ``count_new``: limits on solutions count only what this search finds
    (a task seeded with known solutions), not what its state started with.  ``checkpoint``
    (a :class:`~.checkpoint.Checkpoint`) saves the search after batches and tasks.
    ``sizer`` (a :class:`~.batching.BatchSizer`): the size of each serial batch, adapted to
    its timings and the time left; ``None``: ``step.batch_size`` every time.
    """

    def __init__(
        self,
        step: Step,
        state: Any,
        limits: Limits | None = None,
        *,
        progress: ProgressCallback | None = None,
        cancel: Any = None,
        stats: SearchStats | None = None,
        count_new: bool = False,
        checkpoint: Saver | None = None,
        sizer: BatchSizer | None = None,
    ):
        self.step = step
        self.sizer = sizer
        self.state = state
        self.limits = limits or Limits()
        self.progress = progress
        self.cancel = cancel
        self.stats = stats or SearchStats()
        self.reason: SearchStatus | None = None  # why the search stopped, once it has
        self.in_flight = 0  # boxes handed out to tasks and not back yet
        self.checkpoint = checkpoint
        #: slices handed out, by id: their boxes and hints
        self._out: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray | None]] = {}
        self._base = step.tally(state).solutions if count_new else 0
        self._boxes0 = self.stats.boxes
        self._t0 = time.perf_counter()
        self._c0 = time.process_time()
        self._elapsed0 = self.stats.time
        self._cpu0 = self.stats.cpu
        self._task_cpu = 0.0
        self._listed = 0  # the step's records reported so far (Progress.found)

    # -- clock and limits --------------------------------------------------------------------
    def elapsed(self) -> float:
        """Seconds since this search started."""
        return time.perf_counter() - self._t0

    def remaining_time(self) -> float | None:
        t = self.limits.timeout
        return None if t is None else max(t - self.elapsed(), 0.0)

    def solutions(self) -> int:
        return self.step.tally(self.state).solutions - self._base

    def boxes(self) -> int:
        """Boxes processed by this search (not counting earlier runs of the same state)."""
        return self.stats.boxes - self._boxes0

    def stopped(self) -> bool:
        """True once a limit, the cancel event or the progress callback stopped the search."""
        if self.reason is not None:
            return True
        lim = self.limits
        if self.cancel is not None and self.cancel.is_set():
            self.reason = SearchStatus.CANCELLED
        elif lim.timeout is not None and self.elapsed() >= lim.timeout:
            self.reason = SearchStatus.TIMEOUT
        elif lim.max_boxes is not None and self.boxes() >= lim.max_boxes:
            self.reason = SearchStatus.MAX_BOXES
        elif lim.max_solutions is not None and self.solutions() >= lim.max_solutions:
            self.reason = SearchStatus.MAX_SOLUTIONS
        return self.reason is not None

    @property
    def pending(self) -> int:
        return len(self.state.stack) + self.in_flight

    # -- serial work -------------------------------------------------------------------------
    def batch(self) -> None:
        """Process one batch from the buffer here."""
        sizer = self.sizer
        left = self.remaining_time()
        deadline = None if left is None else time.monotonic() + left
        k = self.step.batch_size if sizer is None else sizer.next(left)
        lo, hi, hints = self.state.stack.pop_hinted(k)
        # hints come only from the step's own contractors (the buffer's docstring): a step
        # that never leaves any is never passed them
        more = {} if hints is None else {"hints": hints}
        t0 = time.perf_counter()
        self.step.process(lo, hi, self.state, deadline=deadline, **more)
        if sizer is not None:
            sizer.record(lo.shape[0], time.perf_counter() - t0, self.remaining_time())
        self.stats.boxes += lo.shape[0]
        self.stats.batches += 1
        self.stats.max_pending = max(self.stats.max_pending, self.pending)
        self.report()
        if self.checkpoint is not None:
            self.checkpoint.tick(self)

    def run_serial(self, *, until: float | None = None, grow_to: int | None = None) -> None:
        """Process batches here until the buffer is empty or the search stopped; also stop
        after ``until`` seconds, or once the buffer holds ``grow_to`` boxes."""
        stack = self.state.stack
        with np.errstate(all="ignore"):
            while len(stack) and not self.stopped():
                if until is not None and self.elapsed() >= until:
                    break
                if grow_to is not None and len(stack) >= grow_to:
                    break
                self.batch()

    # -- work on tasks -----------------------------------------------------------------------
    def take(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Hand out up to ``k`` boxes from the buffer, with their hints (``None``: none);
        they stay counted as pending."""
        lo, hi, hints = self.state.stack.pop_hinted(k)
        self.in_flight += lo.shape[0]
        self._out[id(lo)] = (lo, hi, hints)
        return lo, hi, hints

    def give_back(self, lo: np.ndarray, hi: np.ndarray, hints: np.ndarray | None = None) -> None:
        """Boxes of a task that will not return (lost worker, cancelled): pending again."""
        self.in_flight -= lo.shape[0]
        self._out.pop(id(lo), None)
        self.state.stack.push(lo, hi, hints)

    def absorb(self, lo: np.ndarray, result: TaskResult) -> None:
        """A task's result for the slice ``lo`` (as :meth:`take` handed it out): its
        records, its unfinished boxes."""
        self.in_flight -= lo.shape[0]
        self._out.pop(id(lo), None)
        # the boxes first: a phase the merge runs (.starts) draws from them too
        self.state.stack.push(result.lo, result.hi, result.hints)
        self.step.merge(self.state, result.found)
        self.stats.boxes += result.boxes
        self.stats.batches += result.batches
        self.stats.tasks += 1
        self.stats.max_pending = max(self.stats.max_pending, self.pending)
        self._task_cpu += result.cpu
        if self.checkpoint is not None:
            self.checkpoint.tick(self)

    def pending_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the pending boxes: the buffer, then the slices handed out to tasks."""
        lo, hi = self.state.stack.snapshot()
        if self._out:
            lo = np.concatenate([lo, *(a for a, _, _ in self._out.values())])
            hi = np.concatenate([hi, *(b for _, b, _ in self._out.values())])
        return lo, hi

    def pending_hints(self) -> np.ndarray | None:
        """The hints of :meth:`pending_boxes`, in their order (``None``: none)."""
        stack = self.state.stack
        parts = [(len(stack), stack.hints())]
        parts += [(a.shape[0], h) for a, _, h in self._out.values()]
        return stacked_hints(parts)

    def counters(self) -> SearchStats:
        """A copy of the counters as they are now (time and CPU included)."""
        stats = SearchStats(**self.stats.to_dict())
        stats.time = self._elapsed0 + self.elapsed()
        stats.cpu = self._cpu0 + time.process_time() - self._c0 + self._task_cpu
        return stats

    def task_limits(self, slots: int, seconds: float, boxes: int | None = None) -> Limits:
        """Limits for one task of at most ``seconds`` and ``boxes`` when ``slots`` tasks
        share the remaining budget."""
        lim = self.limits
        t = self.remaining_time()
        sols = None
        if lim.max_boxes is not None:
            share = max(1, math.ceil((lim.max_boxes - self.boxes()) / slots))
            boxes = share if boxes is None else min(boxes, share)
        if lim.max_solutions is not None:
            sols = max(1, lim.max_solutions - self.solutions())
        return Limits(
            timeout=seconds if t is None else min(seconds, t), max_boxes=boxes, max_solutions=sols
        )

    # -- reporting ---------------------------------------------------------------------------
    def report(self) -> None:
        """Call the progress callback; ``False`` from it cancels the search."""
        if self.progress is None:
            return
        t = self.step.tally(self.state)
        found: list[Any] = []
        if isinstance(self.step, Listing):
            found, self._listed = self.step.listed(self.state, self._listed)
        p = Progress(
            self.stats.boxes,
            self.pending,
            t.solutions,
            t.undecided,
            self._elapsed0 + self.elapsed(),
            self.stats.tasks,
            dict(t.extra),
            found,
        )
        if self.progress(p) is False and self.reason is None:
            self.reason = SearchStatus.CANCELLED

    def finish(self) -> SearchRun:
        """The run's status and counters (call once every task is back)."""
        if self.in_flight:
            raise RuntimeError("search finished with boxes still handed out")
        self.stats.time = self._elapsed0 + self.elapsed()
        self.stats.cpu = self._cpu0 + time.process_time() - self._c0 + self._task_cpu
        if len(self.state.stack) == 0:
            status = SearchStatus.COMPLETE
        elif self.reason is None:
            raise RuntimeError("search stopped with pending boxes and no reason")
        else:
            status = self.reason
        return SearchRun(status=status, state=self.state, stats=self.stats)


class Executor(Protocol):
    """Where the batches of a :class:`Search` run."""

    name: str

    def run(self, search: Search) -> None:
        """Work until the buffer is empty and every task is back, or the search stopped."""


class SerialExecutor:
    """Every batch in this process, one after the other."""

    name = "serial"

    def run(self, search: Search) -> None:
        search.run_serial()

    def __repr__(self) -> str:
        return "SerialExecutor()"


def run_search(
    step: Step,
    lo: np.ndarray | None = None,
    hi: np.ndarray | None = None,
    *,
    limits: Limits | None = None,
    executor: Executor | None = None,
    progress: ProgressCallback | None = None,
    cancel: Any = None,
    previous: SearchRun | None = None,
    checkpoint: Saver | None = None,
    sizer: BatchSizer | None = None,
) -> SearchRun:
    """Search the boxes ``lo, hi`` (``(B, n)``) with ``step`` (see the module docstring).

    ``previous`` continues an earlier run: its state (records and pending boxes) and
    counters; ``lo, hi`` are then added to its buffer.  ``executor`` defaults to
    :class:`SerialExecutor` (see :func:`.executors.resolve_executor` for the others).

    ``checkpoint`` (:class:`~.checkpoint.Checkpoint`): if it holds a snapshot of this
    search (same step, problem and initial boxes ``lo, hi``), the search resumes from it
    instead of starting from ``lo, hi``; it is saved every ``checkpoint.interval``
    seconds and when the search stops.  ``sizer``: the adaptive size of the batches run
    here (:class:`~.batching.BatchSizer`; worker tasks take ``step.batch_size`` boxes).
    """
    executor = executor or SerialExecutor()
    resumed = None
    if checkpoint is not None:
        if previous is not None:
            raise ValueError("a checkpointed search cannot continue a previous run")
        resumed = checkpoint.begin(step, lo, hi)
    if resumed is not None:
        state, stats = resumed
    elif previous is None:
        state, stats = step.start(), SearchStats()
    else:
        state, stats = previous.state, previous.stats
    if lo is not None and resumed is None:
        assert hi is not None, "boxes: lo and hi together"
        state.stack.push(np.atleast_2d(lo), np.atleast_2d(hi))
    search = Search(
        step,
        state,
        limits,
        progress=progress,
        cancel=cancel,
        stats=stats,
        checkpoint=checkpoint,
        sizer=sizer,
    )
    search.stats.executor = executor.name
    executor.run(search)
    if checkpoint is not None:
        checkpoint.write(search)
    return search.finish()


@dataclass(kw_only=True)
class TaskResult:
    """What a task sends back: the step's new records and the boxes it did not finish."""

    found: Any
    lo: np.ndarray
    hi: np.ndarray
    boxes: int
    batches: int
    cpu: float  # thread CPU seconds of the task
    wall: float
    hints: np.ndarray | None = None  # the unfinished boxes' hints (:mod:`.buffer`)


def run_task(
    step: Step,
    lo: np.ndarray,
    hi: np.ndarray,
    known: Any,
    limits: Limits,
    hints: np.ndarray | None = None,
) -> TaskResult:
    """The worker side of every executor: the batch loop on a slice of the buffer.

    A function of its inputs only: ``step`` (scattered once per search with Dask),
    the boxes and their hints, what is known and the task's limits.
    """
    t0, c0 = time.perf_counter(), time.thread_time()
    state = step.start(known)
    state.stack.push(lo, hi, hints)
    search = Search(step, state, limits, count_new=True)
    search.run_serial()
    rlo, rhi = state.stack.snapshot()
    return TaskResult(
        found=step.found(state),
        lo=rlo,
        hi=rhi,
        hints=state.stack.hints(),
        boxes=search.stats.boxes,
        batches=search.stats.batches,
        cpu=time.thread_time() - c0,
        wall=time.perf_counter() - t0,
    )
