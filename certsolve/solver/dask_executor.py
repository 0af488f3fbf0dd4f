"""The search driver on a Dask cluster (``distributed``; optional extra ``certsolve[distributed]``).

Per search, the step (the compiled system with its contractors, or the robot for a
paving) is **scattered once** to every worker (``Client.scatter(broadcast=True)``); each
task then carries only boxes, the known solutions and its limits, and returns its records
and unfinished boxes (:func:`~.search.run_task`).  The driver waits on the futures with
``distributed.as_completed`` -- it never polls -- and adds new tasks to it as slots free.

**Lost workers.**  The scheduler itself runs again the tasks of a worker that died (up to
its ``distributed.scheduler.allowed-failures``); a task that still fails with the worker
(``KilledWorker``, a closed connection, a cancelled future whose input was lost) gives its
boxes back to the driver, which hands them out again -- the driver owns every box until
a result for it comes back.  If the scattered step was lost with its workers it is
scattered again.  Workers may join or leave during a search: the number of tasks in
flight follows ``Client.nthreads()``.
"""

from __future__ import annotations

import logging
import os
import time
from typing import Any

from .search import Step, run_task
from .workers import TaskExecutor, TaskPool

__all__ = ["DaskExecutor", "import_distributed", "lost_errors"]

log = logging.getLogger(__name__)

#: below this, glibc's fixed trim threshold makes every large numpy temporary a fresh mmap
_TRIM_WARNING = 1 << 20


def import_distributed():
    """The ``distributed`` package, or an ImportError that names the extra to install."""
    try:
        import distributed
    except ImportError:
        raise ImportError(
            "running on a Dask cluster needs the optional dependency 'distributed': "
            "pip install 'certsolve[distributed]'"
        ) from None
    return distributed


class _DaskPool(TaskPool):
    def __init__(self, client, step: Step, *, owned: bool, worker_timeout: float):
        distributed = import_distributed()
        self.client = client
        self._owned = owned
        self._as_completed = distributed.as_completed(loop=client.loop)
        self._lost_types = lost_errors()
        try:
            client.wait_for_workers(1, timeout=worker_timeout)
        except TimeoutError:
            raise TimeoutError(
                f"no Dask worker joined the scheduler {client.scheduler.address} "
                f"within {worker_timeout:g} s"
            ) from None
        _check_malloc(client)
        self._step_obj = step
        self._step = client.scatter(step, broadcast=True, hash=False)
        self._next_refresh = 0.0
        self.workers = self.slots = 0
        self.refresh()

    def refresh(self) -> None:
        now = time.monotonic()
        if now < self._next_refresh:
            return
        self._next_refresh = now + 2.0
        nthreads = self.client.nthreads()
        # one queued task per worker hides the round trip to the scheduler
        self.slots = max(1, sum(nthreads.values()) + len(nthreads))
        self.workers = max(self.workers, len(nthreads))

    def submit(self, lo, hi, known, limits, hints=None):
        if self._step.status != "finished":  # lost with its workers: scatter it again
            self._step = self.client.scatter(self._step_obj, broadcast=True, hash=False)
        fut = self.client.submit(run_task, self._step, lo, hi, known, limits, hints, pure=False)
        self._as_completed.add(fut)
        return fut

    def next_done(self):
        fut = next(self._as_completed)
        try:
            return fut, fut.result(), None
        except Exception as exc:  # noqa: BLE001 - handed to the driver
            return fut, None, exc

    def lost(self, error):
        return isinstance(error, self._lost_types)

    def cancel(self, handles):
        self.client.cancel(handles)

    def close(self):
        self._as_completed.clear()
        self._step.release()
        if self._owned:
            self.client.close()


def _trim_threshold() -> str | None:
    return os.environ.get("MALLOC_TRIM_THRESHOLD_")


def _check_malloc(client) -> None:
    """Warn about Dask's default ``MALLOC_TRIM_THRESHOLD_=65536`` on the workers.

    It fixes glibc's mmap threshold, so every large numpy temporary of a batch is a fresh
    mmap with its page faults: measured, the solver's batches take twice the CPU time.
    """
    try:
        values = client.run(_trim_threshold)
    except Exception:  # noqa: BLE001 - a diagnostic only
        return
    low = [v for v in values.values() if v is not None and v.isdigit() and int(v) < _TRIM_WARNING]
    if low:
        log.warning(
            "%d Dask worker(s) run with MALLOC_TRIM_THRESHOLD_=%s (Dask's default): "
            "certsolve's batches take about twice the CPU time there; start the workers "
            "with MALLOC_TRIM_THRESHOLD_=1000000000 in their environment (docs/distributed.md)",
            len(low),
            low[0],
        )


def lost_errors() -> tuple[type[BaseException], ...]:
    """The errors of a future whose task was lost with its worker (not the task's own)."""
    from distributed.client import FutureCancelledError
    from distributed.comm.core import CommClosedError
    from distributed.scheduler import KilledWorker

    return (KilledWorker, CommClosedError, FutureCancelledError)


class DaskExecutor(TaskExecutor):
    """Tasks on the workers of a Dask cluster.

    ``cluster``: a ``distributed.Client``, or the scheduler's address (``tcp://host:8786``),
    to which a client connects for each search.  Options as :class:`.TaskExecutor`; the
    serial warm-up defaults to 0.5 s (a task round trip costs milliseconds, not the seconds
    of starting processes).
    """

    name = "dask"

    def __init__(
        self, cluster: Any, *, warmup: float = 0.5, worker_timeout: float = 30.0, **options
    ):
        super().__init__(warmup=warmup, **options)
        import_distributed()
        self.address: str | None
        if isinstance(cluster, str):
            self.address, self.client = cluster, None
        else:
            self.address, self.client = None, cluster
        self.worker_timeout = float(worker_timeout)

    def open(self, step: Step) -> TaskPool:
        if self.client is not None:
            return _DaskPool(self.client, step, owned=False, worker_timeout=self.worker_timeout)
        distributed = import_distributed()
        client = distributed.Client(self.address, set_as_default=False)
        try:
            return _DaskPool(client, step, owned=True, worker_timeout=self.worker_timeout)
        except BaseException:
            client.close()
            raise

    def __repr__(self) -> str:
        return f"DaskExecutor({self.address or self.client!r})"
