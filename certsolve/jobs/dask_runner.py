"""The job service on a Dask cluster: the second runner of :class:`~.service.JobService`,
beside the local :class:`~.pool.WorkerPool`, chosen by ``settings.scheduler``.

The store stays the record of every job: jobs are submitted, claimed, cancelled and
finished there exactly as with the pool.  A dispatcher thread of the service claims a
queued job whenever a Dask worker thread is free (one job per thread; queued jobs wait in
the store, where a cancel or an owner's quota still applies) and submits it as one task,
:func:`run_on_dask`.  That task is the pool's own :func:`~.worker.run_job`, given a
:class:`DaskChannel` in place of the store, since the Dask workers need not see the
service's disk:

* **progress** goes to the service as a worker event (``Worker.log_event`` on the topic
  :data:`TOPIC`); the service's subscription hands it to the dispatcher, which writes it
  to the store (``JobStore.heartbeat``), so ``GET /v1/jobs/{id}`` shows it;
* **cancel**: the job's progress callback reads a Dask ``Event`` named after the job and
  its lease, which the dispatcher sets when the store holds a cancel request (or the job
  was taken away); the search stops between two rounds and its partial result is kept.
  A job still running ``cancel_grace`` seconds after the request (past its time limit by
  ``kill_grace``, or ``finish_grace`` after it said it is storing its result:
  :func:`.worker.overdue`) is ended in the store, its task cancelled and the worker running it
  restarted (by its nanny), as the pool kills its process;
* the **outcome** is the task's return value, which the dispatcher records with
  ``JobStore.finish`` under the job's lease (a job ended meanwhile is left as it is);
* a **lost worker**: the scheduler first runs the task again elsewhere (up to its
  ``distributed.scheduler.allowed-failures``); a task that still fails with its worker
  (``KilledWorker``, a lost connection, a cancelled future) releases its job in the store,
  which queues it again for another attempt or fails it with the reason once it has used
  ``max_attempts`` -- one job, never the others.

Nothing of the job's memory limit applies on Dask (``memory_mb``): a worker's memory is
bounded by its nanny (``--memory-limit``), which restarts a worker past it -- a lost worker
as above.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

from .settings import ServiceSettings
from .status import JobStatus
from .store import JobRow, JobStore
from .worker import overdue, run_job

__all__ = [
    "TOPIC",
    "DaskChannel",
    "DaskJobRunner",
    "check_scheduler",
    "run_on_dask",
    "stop_flag_name",
]

log = logging.getLogger("certsolve.jobs")

#: the topic of the progress events of jobs on Dask workers
TOPIC = "certsolve-job-progress"


def stop_flag_name(job_id: str, lease: str) -> str:
    """The Dask ``Event`` that tells the run of ``job_id`` under ``lease`` to stop."""
    return f"certsolve-stop-{job_id}-{lease}"


class DaskChannel:
    """What a job on a Dask worker writes to in place of the store (a
    :class:`~.worker.JobChannel`): progress as a worker event, the stop flag from a Dask
    ``Event``, the outcome kept for the task to return."""

    def __init__(self, job_id: str, lease: str):
        from distributed import Event, get_worker

        self.worker = get_worker()
        self.flag = Event(stop_flag_name(job_id, lease))
        self.outcome: dict[str, Any] | None = None

    def heartbeat(
        self, job_id: str, lease: str, progress: dict | None, *, stopping: bool = False
    ) -> tuple[bool, bool]:
        try:
            event = {"id": job_id, "lease": lease, "progress": progress, "stopping": stopping}
            self.worker.log_event(TOPIC, event)
            return True, bool(self.flag.is_set())
        except Exception as exc:  # noqa: BLE001 - the scheduler is away: carry on
            log.warning("progress of job %s not sent: %s", job_id, exc)
            return True, False

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
        self.outcome = {
            "status": str(status),
            "result": result,
            "error": error,
            "progress": progress,
        }
        return True


def run_on_dask(job: JobRow, lease: str, settings: ServiceSettings) -> dict[str, Any] | None:
    """The task of one job on a Dask worker: :func:`~.worker.run_job`; returns the outcome
    (``status``, ``result`` JSON text, ``error``, ``progress``) for the service to store."""
    channel = DaskChannel(job.id, lease)
    run_job(channel, job, lease, settings, limit_memory=False)
    return channel.outcome


@dataclass(kw_only=True)
class _Flight:
    """A job submitted to the cluster: its row, lease and future."""

    job: JobRow
    lease: str
    future: Any
    stopping: bool = False  # its stop flag is set
    abandoned: bool = False  # ended in the store by the dispatcher; its task cancelled


class DaskJobRunner:
    """Jobs of ``store`` run on the Dask cluster of ``settings.scheduler`` (see the module
    docstring); the same interface as :class:`~.pool.WorkerPool`.

    ``restarts`` counts the jobs whose Dask worker was lost (each released in the store).
    """

    def __init__(self, settings: ServiceSettings, store: JobStore, *, connect_timeout=30.0):
        if settings.scheduler is None:
            raise ValueError("DaskJobRunner needs settings.scheduler")
        self.settings = settings
        self.store = store
        self.address = settings.scheduler
        self.connect_timeout = float(connect_timeout)
        self.client: Any = None
        self.restarts = 0
        self.size = 0  # worker threads of the cluster (refreshed)
        self._workers = 0
        self._next_refresh = 0.0
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._flights: dict[str, _Flight] = {}  # by lease
        self._ended: deque[str] = deque(maxlen=1024)  # leases of the last jobs ended
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lost_types: tuple[type[BaseException], ...] = ()

    # -- control ------------------------------------------------------------------------------
    def start(self) -> None:
        """Connect to the scheduler (``OSError`` if it cannot be reached) and start the
        dispatcher thread."""
        from ..solver.dask_executor import import_distributed, lost_errors

        distributed = import_distributed()
        self._lost_types = lost_errors()
        self.client = distributed.Client(
            self.address, set_as_default=False, timeout=self.connect_timeout
        )
        self.client.subscribe_topic(TOPIC, self._on_event)
        self._refresh(force=True)
        self._thread = threading.Thread(target=self._run, name="certsolve-dask", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        """Stop dispatching; running jobs go back to the queue (no attempt used)."""
        self._stop.set()
        self._inbox.put(None)
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def notify(self) -> None:
        """New jobs were queued: wake the dispatcher."""
        self._inbox.put(None)

    def alive(self) -> int:
        """Dask workers connected to the scheduler (at the last refresh)."""
        return self._workers

    # -- the dispatcher -----------------------------------------------------------------------
    def _on_event(self, event) -> None:  # in the client's event loop: hand over, no I/O
        _, msg = event
        self._inbox.put(("progress", msg))

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                item = self._inbox.get(timeout=self.settings.supervise_interval)
                while True:
                    self._handle(item)
                    item = self._inbox.get_nowait()
            except queue.Empty:
                pass
            except Exception:  # never let the dispatcher die
                log.exception("handling a Dask job event failed")
            if self._stop.is_set():
                break
            try:
                self._supervise()
                self._fill()
            except Exception:
                log.exception("dispatching jobs to Dask failed")
        self._shutdown()

    def _handle(self, item) -> None:
        if item is None:  # a wake-up
            return
        what, data = item
        if what == "done":
            flight = self._flights.pop(data, None)
            if flight is not None:
                self._ended.append(data)
                self._finished(flight)
        elif what == "progress":
            job_id, lease = str(data.get("id")), str(data.get("lease"))
            owned, cancel = self.store.heartbeat(
                job_id, lease, data.get("progress"), stopping=bool(data.get("stopping"))
            )
            if not owned or cancel:
                flight = self._flights.get(lease)
                if flight is not None:
                    self._halt(flight)
                elif lease not in self._ended:  # a task of an earlier run: stop it too
                    self._set_flag(job_id, lease)

    def _refresh(self, *, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now < self._next_refresh:
            return
        self._next_refresh = now + 2.0
        nthreads = self.client.nthreads()
        self.size = sum(nthreads.values())
        self._workers = len(nthreads)

    def _fill(self) -> None:
        """Claim queued jobs while the cluster has free threads, submit each as a task."""
        self._refresh()
        settings = self.settings.for_workers
        while len(self._flights) < self.size and not self._stop.is_set():
            claimed = self.store.claim(None)
            if claimed is None:
                return
            job, lease = claimed
            fut = self.client.submit(
                run_on_dask, job, lease, settings, key=f"certsolve-job-{job.id}-{lease}"
            )
            self._flights[lease] = _Flight(job=job, lease=lease, future=fut)
            fut.add_done_callback(lambda _f, lease=lease: self._inbox.put(("done", lease)))

    def _finished(self, flight: _Flight) -> None:
        job, lease, fut = flight.job, flight.lease, flight.future
        if flight.stopping:
            self._clear_flag(job.id, lease)
        if flight.abandoned:
            return
        exc: BaseException | None = None
        if fut.status == "finished":
            try:
                out = fut.result() or {}
            except Exception as err:  # noqa: BLE001 - lost with its worker after all
                exc = err
        if fut.status == "finished" and exc is None:
            self.store.finish(
                job.id,
                lease,
                JobStatus(out.get("status", JobStatus.FAILED)),
                result=out.get("result"),
                error=out.get("error") or (None if out else "the Dask task returned nothing"),
                progress=out.get("progress"),
            )
            return
        if fut.status == "error":
            exc = fut.exception()
        if exc is None or isinstance(exc, self._lost_types):
            why = "the task was cancelled" if exc is None else f"{type(exc).__name__}: {exc}"
            self.restarts += 1
            released = self.store.release(f"its Dask worker was lost ({why})"[:500], leases=[lease])
            log.warning("job %s lost its Dask worker (%s): %s", job.id, why, released)
        else:
            self.store.finish(
                job.id,
                lease,
                JobStatus.FAILED,
                error=f"internal error on the Dask worker: {type(exc).__name__}: {exc}"[:1000],
            )

    def _supervise(self) -> None:
        """Cancel requests and time limits of the jobs in flight (the pool's rules)."""
        if not self._flights:
            return
        now = time.time()
        s = self.settings
        for job in self.store.running():
            flight = self._flights.get(job.lease or "")
            if flight is None:
                continue
            if job.cancel_requested_at is not None:
                self._halt(flight)
                if now - job.cancel_requested_at > s.cancel_grace:
                    self._abandon(
                        flight, JobStatus.CANCELLED, "cancelled (its Dask task was dropped)"
                    )
            elif (why := overdue(job, now, s)) is not None:
                self._abandon(flight, JobStatus.FAILED, f"{why}; its Dask task was dropped")

    def _halt(self, flight: _Flight) -> None:
        if not flight.stopping:
            flight.stopping = True
            self._set_flag(flight.job.id, flight.lease)

    def _abandon(self, flight: _Flight, status: JobStatus, error: str) -> None:
        """End the job in the store, cancel its task and restart the worker running it
        (as the pool kills its process): a thread cannot be stopped from outside."""
        if self.store.force_finish(flight.job.id, flight.lease, status, error):
            flight.abandoned = True
            self._halt(flight)
            key = flight.future.key
            where = [w for w, keys in self.client.processing().items() if key in keys]
            self.client.cancel([flight.future])
            if where:
                threading.Thread(
                    target=self._restart, args=(where,), name="certsolve-dask-restart", daemon=True
                ).start()

    def _restart(self, workers: list[str]) -> None:
        log.warning("restarting Dask worker(s) %s: a dropped job was still running", workers)
        try:
            self.client.restart_workers(workers, raise_for_error=False)
        except Exception as exc:  # noqa: BLE001 - no nanny, or the client is closing
            log.warning("cannot restart Dask worker(s) %s: %s", workers, exc)

    def _set_flag(self, job_id: str, lease: str) -> None:
        from distributed import Event

        try:
            Event(stop_flag_name(job_id, lease), client=self.client).set()
        except Exception as exc:  # noqa: BLE001 - the supervisor tries again
            log.warning("cannot tell job %s to stop: %s", job_id, exc)

    def _clear_flag(self, job_id: str, lease: str) -> None:
        from distributed import Event

        try:  # a cleared flag is forgotten by the scheduler
            Event(stop_flag_name(job_id, lease), client=self.client).clear()
        except Exception:  # noqa: BLE001
            pass

    def _shutdown(self) -> None:
        flights, self._flights = list(self._flights.values()), {}
        for flight in flights:  # stop the tasks, give their jobs back to the queue
            self._set_flag(flight.job.id, flight.lease)
        if flights:
            try:
                self.client.cancel([f.future for f in flights])
            except Exception:  # noqa: BLE001 - pragma: no cover
                log.exception("cannot cancel the Dask tasks")
            try:
                self.store.release(
                    "the service stopped",
                    leases=[f.lease for f in flights],
                    count_attempt=False,
                )
            except Exception:  # pragma: no cover
                log.exception("cannot re-queue the running jobs")
        try:
            self.client.unsubscribe_topic(TOPIC)
            self.client.close()
        except Exception:  # noqa: BLE001 - pragma: no cover
            pass
        self.client = None


def check_scheduler(address: str, timeout: float = 10.0) -> int:
    """Connect to the scheduler at ``address`` and count its workers; ``OSError`` (or
    ``TimeoutError``) when it cannot be reached."""
    from ..solver.dask_executor import import_distributed

    distributed = import_distributed()
    client = distributed.Client(address, set_as_default=False, timeout=timeout)
    try:
        return len(client.nthreads())
    finally:
        client.close()
