"""The loop shared by the executors with workers (:mod:`.executors` describes it).

:class:`TaskPool` is what an executor provides (workers that run tasks for one search);
:class:`TaskExecutor` drives any pool: the serial warm-up, tasks handed out from the
buffer, results merged as their futures complete, lost tasks handed out again.  Kept apart
from :mod:`.executors` (which chooses an executor, and may import the Dask one) so that
:mod:`.dask_executor` and :mod:`.executors` do not import each other.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections import deque
from typing import Any

import numpy as np

from .search import Limits, Search, SearchStatus, Step, TaskResult

__all__ = ["TaskExecutor", "TaskPool"]


class TaskPool(ABC):
    """Workers that run tasks for one search (opened and closed by :class:`TaskExecutor`)."""

    workers: int  # worker processes
    slots: int  # tasks kept in flight

    @abstractmethod
    def submit(
        self, lo: np.ndarray, hi: np.ndarray, known: Any, limits: Limits, hints: Any = None
    ) -> Any:
        """Start a task (:func:`~.search.run_task`'s arguments); returns a handle."""

    @abstractmethod
    def next_done(self) -> tuple[Any, TaskResult | None, BaseException | None]:
        """Block until a task ends: ``(handle, result, None)`` or ``(handle, None, error)``."""

    @abstractmethod
    def lost(self, error: BaseException) -> bool:
        """True if ``error`` means the task's worker was lost (the task may be run again)."""

    @abstractmethod
    def cancel(self, handles: list) -> None:
        """Cancel running tasks (their results are not waited for)."""

    def refresh(self) -> None:  # noqa: B027 - optional hook
        """Update :attr:`slots` (e.g. workers joined or left a cluster)."""

    @abstractmethod
    def close(self) -> None: ...


# stops that do not wait for the running tasks (the others end within their task budget)
_PROMPT = (SearchStatus.CANCELLED, SearchStatus.MAX_SOLUTIONS)


class TaskExecutor(ABC):
    """The loop shared by the executors with workers (see the module docstring)."""

    name = "tasks"

    def __init__(
        self,
        *,
        warmup: float = 2.0,
        task_seconds: float = 1.0,
        slice_size: int | None = None,
        task_max_boxes: int | None = None,
        grow: float = 1.0,
        max_attempts: int = 4,
    ):
        if not warmup >= 0:
            raise ValueError("warmup must be >= 0 (seconds)")
        if not task_seconds > 0:
            raise ValueError("task_seconds must be positive")
        if slice_size is not None and int(slice_size) < 1:
            raise ValueError("slice_size must be >= 1")
        if task_max_boxes is not None and int(task_max_boxes) < 1:
            raise ValueError("task_max_boxes must be >= 1")
        self.warmup = float(warmup)
        self.task_seconds = float(task_seconds)
        self.slice_size = slice_size
        self.task_max_boxes = task_max_boxes
        if not grow >= 0:
            raise ValueError("grow must be >= 0 (batches per slot)")
        self.grow = float(grow)
        self.max_attempts = int(max_attempts)

    @abstractmethod
    def open(self, step: Step) -> TaskPool: ...

    def run(self, search: Search) -> None:
        def done() -> bool:
            return search.stopped() or not len(search.state.stack)

        search.run_serial(until=self.warmup / 2)
        if done():
            return  # done (or stopped) before the workers were needed
        pool = self.open(search.step)  # workers start while the warm-up goes on
        try:
            search.run_serial(until=self.warmup)
            if done():
                return
            # at most as long again as the warm-up: the depth-first order keeps the buffer
            # small (katsura-7's peaks at ~3,500 boxes, where it was ~7,000)
            full = math.ceil(self.grow * pool.slots * search.step.batch_size)
            search.run_serial(until=2.0 * self.warmup, grow_to=full)
            if done():
                return
            search.stats.workers = pool.workers
            self._loop(search, pool)
        finally:
            pool.close()

    def _loop(self, search: Search, pool: TaskPool) -> None:
        step, state = search.step, search.state
        batch = step.batch_size
        most = 2 * batch if self.slice_size is None else self.slice_size
        # a slice: the boxes, their hints, and the attempt
        running: dict[Any, tuple[np.ndarray, np.ndarray, Any, int]] = {}
        retry: deque[tuple[np.ndarray, np.ndarray, Any, int]] = deque()  # lost tasks' slices
        while True:
            if not search.stopped():
                known = None
                while len(running) < pool.slots and (retry or len(state.stack)):
                    if known is None:
                        known = step.known(state)
                    if retry:
                        lo, hi, hints, attempt = retry.popleft()
                    else:
                        # an even share, but a full batch if there is one: a small batch
                        # costs nearly what a full one does (numpy calls per batch)
                        share = math.ceil(len(state.stack) / (pool.slots - len(running)))
                        lo, hi, hints = search.take(min(most, max(share, batch)))
                        attempt = 1
                    limits = search.task_limits(pool.slots, self.task_seconds, self.task_max_boxes)
                    running[pool.submit(lo, hi, known, limits, hints)] = (lo, hi, hints, attempt)
            if not running:
                break
            handle, result, error = pool.next_done()
            lo, hi, hints, attempt = running.pop(handle)
            if error is not None:
                if not pool.lost(error):
                    raise error
                if attempt >= self.max_attempts:
                    raise RuntimeError(
                        f"a task failed {attempt} times (its worker was lost each time)"
                    ) from error
                search.stats.resubmitted += 1
                retry.append((lo, hi, hints, attempt + 1))
                continue
            assert result is not None  # a task ends with a result or an error
            search.absorb(lo, result)
            search.report()
            pool.refresh()
            if search.stopped() and search.reason in _PROMPT and running:
                pool.cancel(list(running))
                for lo, hi, hints, _ in running.values():
                    search.give_back(lo, hi, hints)
                running.clear()
        for lo, hi, hints, _ in retry:  # stopped before they were handed out again
            search.give_back(lo, hi, hints)
