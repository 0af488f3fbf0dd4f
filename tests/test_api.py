"""The HTTP API in-process (no workers): validation, limits, listing, cancellation, errors."""

import copy
import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from certsolve.api.app import create_app
from certsolve.jobs import ServiceSettings

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())


def make_settings(tmp_path, **kw):
    base = dict(
        data_dir=tmp_path / "data",
        workers=0,
        max_body_bytes=300_000,
        max_batch=20,
        max_queued=50,
        max_timeout=100.0,
        default_timeout=10.0,
    )
    base.update(kw)
    return ServiceSettings(**base)


@pytest.fixture
def client(tmp_path):
    app = create_app(make_settings(tmp_path))
    with TestClient(app, base_url="http://localhost") as c:
        yield c


def robot(**changes):
    r = copy.deepcopy(PLANAR)
    r.update(changes)
    return r


def detail_fields(resp):
    assert resp.status_code == 422, resp.text
    body = resp.json()
    assert isinstance(body["error"], str) and body["error"]
    return {d["field"]: d["msg"] for d in body["detail"]}


# -- submitting and reading -------------------------------------------------------------------
def test_submit_get_list_cancel(client):
    r = client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE, "params": {"eps": 1e-9}})
    assert r.status_code == 202
    job = r.json()
    assert job["status"] == "queued" and job["url"].endswith("/v1/jobs/" + job["id"])
    assert r.headers["location"] == job["url"]
    rec = client.get(f"/v1/jobs/{job['id']}").json()
    assert rec["status"] == "queued" and rec["kind"] == "solve" and rec["result"] is None
    assert rec["limits"] == {"timeout": 10.0, "max_boxes": 50_000_000, "memory_mb": 4096}
    assert rec["progress"] is None and rec["attempts"] == 0
    # no result yet
    r = client.get(f"/v1/jobs/{job['id']}/result")
    assert r.status_code == 409 and "queued" in r.json()["error"]
    # a queued job is cancelled at once
    r = client.delete(f"/v1/jobs/{job['id']}")
    assert r.status_code == 200 and r.json()["status"] == "cancelled"
    assert client.delete(f"/v1/jobs/{job['id']}").status_code == 200  # idempotent
    assert client.get("/v1/jobs/doesnotexist").status_code == 404
    assert client.delete("/v1/jobs/doesnotexist").status_code == 404
    assert client.get("/v1/jobs/bad id!").status_code in (404, 422)


def test_pagination_and_status_filter(client):
    ids = []
    for _ in range(5):
        ids.append(client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE}).json()["id"])
    client.delete(f"/v1/jobs/{ids[1]}")
    seen, cursor = [], None
    while True:
        q = "/v1/jobs?limit=2" + (f"&cursor={cursor}" if cursor else "")
        page = client.get(q).json()
        seen += [j["id"] for j in page["items"]]
        assert all("result" not in j for j in page["items"])
        cursor = page["next_cursor"]
        if cursor is None:
            break
    assert seen == ids[::-1]
    page = client.get("/v1/jobs?status=cancelled").json()
    assert [j["id"] for j in page["items"]] == [ids[1]]
    page = client.get("/v1/jobs?status=queued&kind=solve&limit=500").json()
    assert len(page["items"]) == 4 and page["next_cursor"] is None
    assert client.get("/v1/jobs?status=nonsense").status_code == 422
    assert client.get("/v1/jobs?cursor=abc").status_code == 422
    assert client.get("/v1/jobs?limit=0").status_code == 422
    r = client.get("/v1/jobs?kind=fkk")  # a typo is refused, not an empty list
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "kind"]
    assert "fk" in r.json()["error"]


def test_batch_forms(client):
    jobs = [{"kind": "solve", "system": CIRCLE}, {"kind": "solve", "system": CIRCLE}]
    r = client.post("/v1/jobs/batch", json={"jobs": jobs})
    assert r.status_code == 202
    b = r.json()
    assert len(b["ids"]) == 2
    status = client.get(f"/v1/batches/{b['batch']}").json()
    assert status["total"] == 2 and status["counts"]["queued"] == 2 and not status["finished"]
    listed = client.get(f"/v1/jobs?batch={b['batch']}").json()["items"]
    assert {j["id"] for j in listed} == set(b["ids"])
    # one robot, many control vectors
    sweep = {"kind": "fk", "robot": PLANAR, "params": [{"u": [0, 0, 0, i]} for i in range(5)]}
    r = client.post("/v1/jobs/batch", json=sweep)
    assert r.status_code == 202 and len(r.json()["ids"]) == 5
    # the bad item is named, nothing is queued
    before = client.get("/healthz").json()["jobs"]["queued"]
    sweep["params"][3] = {"u": [1, 2]}
    fields = detail_fields(client.post("/v1/jobs/batch", json=sweep))
    assert "params.3.u" in fields
    fields = detail_fields(
        client.post("/v1/jobs/batch", json={"jobs": [jobs[0], {"kind": "solve", "system": "x"}]})
    )
    assert "jobs.1.system" in fields
    assert client.get("/healthz").json()["jobs"]["queued"] == before
    assert client.get("/v1/batches/nothere").status_code == 404
    # neither form, both forms, empty
    assert client.post("/v1/jobs/batch", json={}).status_code == 422
    assert client.post("/v1/jobs/batch", json={"jobs": jobs, "kind": "fk"}).status_code == 422
    assert client.post("/v1/jobs/batch", json={"jobs": []}).status_code == 422


# -- bad input ------------------------------------------------------------------------------------
def test_robot_errors_name_the_field(client):
    bad = robot()
    bad["wires"][3]["tau"] = [5, 1]
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "fk", "robot": bad, "params": {"u": [0] * 4}})
    )
    assert fields == {"robot.wires.3.tau": "tau_min must be <= tau_max"}
    bad = robot()
    bad["wires"][0]["base"] = [1, 2, 3]
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "ik", "robot": bad, "params": {"pose": [1, 2]}})
    )
    assert "robot.wires.0.base" in fields
    bad = robot()
    del bad["wires"][2]["tau"]
    assert "robot.wires.2.tau" in detail_fields(
        client.post("/v1/jobs", json={"kind": "fk", "robot": bad, "params": {"u": [0] * 4}})
    )
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "fk", "robot": PLANAR, "params": {"u": [0] * 3}})
    )
    assert fields == {"params.u": "expected 4 values (one per wire), got 3"}
    fields = detail_fields(
        client.post(
            "/v1/jobs", json={"kind": "ik", "robot": PLANAR, "params": {"pose": [1, 2, 3, 4]}}
        )
    )
    assert "params.pose" in fields
    # extra fields are refused, as in robot files
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "solve", "system": CIRCLE, "params": {"epz": 1}})
    )
    assert "params.epz" in fields


def test_minibex_errors_carry_line_and_column(client):
    text = "Variables\n  x in [0, 1];\nConstraints\n  x^2 = ;\nend\n"
    fields = detail_fields(client.post("/v1/jobs", json={"kind": "solve", "system": text}))
    assert fields["system"].startswith("line 4, column 9:")
    deep = "Variables\n x in [0,1];\nConstraints\n" + "(" * 5000 + "x" + ")" * 5000 + " = 0;\nend"
    fields = detail_fields(client.post("/v1/jobs", json={"kind": "solve", "system": deep}))
    assert "system" in fields


def test_unknown_kind_and_bad_values(client):
    r = client.post("/v1/jobs", json={"kind": "teleport", "robot": PLANAR})
    assert r.status_code == 422 and "teleport" in r.json()["error"]
    assert client.post("/v1/jobs", json={"system": CIRCLE}).status_code == 422
    assert client.post("/v1/jobs", json=[1, 2]).status_code == 422
    # NaN / Infinity (accepted by Python's JSON parser) are refused, never echoed back
    for raw in (b'{"kind":"solve","system":"x","params":{"eps":NaN}}', b'{"kind": Infinity}'):
        r = client.post("/v1/jobs", content=raw, headers={"content-type": "application/json"})
        assert r.status_code == 422
        json.loads(r.text)  # strict JSON
    r = client.post("/v1/jobs", content=b"{nope", headers={"content-type": "application/json"})
    assert r.status_code == 400 and "not valid JSON" in r.json()["error"]
    # the hidden test kind is off by default
    assert client.post("/v1/jobs", json={"kind": "sleep"}).status_code == 422


def test_limits_and_sizes(client):
    fields = detail_fields(
        client.post(
            "/v1/jobs", json={"kind": "solve", "system": CIRCLE, "params": {"timeout": 1e6}}
        )
    )
    assert fields == {"params.timeout": "at most 100 s on this server"}
    fields = detail_fields(
        client.post(
            "/v1/jobs", json={"kind": "solve", "system": CIRCLE, "limits": {"memory_mb": 10}}
        )
    )
    assert "limits.memory_mb" in fields
    # too many wires: the robot schema caps at 32
    big = robot(domain=None)
    big["wires"] = big["wires"] * 9
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "fk", "robot": big, "params": {"u": [0] * 36}})
    )
    assert "robot.wires" in fields and "32" in fields["robot.wires"]
    # enormous domains and grids
    huge = robot()
    huge["domain"] = {"points": [[-1e300, 1e300], [0, 1]]}
    fields = detail_fields(
        client.post("/v1/jobs", json={"kind": "fk", "robot": huge, "params": {"u": [0] * 4}})
    )
    assert fields["robot.domain.points.0.0"] == "must be greater than or equal to -1000000"
    grid = {"grid": [0, 1, 0, 1], "nx": 2000, "ny": 2000}
    r = client.post("/v1/jobs", json={"kind": "isotropic-map", "robot": PLANAR, "params": grid})
    assert r.status_code == 422 and "at most" in r.json()["error"]
    # over-long system text, body size, batch size
    fields = detail_fields(client.post("/v1/jobs", json={"kind": "solve", "system": "x" * 200_001}))
    assert "200000 characters" in fields["system"]
    r = client.post("/v1/jobs", json={"kind": "solve", "system": "x" * 300_001})
    assert r.status_code == 413 and "too large" in r.json()["error"]
    chunks = iter([b'{"kind": "solve", "system": "', b"x" * 200_000, b"x" * 200_000, b'"}'])
    r = client.post("/v1/jobs", content=chunks, headers={"content-type": "application/json"})
    assert r.status_code == 413  # chunked, no Content-Length
    r = client.post("/v1/jobs", json={"kind": "solve", "system": "/" * 150_000})
    assert r.status_code == 422  # not a system, though small enough
    r = client.post("/v1/jobs/batch", json={"jobs": [{"kind": "solve", "system": CIRCLE}] * 21})
    assert r.status_code == 413 and "at most 20" in r.json()["error"]


def test_queue_limit_gives_429(tmp_path):
    app = create_app(make_settings(tmp_path, max_queued=3))
    with TestClient(app, base_url="http://localhost") as c:
        job = {"kind": "solve", "system": CIRCLE}
        assert c.post("/v1/jobs/batch", json={"jobs": [job] * 3}).status_code == 202
        r = c.post("/v1/jobs", json=job)
        assert r.status_code == 429 and "queue" in r.json()["error"]


def test_health_kinds_docs(client):
    h = client.get("/healthz").json()
    assert h["status"] == "ok" and h["workers"]["configured"] == 0
    kinds = {k["kind"]: k for k in client.get("/v1/kinds").json()["kinds"]}
    assert set(kinds) == {
        "solve",
        "fk",
        "ik",
        "ik-sweep",
        "isotropic-map",
        "workspace",
        "design",
        "trajectory",
    }
    assert kinds["solve"]["available"] and kinds["solve"]["input"] == "system"
    assert "eps" in kinds["solve"]["params"]["properties"]
    assert client.get("/docs").status_code == 200
    schema = client.get("/openapi.json").json()
    assert "/v1/jobs" in schema["paths"] and "/v1/jobs/{job_id}" in schema["paths"]
    r = client.get("/nowhere")
    assert r.status_code == 404 and r.json()["error"] == "no route GET /nowhere"
    assert r.json()["detail"][0]["field"] == "path"
    assert client.put("/v1/jobs").status_code == 405


def _has(module, name):
    try:
        mod = __import__(module, fromlist=[name])
        return hasattr(mod, name)
    except Exception:
        return False


def test_quick_endpoints(client):
    calls = [
        (
            "/v1/ik",
            {"robot": PLANAR, "params": {"pose": [90, 60, 0]}},
            "certsolve.kinematics",
            "inverse_kinematics",
        ),
        (
            "/v1/isotropic",
            {"robot": PLANAR, "params": {"pose": [90, 60, 0]}},
            "certsolve.force",
            "isotropic_force",
        ),
        (
            "/v1/fk/track",
            {"robot": PLANAR, "params": {"u": [0] * 4, "near_pose": [90, 60, 0]}},
            "certsolve.kinematics",
            "track",
        ),
    ]
    for path, body, module, name in calls:
        r = client.post(path, json=body)
        if _has(module, name):
            assert r.status_code in (200, 422), r.text
        else:
            assert r.status_code == 501 and "not available" in r.json()["error"]
        bad = copy.deepcopy(body)
        bad["robot"]["wires"][1]["tau"] = [3, 2]
        assert "robot.wires.1.tau" in detail_fields(client.post(path, json=bad))
    fields = detail_fields(
        client.post("/v1/fk/track", json={"robot": PLANAR, "params": {"u": [0], "near_pose": [1]}})
    )
    assert "params.near_pose" in fields


# -- never a 5xx --------------------------------------------------------------------------------
_json = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=20,
)
_fields = st.fixed_dictionaries(
    {},
    optional={
        "kind": st.sampled_from(["solve", "fk", "ik", "isotropic-map", "workspace", "x"]) | _json,
        "robot": st.just(PLANAR) | _json,
        "system": st.just(CIRCLE) | st.text(max_size=60) | _json,
        "params": _json,
        "limits": _json,
        "jobs": st.lists(_json, max_size=3),
    },
)


@pytest.fixture(scope="module")
def shared_client(tmp_path_factory):
    app = create_app(make_settings(tmp_path_factory.mktemp("garbage"), max_queued=10_000))
    with TestClient(app, raise_server_exceptions=False, base_url="http://localhost") as c:
        yield c


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    path=st.sampled_from(["/v1/jobs", "/v1/jobs/batch", "/v1/ik", "/v1/isotropic", "/v1/fk/track"]),
    body=_fields | _json,
)
def test_garbage_never_gives_5xx(shared_client, path, body):
    r = shared_client.post(
        path, content=json.dumps(body), headers={"content-type": "application/json"}
    )
    assert r.status_code < 500 or r.status_code == 501, r.text
    assert "error" in r.json() or r.status_code in (200, 202)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(raw=st.binary(max_size=200), path=st.sampled_from(["/v1/jobs", "/v1/jobs/batch"]))
def test_raw_bytes_never_give_5xx(shared_client, raw, path):
    r = shared_client.post(path, content=raw, headers={"content-type": "application/json"})
    assert r.status_code < 500, r.text
