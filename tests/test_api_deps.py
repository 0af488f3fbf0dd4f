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
