"""The SQLite job store: WAL, claims and leases, recovery, cancellation, pagination."""

import json
import sqlite3
import threading
import time

import pytest

from certsolve.jobs.store import JobStore, NewJob, QueueFull

LIMITS = {"timeout": 10.0, "max_boxes": 1000, "memory_mb": 1024}


def new(kind="solve", attempts=2, batch=None):
    return NewJob(
        kind=kind,
        request=json.dumps({"kind": kind}),
        limits=LIMITS,
        max_attempts=attempts,
        batch=batch,
    )


@pytest.fixture
def store(tmp_path):
    s = JobStore(tmp_path / "jobs.sqlite3")
    yield s
    s.close()


def test_wal_mode_and_schema(store, tmp_path):
    assert store.journal_mode() == "wal"
    con = sqlite3.connect(tmp_path / "jobs.sqlite3")
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    cols = {r[1] for r in con.execute("PRAGMA table_info(jobs)")}
    assert {"id", "status", "request", "result", "lease", "attempts", "fseq"} <= cols
    con.close()
    # reopening an existing store keeps the jobs
    (job_id,) = store.add([new()])
    again = JobStore(tmp_path / "jobs.sqlite3")
    assert again.get(job_id).status == "queued"
    again.close()


def test_claim_fifo_lease_and_finish(store):
    ids = store.add([new(), new(), new()])
    job, lease = store.claim(worker_pid=111)
    assert job.id == ids[0] and job.status == "running" and job.attempts == 1
    assert job.worker_pid == 111 and json.loads(job.request) == {"kind": "solve"}
    job2, lease2 = store.claim(worker_pid=222)
    assert job2.id == ids[1] and lease2 != lease
    # progress and the cancel flag travel through the heartbeat
    assert store.heartbeat(job.id, lease, {"boxes": 5}) == (True, False)
    assert store.get(job.id).progress == {"boxes": 5}
    # a wrong lease cannot write
    assert store.heartbeat(job.id, "nope", {"boxes": 6}) == (False, True)
    assert not store.finish(job.id, "nope", "done", result="{}")
    assert store.finish(job.id, lease, "done", result='{"x": 1}')
    row = store.get(job.id)
    assert row.status == "done" and row.result == '{"x": 1}' and row.finished_at is not None
    # finishing twice is refused
    assert not store.finish(job.id, lease, "failed", error="late")
    assert store.result_text(job.id) == ("done", '{"x": 1}')
    assert store.result_text("missing") is None
    with pytest.raises(ValueError):
        store.finish(job2.id, lease2, "running")


def test_claim_is_atomic_across_threads(tmp_path):
    path = tmp_path / "jobs.sqlite3"
    store = JobStore(path)
    store.add([new() for _ in range(40)])
    got: list[str] = []
    lock = threading.Lock()

    def worker(pid):
        s = JobStore(path)
        while (c := s.claim(pid)) is not None:
            with lock:
                got.append(c[0].id)
        s.close()

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 40 and len(set(got)) == 40
    store.close()


def test_release_requeues_then_fails_after_max_attempts(store):
    (job_id,) = store.add([new(attempts=2)])
    job, lease = store.claim(10)
    assert store.release("worker died", worker_pids=[10]) == [(job_id, "queued")]
    row = store.get(job_id)
    assert row.status == "queued" and row.lease is None and "worker died" in row.error
    # the old worker's lease is void
    assert not store.finish(job_id, lease, "done", result="{}")
    job, lease = store.claim(11)
    assert job.attempts == 2
    assert store.release("worker died", worker_pids=[11]) == [(job_id, "failed")]
    row = store.get(job_id)
    assert row.status == "failed" and "attempt 2 of 2" in row.error
    # other workers' jobs are untouched
    (other,) = store.add([new()])
    store.claim(12)
    assert store.release("x", worker_pids=[99]) == []
    assert store.get(other).status == "running"


def test_release_by_lease_touches_that_job_alone(store):
    """Jobs claimed for no local process (a Dask worker) share worker_pid NULL: each is
    released by its lease."""
    a, b = store.add([new(), new()])
    (ja, la), (jb, _) = store.claim(None), store.claim(None)
    assert {ja.id, jb.id} == {a, b} and store.get(a).worker_pid is None
    assert store.release("its Dask worker was lost", leases=[la]) == [(ja.id, "queued")]
    assert store.get(jb.id).status == "running"
    assert store.release("x", leases=[]) == [] and store.release("x", leases=["nope"]) == []
    assert store.get(jb.id).status == "running"


def test_restart_recovery_and_orderly_shutdown(store):
    a, b, c = store.add([new(), new(), new()])
    store.claim(1)
    store.claim(2)
    # an orderly shutdown gives the attempt back
    assert sorted(store.release("stopped", worker_pids=[1], count_attempt=False)) == [(a, "queued")]
    assert store.get(a).attempts == 0 and store.get(a).error is None
    # recovery after a crash: every running job (no pid filter) is re-queued
    assert store.release("service restarted") == [(b, "queued")]
    assert store.get(b).attempts == 1
    assert store.counts() == {"queued": 3, "running": 0, "done": 0, "failed": 0, "cancelled": 0}
    assert store.get(c).status == "queued"


def test_cancel_queued_and_running(store):
    a, b = store.add([new(), new()])
    row = store.request_cancel(a)
    assert row.status == "cancelled" and row.finished_at is not None
    job, lease = store.claim(5)
    assert job.id == b  # the cancelled job is never claimed
    row = store.request_cancel(b)
    assert row.status == "running" and row.cancel_requested_at is not None
    assert store.heartbeat(b, lease, None) == (True, True)
    assert store.finish(b, lease, "cancelled", result='{"partial": true}')
    assert store.request_cancel("nope") is None
    # a worker dying while its job is being cancelled ends it cancelled, not re-queued
    (c,) = store.add([new()])
    store.claim(6)
    store.request_cancel(c)
    assert store.release("died", worker_pids=[6]) == [(c, "cancelled")]


def test_pagination_and_filters(store):
    ids = store.add([new(kind="solve") for _ in range(7)])
    ids += store.add([new(kind="fk", batch="b1") for _ in range(3)])
    seen, cursor = [], None
    while True:
        rows, cursor = store.list(limit=3, cursor=cursor)
        seen += [r.id for r in rows]
        if cursor is None:
            break
    assert seen == ids[::-1]  # newest first, each once
    rows, nxt = store.list(kind="fk", limit=10)
    assert [r.id for r in rows] == ids[7:][::-1] and nxt is None
    rows, _ = store.list(batch="b1", oldest_first=True)
    assert [r.id for r in rows] == ids[7:]
    job, lease = store.claim(1)
    store.finish(job.id, lease, "done", result="{}")
    rows, _ = store.list(status="done")
    assert [r.id for r in rows] == [ids[0]]
    assert store.counts(batch="b1")["queued"] == 3


def test_finish_order_is_recorded(store):
    ids = store.add([new() for _ in range(4)])
    claims = [store.claim(i) for i in range(4)]
    # finish in reverse order: finished_since reports completion order
    for job, lease in reversed(claims):
        store.finish(job.id, lease, "done", result="1")
    rows = store.finished_since(0)
    assert [r.id for r in rows] == ids[::-1]
    assert store.finished_since(rows[1].fseq)[0].id == ids[1]
    assert rows[0].result == "1"


def test_queue_limit(store):
    store.add([new(), new()], max_queued=3)
    with pytest.raises(QueueFull):
        store.add([new(), new()], max_queued=3)
    assert store.counts()["queued"] == 2  # all or none


def test_statuses_are_enum_members(store):
    from certsolve.jobs.status import FINAL_STATUSES, JobStatus

    (job_id,) = store.add([new()])
    row = store.get(job_id)
    assert row.status is JobStatus.QUEUED and not row.final
    job, lease = store.claim(worker_pid=7)
    assert job.status is JobStatus.RUNNING
    with pytest.raises(ValueError):
        store.finish(job_id, lease, JobStatus.QUEUED)  # not a final status
    assert store.finish(job_id, lease, JobStatus.DONE, result="{}")
    row = store.get(job_id)
    assert row.status is JobStatus.DONE and row.final and row.status in FINAL_STATUSES
    assert store.counts() == {s: int(s is JobStatus.DONE) for s in JobStatus}
    assert store.result_text(job_id)[0] is JobStatus.DONE


# -- owners, retention, migration -----------------------------------------------------------------
def owned(owner):
    job = new()
    job.owner = owner
    return job


def test_owners_quotas_and_running_limits(store):
    store.add([owned("a"), owned("a"), owned("a"), owned("b")])
    with pytest.raises(QueueFull, match="a has 3 queued jobs"):
        store.add([owned("a")], owner_max_queued=3)
    store.add([owned("b")], owner_max_queued=3)  # b has 1
    assert store.counts(owner="a")["queued"] == 3
    rows, _ = store.list(owner="b")
    assert {r.owner for r in rows} == {"b"} and len(rows) == 2
    # a may run one job at a time: the workers skip its other jobs while it runs one
    store.set_owner_limits({"a": 1, "b": None})
    first, _ = store.claim(1)
    second, _ = store.claim(2)
    third, _ = store.claim(3)
    assert (first.owner, second.owner, third.owner) == ("a", "b", "b")
    assert store.claim(4) is None  # only a's jobs are left, and a is at its limit
    store.release("done", worker_pids=[1], count_attempt=False)
    assert store.claim(5)[0].owner == "a"


def test_purge_and_checkpoint(store):
    ids = store.add([new() for _ in range(5)])
    for pid in range(3):
        job, lease = store.claim(pid)
        store.finish(job.id, lease, "done", result='{"x": "' + "y" * 10_000 + '"}')
    store.request_cancel(ids[3])  # cancelled while queued: finished
    assert store.purge(time.time() - 3600) == 0  # nothing is an hour old
    sizes = store.file_sizes()
    assert sizes["wal"] == 0 and sizes["db"] > 30_000  # checkpointed, results in the file
    assert store.purge(time.time() + 1) == 4
    assert [r.id for r in store.list()[0]] == [ids[4]]  # the queued one stays
    assert store.file_sizes()["db"] < sizes["db"]  # freed pages go back (auto_vacuum)


def test_version_1_store_is_migrated(tmp_path):
    path = tmp_path / "old.sqlite3"
    con = sqlite3.connect(path)
    con.executescript(
        """
        CREATE TABLE jobs (
            seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT NOT NULL UNIQUE, kind TEXT NOT NULL,
            status TEXT NOT NULL, request TEXT NOT NULL, limits TEXT NOT NULL, batch TEXT,
            created_at REAL NOT NULL, started_at REAL, finished_at REAL,
            attempts INTEGER NOT NULL DEFAULT 0, max_attempts INTEGER NOT NULL,
            worker_pid INTEGER, lease TEXT, progress TEXT, heartbeat_at REAL,
            cancel_requested_at REAL, result TEXT, error TEXT, fseq INTEGER);
        INSERT INTO jobs (id, kind, status, request, limits, created_at, max_attempts)
            VALUES ('old1', 'solve', 'queued', '{}', '{}', 1.0, 2);
        PRAGMA user_version = 1;
        """
    )
    con.close()
    store = JobStore(path)
    assert store.schema_version() == 4
    row = store.get("old1")
    assert row.status == "queued" and row.owner is None
    (job_id,) = store.add([owned("a")])
    assert store.get(job_id).owner == "a"
    job, lease = store.claim(1)
    assert job.id == "old1"
    assert store.save_search_checkpoint("old1", lease, b"x")  # the table was created
    store.close()


def test_search_checkpoints_follow_the_lease_and_the_job(tmp_path):
    store = JobStore(tmp_path / "jobs.sqlite3")
    a, b = store.add([owned(None), owned(None)])
    job, lease = store.claim(1)
    assert job.id == a and store.search_checkpoint(a) is None
    assert store.save_search_checkpoint(a, lease, b"one")
    assert store.save_search_checkpoint(a, lease, b"two")  # replaced
    assert not store.save_search_checkpoint(a, "another lease", b"stale")
    assert not store.save_search_checkpoint(b, lease, b"not running")
    assert store.search_checkpoint(a) == b"two" and store.search_checkpoint(b) is None
    # the worker died: the job is queued again and keeps its checkpoint for the next run
    assert store.release("killed", worker_pids=[1]) == [(a, "queued")]
    assert store.search_checkpoint(a) == b"two"
    job, lease2 = store.claim(2)
    assert job.id == a and not store.save_search_checkpoint(a, lease, b"old lease")
    assert store.save_search_checkpoint(a, lease2, b"three")
    # a final status drops it
    assert store.finish(a, lease2, "done", result="{}")
    assert store.search_checkpoint(a) is None
    store.close()
