"""The job service with its jobs on a Dask cluster (``settings.scheduler``).

One ``distributed.LocalCluster`` (2 worker processes, ``allowed-failures = 0``: a task on a
killed worker fails at once, so the service itself must run the job again) and one
service on it (FastAPI ``TestClient``) serve the module.  A job on the cluster gives the
result the local pool gives; a cancel stops the running search through its progress
callback (partial result kept), and a job that never reads its flag has its worker
restarted after the grace; a worker killed mid-job costs that job one attempt, not
the other job running beside it, and the service keeps serving.
"""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")
from fastapi.testclient import TestClient  # noqa: E402

from certsolve.api.app import create_app  # noqa: E402
from certsolve.jobs import ServiceSettings  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
K5 = (ROOT / "examples/systems/katsura-5.mbx").read_text()  # 16 solutions, ~8k boxes
FINAL = ("done", "failed", "cancelled")


def hard_system(n: int = 8) -> str:
    """3^n real solutions in [-2, 2]^n: minutes of work for the solver."""
    decls = "\n".join(f"  x{i} in [-2, 2];" for i in range(n))
    eqs = "\n".join(f"  x{i}^3 - x{i} - 0.01*x{(i + 1) % n} = 0;" for i in range(n))
    return f"Variables\n{decls}\nConstraints\n{eqs}\nend\n"


def settings_for(data_dir: Path, **kw) -> ServiceSettings:
    return ServiceSettings(
        data_dir=data_dir,
        enable_test_kinds=True,
        quick_workers=1,
        quick_heavy_workers=1,
        progress_interval=0.1,
        **kw,
    )


@pytest.fixture(scope="module")
def service(dask_client, tmp_path_factory):
    """The HTTP API of a service whose jobs run on the module's cluster."""
    address = dask_client.scheduler.address
    settings = settings_for(
        tmp_path_factory.mktemp("dask-svc"), scheduler=address, cancel_grace=3.0
    )
    with TestClient(create_app(settings), base_url="http://localhost") as http:
        yield http


def submit(http, job: dict) -> str:
    r = http.post("/v1/jobs", json=job)
    assert r.status_code == 202, r.text
    return r.json()["id"]


def wait(http, job_id: str, until=lambda j: j["status"] in FINAL, timeout=90.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        r = http.get(f"/v1/jobs/{job_id}")
        assert r.status_code == 200, r.text
        j = r.json()
        if until(j):
            return j
        if time.monotonic() > deadline:
            raise AssertionError(f"job {job_id} stuck: {j}")
        time.sleep(0.05)


def comparable(result: dict) -> dict:
    """A solve result without what depends on the run (times, executor)."""
    out = dict(result)
    stats = dict(out.pop("stats"))
    for key in list(stats):
        if key in ("time", "cpu", "elapsed"):
            stats.pop(key)
    out["stats"] = stats
    return out


def test_a_job_on_the_cluster_equals_the_local_pool(service, dask_client, tmp_path):
    job = {"kind": "solve", "system": K5, "params": {"eps": 1e-9}}
    on_dask = wait(service, submit(service, job))
    assert on_dask["status"] == "done", on_dask
    assert on_dask["attempts"] == 1 and on_dask["worker_pid"] is None
    assert on_dask["progress"]["boxes"] > 0  # relayed from the Dask worker to the store
    h = service.get("/healthz").json()["workers"]
    assert h["runner"] == "dask" and h["scheduler"] == dask_client.scheduler.address
    assert h["alive"] == 2

    with TestClient(
        create_app(settings_for(tmp_path / "pool", workers=1)), base_url="http://localhost"
    ) as local:
        on_pool = wait(local, submit(local, job))
        assert local.get("/healthz").json()["workers"]["runner"] == "processes"
    assert on_pool["status"] == "done", on_pool
    a = service.get(f"/v1/jobs/{on_dask['id']}/result").json()
    b = json.loads(json.dumps(on_pool["result"]))
    assert a["status"] == b["status"] == "complete" and len(a["solutions"]) == 16
    assert comparable(a) == comparable(b)


def test_cancel_stops_the_running_search(service):
    job_id = submit(service, {"kind": "solve", "system": hard_system(), "params": {"eps": 1e-12}})
    # progress reaches GET /v1/jobs/{id} while the job runs on the cluster
    j = wait(service, job_id, until=lambda j: (j["progress"] or {}).get("boxes", 0) > 0)
    assert j["status"] == "running"
    r = service.delete(f"/v1/jobs/{job_id}")
    assert r.status_code == 202 and r.json()["cancel_requested"]
    t0 = time.monotonic()
    j = wait(service, job_id)
    assert j["status"] == "cancelled", j
    # stopped by the progress callback, not dropped after the grace: the partial result
    res = service.get(f"/v1/jobs/{job_id}/result").json()
    assert res["status"] == "cancelled" and res["stats"]["stopped_by"] == "cancelled"
    assert res["pending"] and len(res["solutions"]) == j["progress"]["solutions"]
    assert j["error"] == "cancelled while running (partial result)"
    assert time.monotonic() - t0 < 60  # a bound on a hang, not a timing claim
    # the worker is free again: a quick job runs
    other = wait(service, submit(service, {"kind": "sleep", "params": {"seconds": 0.1}}))
    assert other["status"] == "done"


def test_cancel_of_a_job_that_never_reads_its_flag_restarts_its_worker(service, dask_client):
    job_id = submit(service, {"kind": "sleep", "params": {"seconds": 120, "cooperative": False}})
    wait(service, job_id, until=lambda j: j["status"] == "running")
    deadline = time.monotonic() + 30
    while not (
        busy := [w for w, k in dask_client.processing().items() if any(job_id in x for x in k)]
    ):
        assert time.monotonic() < deadline, "the job's task never started"
        time.sleep(0.05)
    pid = dask_client.run(os.getpid, workers=busy)[busy[0]]
    assert service.delete(f"/v1/jobs/{job_id}").status_code == 202
    j = wait(service, job_id)
    assert j["status"] == "cancelled" and "dropped" in j["error"], j
    # its worker process was restarted by its nanny: the thread is gone with it (a worker
    # that goes away while being asked is left out of the answer, not an error)
    deadline = time.monotonic() + 60
    while (
        pid in dask_client.run(os.getpid, on_error="ignore").values()
        or len(dask_client.nthreads()) < 2
    ):
        assert time.monotonic() < deadline, "the worker was not restarted"
        time.sleep(0.2)
    other = wait(service, submit(service, {"kind": "sleep", "params": {"seconds": 0.1}}))
    assert other["status"] == "done"


def test_a_killed_worker_costs_its_job_one_attempt(service, dask_client):
    pids = dask_client.run(os.getpid)
    victim = submit(service, {"kind": "sleep", "params": {"seconds": 3}})
    bystander = submit(service, {"kind": "sleep", "params": {"seconds": 3}})
    for job_id in (victim, bystander):
        wait(service, job_id, until=lambda j: (j["progress"] or {}).get("boxes", 0) > 0)
    busy = {
        w: keys for w, keys in dask_client.processing().items() if any(victim in k for k in keys)
    }
    assert len(busy) == 1, dask_client.processing()
    (worker,) = busy
    os.kill(pids[worker], signal.SIGKILL)

    # the victim is queued again (attempt 1 lost with its worker) and then runs to the end
    j = wait(service, victim, until=lambda j: j["attempts"] >= 2 or j["status"] in FINAL)
    assert j["attempts"] == 2 and "Dask worker was lost" in (j["error"] or ""), j
    assert wait(service, victim)["status"] == "done"
    b = wait(service, bystander)
    assert b["status"] == "done" and b["attempts"] == 1 and b["error"] is None
    h = service.get("/healthz").json()
    assert h["status"] == "ok" and h["workers"]["restarts"] >= 1
    dask_client.wait_for_workers(2, timeout=60)


def test_a_job_that_kills_its_workers_fails_alone(service, dask_client):
    crasher = submit(service, {"kind": "sleep", "params": {"seconds": 0.6, "crash": True}})
    other = submit(service, {"kind": "sleep", "params": {"seconds": 0.2}})
    j = wait(service, crasher, timeout=120)
    assert j["status"] == "failed" and j["attempts"] == 2, j
    assert "Dask worker was lost" in j["error"] and "attempt 2 of 2" in j["error"]
    assert wait(service, other)["status"] == "done"
    dask_client.wait_for_workers(2, timeout=60)


# -- the command line -------------------------------------------------------------------------
def serve_settings(monkeypatch, *argv, env: str | None = None):
    import argparse

    from certsolve.cli import service as cli_service

    if env is None:
        monkeypatch.delenv("CERTSOLVE_SCHEDULER", raising=False)
    else:
        monkeypatch.setenv("CERTSOLVE_SCHEDULER", env)
    parser = argparse.ArgumentParser()
    cli_service.register(parser.add_subparsers())
    return cli_service._settings(parser.parse_args(["serve", *argv]))


def test_serve_scheduler_option_and_environment(monkeypatch):
    from certsolve.cli.common import CliError

    assert serve_settings(monkeypatch).scheduler is None  # the local pool by default
    s = serve_settings(monkeypatch, "--scheduler", "10.0.0.5:8786")
    assert s.scheduler == "tcp://10.0.0.5:8786"
    assert serve_settings(monkeypatch, env="tcp://h:1").scheduler == "tcp://h:1"
    s = serve_settings(monkeypatch, "--workers", "2", env="tcp://h:1")  # --workers wins
    assert s.scheduler is None and s.workers == 2
    with pytest.raises(CliError, match="--workers and --scheduler"):
        serve_settings(monkeypatch, "--workers", "2", "--scheduler", "tcp://h:1")
    with pytest.raises(CliError, match="scheduler address"):
        serve_settings(monkeypatch, "--scheduler", " ")
    # batch has no --scheduler: the variable does not move it to a cluster
    from certsolve.cli import service as cli_service

    class Args:
        workers = 1

    monkeypatch.setenv("CERTSOLVE_SCHEDULER", "tcp://h:1")
    assert cli_service._settings(Args()).scheduler is None


def test_settings_from_the_environment():
    s = ServiceSettings.from_env({"CERTSOLVE_SCHEDULER": " tcp://h:8786 "})
    assert s.scheduler == "tcp://h:8786"
    assert ServiceSettings.from_env({}).scheduler is None
    with pytest.raises(ValueError, match="scheduler"):
        ServiceSettings(scheduler="tcp://a b")
