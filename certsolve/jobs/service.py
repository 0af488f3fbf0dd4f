"""The job service: validated requests in, job records out; owns the store and the runner
of its jobs -- local worker processes (:class:`~.pool.WorkerPool`), or the Dask cluster of
``settings.scheduler`` (:class:`~.dask_runner.DaskJobRunner`); both run the same
:func:`~.worker.run_job` and record everything in the store.

The store is checked before use: :meth:`JobService.check_store` (``certsolve serve`` calls
it at start) refuses a damaged file, and :meth:`JobService.health` reports a store that
fails its check (``PRAGMA quick_check``, re-run at most every ``store_check_interval``
seconds: it reads the whole file) or cannot be read, so ``/healthz`` is not ``ok`` while
job requests fail.

Used by the HTTP API (:mod:`certsolve.api`) and the offline batch runner.  One service owns
a data directory at a time (an exclusive ``flock`` on ``service.lock``); on start it
re-queues the jobs a previous run left ``running`` (or fails those out of attempts).

A batch (:class:`BatchRequest`) is either full job requests or one kind and input with a
list of params; :meth:`JobService.submit_batch` expands and validates it (every problem
reported at its index, ``jobs.1.system`` / ``params.3.u``) and queues all or nothing.

Every method that reads or changes jobs takes the calling :class:`~.access.Client` (None
when the service has no tokens): a client's jobs are its own -- another client's job is
reported as missing (:class:`NoSuchJob`) and left out of listings -- and an admin sees
them all.  Finished jobs older than ``keep_days`` are purged by a housekeeping thread
(:mod:`.retention`), which also truncates the store's write-ahead log.
"""

from __future__ import annotations

import logging
import os
import sqlite3
import time
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Protocol

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ..robot.schema import RobotSpec
from .access import Client
from .errors import summary, validation_details
from .kinds import KINDS, MAX_SYSTEM_CHARS, JobLimits, public_kinds, request_adapter
from .pool import WorkerPool
from .retention import Housekeeper
from .settings import ServiceSettings
from .status import JobStatus
from .store import JobRow, JobStore, NewJob, StoreError, new_job_id

__all__ = [
    "BatchError",
    "BatchRequest",
    "JobRunner",
    "JobService",
    "LimitError",
    "NoResult",
    "NoSuchJob",
    "NotAllowed",
    "ServiceError",
    "job_record",
    "iso_time",
    "make_runner",
    "owner_filter",
]

log = logging.getLogger("certsolve.jobs")


class ServiceError(Exception):
    """The service cannot start (data directory in use, not writable, ...)."""


@dataclass
class LimitError(ValueError):
    """A per-job limit above the service's ceiling; ``field`` is a dotted request path."""

    field: str
    message: str

    def __str__(self) -> str:
        return f"{self.field}: {self.message}"


class NoSuchJob(LookupError):
    """No job (or batch) with that id."""


class NoResult(Exception):
    """The job has no result (yet): queued, running, failed, or cancelled before it ran."""


class NotAllowed(Exception):
    """The calling client may not do this (an admin's operation)."""


@dataclass
class BatchError(ValueError):
    """A batch that cannot be queued; ``details`` are validation details (``loc`` relative
    to the batch), ``too_large`` when it has more jobs than the service takes at once."""

    message: str
    details: list[dict] | None = None
    too_large: bool = False

    def __str__(self) -> str:
        return self.message


_ONE_OF: list[Any] = [
    {
        "required": ["jobs"],
        "properties": {"jobs": {"type": "array"}},
        "not": {"anyOf": [{"required": [k]} for k in ("kind", "robot", "system", "params")]},
    },
    {
        "required": ["kind", "params"],
        "properties": {"kind": {"type": "string"}, "params": {"type": "array"}},
        "not": {"required": ["jobs"]},
    },
]


class BatchRequest(BaseModel):
    """Either ``jobs`` (full job requests) or one ``kind`` + input with a ``params`` list."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={"oneOf": _ONE_OF})
    jobs: list[dict[str, Any]] | None = Field(
        default=None, min_length=1, description="job requests, each as for POST /v1/jobs"
    )
    kind: str | None = Field(default=None, max_length=32, description="kind of every job")
    robot: RobotSpec | None = None
    system: str | None = Field(default=None, max_length=MAX_SYSTEM_CHARS)
    limits: JobLimits | None = None
    params: list[dict[str, Any]] | None = Field(
        default=None,
        min_length=1,
        description="one params object per job (with kind and robot/system)",
    )


def iso_time(t: float | None) -> str | None:
    if t is None:
        return None
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def job_record(row: JobRow, *, now: float | None = None) -> dict[str, Any]:
    """The public description of a job (without its result and request)."""
    now = time.time() if now is None else now
    elapsed = None
    if row.started_at is not None:
        end = row.finished_at if row.finished_at is not None else now
        elapsed = max(0.0, end - row.started_at)
    return {
        "id": row.id,
        "kind": row.kind,
        "status": row.status,
        "batch": row.batch,
        "created_at": iso_time(row.created_at),
        "started_at": iso_time(row.started_at),
        "finished_at": iso_time(row.finished_at),
        "elapsed": elapsed,
        "attempts": row.attempts,
        "max_attempts": row.max_attempts,
        "limits": row.limits,
        "progress": row.progress,
        "cancel_requested": row.cancel_requested_at is not None,
        "worker_pid": row.worker_pid if row.status is JobStatus.RUNNING else None,
        "error": row.error,
        "owner": row.owner,
    }


def owner_filter(client: Client | None) -> str | None:
    """The owner whose jobs ``client`` sees (None: every job)."""
    return None if client is None or client.admin else client.name


class JobRunner(Protocol):
    """Where the jobs of the store run: :class:`.WorkerPool` or :class:`.DaskJobRunner`."""

    restarts: int

    def start(self) -> None: ...
    def stop(self, timeout: float = 10.0) -> None: ...
    def notify(self) -> None: ...
    def alive(self) -> int: ...


def make_runner(settings: ServiceSettings, store: JobStore) -> JobRunner | None:
    """The runner ``settings`` ask for: the Dask cluster of ``scheduler``, else
    ``workers`` local processes (None for 0: jobs are accepted, none run)."""
    if settings.scheduler is not None:
        from .dask_runner import DaskJobRunner

        return DaskJobRunner(settings, store)
    if settings.workers > 0:
        return WorkerPool(settings, store)
    return None


class JobService:
    """Submit, inspect and cancel jobs; run them on a :class:`JobRunner`."""

    def __init__(self, settings: ServiceSettings):
        self.settings = settings
        try:
            settings.data_dir.mkdir(parents=True, exist_ok=True)
            self.store = JobStore(settings.db_path)
        except OSError as exc:
            raise ServiceError(
                f"{settings.data_dir}: cannot use as data directory ({exc})"
            ) from None
        except StoreError as exc:
            raise ServiceError(str(exc)) from None
        self._store_checked: tuple[float, str | None] | None = None  # (when, problem)
        self.adapter = request_adapter(settings.enable_test_kinds)
        self.pool: JobRunner | None = None
        self.housekeeper: Housekeeper | None = None
        self._lock_fd: int | None = None

    # -- life cycle ---------------------------------------------------------------------------
    def acquire(self) -> None:
        """Take the data directory (exclusive); :class:`ServiceError` if another has it."""
        if self._lock_fd is not None:
            return
        import fcntl

        path = self.settings.lock_path
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise ServiceError(
                f"{self.settings.data_dir} is in use by another certsolve service"
            ) from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._lock_fd = fd

    def check_store(self) -> None:
        """:class:`ServiceError` naming the store file if ``PRAGMA quick_check`` finds it
        damaged."""
        problem = self._store_problem(force=True)
        if problem is not None:
            raise ServiceError(
                f"{self.settings.db_path}: the job store is damaged ({problem}); restore it "
                "from a backup or move it away to start with an empty store"
            )

    def _store_problem(self, force: bool = False) -> str | None:
        """The store's quick check (the last answer if younger than
        ``store_check_interval``): None when sound."""
        now = time.monotonic()
        last = self._store_checked
        if force or last is None or now - last[0] >= self.settings.store_check_interval:
            last = self._store_checked = (now, self.store.check())
        return last[1]

    def start(self) -> None:
        """Take the data directory, recover interrupted jobs, start the runner (on a
        Dask cluster: ``OSError`` / ``TimeoutError`` if its scheduler cannot be reached)."""
        self.acquire()
        recovered = self.store.release("the service stopped while the job was running")
        if recovered:
            log.warning("recovered %d interrupted job(s): %s", len(recovered), recovered)
        access = self.settings.access
        self.store.set_owner_limits(
            {}
            if access is None
            else {c.name: c.max_running or self.settings.quota_running for c in access.clients}
        )
        if self.housekeeper is None:
            self.housekeeper = Housekeeper(self.store, self.settings)
            self.housekeeper.start()
        if self.pool is None:
            runner = make_runner(self.settings, self.store)
            if runner is not None:
                runner.start()
                self.pool = runner

    def close(self) -> None:
        if self.housekeeper is not None:
            self.housekeeper.stop()
            self.housekeeper = None
        if self.pool is not None:
            self.pool.stop()
            self.pool = None
        self.store.close()
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def __enter__(self) -> JobService:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- requests -----------------------------------------------------------------------------
    def validate(self, data: Any, memo: dict | None = None):
        """A request dict -> the kind's model (raises pydantic ``ValidationError``);
        ``memo`` keeps the answers of costly checks across the requests of one batch."""
        return self.adapter.validate_python(data, context={"memo": memo})

    def limits_for(self, req) -> dict[str, Any]:
        """Effective limits of a validated request; :class:`LimitError` above a ceiling."""
        s = self.settings
        params = getattr(req, "params", None)
        lim = req.limits or JobLimits()

        def pick(name: str, default, ceiling, unit: str):
            asked = [
                (f"params.{name}", getattr(params, name, None)),
                (f"limits.{name}", getattr(lim, name, None)),
            ]
            for field, v in asked:
                if v is not None and v > ceiling:
                    shown = f"{ceiling:g}" if isinstance(ceiling, float) else str(ceiling)
                    raise LimitError(field, f"at most {shown}{unit} on this server")
            vals = [v for _, v in asked if v is not None]
            return min(vals) if vals else default

        limits = {
            "timeout": float(pick("timeout", s.default_timeout, s.max_timeout, " s")),
            "max_boxes": int(pick("max_boxes", s.default_max_boxes, s.max_max_boxes, "")),
            "memory_mb": int(pick("memory_mb", s.default_memory_mb, s.max_memory_mb, " MiB")),
        }
        if limits["memory_mb"] < s.min_memory_mb:
            raise LimitError("limits.memory_mb", f"at least {s.min_memory_mb} MiB")
        return limits

    def prepare(self, req, *, batch: str | None = None, owner: str | None = None) -> NewJob:
        return NewJob(
            kind=req.kind,
            request=req.model_dump_json(),
            limits=self.limits_for(req),
            max_attempts=self.settings.max_attempts,
            batch=batch,
            owner=owner,
        )

    def submit(
        self,
        reqs: list,
        *,
        batch: str | None = None,
        max_queued: bool = True,
        client: Client | None = None,
    ) -> list[str]:
        """Queue validated requests (all or none) owned by ``client``; returns their ids.
        :class:`~.store.QueueFull` past the service's queue or the client's quota."""
        owner = None if client is None else client.name
        jobs = [self.prepare(r, batch=batch, owner=owner) for r in reqs]
        quota = None
        if client is not None:
            quota = self.settings.quota_queued if client.max_queued is None else client.max_queued
        ids = self.store.add(
            jobs,
            max_queued=self.settings.max_queued if max_queued else None,
            owner_max_queued=quota,
        )
        if self.pool is not None:
            self.pool.notify()
        return ids

    @staticmethod
    def new_batch_id() -> str:
        return "b" + new_job_id()[:15]

    def expand_batch(self, batch: BatchRequest) -> list:
        """The validated job requests of a batch; :class:`BatchError` naming each problem."""
        shared = batch.kind is not None or batch.robot is not None or batch.system is not None
        if batch.jobs is not None and (shared or batch.params is not None):
            raise BatchError("give either jobs, or kind + robot/system + params (a list)")
        if batch.jobs is None and (batch.kind is None or batch.params is None):
            raise BatchError("give jobs (a list), or kind + robot/system + params (a list)")
        items = batch.jobs if batch.jobs is not None else batch.params
        assert items is not None
        kinds = public_kinds(self.settings.enable_test_kinds)
        if batch.jobs is None and batch.kind not in kinds:
            msg = f"must be one of {', '.join(repr(k) for k in kinds)}"
            problem = {"loc": ("kind",), "msg": msg, "type": "enum"}
            raise BatchError(f"kind: {msg}", validation_details([problem]))
        most = self.settings.max_batch
        if len(items) > most:
            raise BatchError(f"{len(items)} jobs in one batch; at most {most}", too_large=True)
        reqs, details = [], []
        memo: dict = {}  # one robot, many params: its costly checks run once
        for i, item in enumerate(items):
            prefix: tuple = ()
            if batch.jobs is not None:
                data, prefix = item, ("jobs", i)
            else:
                data = {"kind": batch.kind, "params": item}
                if batch.robot is not None:
                    data["robot"] = batch.robot.model_dump()
                if batch.system is not None:
                    data["system"] = batch.system
                if batch.limits is not None:
                    data["limits"] = batch.limits.model_dump()
            try:
                req = self.validate(data, memo)
                self.limits_for(req)
                reqs.append(req)
            except ValidationError as exc:
                errs: list[Mapping[str, Any]] = list(exc.errors())
                if batch.jobs is None:  # params errors belong to params[i]
                    errs = [_sweep_item(e, i) for e in errs]
                details.extend(validation_details(errs, prefix))
            except LimitError as exc:
                loc = (*prefix, *exc.field.split("."))
                details.extend(
                    validation_details([{"loc": loc, "msg": exc.message, "type": "limit"}])
                )
            if len(details) >= 50:
                break
        if details:
            seen, unique = set(), []
            for d in details:
                key = (d["field"], d["msg"])
                if key not in seen:
                    seen.add(key)
                    unique.append(d)
            raise BatchError(summary(unique), unique)
        return reqs

    def submit_batch(
        self, batch: BatchRequest, *, client: Client | None = None
    ) -> tuple[str, list[str]]:
        """Expand, validate and queue a batch (all or none): ``(batch id, job ids)``."""
        reqs = self.expand_batch(batch)
        batch_id = self.new_batch_id()
        return batch_id, self.submit(reqs, batch=batch_id, client=client)

    # -- reading and cancelling (a client's own jobs; an admin's: all) ------------------------
    def job(self, job_id: str, client: Client | None = None, *, result: bool = True) -> JobRow:
        """The job (with its result text); :class:`NoSuchJob` if ``client`` may not see it."""
        row = self.store.get(job_id, result=result)
        owner = owner_filter(client)
        if row is None or (owner is not None and row.owner != owner):
            raise NoSuchJob(f"no job {job_id}")
        return row

    def jobs(self, client: Client | None = None, **filters: Any) -> tuple[list[JobRow], Any]:
        """One page of the jobs ``client`` sees (filters and paging of
        :meth:`.JobStore.list`)."""
        return self.store.list(owner=owner_filter(client), **filters)

    def cancel(self, job_id: str, client: Client | None = None) -> JobRow:
        """Cancel a queued job at once, ask a running one to stop; :class:`NoSuchJob`."""
        self.job(job_id, client, result=False)
        row = self.store.request_cancel(job_id)
        if row is None:
            raise NoSuchJob(f"no job {job_id}")
        return row

    def result_text(self, job_id: str, client: Client | None = None) -> tuple[JobStatus, str]:
        """The job's status and stored result (JSON text) -- the partial result of a job
        stopped by a limit or a cancel too; :class:`NoSuchJob`, or :class:`NoResult` saying
        why there is none."""
        row = self.job(job_id, client, result=True)
        if row.result is None:
            why = f": {row.error}" if row.error else ""
            raise NoResult(f"job {job_id} is {row.status} and has no result{why}")
        return row.status, row.result

    def purge(self, older_than_days: float, client: Client | None = None) -> dict[str, Any]:
        """Delete the finished jobs older than ``older_than_days`` (admins only, or anyone
        when the service has no tokens); :class:`NotAllowed` otherwise."""
        if client is not None and not client.admin:
            raise NotAllowed("purging jobs needs an admin token")
        cutoff = time.time() - float(older_than_days) * 86400.0
        deleted = self.store.purge(cutoff)
        return {"deleted": deleted, "older_than_days": older_than_days, **self.store.file_sizes()}

    def batch_status(self, batch_id: str, client: Client | None = None) -> dict[str, Any]:
        """How many jobs of a batch are in each status; :class:`NoSuchJob` if none."""
        counts = self.store.counts(batch=batch_id, owner=owner_filter(client))
        total = sum(counts.values())
        if total == 0:
            raise NoSuchJob(f"no batch {batch_id}")
        finished = all(n == 0 for status, n in counts.items() if not status.final)
        return {"batch": batch_id, "total": total, "counts": counts, "finished": finished}

    def health(self) -> dict[str, Any]:
        """What ``/healthz`` shows: ``status`` is ``ok``, or ``failing`` when the store
        fails its check or cannot be read (``store.error`` says why)."""
        try:
            problem = self._store_problem()
            counts = self.store.counts()
        except sqlite3.Error as exc:
            problem, counts = str(exc), None
        scheduler = self.settings.scheduler
        return {
            "status": "ok" if problem is None else "failing",
            "store": {"ok": problem is None, "error": problem},
            "workers": {
                "runner": "processes" if scheduler is None else "dask",
                "scheduler": scheduler,
                "configured": self.settings.workers if scheduler is None else None,
                "alive": self.pool.alive() if self.pool else 0,
                "restarts": self.pool.restarts if self.pool else 0,
            },
            "jobs": {
                "queued": None if counts is None else counts[JobStatus.QUEUED],
                "running": None if counts is None else counts[JobStatus.RUNNING],
            },
            "kinds": [k for k in KINDS if self.settings.enable_test_kinds or not KINDS[k].hidden],
        }


def _sweep_item(e: Mapping[str, Any], i: int) -> Mapping[str, Any]:
    """An error of the i-th job of a sweep batch, placed at ``params[i]``."""
    loc = tuple(e.get("loc", ()))
    if loc[1:2] == ("params",):
        return {**e, "loc": ("params", i, *loc[2:])}
    msg = str(e.get("msg", ""))
    if len(loc) <= 1 and msg.startswith("Value error, params."):
        return {**e, "msg": msg.replace("params.", f"params[{i}].", 1)}
    return e
