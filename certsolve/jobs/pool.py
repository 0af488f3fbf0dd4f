"""The worker pool and its supervisor thread.

The supervisor (a thread of the service process) starts ``settings.workers`` worker
processes and then, every ``supervise_interval`` seconds:

* reaps dead workers (crash, ``kill -9``, memory error): their running job is re-queued or
  failed (:meth:`.JobStore.release`), and a new worker takes the slot -- with a back-off
  when a slot keeps dying;
* kills the worker of a job cancelled more than ``cancel_grace`` seconds ago that has not
  stopped (the job ends ``cancelled``), or of a job past its time limit by ``kill_grace``
  -- by ``finish_grace`` from the moment its worker said it was storing its result
  (:func:`.worker.overdue`) -- (the job ends ``failed``);
* releases running jobs held by no live worker (orphans).

The supervisor thread also starts every worker, so ``PR_SET_PDEATHSIG`` (tied to the
thread that forked) fires only when the service goes away.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import threading
import time
from collections import deque

from .settings import ServiceSettings
from .status import JobStatus
from .store import JobStore
from .worker import EXIT_FRESH, overdue, worker_main

__all__ = ["WorkerPool", "describe_exit"]

log = logging.getLogger("certsolve.jobs")

_THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def describe_exit(code: int | None) -> str:
    if code is None:
        return "worker process vanished"
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"worker process died (killed by {name})"
    return f"worker process died (exit status {code})"


class WorkerPool:
    """``settings.workers`` supervised worker processes running jobs from ``store``."""

    def __init__(self, settings: ServiceSettings, store: JobStore):
        self.settings = settings
        self.store = store
        self.size = settings.workers
        self._ctx = multiprocessing.get_context("spawn")
        self._procs: list = [None] * self.size
        self._wakers: list = [None] * self.size  # write ends of the workers' wake-up pipes
        self._wlock = threading.Lock()
        self._deaths: list[deque] = [deque(maxlen=5) for _ in range(self.size)]
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._started = threading.Event()
        self._killed: set[int] = set()  # pids the supervisor killed (not crashes)
        self._ever = [False] * self.size  # slot started once (later starts are restarts)
        self.restarts = 0

    # -- control ------------------------------------------------------------------------------
    def start(self) -> None:
        for name in _THREAD_ENV:  # one BLAS thread per worker: the pool is the parallelism
            os.environ.setdefault(name, "1")
        self._thread = threading.Thread(target=self._run, name="certsolve-supervisor", daemon=True)
        self._thread.start()
        self._started.wait(30)

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the workers; their running jobs go back to the queue (no attempt used)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def notify(self) -> None:
        """Wake idle workers (new jobs were queued).

        One byte down each worker's pipe, never blocking: a full pipe already means "wake
        up", and a dead worker's pipe is simply ignored.  (A ``multiprocessing.Event``
        would hang the service if a worker were killed while waiting on it.)
        """
        with self._wlock:  # never write to a descriptor being closed (and maybe reused)
            for w in self._wakers:
                if w is None:
                    continue
                try:
                    os.write(w.fileno(), b"!")
                except (BlockingIOError, BrokenPipeError, OSError, ValueError):
                    pass

    def pids(self) -> list[int]:
        return [p.pid for p in self._procs if p is not None and p.pid is not None]

    def alive(self) -> int:
        return sum(1 for p in self._procs if p is not None and p.is_alive())

    # -- the supervisor -----------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.supervise_once()  # the first pass starts the workers
            except Exception:  # never let the supervisor die
                log.exception("supervisor pass failed")
            self._started.set()
            self._stop.wait(self.settings.supervise_interval)
        self._shutdown()

    def _spawn(self, slot: int):
        with self._wlock:
            old, self._wakers[slot] = self._wakers[slot], None
            if old is not None:
                old.close()
        r, w = self._ctx.Pipe(duplex=False)
        os.set_blocking(w.fileno(), False)
        p = self._ctx.Process(
            target=worker_main,
            args=(str(self.store.path), self.settings.for_workers, os.getpid(), r),
            name=f"certsolve-worker-{slot}",
            daemon=True,
        )
        p.start()
        r.close()  # the child has its copy
        with self._wlock:
            self._wakers[slot] = w
        return p

    def supervise_once(self) -> None:
        now = time.time()
        for i, p in enumerate(self._procs):
            if p is not None and not p.is_alive():
                p.join(0.1)
                reason = describe_exit(p.exitcode)
                released = self.store.release(reason, worker_pids=[p.pid])
                if p.exitcode != EXIT_FRESH or released:
                    log.warning("%s (pid %s); jobs: %s", reason, p.pid, released or "none")
                self._procs[i] = None
                if p.exitcode != EXIT_FRESH and p.pid not in self._killed:
                    self._deaths[i].append(now)  # a crash: counts towards the back-off
                self._killed.discard(p.pid)
                p.close()
            if self._procs[i] is None and not self._stop.is_set():
                d = self._deaths[i]
                if len(d) == d.maxlen and now - d[0] < 60 and now - d[-1] < 10:
                    continue  # crash loop: wait a little before the next try
                if self._ever[i]:
                    self.restarts += 1
                self._procs[i] = self._spawn(i)
                self._ever[i] = True

        live = {p.pid: p for p in self._procs if p is not None}
        s = self.settings
        for job in self.store.running():
            proc = live.get(job.worker_pid)
            lease = job.lease or ""  # a running job has one ("" matches no row, as None)
            if job.cancel_requested_at is not None and now - job.cancel_requested_at > (
                s.cancel_grace
            ):
                if self.store.force_finish(
                    job.id, lease, JobStatus.CANCELLED, "cancelled (the worker was stopped)"
                ):
                    self._kill(proc)
            elif (why := overdue(job, now, s)) is not None:
                if self.store.force_finish(
                    job.id, lease, JobStatus.FAILED, f"{why}; the worker was stopped"
                ):
                    self._kill(proc)
            elif proc is None and (job.heartbeat_at or 0) < now - 5:
                # held by no worker of ours (not even a just-started one)
                self.store.release("its worker disappeared", worker_pids=[job.worker_pid or -1])

    def _kill(self, proc) -> None:
        if proc is None:
            return
        self._killed.add(proc.pid)
        try:
            os.kill(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass

    def _shutdown(self) -> None:
        procs = [p for p in self._procs if p is not None]
        for p in procs:
            if p.is_alive():
                p.terminate()
        deadline = time.monotonic() + 3
        for p in procs:
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join(1)
        pids = [p.pid for p in procs]
        try:
            self.store.release("the service stopped", worker_pids=pids, count_attempt=False)
        except Exception:  # pragma: no cover
            log.exception("cannot re-queue the running jobs")
        for p in procs:
            try:
                p.close()
            except ValueError:  # pragma: no cover - still running
                pass
        with self._wlock:
            for w in self._wakers:
                if w is not None:
                    w.close()
            self._wakers = [None] * self.size
        self._procs = [None] * self.size
