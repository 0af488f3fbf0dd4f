"""Executors of the search driver: where the batches of a :class:`~.search.Search` run.

* :class:`~.search.SerialExecutor` -- in this process (the default);
* :class:`ProcessExecutor` -- local worker processes (``concurrent.futures``, spawned);
* :class:`~.dask_executor.DaskExecutor` -- the workers of a Dask cluster
  (``distributed.Client``; optional extra ``certsolve[distributed]``).

The two executors with workers share one loop (:class:`~.workers.TaskExecutor`, in
its own module so that :mod:`.dask_executor` does not import this one back):

1. a **serial warm-up** of ``warmup`` seconds in this process: a search that ends within
   half of it never starts workers (starting processes costs 0.5-2 s), one that ends within
   it never sends them a task; the workers start during the second half; then the buffer is
   grown until it holds ``grow`` full batches for every slot (a batch of 5 boxes costs
   nearly what one of 500 does: the numpy calls are the same), or for another ``warmup``
   seconds at most (the depth-first order can keep the buffer below that for the whole
   search);
2. **tasks**: a slice of the buffer (an even share, at least a batch, at most
   ``slice_size`` boxes, default two batches), what the step already
   knows (e.g. certified solutions, so that workers prune them instead of proving them
   again) and limits (``task_seconds`` of work, at most ``task_max_boxes`` boxes, the
   remaining share of ``max_boxes`` and ``max_solutions``).  A task runs the batch loop on
   its slice (:func:`~.search.run_task`) and returns its records and its unfinished
   boxes, which go back into the buffer;
3. the driver **waits on futures** (never polls), merges each result, reports progress,
   hands out more work, and checks the limits.  A task whose worker was lost gives its
   boxes back to the buffer; they are handed out again (up to ``max_attempts`` times).
   On cancellation, and once ``max_solutions`` are certified, the running tasks are
   cancelled and their boxes are pending; on the other limits the running tasks are
   waited for (their budgets end with the time limit and share ``max_boxes``).

Every box handed out comes back, processed or as a remaining box, so the result holds
the same solutions, undecided regions and status as a serial run; box boundaries, box
counts and the order of discovery may differ.
"""

from __future__ import annotations

import os
import pickle
from collections import deque
from typing import TYPE_CHECKING, Any

import numpy as np

from .search import (
    Executor,
    Limits,
    SerialExecutor,
    Step,
    TaskResult,
    run_task,
)
from .workers import TaskExecutor, TaskPool

if TYPE_CHECKING:
    from concurrent.futures import ProcessPoolExecutor

__all__ = [
    "ProcessExecutor",
    "TaskExecutor",
    "TaskPool",
    "available_cores",
    "resolve_executor",
]


def available_cores() -> int:
    """Cores this process may run on (``sched_getaffinity``, else ``os.cpu_count``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


# -- local processes ------------------------------------------------------------------------
#: in a worker process: the step of the search its pool was made for, unpickled once by
#: the process's initializer (:func:`_start_worker`).  A pool serves one search
#: (:meth:`ProcessExecutor.open`) and its processes end with it, so this is the worker's
#: copy of its one step, as a Dask worker keeps the step scattered to it; never set in the
#: driver.
_STEP: Step | None = None


def _start_worker(step_bytes: bytes) -> None:
    """Worker start-up: Ctrl-C is the driver's business (it stops the search itself), and
    the step is unpickled here, once, not with every task (~35 ms for general-19's, where
    a task of its search at 60 N runs ~0.3 s)."""
    import signal

    global _STEP
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STEP = pickle.loads(step_bytes)


def _ready() -> None:
    """Start-up task: it makes the pool start its process while the driver's warm-up goes
    on (the initializer does the work)."""


def _run(lo, hi, known, limits: Limits, hints=None) -> TaskResult:
    """A task in a worker process, on the step its initializer unpickled."""
    if _STEP is None:
        raise RuntimeError("a worker task ran before its process was initialised")
    return run_task(_STEP, lo, hi, known, limits, hints)


class _ProcessPool(TaskPool):
    """A ``ProcessPoolExecutor``; when a worker process dies the pool is broken (every
    running task fails with ``BrokenProcessPool``): a new pool runs the next tasks.

    ``concurrent.futures.process`` and ``multiprocessing`` are imported when a pool is
    made, not with this module: a one-process solve (and the CLI's start-up) does not pay
    for them."""

    def __init__(self, step: Step, workers: int, max_restarts: int = 8):
        self.workers = workers
        self.slots = workers + 1  # one queued task hides the round trip
        self._step = pickle.dumps(step)
        self._pool: ProcessPoolExecutor | None = None
        self._generation = 0  # of the current pool
        self._running: dict = {}  # future -> generation of its pool
        self._ready: deque = deque()
        self._restarts = 0
        self._max_restarts = max_restarts
        self._start()

    def _start(self) -> None:
        from concurrent.futures import ProcessPoolExecutor
        from multiprocessing import get_context

        self._pool = ProcessPoolExecutor(
            self.workers,
            mp_context=get_context("spawn"),
            initializer=_start_worker,
            initargs=(self._step,),
        )
        for _ in range(self.workers):
            self._pool.submit(_ready)

    def submit(self, lo, hi, known, limits, hints=None):
        from concurrent.futures.process import BrokenProcessPool

        if self._pool is None:
            self._start()
        try:
            fut = self._pool.submit(_run, lo, hi, known, limits, hints)
        except BrokenProcessPool:  # a worker died while no task was running
            self._restart()
            if self._restarts > self._max_restarts:
                raise
            fut = self._pool.submit(_run, lo, hi, known, limits, hints)
        self._running[fut] = self._generation
        return fut

    def _restart(self) -> None:
        assert self._pool is not None
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._generation += 1
        self._restarts += 1
        self._start()

    def next_done(self):
        from concurrent.futures import FIRST_COMPLETED, wait  # (not on a serial run)
        from concurrent.futures.process import BrokenProcessPool

        if not self._ready:
            done, _ = wait(list(self._running), return_when=FIRST_COMPLETED)
            self._ready.extend(done)
        fut = self._ready.popleft()
        generation = self._running.pop(fut, -1)
        try:
            return fut, fut.result(), None
        except BrokenProcessPool as exc:
            if generation == self._generation:
                self._restart()
            return fut, None, exc
        except Exception as exc:  # noqa: BLE001 - handed to the driver
            return fut, None, exc

    def lost(self, error):
        from concurrent.futures.process import BrokenProcessPool

        return isinstance(error, BrokenProcessPool) and self._restarts <= self._max_restarts

    def cancel(self, handles):
        for fut in handles:
            fut.cancel()
            self._running.pop(fut, None)

    def close(self):
        if self._pool is not None:
            # tasks still running after a cancellation end within their time budget
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None


class ProcessExecutor(TaskExecutor):
    """Local worker processes (spawned for each search, after the serial warm-up)."""

    name = "processes"

    def __init__(self, workers: int | None = None, **options):
        super().__init__(**options)
        workers = available_cores() if workers is None else workers
        if isinstance(workers, bool) or int(workers) != workers or workers < 1:
            raise ValueError("workers must be an integer >= 1")
        self.workers = int(workers)

    def open(self, step: Step) -> TaskPool:
        return _ProcessPool(step, self.workers)

    def __repr__(self) -> str:
        return f"ProcessExecutor(workers={self.workers})"


# -- choosing an executor -------------------------------------------------------------------
def _is_dask_client(obj) -> bool:
    cls = type(obj)
    return cls.__name__ == "Client" and cls.__module__.split(".")[0] == "distributed"


def resolve_executor(spec: Any = None, *, workers: int | None = None) -> Executor:
    """An executor from a user's choice.

    ``None`` / ``"serial"`` / ``1``: this process; an integer ``n > 1``: ``n`` local
    processes; ``"auto"`` / ``"processes"``: one process per available core (serial on a
    single core); a ``distributed.Client`` or a scheduler address (``"tcp://host:8786"``):
    that Dask cluster; an executor object: itself.  ``workers`` is the older name of an
    integer ``spec`` (give one or the other).
    """
    if workers is not None:
        if spec is not None:
            raise ValueError("give either executor or workers, not both")
        spec = workers
    if spec is None:
        return SerialExecutor()
    if isinstance(spec, str):
        s = spec.strip()
        if s in ("serial", "1"):
            return SerialExecutor()
        if s in ("auto", "processes"):
            n = available_cores()
            return SerialExecutor() if n == 1 else ProcessExecutor(n)
        if "://" in s:
            from .dask_executor import DaskExecutor

            return DaskExecutor(s)
        if s.isdigit():
            return resolve_executor(int(s))
        raise ValueError(
            f"executor: expected 'serial', 'auto', 'processes', a number of workers, a "
            f"scheduler address (tcp://host:port) or a distributed.Client; got {spec!r}"
        )
    if isinstance(spec, bool):
        raise ValueError("executor: expected a number of workers, not a boolean")
    if isinstance(spec, (int, np.integer)):
        if spec < 1:
            raise ValueError("executor: the number of workers must be >= 1")
        return SerialExecutor() if spec == 1 else ProcessExecutor(int(spec))
    if _is_dask_client(spec):
        from .dask_executor import DaskExecutor

        return DaskExecutor(spec)
    if callable(getattr(spec, "run", None)) and isinstance(getattr(spec, "name", None), str):
        return spec
    raise ValueError(f"executor: cannot run a search on {type(spec).__name__}")
