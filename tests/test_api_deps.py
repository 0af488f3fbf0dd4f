"""The API's routes get their settings and services through FastAPI dependencies: a test
(or another deployment) swaps one without touching the routes."""

from pathlib import Path

from fastapi.testclient import TestClient

from certsolve.api.app import create_app
from certsolve.api.deps import get_quick
from certsolve.jobs import ServiceSettings
from certsolve.jobs.quick import Busy

PLANAR = (Path(__file__).resolve().parents[1] / "examples/robots/planar.json").read_text()


class FullQuickCalls:
    def run(self, name, req, gone):
        raise Busy("no slot", retry_after=3)


def test_quick_calls_are_injected(tmp_path):
    app = create_app(ServiceSettings(data_dir=tmp_path, workers=0))
    app.dependency_overrides[get_quick] = FullQuickCalls
    body = '{"robot": ' + PLANAR + ', "params": {"pose": [90, 60, 0]}}'
    with TestClient(app, base_url="http://localhost") as client:
        r = client.post("/v1/ik", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 429 and r.json()["error"] == "no slot"
        assert r.headers["retry-after"] == "3" and r.json()["detail"][0]["type"] == "busy"
        app.dependency_overrides.clear()
        r = client.post("/v1/ik", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 200 and r.json()["status"] == "ok"


def test_robot_checks_run_once_off_the_event_loop(tmp_path, monkeypatch):
    """FastAPI parses the body on its event loop; the checks against the robot (an FK
    formulation built: milliseconds) run once, in the threadpool of a sync dependency,
    and a refusal is the 422 the body's validation gives."""
    import asyncio
    import json

    from certsolve.jobs.kinds.fk import FkParams, TrackParams

    on_loop = []

    def spy(original):
        def check_robot(self, robot, memo=None):
            try:
                asyncio.get_running_loop()
                on_loop.append(True)
            except RuntimeError:
                on_loop.append(False)
            return original(self, robot, memo)

        return check_robot

    monkeypatch.setattr(FkParams, "check_robot", spy(FkParams.check_robot))
    monkeypatch.setattr(TrackParams, "check_robot", spy(TrackParams.check_robot))
    robot = json.loads(PLANAR)
    app = create_app(ServiceSettings(data_dir=tmp_path, workers=0))
    with TestClient(app, base_url="http://localhost") as client:
        r = client.post("/v1/jobs", json={"kind": "fk", "robot": robot, "params": {"u": [0] * 4}})
        assert r.status_code == 202 and on_loop == [False]
        r = client.post("/v1/jobs", json={"kind": "fk", "robot": robot, "params": {"u": [0] * 3}})
        assert r.status_code == 422 and on_loop == [False, False]
        assert r.json()["detail"] == [
            {
                "field": "params.u",
                "loc": ["body", "params", "u"],
                "msg": "expected 4 values (one per wire), got 3",
                "type": "value_error",
            }
        ]
        body = {"robot": robot, "params": {"u": [0] * 3, "near_pose": [90, 60, 0]}}
        r = client.post("/v1/fk/track", json=body)
        assert r.status_code == 422 and "params.u" in {d["field"] for d in r.json()["detail"]}
        assert on_loop == [False, False, False]
