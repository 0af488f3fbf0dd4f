"""One error contract: every error answer is ``{"error", "detail": [{loc, field, msg,
type}, ...]}`` naming what is at fault, and the OpenAPI schema lists it."""

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from certsolve.api.app import create_app
from certsolve.jobs import ServiceSettings

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = ServiceSettings(
        data_dir=tmp_path_factory.mktemp("errors"), workers=0, max_body_bytes=100_000, max_queued=2
    )
    with TestClient(
        create_app(settings), raise_server_exceptions=False, base_url="http://localhost"
    ) as c:
        yield c


def error(resp, status: int) -> list[dict]:
    assert resp.status_code == status, resp.text
    body = resp.json()
    assert set(body) == {"error", "detail"} and isinstance(body["error"], str)
    assert body["detail"], body
    for d in body["detail"]:
        assert {"loc", "field", "msg", "type"} <= set(d) and isinstance(d["loc"], list)
    return body["detail"]


@pytest.mark.parametrize(
    "raw, words",
    [
        (b'{"kind": "solve",\n "system": }', "not valid JSON at line 2, column"),
        (b'{"kind": "\xff"}', "not UTF-8"),
        (b"[" * 100_000 + b"]" * 100_000, None),  # too large here: 413
        (b"[" * 50_000 + b"]" * 50_000, "nested too deeply"),
        (b"", None),
    ],
)
def test_unparseable_bodies(client, raw, words):
    for path in ("/v1/jobs", "/v1/jobs/batch", "/v1/ik", "/v1/admin/purge"):
        r = client.post(path, content=raw, headers=JSON)
        if len(raw) > 100_000:
            (d,) = error(r, 413)
            assert d["field"] == "body" and d["type"] == "too_large"
        elif not raw:
            assert error(r, 422)[0]["field"] in ("", "body")  # a missing body is invalid
        else:
            (d,) = error(r, 400)
            assert d["field"] == "body" and words in d["msg"], d
    (d,) = error(client.post("/v1/jobs", content=b'{"a":\n  x}', headers=JSON), 400)
    assert (d["line"], d["column"]) == (2, 3)


def test_not_found_conflict_validation_and_full_queue(client):
    (d,) = error(client.get("/v1/jobs/nope"), 404)
    assert d["field"] == "job_id" and d["loc"] == ["path", "job_id"]
    (d,) = error(client.get("/v1/batches/nope"), 404)
    assert d["field"] == "batch_id"
    (d,) = error(client.get("/v1/nowhere"), 404)
    assert d["field"] == "path"
    error(client.put("/v1/jobs"), 405)
    assert error(client.get("/v1/jobs?limit=0"), 422)[0]["field"] == "limit"
    assert error(client.get("/v1/jobs/bad id!"), 422)[0]["field"] == "job_id"
    job_id = client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE}).json()["id"]
    (d,) = error(client.get(f"/v1/jobs/{job_id}/result"), 409)
    assert d["field"] == "job_id" and "queued" in d["msg"]
    client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE})
    r = client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE})
    (d,) = error(r, 429)
    assert r.headers["retry-after"].isdigit() and d["type"] == "queue_full"


def test_minibex_errors_give_line_and_column(client):
    text = "Variables\n  x in [0, 1];\nConstraints\n  x^2 = ;\nend\n"
    r = client.post("/v1/jobs", json={"kind": "solve", "system": text})
    (d,) = error(r, 422)
    assert d["field"] == "system" and (d["line"], d["column"]) == (4, 9)
    assert r.json()["error"].startswith("system: line 4, column 9:")


def test_openapi_lists_the_errors(client):
    paths = client.get("/openapi.json").json()["paths"]
    for path, ops in paths.items():
        for method, op in ops.items():
            codes = set(op["responses"])
            if path.startswith("/v1/"):
                assert {"401", "429"} <= codes, (method, path, codes)
            if op.get("parameters") or op.get("requestBody"):
                assert "422" in codes, (method, path, codes)
            if method == "post" and path.startswith("/v1/"):
                assert {"400", "413"} <= codes, (method, path, codes)
            if "{job_id}" in path or "{batch_id}" in path:
                assert "404" in codes
            for code, resp in op["responses"].items():
                if code.startswith(("4", "5")):
                    ref = resp["content"]["application/json"]["schema"]["$ref"]
                    assert ref.endswith("/ErrorBody"), (method, path, code)


def test_a_body_nested_100000_deep(tmp_path):
    """The issue's case, within the default 16 MiB body limit: a 400 naming the body."""
    with TestClient(
        create_app(ServiceSettings(data_dir=tmp_path, workers=0)), base_url="http://localhost"
    ) as c:
        raw = b"[" * 100_000 + b"]" * 100_000
        (d,) = error(c.post("/v1/jobs", content=raw, headers=JSON), 400)
        assert d["field"] == "body" and "nested too deeply" in d["msg"]
