"""The job store: jobs, their progress and results in one SQLite file (WAL mode).

Every process (the HTTP service, each worker, the batch runner) opens its own connections;
SQLite's locking makes the state transitions atomic:

* ``queued -> running`` (:meth:`JobStore.claim`): one worker takes the oldest queued job and
  gets a random *lease*; every later write of that worker names the lease, so a worker that
  lost its job (killed, re-queued, cancelled) cannot overwrite what happened since;
* ``running -> done | failed | cancelled`` (:meth:`JobStore.finish`);
* ``running -> queued`` when the worker died (:meth:`JobStore.release`), until the job has
  used its ``max_attempts``: it then fails with the reason;
* ``queued -> cancelled`` at once, ``running`` jobs get a cancel request that the worker
  reads with its progress heartbeat (:meth:`JobStore.heartbeat`).

Nothing here imports numpy or the solver.
"""

from __future__ import annotations

import builtins
import json
import os
import secrets
import sqlite3
import threading
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .status import FINAL_STATUSES, STATUSES, JobStatus

__all__ = [
    "FINAL_STATUSES",
    "JobRow",
    "JobStore",
    "NewJob",
    "QueueFull",
    "STATUSES",
    "new_job_id",
]

_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS jobs (
    seq                 INTEGER PRIMARY KEY AUTOINCREMENT,
    id                  TEXT NOT NULL UNIQUE,
    kind                TEXT NOT NULL,
    status              TEXT NOT NULL,
    request             TEXT NOT NULL,
    limits              TEXT NOT NULL,
    batch               TEXT,
    created_at          REAL NOT NULL,
    started_at          REAL,
    finished_at         REAL,
    attempts            INTEGER NOT NULL DEFAULT 0,
    max_attempts        INTEGER NOT NULL,
    worker_pid          INTEGER,
    lease               TEXT,
    progress            TEXT,
    heartbeat_at        REAL,
    cancel_requested_at REAL,
    result              TEXT,
    error               TEXT,
    fseq                INTEGER
);
CREATE INDEX IF NOT EXISTS jobs_status ON jobs(status, seq);
CREATE INDEX IF NOT EXISTS jobs_batch ON jobs(batch, seq);
CREATE INDEX IF NOT EXISTS jobs_fseq ON jobs(fseq);
CREATE INDEX IF NOT EXISTS jobs_worker ON jobs(worker_pid) WHERE status = '{JobStatus.RUNNING}';
"""

_SUMMARY_COLS = (
    "seq, id, kind, status, limits, batch, created_at, started_at, finished_at, attempts, "
    "max_attempts, worker_pid, lease, progress, heartbeat_at, cancel_requested_at, error, fseq"
)
# order of reaching a final status: write transactions are serialised, so a reader that has
# seen fseq = n will see every later final job with fseq > n
_NEXT_FSEQ = "(SELECT coalesce(max(fseq), 0) + 1 FROM jobs)"


class QueueFull(Exception):
    """Too many queued jobs: the store refuses new ones."""


def new_job_id() -> str:
    return secrets.token_hex(12)


@dataclass
class NewJob:
    kind: str
    request: str  # JSON text of the validated request
    limits: dict
    max_attempts: int
    batch: str | None = None
    id: str = ""

    def __post_init__(self):
        if not self.id:
            self.id = new_job_id()


@dataclass
class JobRow:
    seq: int
    id: str
    kind: str
    status: JobStatus
    limits: dict
    batch: str | None
    created_at: float
    started_at: float | None
    finished_at: float | None
    attempts: int
    max_attempts: int
    worker_pid: int | None
    lease: str | None
    progress: dict | None
    heartbeat_at: float | None
    cancel_requested_at: float | None
    error: str | None
    fseq: int | None = None
    request: str | None = None  # JSON text (only when asked for)
    result: str | None = None  # JSON text (only when asked for)

    @property
    def final(self) -> bool:
        return self.status.final

    @classmethod
    def _from(cls, row: sqlite3.Row) -> JobRow:
        keys = row.keys()
        d = {k: row[k] for k in keys}
        d["status"] = JobStatus(d["status"])
        d["limits"] = json.loads(d["limits"])
        d["progress"] = json.loads(d["progress"]) if d["progress"] else None
        return cls(**d)


class JobStore:
    """Jobs in ``path`` (created if missing).  Thread-safe: one connection per thread."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._local = threading.local()
        self._all: list[sqlite3.Connection] = []
        self._lock = threading.Lock()
        con = self._conn()
        mode = con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        if str(mode).lower() != "wal":  # pragma: no cover - e.g. a network file system
            raise RuntimeError(f"{self.path}: cannot use SQLite WAL mode (got {mode})")
        for stmt in _SCHEMA.strip().split(";"):
            if stmt.strip():
                con.execute(stmt)
        con.execute("PRAGMA user_version = 1")

    # -- connections ----------------------------------------------------------------------------
    def _conn(self) -> sqlite3.Connection:
        con = getattr(self._local, "con", None)
        if con is None:
            con = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
            con.row_factory = sqlite3.Row
            con.execute("PRAGMA busy_timeout = 30000")
            con.execute("PRAGMA synchronous = NORMAL")
            self._local.con = con
            with self._lock:
                self._all.append(con)
        return con

    def close(self) -> None:
        """Close every connection this object opened (all threads)."""
        with self._lock:
            cons, self._all = self._all, []
        for con in cons:
            try:
                con.close()
            except sqlite3.Error:  # pragma: no cover
                pass
        self._local = threading.local()

    @contextmanager
    def _tx(self) -> Iterator[sqlite3.Connection]:
        """A write transaction (``BEGIN IMMEDIATE``: takes the write lock at once)."""
        con = self._conn()
        con.execute("BEGIN IMMEDIATE")
        try:
            yield con
        except BaseException:
            con.execute("ROLLBACK")
            raise
        else:
            con.execute("COMMIT")

    def journal_mode(self) -> str:
        return str(self._conn().execute("PRAGMA journal_mode").fetchone()[0]).lower()

    # -- submitting -----------------------------------------------------------------------------
    def add(self, jobs: Iterable[NewJob], *, max_queued: int | None = None) -> builtins.list[str]:
        """Queue jobs atomically (all or none); :class:`QueueFull` beyond ``max_queued``."""
        jobs = list(jobs)
        now = time.time()
        with self._tx() as con:
            if max_queued is not None:
                (n,) = con.execute(
                    "SELECT count(*) FROM jobs WHERE status = ?", (JobStatus.QUEUED,)
                ).fetchone()
                if n + len(jobs) > max_queued:
                    raise QueueFull(
                        f"the queue holds {n} jobs; at most {max_queued} may wait, try later"
                    )
            con.executemany(
                "INSERT INTO jobs (id, kind, status, request, limits, batch, created_at, "
                "max_attempts) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [
                    (
                        j.id,
                        j.kind,
                        JobStatus.QUEUED,
                        j.request,
                        json.dumps(j.limits),
                        j.batch,
                        now,
                        j.max_attempts,
                    )
                    for j in jobs
                ],
            )
        return [j.id for j in jobs]

    # -- reading --------------------------------------------------------------------------------
    def get(self, job_id: str, *, result: bool = True, request: bool = False) -> JobRow | None:
        cols = _SUMMARY_COLS + (", result" if result else "") + (", request" if request else "")
        row = self._conn().execute(f"SELECT {cols} FROM jobs WHERE id = ?", (job_id,)).fetchone()
        return JobRow._from(row) if row else None

    def result_text(self, job_id: str) -> tuple[JobStatus, str | None] | None:
        """``(status, result JSON text)`` of a job, or None if there is no such job."""
        row = (
            self._conn()
            .execute("SELECT status, result FROM jobs WHERE id = ?", (job_id,))
            .fetchone()
        )
        return (JobStatus(row[0]), row[1]) if row else None

    def list(
        self,
        *,
        status: JobStatus | None = None,
        kind: str | None = None,
        batch: str | None = None,
        limit: int = 50,
        cursor: int | None = None,
        oldest_first: bool = False,
    ) -> tuple[builtins.list[JobRow], int | None]:
        """One page of jobs (newest first unless ``oldest_first``) and the next cursor."""
        where: builtins.list[str] = []
        args: builtins.list[Any] = []
        for col, val in (("status", status), ("kind", kind), ("batch", batch)):
            if val is not None:
                where.append(f"{col} = ?")
                args.append(val)
        if cursor is not None:
            where.append("seq > ?" if oldest_first else "seq < ?")
            args.append(int(cursor))
        sql = f"SELECT {_SUMMARY_COLS} FROM jobs"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += f" ORDER BY seq {'ASC' if oldest_first else 'DESC'} LIMIT ?"
        args.append(int(limit) + 1)
        rows = [JobRow._from(r) for r in self._conn().execute(sql, args).fetchall()]
        more = len(rows) > limit
        rows = rows[:limit]
        return rows, (rows[-1].seq if more and rows else None)

    def counts(self, *, batch: str | None = None) -> dict[JobStatus, int]:
        sql = "SELECT status, count(*) FROM jobs"
        args: tuple = ()
        if batch is not None:
            sql += " WHERE batch = ?"
            args = (batch,)
        out = dict.fromkeys(STATUSES, 0)
        for status, n in self._conn().execute(sql + " GROUP BY status", args):
            out[JobStatus(status)] = n
        return out

    def running(self) -> builtins.list[JobRow]:
        rows = (
            self._conn()
            .execute(
                f"SELECT {_SUMMARY_COLS} FROM jobs WHERE status = ? ORDER BY seq",
                (JobStatus.RUNNING,),
            )
            .fetchall()
        )
        return [JobRow._from(r) for r in rows]

    def finished_since(self, fseq: int, *, limit: int = 500) -> builtins.list[JobRow]:
        """Jobs that reached a final status after the one numbered ``fseq``, with results,
        in the order they finished (the batch runner's output loop)."""
        rows = (
            self._conn()
            .execute(
                f"SELECT {_SUMMARY_COLS}, result FROM jobs WHERE fseq > ? ORDER BY fseq LIMIT ?",
                (int(fseq), int(limit)),
            )
            .fetchall()
        )
        return [JobRow._from(r) for r in rows]

    # -- workers --------------------------------------------------------------------------------
    def claim(self, worker_pid: int) -> tuple[JobRow, str] | None:
        """Take the oldest queued job: ``(job with its request, lease)`` or None."""
        con = self._conn()
        # a plain read first: idle workers poll without taking the write lock
        queued = (JobStatus.QUEUED,)
        if con.execute("SELECT 1 FROM jobs WHERE status = ? LIMIT 1", queued).fetchone() is None:
            return None
        lease = secrets.token_hex(8)
        now = time.time()
        with self._tx() as con:
            row = con.execute(
                "SELECT id FROM jobs WHERE status = ? ORDER BY seq LIMIT 1", queued
            ).fetchone()
            if row is None:
                return None
            con.execute(
                "UPDATE jobs SET status = ?, attempts = attempts + 1, started_at = ?, "
                "finished_at = NULL, worker_pid = ?, lease = ?, heartbeat_at = ?, "
                "progress = NULL WHERE id = ?",
                (JobStatus.RUNNING, now, worker_pid, lease, now, row[0]),
            )
        job = self.get(row[0], result=False, request=True)
        assert job is not None
        return job, lease

    def heartbeat(self, job_id: str, lease: str, progress: dict | None) -> tuple[bool, bool]:
        """Record progress; return ``(still ours, cancel requested)``."""
        row = (
            self._conn()
            .execute(
                "UPDATE jobs SET progress = ?, heartbeat_at = ? "
                "WHERE id = ? AND lease = ? AND status = ? "
                "RETURNING cancel_requested_at",
                (
                    json.dumps(progress) if progress else None,
                    time.time(),
                    job_id,
                    lease,
                    JobStatus.RUNNING,
                ),
            )
            .fetchone()
        )
        if row is None:
            return False, True
        return True, row[0] is not None

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
        """End a running job held under ``lease``; False if it is no longer ours."""
        if not JobStatus(status).final:
            raise ValueError(f"not a final status: {status}")
        sets = f"status = ?, result = ?, error = ?, finished_at = ?, fseq = {_NEXT_FSEQ}"
        args: list[Any] = [status, result, error, time.time()]
        if progress is not None:
            sets += ", progress = ?"
            args.append(json.dumps(progress))
        cur = self._conn().execute(
            f"UPDATE jobs SET {sets} WHERE id = ? AND lease = ? AND status = ?",
            [*args, job_id, lease, JobStatus.RUNNING],
        )
        return cur.rowcount == 1

    def request_cancel(self, job_id: str) -> JobRow | None:
        """Cancel a queued job at once; ask a running one to stop.  None if unknown."""
        now = time.time()
        with self._tx() as con:
            row = con.execute("SELECT status FROM jobs WHERE id = ?", (job_id,)).fetchone()
            if row is None:
                return None
            status = JobStatus(row[0])
            if status is JobStatus.QUEUED:
                con.execute(
                    "UPDATE jobs SET status = ?, finished_at = ?, "
                    "cancel_requested_at = ?, error = 'cancelled before it started', "
                    f"fseq = {_NEXT_FSEQ} WHERE id = ?",
                    (JobStatus.CANCELLED, now, now, job_id),
                )
            elif status is JobStatus.RUNNING:
                con.execute(
                    "UPDATE jobs SET cancel_requested_at = coalesce(cancel_requested_at, ?) "
                    "WHERE id = ?",
                    (now, job_id),
                )
        return self.get(job_id, result=False)

    def release(
        self,
        reason: str,
        *,
        worker_pids: Iterable[int] | None = None,
        count_attempt: bool = True,
    ) -> builtins.list[tuple[str, JobStatus]]:
        """Running jobs whose worker is gone (all running jobs if ``worker_pids`` is None).

        Each is re-queued if it has attempts left, failed with ``reason`` otherwise, and
        cancelled if a cancel was requested.  ``count_attempt=False`` (an orderly shutdown)
        gives the attempt back.  Returns ``(job id, new status)`` pairs.
        """
        now = time.time()
        out = []
        with self._tx() as con:
            sql = (
                "SELECT id, attempts, max_attempts, cancel_requested_at FROM jobs WHERE status = ?"
            )
            args: list[Any] = [JobStatus.RUNNING]
            if worker_pids is not None:
                pids = [int(p) for p in worker_pids]
                if not pids:
                    return []
                sql += f" AND worker_pid IN ({', '.join('?' * len(pids))})"
                args += pids
            for job_id, attempts, max_attempts, cancel_at in con.execute(sql, args).fetchall():
                if not count_attempt:
                    attempts = max(0, attempts - 1)
                if cancel_at is not None:
                    status = JobStatus.CANCELLED
                    error: str | None = f"cancelled ({reason})"
                elif attempts < max_attempts:
                    status = JobStatus.QUEUED
                    error = f"attempt {attempts} interrupted: {reason}" if count_attempt else None
                else:
                    status = JobStatus.FAILED
                    error = f"{reason} (attempt {attempts} of {max_attempts})"
                final = status.final
                con.execute(
                    "UPDATE jobs SET status = ?, error = ?, attempts = ?, lease = NULL, "
                    f"finished_at = ?, fseq = {_NEXT_FSEQ if final else 'NULL'} WHERE id = ?",
                    (status, error, attempts, now if final else None, job_id),
                )
                out.append((job_id, status))
        return out

    def force_finish(self, job_id: str, lease: str, status: JobStatus, error: str) -> bool:
        """The supervisor ends a running job itself (then kills its worker)."""
        return self.finish(job_id, lease, status, error=error)
