"""A time limit ends in a stored partial result, however long storing it takes.

The supervisor (:class:`~certsolve.jobs.pool.WorkerPool`) kills a job ``kill_grace`` past
its limit, and a loaded machine once took longer than that to stop a large search and
store its result: the job ended ``failed`` with nothing.  Now the worker says when it is
storing (``stopping_at``) and the supervisor gives it ``finish_grace`` from then on
(:func:`~certsolve.jobs.worker.overdue`).  Deterministic: the "stall" is a supervisor pass
made while the worker stores its result, with the job's start moved an hour back -- no
timing is asserted.
"""

import json
import os
import sqlite3

import pytest

from certsolve.jobs import ServiceSettings
from certsolve.jobs.pool import WorkerPool
from certsolve.jobs.status import JobStatus
from certsolve.jobs.store import JobStore, NewJob
from certsolve.jobs.worker import overdue, run_job

LIMITS = {"timeout": 0.3, "max_boxes": 1000, "memory_mb": 4096}


@pytest.fixture
def settings(tmp_path):
    return ServiceSettings(data_dir=tmp_path, workers=0, enable_test_kinds=True)


@pytest.fixture
def store(settings):
    s = JobStore(settings.db_path)
    yield s
    s.close()


def claimed_sleep_job(store, seconds=30.0):
    """A cooperative sleep job (it stops at its 0.3 s limit with a partial result),
    claimed as a worker would."""
    request = json.dumps({"kind": "sleep", "params": {"seconds": seconds}})
    store.add([NewJob(kind="sleep", request=request, limits=LIMITS, max_attempts=1)])
    job, lease = store.claim(os.getpid())
    return job, lease


def an_hour_ago(store, job_id, column="started_at"):
    """As if the job had been stalled for an hour since ``column``."""
    con = sqlite3.connect(store.path)
    con.execute(f"UPDATE jobs SET {column} = {column} - 3600 WHERE id = ?", (job_id,))
    con.commit()
    con.close()


class StallingStore:
    """The worker's store, with a stall while it stores the result: before ``finish``,
    an hour passes (the job's start moves back) and the supervisor makes a pass."""

    def __init__(self, store, pool):
        self.store = store
        self.pool = pool
        self.seen: JobStatus | None = None

    def heartbeat(self, *args, **kwargs):
        return self.store.heartbeat(*args, **kwargs)

    def finish(self, job_id, lease, status, **kwargs):
        an_hour_ago(self.store, job_id)
        self.pool.supervise_once()
        self.seen = self.store.get(job_id).status  # what the supervisor left
        return self.store.finish(job_id, lease, status, **kwargs)


def test_a_job_storing_its_partial_result_past_the_grace_is_not_killed(store, settings):
    pool = WorkerPool(settings, store)  # not started: its passes are made by hand
    job, lease = claimed_sleep_job(store)
    channel = StallingStore(store, pool)
    run_job(channel, job, lease, settings, limit_memory=False)
    assert channel.seen == JobStatus.RUNNING  # past kill_grace, yet not failed
    row = store.get(job.id)
    assert row.status == JobStatus.DONE, row.error
    assert row.stopping_at is not None
    result = json.loads(row.result)
    assert result["stopped_by"] == "timeout" and result["ticks"] > 0  # the partial result


def test_a_job_that_never_said_it_stops_is_failed_past_kill_grace(store, settings):
    """A call that ignores its limits (no progress, no stopping_at): failed as before."""
    pool = WorkerPool(settings, store)
    job, lease = claimed_sleep_job(store)
    an_hour_ago(store, job.id)
    pool.supervise_once()
    row = store.get(job.id)
    assert row.status == JobStatus.FAILED and "time limit exceeded (0.3 s)" in row.error
    assert not store.finish(job.id, lease, JobStatus.DONE, result="{}")  # too late


def test_finish_grace_ends_too(store, settings):
    pool = WorkerPool(settings, store)
    job, lease = claimed_sleep_job(store)
    assert store.heartbeat(job.id, lease, {"boxes": 3}, stopping=True) == (True, False)
    an_hour_ago(store, job.id)
    pool.supervise_once()
    assert store.get(job.id).status == JobStatus.RUNNING  # storing: within finish_grace
    an_hour_ago(store, job.id, "stopping_at")
    pool.supervise_once()
    row = store.get(job.id)
    assert row.status == JobStatus.FAILED
    assert "its result was not stored 120 s after its search stopped" in row.error


def test_overdue_rules(settings):
    from certsolve.jobs.store import JobRow

    def row(started, stopping=None):
        return JobRow(
            seq=1, id="j", kind="sleep", status=JobStatus.RUNNING, limits={"timeout": 60},
            batch=None, created_at=0, started_at=started, finished_at=None, attempts=1,
            max_attempts=1, worker_pid=None, lease="l", progress=None, heartbeat_at=None,
            cancel_requested_at=None, error=None, stopping_at=stopping,
        )  # fmt: skip

    now = 1000.0
    assert overdue(row(now - 60 - settings.kill_grace + 1), now, settings) is None
    assert overdue(row(now - 66), now, settings) == "time limit exceeded (60 s)"
    assert overdue(row(now - 200, stopping=now - 100), now, settings) is None
    assert "not stored" in overdue(row(now - 200, stopping=now - 121), now, settings)
    assert overdue(row(None), now, settings) is None


def test_a_claim_forgets_the_previous_runs_stop(store):
    job, lease = claimed_sleep_job(store)
    store.heartbeat(job.id, lease, None, stopping=True)
    assert store.get(job.id).stopping_at is not None
    store.release("test", leases=[lease], count_attempt=False)
    again, _ = store.claim(os.getpid())
    assert again.id == job.id and again.stopping_at is None
