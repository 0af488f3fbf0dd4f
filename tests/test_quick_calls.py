"""The quick-call processes (certsolve.jobs.quick): deadlines, memory limits, clients that go
away, separate lanes, a bounded wait -- with the hidden ``sleep`` call, whose cost
estimate is whatever the test says, and the issue's 32-wire reproducer over HTTP."""

import random
import threading
import time

import pytest
from fastapi.testclient import TestClient

from certsolve.jobs import ServiceSettings
from certsolve.jobs.kinds.sleep import SleepCall
from certsolve.jobs.quick import Busy, Gone, QuickCalls, TooCostly


def sleep(seconds=0.0, estimate=0.0, **kw) -> SleepCall:
    return SleepCall(params={"seconds": seconds, "estimate": estimate, **kw})


@pytest.fixture
def quick(tmp_path):
    settings = ServiceSettings(
        data_dir=tmp_path,
        workers=0,
        quick_workers=1,
        quick_heavy_workers=1,
        quick_timeout=3.0,
        quick_heavy_timeout=6.0,
        quick_memory_mb=1024,
        quick_wait=0.3,
        quick_queue=1,
    )
    q = QuickCalls(settings)
    yield q
    q.close()


def test_calls_run_in_other_processes(quick):
    import json
    import os

    out = json.loads(quick.run("sleep", sleep()))
    assert out["pid"] != os.getpid() and out["pid"] in quick.pids()
    with pytest.raises(ValueError, match="bad input"):
        quick.run("sleep", sleep(fail="bad input"))
    with pytest.raises(TooCostly, match="would take about 60 s") as info:
        quick.run("sleep", sleep(estimate=60))  # refused before it runs
    assert info.value.field == "params.seconds"


def test_a_call_over_its_deadline_is_killed(quick):
    quick.run("sleep", sleep())  # the light process is up
    before = quick.stats()["light"]["started"]
    t0 = time.monotonic()
    with pytest.raises(TooCostly, match="ran longer than 3 s"):
        quick.run("sleep", sleep(seconds=30, estimate=0.1))
    assert time.monotonic() - t0 < 20
    stats = quick.stats()["light"]
    assert stats["started"] == before + 1 and stats["busy"] == 0  # replaced at once
    assert quick.run("sleep", sleep())  # and the lane still answers


def test_memory_limit_of_a_call(quick):
    with pytest.raises(TooCostly, match="more than 1024 MiB"):
        quick.run("sleep", sleep(allocate_mb=4000))
    assert quick.run("sleep", sleep())


def test_a_client_that_goes_away_stops_its_computation(quick):
    quick.run("sleep", sleep())
    pids = set(quick.pids())
    t0 = time.monotonic()
    with pytest.raises(Gone):
        quick.run("sleep", sleep(seconds=60), gone=lambda: time.monotonic() - t0 > 0.5)
    assert time.monotonic() - t0 < 10
    assert not pids <= set(quick.pids())  # the process that ran it is gone


def test_heavy_calls_do_not_starve_light_ones(quick):
    results = {}

    def heavy(i):
        try:
            results[i] = quick.run("sleep", sleep(seconds=2, estimate=5))
        except Busy as exc:
            results[i] = exc

    threads = [threading.Thread(target=heavy, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    time.sleep(0.5)
    light = [quick.run("sleep", sleep(seconds=0.01, estimate=0.01)) for _ in range(5)]
    for t in threads:
        t.join()
    assert len(light) == 5  # answered while the heavy lane was full
    busy = [r for r in results.values() if isinstance(r, Busy)]
    assert busy and all(b.retry_after >= 1 for b in busy)  # one ran, one waited, one refused
    assert sum(isinstance(r, str) for r in results.values()) >= 1


def spatial_robot(m: int, seed: int = 1) -> dict:
    """A spatial robot with ``m`` wires at random anchors and attachments (no elastic
    model: what the force index needs)."""
    rng = random.Random(seed)

    def v(scale):
        return [rng.uniform(-scale, scale) for _ in range(3)]

    wires = [{"base": v(100), "platform": v(10), "tau": [0, 100]} for _ in range(m)]
    return {"name": f"random-{m}", "dof": 6, "gravity": [0, 0, -9.81],
            "platform": {"mass": 1.0}, "wires": wires}  # fmt: skip


def test_the_32_wire_robot_is_refused_at_once(tmp_path):
    """Issue 13's reproducer: hyperplane shifting on 32 wires (2 C(32, 5) facet planes)."""
    from certsolve.api.app import create_app

    app = create_app(ServiceSettings(data_dir=tmp_path, workers=0))
    body = {"robot": spatial_robot(32), "params": {"pose": [0, 0, 100, 0, 0, 0]}}
    with TestClient(app, base_url="http://localhost") as client:
        t0 = time.monotonic()
        r = client.post("/v1/isotropic", json=body)
        assert time.monotonic() - t0 < 10
        assert r.status_code == 422 and "submit a job" in r.json()["error"]
        (d,) = r.json()["detail"]
        assert d["field"] == "robot.wires" and d["type"] == "too_costly"
        assert client.get("/healthz").json()["quick"]["heavy"]["processes"] == 0  # never ran
