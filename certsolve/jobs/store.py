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

Each job has an ``owner`` (the client name of its token, :mod:`.access`; NULL when the
service has no tokens).  Listings and counts can be limited to one owner; a client's
queued jobs are counted at submission (its quota) and :meth:`JobStore.claim` skips the
jobs of owners that already run their ``max_running`` (the ``owners`` table).  Finished
jobs older than a cut-off are deleted by :meth:`JobStore.purge`, which then truncates the
write-ahead log.

A running job's search saves itself in the ``checkpoints`` table
(:meth:`JobStore.save_search_checkpoint`, under the job's lease; one opaque blob per job,
written by :mod:`certsolve.solver.checkpoint`): a job re-queued after its worker died
resumes from it (:meth:`JobStore.search_checkpoint`).  The blob is deleted when the job
reaches a final status (and with the job by :meth:`JobStore.purge`).

A file that is not this project's store is refused when opened (:class:`StoreError`): not
SQLite at all, or a database with tables but no ``jobs`` table of this schema's columns, or
a newer schema version; nothing is written to it.  :meth:`JobStore.check` runs SQLite's
``PRAGMA quick_check`` (every page, every index entry; linear in the file's size), which
finds bytes overwritten inside the tables that reads of a few rows can miss.

Schema versions (``PRAGMA user_version``): 1 -- the jobs table; 2 -- ``jobs.owner`` and
the ``owners`` table (a version-1 store is migrated when opened: existing jobs have no
owner, so only admins see them once tokens are required); 3 -- the ``checkpoints`` table
(created when an older store is opened); 4 -- ``jobs.stopping_at``, when the job's worker
said its search has stopped and its result is being stored (:meth:`JobStore.heartbeat`
with ``stopping``; the supervisor then waits ``finish_grace`` for it).

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
    "StoreError",
    "new_job_id",
]

SCHEMA_VERSION = 4

_TABLES = """
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
    fseq                INTEGER,
    owner               TEXT,
    stopping_at         REAL
);
CREATE TABLE IF NOT EXISTS owners (
    name                TEXT PRIMARY KEY,
    max_running         INTEGER
);
CREATE TABLE IF NOT EXISTS checkpoints (
    job_id              TEXT PRIMARY KEY,
    data                BLOB NOT NULL,
    saved_at            REAL NOT NULL
);
"""
_INDEXES = f"""
CREATE INDEX IF NOT EXISTS jobs_status ON jobs(status, seq);
CREATE INDEX IF NOT EXISTS jobs_batch ON jobs(batch, seq);
CREATE INDEX IF NOT EXISTS jobs_fseq ON jobs(fseq);
CREATE INDEX IF NOT EXISTS jobs_worker ON jobs(worker_pid) WHERE status = '{JobStatus.RUNNING}';
CREATE INDEX IF NOT EXISTS jobs_owner ON jobs(owner, status, seq);
CREATE INDEX IF NOT EXISTS jobs_finished ON jobs(finished_at) WHERE finished_at IS NOT NULL;
"""

_SUMMARY_COLS = (
    "seq, id, kind, status, limits, batch, created_at, started_at, finished_at, attempts, "
    "max_attempts, worker_pid, lease, progress, heartbeat_at, cancel_requested_at, error, fseq, "
    "owner, stopping_at"
)
# owners whose running jobs reach their max_running: their queued jobs wait
_BUSY_OWNERS = (
    "SELECT r.owner FROM jobs r JOIN owners o ON o.name = r.owner "
    f"WHERE r.status = '{JobStatus.RUNNING}' GROUP BY r.owner HAVING count(*) >= o.max_running"
)
_NEXT_QUEUED = (
    f"SELECT id FROM jobs WHERE status = '{JobStatus.QUEUED}' "
    f"AND (owner IS NULL OR owner NOT IN ({_BUSY_OWNERS})) ORDER BY seq LIMIT 1"
)
# order of reaching a final status: write transactions are serialised, so a reader that has
# seen fseq = n will see every later final job with fseq > n
_NEXT_FSEQ = "(SELECT coalesce(max(fseq), 0) + 1 FROM jobs)"


class StoreError(Exception):
    """The file is not a job store of this project, or it is damaged; the message names
    the file."""


class QueueFull(Exception):
    """Too many queued jobs (all of them, or of one owner): the store refuses new ones."""


def new_job_id() -> str:
    return secrets.token_hex(12)


@dataclass
class NewJob:
    kind: str
    request: str  # JSON text of the validated request
    limits: dict
    max_attempts: int
    batch: str | None = None
    owner: str | None = None
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
    owner: str | None = None
    stopping_at: float | None = None  # the search stopped, the result is being stored
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
        try:
            self._open()
        except sqlite3.DatabaseError as exc:
            self.close()
            raise StoreError(
                f"{self.path}: damaged, or not a certsolve job store ({exc})"
            ) from None
        except StoreError:
            self.close()
            raise

    def _open(self) -> None:
        """Check that the file is empty or ours (:meth:`_refuse_foreign`), then create or
        migrate the tables."""
        con = self._conn()
        self._refuse_foreign(con)
        # a new file gives freed pages back to the file system (after a purge)
        con.execute("PRAGMA auto_vacuum = INCREMENTAL")
        mode = con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        if str(mode).lower() != "wal":  # pragma: no cover - e.g. a network file system
            raise RuntimeError(f"{self.path}: cannot use SQLite WAL mode (got {mode})")
        with self._tx() as con:
            for stmt in _TABLES.strip().split(";"):
                if stmt.strip():
                    con.execute(stmt)
            self._migrate(con)
            for stmt in _INDEXES.strip().split(";"):
                if stmt.strip():
                    con.execute(stmt)
            con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")

    def _refuse_foreign(self, con: sqlite3.Connection) -> None:
        """:class:`StoreError` unless the database is new (no table) or has this project's
        ``jobs`` table at a schema version this code knows."""
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        tables.discard("sqlite_sequence")
        if not tables:
            return
        cols = {r[1] for r in con.execute("PRAGMA table_info(jobs)")}
        ours = {"id", "kind", "status", "request", "limits", "created_at", "lease", "result"}
        if not ours <= cols:
            found = ", ".join(sorted(tables)[:5])
            raise StoreError(
                f"{self.path}: not a certsolve job store (a SQLite database with tables {found})"
            )
        version = int(con.execute("PRAGMA user_version").fetchone()[0])
        if version > SCHEMA_VERSION:
            raise StoreError(
                f"{self.path}: a job store of a newer certsolve (schema {version}; this one "
                f"knows up to {SCHEMA_VERSION})"
            )

    def check(self) -> str | None:
        """None when SQLite's ``PRAGMA quick_check`` finds the file sound, else its first
        complaint (also when the check itself cannot read the file)."""
        try:
            rows = self._conn().execute("PRAGMA quick_check(5)").fetchall()
        except sqlite3.DatabaseError as exc:
            return str(exc)
        problems = [str(r[0]) for r in rows if str(r[0]) != "ok"]
        return "; ".join(problems[:3]) or None

    @staticmethod
    def _migrate(con: sqlite3.Connection) -> None:
        """Bring an older store up to :data:`SCHEMA_VERSION` (inside the opening
        transaction, so concurrent openers see it done once)."""
        cols = {r[1] for r in con.execute("PRAGMA table_info(jobs)")}
        if "owner" not in cols:  # version 1: jobs had no owner
            con.execute("ALTER TABLE jobs ADD COLUMN owner TEXT")
        if "stopping_at" not in cols:  # versions 1-3
            con.execute("ALTER TABLE jobs ADD COLUMN stopping_at REAL")

    def schema_version(self) -> int:
        return int(self._conn().execute("PRAGMA user_version").fetchone()[0])

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
    def add(
        self,
        jobs: Iterable[NewJob],
        *,
        max_queued: int | None = None,
        owner_max_queued: int | None = None,
    ) -> builtins.list[str]:
        """Queue jobs atomically (all or none).  :class:`QueueFull` beyond ``max_queued``
        queued jobs in all, or ``owner_max_queued`` of the (one) owner of ``jobs``."""
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
            owners = {j.owner for j in jobs}
            if owner_max_queued is not None and len(owners) == 1 and None not in owners:
                (owner,) = owners
                (n,) = con.execute(
                    "SELECT count(*) FROM jobs WHERE owner = ? AND status = ?",
                    (owner, JobStatus.QUEUED),
                ).fetchone()
                if n + len(jobs) > owner_max_queued:
                    raise QueueFull(
                        f"{owner} has {n} queued jobs; at most {owner_max_queued} may wait, "
                        "try later"
                    )
            con.executemany(
                "INSERT INTO jobs (id, kind, status, request, limits, batch, created_at, "
                "max_attempts, owner) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
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
                        j.owner,
                    )
                    for j in jobs
                ],
            )
        return [j.id for j in jobs]

    def set_owner_limits(self, max_running: dict[str, int | None]) -> None:
        """The running-job limit of each owner (None or absent: no limit of its own)."""
        with self._tx() as con:
            con.execute("DELETE FROM owners")
            con.executemany(
                "INSERT INTO owners (name, max_running) VALUES (?, ?)",
                [(name, n) for name, n in max_running.items() if n is not None],
            )

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
        owner: str | None = None,
        limit: int = 50,
        cursor: int | None = None,
        oldest_first: bool = False,
    ) -> tuple[builtins.list[JobRow], int | None]:
        """One page of jobs (newest first unless ``oldest_first``) and the next cursor;
        ``owner``: only that owner's jobs."""
        where: builtins.list[str] = []
        args: builtins.list[Any] = []
        for col, val in (("owner", owner), ("status", status), ("kind", kind), ("batch", batch)):
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

    def counts(self, *, batch: str | None = None, owner: str | None = None) -> dict[JobStatus, int]:
        """Jobs per status (of one batch, of one owner)."""
        sql = "SELECT status, count(*) FROM jobs"
        where, args = [], []
        for col, val in (("batch", batch), ("owner", owner)):
            if val is not None:
                where.append(f"{col} = ?")
                args.append(val)
        if where:
            sql += " WHERE " + " AND ".join(where)
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
    def claim(self, worker_pid: int | None) -> tuple[JobRow, str] | None:
        """Take the oldest queued job whose owner may run one more: ``(job with its
        request, lease)`` or None.  ``worker_pid`` is None when the job does not run in
        a process of this host (a Dask worker)."""
        con = self._conn()
        # a plain read first: idle workers poll without taking the write lock
        if con.execute(_NEXT_QUEUED).fetchone() is None:
            return None
        lease = secrets.token_hex(8)
        now = time.time()
        with self._tx() as con:
            row = con.execute(_NEXT_QUEUED).fetchone()
            if row is None:
                return None
            con.execute(
                "UPDATE jobs SET status = ?, attempts = attempts + 1, started_at = ?, "
                "finished_at = NULL, worker_pid = ?, lease = ?, heartbeat_at = ?, "
                "progress = NULL, stopping_at = NULL WHERE id = ?",
                (JobStatus.RUNNING, now, worker_pid, lease, now, row[0]),
            )
        job = self.get(row[0], result=False, request=True)
        assert job is not None
        return job, lease

    def heartbeat(
        self, job_id: str, lease: str, progress: dict | None, *, stopping: bool = False
    ) -> tuple[bool, bool]:
        """Record progress; return ``(still ours, cancel requested)``.  ``stopping``: the
        job's search has stopped (or reached its time limit) and its result is being built
        and stored; the first such heartbeat sets ``stopping_at``."""
        now = time.time()
        row = (
            self._conn()
            .execute(
                "UPDATE jobs SET progress = ?, heartbeat_at = ?, "
                "stopping_at = CASE WHEN ? THEN coalesce(stopping_at, ?) ELSE stopping_at END "
                "WHERE id = ? AND lease = ? AND status = ? "
                "RETURNING cancel_requested_at",
                (
                    json.dumps(progress) if progress else None,
                    now,
                    bool(stopping),
                    now,
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
        with self._tx() as con:
            cur = con.execute(
                f"UPDATE jobs SET {sets} WHERE id = ? AND lease = ? AND status = ?",
                [*args, job_id, lease, JobStatus.RUNNING],
            )
            if cur.rowcount == 1:
                con.execute("DELETE FROM checkpoints WHERE job_id = ?", (job_id,))
        return cur.rowcount == 1

    # -- search checkpoints ---------------------------------------------------------------------
    def save_search_checkpoint(self, job_id: str, lease: str, data: bytes) -> bool:
        """Store the latest checkpoint of a running job's search (replacing the previous
        one); False if the job is no longer held under ``lease``."""
        cur = self._conn().execute(
            "INSERT INTO checkpoints (job_id, data, saved_at) "
            "SELECT id, ?, ? FROM jobs WHERE id = ? AND lease = ? AND status = ? "
            "ON CONFLICT(job_id) DO UPDATE SET data = excluded.data, saved_at = excluded.saved_at",
            (sqlite3.Binary(data), time.time(), job_id, lease, JobStatus.RUNNING),
        )
        return cur.rowcount == 1

    def search_checkpoint(self, job_id: str) -> bytes | None:
        """The last checkpoint stored for a job's search, or None."""
        row = (
            self._conn()
            .execute("SELECT data FROM checkpoints WHERE job_id = ?", (job_id,))
            .fetchone()
        )
        return bytes(row[0]) if row else None

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
                con.execute("DELETE FROM checkpoints WHERE job_id = ?", (job_id,))
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
        leases: Iterable[str] | None = None,
        count_attempt: bool = True,
    ) -> builtins.list[tuple[str, JobStatus]]:
        """Running jobs whose worker is gone: those of ``worker_pids``, or held under one of
        ``leases``, or all running jobs if both are None.

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
            for col, given, cast in (("worker_pid", worker_pids, int), ("lease", leases, str)):
                if given is not None:
                    vals = [cast(v) for v in given]
                    if not vals:
                        return []
                    sql += f" AND {col} IN ({', '.join('?' * len(vals))})"
                    args += vals
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
                if final:
                    con.execute("DELETE FROM checkpoints WHERE job_id = ?", (job_id,))
                out.append((job_id, status))
        return out

    def force_finish(self, job_id: str, lease: str, status: JobStatus, error: str) -> bool:
        """The supervisor ends a running job itself (then kills its worker)."""
        return self.finish(job_id, lease, status, error=error)

    # -- retention ------------------------------------------------------------------------------
    def purge(self, before: float, *, chunk: int = 500) -> int:
        """Delete the finished jobs (done, failed, cancelled) that finished before the time
        ``before`` (seconds since the epoch), ``chunk`` per transaction so that writers
        wait little; then give the space back (:meth:`checkpoint`).  Returns how many."""
        final = tuple(FINAL_STATUSES)
        marks = ", ".join("?" * len(final))
        total = 0
        while True:
            with self._tx() as con:
                cur = con.execute(
                    f"DELETE FROM jobs WHERE seq IN (SELECT seq FROM jobs WHERE finished_at < ? "
                    f"AND status IN ({marks}) LIMIT ?)",
                    (float(before), *final, int(chunk)),
                )
                n = cur.rowcount
                con.execute("DELETE FROM checkpoints WHERE job_id NOT IN (SELECT id FROM jobs)")
            total += n
            if n < chunk:
                break
        if total:  # stepped to the end (sqlite3's execute frees one page per step)
            self._conn().executescript("PRAGMA incremental_vacuum;")
        self.checkpoint()
        return total

    def checkpoint(self) -> tuple[int, int, int]:
        """Copy the write-ahead log into the database and truncate it (``PRAGMA
        wal_checkpoint(TRUNCATE)``): ``(busy, log pages, pages checkpointed)``; busy is 1
        when a reader kept it from finishing (it is tried again next time)."""
        row = self._conn().execute("PRAGMA wal_checkpoint(TRUNCATE)").fetchone()
        return int(row[0]), int(row[1]), int(row[2])

    def file_sizes(self) -> dict[str, int]:
        """Bytes of the database file and of its write-ahead log."""
        wal = Path(str(self.path) + "-wal")
        return {
            "db": self.path.stat().st_size if self.path.exists() else 0,
            "wal": wal.stat().st_size if wal.exists() else 0,
        }
