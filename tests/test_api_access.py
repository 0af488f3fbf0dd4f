"""Access control in-process: bearer tokens, job ownership, quotas, purge, the token table."""

import json
import logging
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from certsolve.api.app import create_app
from certsolve.jobs import ServiceSettings
from certsolve.jobs.access import AccessError, load_access

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
TOKENS = {
    "alice": {"token": "alice-token-0123456789"},
    "bob": {"token": "bob-token-0123456789ab", "max_queued": 2},
    "ops": {"token": "ops-token-0123456789ab", "admin": True},
    "slow": {"token": "slow-token-0123456789a", "requests_per_minute": 3},
}
JOB = {"kind": "solve", "system": CIRCLE}


def bearer(name: str) -> dict:
    return {"Authorization": f"Bearer {TOKENS[name]['token']}"}


@pytest.fixture
def client(tmp_path):
    access = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    settings = ServiceSettings(data_dir=tmp_path / "data", workers=0, access=access)
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        yield c


def shape(resp, status: int) -> dict:
    """Every error answer has the documented shape."""
    assert resp.status_code == status, resp.text
    body = resp.json()
    assert isinstance(body["error"], str) and body["error"]
    assert body["detail"] and all({"loc", "field", "msg", "type"} <= set(d) for d in body["detail"])
    return body


def test_requests_need_a_valid_token(client):
    body = shape(client.post("/v1/jobs", json=JOB), 401)
    assert body["detail"][0]["field"] == "Authorization"
    r = client.get("/v1/jobs")
    assert r.status_code == 401 and r.headers["www-authenticate"] == 'Bearer realm="certsolve"'
    r = client.get("/v1/jobs", headers={"Authorization": "Bearer not-a-token-at-all"})
    shape(r, 401)
    assert 'error="invalid_token"' in r.headers["www-authenticate"]
    assert "not-a-token" not in r.text  # never echoed
    r = client.get("/v1/jobs", headers={"Authorization": "Basic " + TOKENS["alice"]["token"]})
    shape(r, 401)
    # a body that is not even JSON is refused for want of a token, before it is read
    r = client.post("/v1/jobs", content=b"\xff{", headers={"content-type": "application/json"})
    shape(r, 401)
    assert client.get("/v1/jobs", headers=bearer("alice")).status_code == 200
    # public: liveness and the documentation
    assert client.get("/healthz").status_code == 200
    assert client.get("/openapi.json").status_code == 200


def test_jobs_belong_to_their_client(client):
    a = client.post("/v1/jobs", json=JOB, headers=bearer("alice")).json()["id"]
    b = client.post("/v1/jobs", json=JOB, headers=bearer("bob")).json()["id"]
    batch = client.post("/v1/jobs/batch", json={"jobs": [JOB]}, headers=bearer("alice")).json()
    # another client: 404 on every route, absent from listings
    for method, path in (
        ("GET", f"/v1/jobs/{a}"),
        ("GET", f"/v1/jobs/{a}/result"),
        ("DELETE", f"/v1/jobs/{a}"),
        ("GET", f"/v1/batches/{batch['batch']}"),
    ):
        body = shape(client.request(method, path, headers=bearer("bob")), 404)
        assert body["detail"][0]["loc"][0] == "path"
    listed = {j["id"] for j in client.get("/v1/jobs", headers=bearer("bob")).json()["items"]}
    assert listed == {b}
    mine = client.get("/v1/jobs", headers=bearer("alice")).json()["items"]
    assert {j["id"] for j in mine} == {a, *batch["ids"]}
    assert {j["owner"] for j in mine} == {"alice"}
    # the owner cancels its own; an admin sees everything
    assert client.delete(f"/v1/jobs/{a}", headers=bearer("alice")).status_code == 200
    every = client.get("/v1/jobs", headers=bearer("ops")).json()["items"]
    assert {j["id"] for j in every} == {a, b, *batch["ids"]}
    assert client.get(f"/v1/jobs/{b}", headers=bearer("ops")).json()["owner"] == "bob"
    assert client.get(f"/v1/batches/{batch['batch']}", headers=bearer("ops")).status_code == 200


def test_quotas_answer_429_with_retry_after(client):
    for _ in range(2):
        assert client.post("/v1/jobs", json=JOB, headers=bearer("bob")).status_code == 202
    r = client.post("/v1/jobs", json=JOB, headers=bearer("bob"))
    body = shape(r, 429)
    assert "bob has 2 queued jobs" in body["error"] and int(r.headers["retry-after"]) >= 1
    r = client.post("/v1/jobs/batch", json={"jobs": [JOB]}, headers=bearer("bob"))
    assert r.status_code == 429
    # the others are not affected
    assert client.post("/v1/jobs", json=JOB, headers=bearer("alice")).status_code == 202
    # requests per minute
    for _ in range(3):
        assert client.get("/v1/kinds", headers=bearer("slow")).status_code == 200
    r = client.get("/v1/kinds", headers=bearer("slow"))
    shape(r, 429)
    assert 1 <= int(r.headers["retry-after"]) <= 20


def test_purge_is_for_admins(client, tmp_path):
    job_id = client.post("/v1/jobs", json=JOB, headers=bearer("alice")).json()["id"]
    client.delete(f"/v1/jobs/{job_id}", headers=bearer("alice"))  # cancelled: finished
    body = shape(
        client.post("/v1/admin/purge", json={"older_than_days": 0}, headers=bearer("alice")), 403
    )
    assert "admin" in body["error"]
    r = client.post("/v1/admin/purge", json={"older_than_days": 1}, headers=bearer("ops"))
    assert r.status_code == 200 and r.json()["deleted"] == 0  # too recent
    time.sleep(0.01)
    r = client.post("/v1/admin/purge", json={"older_than_days": 0}, headers=bearer("ops"))
    assert r.status_code == 200 and r.json()["deleted"] == 1 and r.json()["wal"] == 0
    assert client.get(f"/v1/jobs/{job_id}", headers=bearer("ops")).status_code == 404
    shape(client.post("/v1/admin/purge", json={"older_than_days": -1}, headers=bearer("ops")), 422)


def test_openapi_declares_the_bearer_scheme(client):
    schema = client.get("/openapi.json").json()
    assert schema["components"]["securitySchemes"]["bearer"]["scheme"] == "bearer"
    assert schema["paths"]["/v1/jobs"]["post"]["security"] == [{"bearer": []}]
    assert "security" not in schema["paths"]["/healthz"]["get"]


def test_tokens_are_never_logged(tmp_path, caplog):
    access = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    assert TOKENS["alice"]["token"] not in repr(access)
    settings = ServiceSettings(data_dir=tmp_path / "d", workers=0, access=access)
    assert TOKENS["alice"]["token"] not in repr(settings)
    caplog.set_level(logging.DEBUG)
    with TestClient(
        create_app(settings), raise_server_exceptions=False, base_url="http://localhost"
    ) as c:
        c.get("/v1/jobs", headers={"Authorization": "Bearer wrong-token-0123456789"})
        c.get("/v1/jobs", headers=bearer("alice"))
        c.post("/v1/jobs", json={"kind": "solve"}, headers=bearer("alice"))
    text = caplog.text
    assert "wrong-token" not in text and TOKENS["alice"]["token"] not in text


def test_token_table_errors_name_the_entry(tmp_path):
    def fails(data) -> str:
        with pytest.raises(AccessError) as info:
            load_access(None, {"CERTSOLVE_TOKENS": json.dumps(data)})
        return str(info.value)

    assert "alice.token" in fails({"alice": {"token": "short"}})
    assert "bob.admin" in fails({"bob": {"token": "x" * 20, "admin": "maybe"}})
    assert "carol.tokn" in fails({"carol": {"tokn": "x" * 20}})
    assert "same token as a" in fails({"a": {"token": "x" * 20}, "b": {"token": "x" * 20}})
    assert "no clients" in fails({})
    assert "client name" in fails({"a b": {"token": "x" * 20}})
    path = tmp_path / "tokens.json"
    path.write_text("{not json")
    with pytest.raises(AccessError, match="invalid JSON at line 1"):
        load_access(path)
    with pytest.raises(AccessError, match="cannot read"):
        load_access(tmp_path / "missing.json")
    assert load_access(None, {}) is None
    table = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    assert table.client_for(TOKENS["ops"]["token"]).admin
    assert table.client_for(TOKENS["ops"]["token"] + "x") is None
    assert table.client_for("") is None and table.client_for(None) is None


def test_without_tokens_everything_is_open(tmp_path):
    settings = ServiceSettings(data_dir=tmp_path / "d", workers=0)
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        job_id = c.post("/v1/jobs", json=JOB).json()["id"]
        assert c.get(f"/v1/jobs/{job_id}").json()["owner"] is None
        r = c.post("/v1/admin/purge", json={"older_than_days": 30})
        assert r.status_code == 200
        assert "securitySchemes" not in c.get("/openapi.json").json().get("components", {})


def test_serve_refuses_an_open_host_without_tokens(tmp_path, capsys, monkeypatch):
    from certsolve.cli import main

    monkeypatch.delenv("CERTSOLVE_TOKENS", raising=False)
    data = str(tmp_path / "d")
    assert main(["serve", "--host", "0.0.0.0", "--port", "0", "--data-dir", data]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --host 0.0.0.0") and "--tokens" in err and "--insecure" in err
    bad = tmp_path / "tokens.json"
    bad.write_text('{"alice": {"token": "short"}}')
    assert main(["serve", "--tokens", str(bad), "--data-dir", data]) == 2
    assert "alice.token" in capsys.readouterr().err
    assert main(["serve", "--keep-days", "0", "--data-dir", data]) == 2
    assert "--keep-days" in capsys.readouterr().err


def test_pictures_belong_to_the_job_owner(client):
    """Another client's job has no pictures either: 404, while its owner gets 409 (no result
    yet: no worker runs in this fixture)."""
    job = {"kind": "fk", "robot": json.loads((ROOT / "examples/robots/planar.json").read_text())}
    job["params"] = {"u": [0, 0, 0, 0]}
    r = client.post("/v1/jobs", json=job, headers=bearer("alice"))
    assert r.status_code == 202, r.text
    url = f"/v1/jobs/{r.json()['id']}/poses/0.png"
    shape(client.get(url, headers=bearer("bob")), 404)
    shape(client.get(url, headers=bearer("alice")), 409)
    shape(client.get(url, headers=bearer("ops")), 409)  # an admin sees every job
    shape(client.get(url), 401)
