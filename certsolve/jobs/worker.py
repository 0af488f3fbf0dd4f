"""A worker process: claim a queued job from the store, run it, store the outcome, repeat.

Workers are started (``spawn``) and supervised by :class:`~.pool.WorkerPool`.  While a job
runs, the library's progress callback writes the progress to the store at most every
``progress_interval`` seconds and reads the job's cancel flag at the same time: a cancelled
job's callback returns ``False`` and the search stops between two rounds.  Each job runs
under ``RLIMIT_AS`` (its ``memory_mb``).  The callback also watches the process's address
space: past ``memory_stop`` of the limit it stops the search the same way, so that a job
short of memory ends ``done`` with its partial result (``stopped_by: "memory"``) instead of
failing; only an allocation that jumps over the margin still fails the job (and the worker
exits so that the supervisor starts a fresh one).

A job's search saves itself in the store every ``checkpoint_interval`` seconds
(:func:`job_checkpoint`); when the job runs again after its worker died, it resumes from
the last save with a fresh time limit and box budget.

Whatever stopped the search (its time or box limit, memory, a cancel), the result is
bounded before it is stored (:func:`.partial.stored_result`), with the memory limit lifted
again.  Stopping a large search -- its last checkpoint, the result built and written --
can take longer than ``kill_grace`` on a loaded machine (a search of 1.8M pending boxes
once did), so the worker says when it is at that stage: a heartbeat with ``stopping``
(:meth:`.JobStore.heartbeat`) when its time limit has passed, and again when the library
call has returned.  :func:`overdue` then gives the job ``finish_grace`` from that moment
instead of ``kill_grace`` past its limit: a limit ends in a stored partial result, not a
killed worker.  A job that never reports progress (a call that ignores its limits) is
still killed ``kill_grace`` past its limit.

A worker dies with its parent (``PR_SET_PDEATHSIG``, and a ``getppid`` check in case that
is unavailable), so a killed service never leaves workers writing to the store.

:func:`run_job` writes only through two methods of the store, ``heartbeat`` and ``finish``
(:class:`JobChannel`): a Dask worker runs the very same function with a channel that
relays them to the service (:mod:`.dask_runner`), and without the memory limit (a Dask
worker's memory is the nanny's business).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import signal
import sqlite3
import sys
import time
from typing import Any, Protocol

from .jsonutil import dumps
from .partial import stored_result
from .settings import ServiceSettings
from .status import JobStatus
from .store import JobRow, JobStore

__all__ = [
    "JobChannel",
    "JobMonitor",
    "die_with_parent",
    "overdue",
    "restore_memory_limit",
    "run_job",
    "set_memory_limit",
    "worker_main",
]

log = logging.getLogger("certsolve.jobs.worker")

EXIT_FRESH = 3  # the worker exits after a memory error; the supervisor starts a new one

_PROGRESS_FIELDS = ("boxes", "pending", "solutions", "undecided", "elapsed")


class JobChannel(Protocol):
    """What a running job writes to: the store (:class:`.JobStore`), or a relay to it."""

    def heartbeat(
        self, job_id: str, lease: str, progress: dict | None, *, stopping: bool = False
    ) -> tuple[bool, bool]:
        """Record progress (``stopping``: the search has stopped or reached its time limit,
        the result is being stored); ``(still ours, cancel requested)``."""
        ...

    def finish(
        self,
        job_id: str,
        lease: str,
        status: JobStatus,
        *,
        result: str | None = None,
        error: str | None = None,
        progress: dict | None = None,
    ) -> bool:
        """Record the outcome; False if the job is no longer ours."""
        ...


def overdue(job: JobRow, now: float, settings: ServiceSettings) -> str | None:
    """Why the supervisor must stop this running job now, past its time limit, or None.

    Killed ``kill_grace`` seconds past the limit, unless the worker said it is storing its
    result (``stopping_at``): then ``finish_grace`` seconds from that moment."""
    if job.started_at is None:
        return None
    limit = float(job.limits.get("timeout", settings.default_timeout))
    if now - job.started_at <= limit + settings.kill_grace:
        return None
    if job.stopping_at is None:
        return f"time limit exceeded ({limit:g} s)"
    if now - job.stopping_at <= settings.finish_grace:
        return None
    return (
        f"time limit exceeded ({limit:g} s): its result was not stored "
        f"{settings.finish_grace:g} s after its search stopped"
    )


def die_with_parent(parent_pid: int) -> None:
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
    except Exception:  # pragma: no cover - not Linux
        pass
    if os.getppid() != parent_pid:
        os._exit(0)


def set_memory_limit(mb: int | None):
    """Lower the soft address-space limit to ``mb`` MiB; return the previous limits."""
    try:
        import resource

        old = resource.getrlimit(resource.RLIMIT_AS)
        if mb is None:
            return old
        want = int(mb) * 2**20
        soft, hard = old
        if hard != resource.RLIM_INFINITY:
            want = min(want, hard)
        resource.setrlimit(resource.RLIMIT_AS, (want, hard))
        return old
    except (ImportError, ValueError, OSError):  # pragma: no cover
        return None


def restore_memory_limit(old) -> None:
    if old is None:
        return
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, old)
    except (ImportError, ValueError, OSError):  # pragma: no cover
        pass


def progress_dict(p: Any, elapsed: float) -> dict:
    """The numeric progress fields of a library progress object (or dict).

    ``boxes``, ``pending``, ``solutions``, ``undecided``, ``elapsed`` when present, the
    other numeric fields of a dataclass, and the items of its ``extra`` dict (the search
    driver's progress: e.g. the workspace's ``inside`` / ``outside`` / ``inside_share``).
    """
    names = list(_PROGRESS_FIELDS)
    extra = {} if isinstance(p, dict) else dict(getattr(p, "extra", None) or {})
    if dataclasses.is_dataclass(p):
        names += [f.name for f in dataclasses.fields(p) if f.name not in names][:12]
    names += [k for k in list(extra)[:12] if k not in names]
    out: dict[str, Any] = {}
    for name in names:
        if name in extra:
            v = extra[name]
        else:
            v = p.get(name) if isinstance(p, dict) else getattr(p, name, None)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            item = getattr(v, "item", None)  # numpy scalars
            if item is None:
                continue
            v = item()
        if isinstance(v, (int, float)) and v == v and abs(v) < 1e300:
            out[name] = v
    out.setdefault("elapsed", elapsed)
    return out


class AddressSpace:
    """The address space of this process (what ``RLIMIT_AS`` limits), in bytes: the first
    field of ``/proc/self/statm`` (pages), read through a descriptor kept open."""

    def __init__(self):
        self._page = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
        try:
            self._fd: int | None = os.open("/proc/self/statm", os.O_RDONLY)
        except OSError:  # pragma: no cover - not Linux
            self._fd = None

    def __call__(self) -> int | None:
        if self._fd is None:
            return None
        try:
            return int(os.pread(self._fd, 64, 0).split()[0]) * self._page
        except (OSError, ValueError, IndexError):  # pragma: no cover
            return None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


class JobMonitor:
    """The progress callback of one running job (see the module docstring).

    ``stopped_by`` says why the callback stopped the search when the job itself set the
    limit: ``max_boxes`` (kinds whose library call has no box limit) or ``memory`` (the
    address space passed ``memory_stop_bytes``)."""

    def __init__(
        self,
        store: JobChannel,
        job: JobRow,
        lease: str,
        *,
        interval: float,
        parent_pid: int | None,
        max_boxes: int | None = None,
        memory_stop_bytes: int | None = None,
        time_limit: float | None = None,
    ):
        self.store = store
        self.job = job
        self.lease = lease
        self.interval = interval
        self.parent_pid = parent_pid
        self.max_boxes = max_boxes  # enforced here for kinds whose call has no such limit
        self.memory_stop_bytes = memory_stop_bytes
        self.time_limit = time_limit
        self.stopping = False  # said to the store: the search stops, the result follows
        self.address_space = AddressSpace()
        self.t0 = time.monotonic()
        self.next_tick = self.t0
        self.last: dict | None = None
        self.cancelled = False
        self.lost = False  # the job was taken away (re-queued, cancelled by the supervisor)
        self.stopped_by: str | None = None

    def __call__(self, p: Any) -> bool:
        now = time.monotonic()
        self.last = progress_dict(p, now - self.t0)
        if self.cancelled or self.lost:
            return False
        if self.max_boxes is not None and self.last.get("boxes", 0) >= self.max_boxes:
            self.stopped_by = "max_boxes"
            return False
        if self.memory_stop_bytes is not None:
            used = self.address_space()
            if used is not None and used >= self.memory_stop_bytes:
                self.stopped_by = "memory"
                return False
        if now < self.next_tick and (
            self.stopping or self.time_limit is None or now - self.t0 < self.time_limit
        ):
            return True
        self.next_tick = now + self.interval
        return self.check()

    def check(self) -> bool:
        """Write the progress, read the cancel flag; False if the job must stop.  Past the
        time limit, the heartbeat says the job is stopping (the search stops at its limit,
        on its own clock: this one started earlier, with the job)."""
        if self.parent_pid is not None and os.getppid() != self.parent_pid:
            os._exit(0)
        past = self.time_limit is not None and time.monotonic() - self.t0 >= self.time_limit
        stopping = self.stopping or past
        try:
            owned, cancel = self.store.heartbeat(
                self.job.id, self.lease, self.last, stopping=stopping
            )
        except sqlite3.Error as exc:  # a busy store must not kill the job
            log.warning("progress of job %s not recorded: %s", self.job.id, exc)
            return True
        self.stopping = stopping
        if not owned:
            self.lost = True
            return False
        if cancel:
            self.cancelled = True
            return False
        return True

    def stop(self) -> None:
        """The library call has returned: say that the result is being stored (once; a
        cancel requested from now on no longer changes the outcome)."""
        if self.stopping or self.cancelled or self.lost:
            return
        try:
            self.store.heartbeat(self.job.id, self.lease, self.last, stopping=True)
            self.stopping = True
        except sqlite3.Error as exc:
            log.warning("job %s: its stop not recorded: %s", self.job.id, exc)


def job_checkpoint(store: JobStore, job: JobRow, lease: str, interval: float):
    """The :class:`~certsolve.solver.checkpoint.Checkpoint` of a job's search: saved in the
    store under the job's lease every ``interval`` seconds, resumed from when the job runs
    again after its worker died.  A snapshot that does not fit is ignored (the search starts
    afresh); a store too busy to take one is logged, and the search goes on."""
    from ..solver.checkpoint import Checkpoint

    def save(data: bytes) -> None:
        try:
            store.save_search_checkpoint(job.id, lease, data)
        except sqlite3.Error as exc:
            log.warning("checkpoint of job %s not saved: %s", job.id, exc)

    def load() -> bytes | None:
        return store.search_checkpoint(job.id)

    return Checkpoint(save, load, interval=interval, key=f"job {job.kind}", strict=False)


def run_job(
    store: JobChannel,
    job: JobRow,
    lease: str,
    settings: ServiceSettings,
    *,
    parent_pid: int | None = None,
    limit_memory: bool = True,
) -> bool:
    """Run one claimed job and record its outcome; True if the worker should exit after.

    ``limit_memory=False``: no ``RLIMIT_AS`` and no memory stop (a Dask worker)."""
    from pydantic import ValidationError

    from .kinds import KINDS, KindUnavailable, RunContext, request_adapter

    limits = job.limits
    exit_after = False
    memory_mb = limits.get("memory_mb") if limit_memory else None
    stop_at = None if memory_mb is None else int(settings.memory_stop * memory_mb * 2**20)
    monitor = JobMonitor(
        store,
        job,
        lease,
        interval=settings.progress_interval,
        parent_pid=parent_pid,
        memory_stop_bytes=stop_at,
        time_limit=float(limits["timeout"]),
    )
    status, text, error = JobStatus.FAILED, None, None
    old_limit = None
    try:
        # the service validated the request before storing it: parse it, do not check again
        req = request_adapter(True).validate_json(job.request or "", context={"trusted": True})
        kind = KINDS[req.kind]
        kind.load()  # KindUnavailable when this build lacks its library function
        if not kind.has_max_boxes:
            monitor.max_boxes = limits.get("max_boxes")
        ctx = RunContext(
            time_limit=float(limits["timeout"]),
            max_boxes=int(limits["max_boxes"]),
            progress=monitor,
            # a job on a Dask worker has no store to save into: not checkpointed there
            checkpoint=job_checkpoint(store, job, lease, settings.checkpoint_interval)
            if isinstance(store, JobStore)
            else None,
        )
        old_limit = set_memory_limit(memory_mb)
        try:
            raw = kind.run(req.params, kind.input_of(req), ctx)
        finally:
            restore_memory_limit(old_limit)
            old_limit = None
        monitor.stop()
        result = stored_result(raw, settings.max_result_items)
        if monitor.stopped_by and isinstance(result, dict):
            result["stopped_by"] = monitor.stopped_by  # the library only saw a callback's no
        text = dumps(result)
        if monitor.cancelled:
            status, error = JobStatus.CANCELLED, "cancelled while running (partial result)"
        else:
            status = JobStatus.DONE
    except KindUnavailable as exc:
        error = str(exc)
    except MemoryError:
        restore_memory_limit(old_limit)
        error = f"memory limit exceeded ({memory_mb} MiB)"
        exit_after = True
    except ValidationError as exc:
        from .errors import describe_validation_error

        error = "invalid job: " + describe_validation_error(exc)
    except (ValueError, ArithmeticError) as exc:  # the input's fault (user errors)
        error = str(exc) or type(exc).__name__
    except Exception as exc:
        log.exception("job %s (%s) failed", job.id, job.kind)
        error = f"internal error: {type(exc).__name__}: {exc}"[:1000]
    monitor.address_space.close()
    if monitor.lost:
        return exit_after
    if monitor.cancelled and status is not JobStatus.CANCELLED:
        status, error = JobStatus.CANCELLED, error or "cancelled while running"
    if monitor.stopped_by and monitor.last is not None:
        monitor.last["stopped_by"] = monitor.stopped_by
    try:
        store.finish(job.id, lease, status, result=text, error=error, progress=monitor.last)
    except sqlite3.Error:
        log.exception("cannot record the outcome of job %s", job.id)
        exit_after = True
    return exit_after


def _nap(wake, seconds: float) -> None:
    """Sleep until woken through the pipe (new jobs) or ``seconds`` pass; drain the pipe."""
    try:
        if wake.poll(seconds) and os.read(wake.fileno(), 4096) == b"":
            time.sleep(seconds)  # the service closed its end: it is going away
    except (EOFError, OSError):
        time.sleep(seconds)


def worker_main(db_path: str, settings: ServiceSettings, parent_pid: int, wake) -> None:
    """Entry point of a worker process (see the module docstring).

    ``wake`` is the read end of a pipe on which the service writes when jobs are queued.
    """
    die_with_parent(parent_pid)
    os.set_blocking(wake.fileno(), False)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business
    logging.basicConfig(
        level=logging.WARNING,
        stream=sys.stderr,
        format=f"certsolve worker {os.getpid()}: %(levelname)s %(message)s",
    )
    store = JobStore(db_path)
    pid = os.getpid()
    while True:
        if os.getppid() != parent_pid:
            os._exit(0)
        try:
            claimed = store.claim(pid)
        except sqlite3.Error as exc:
            log.warning("cannot claim a job: %s", exc)
            claimed = None
        if claimed is None:
            _nap(wake, settings.poll_interval)
            continue
        job, lease = claimed
        if run_job(store, job, lease, settings, parent_pid=parent_pid):
            store.close()
            os._exit(EXIT_FRESH)
