"""The web page, the bundled robots and the pictures of finished jobs, in-process.

Jobs are run in the test process by the worker's own :func:`run_job` (no worker processes),
so a picture is drawn from exactly what a worker stores.  The browser test of the page is
``test_web_browser.py`` (slow).
"""

import json
import os
import re
import shutil
import subprocess
import sys
from fnmatch import fnmatch
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from certsolve.api.app import create_app
from certsolve.api.routers.pages import STATIC
from certsolve.jobs import ServiceSettings
from certsolve.jobs.worker import run_job

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "examples/robots"
PLANAR = json.loads((ROBOTS / "planar.json").read_text())
KRUT3 = json.loads((ROBOTS / "krut-3.json").read_text())
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PNG = b"\x89PNG\r\n\x1a\n"
BIG_MEMORY = {"memory_mb": 65536}  # run_job limits the address space of the test process


@pytest.fixture
def app(tmp_path):
    settings = ServiceSettings(data_dir=tmp_path / "data", workers=0, max_memory_mb=65536)
    return create_app(settings)


@pytest.fixture
def client(app):
    with TestClient(app, base_url="http://localhost") as c:
        yield c


def submit(client, job) -> str:
    r = client.post("/v1/jobs", json={**job, "limits": BIG_MEMORY})
    assert r.status_code == 202, r.text
    return r.json()["id"]


def run_queued(app) -> None:
    """Run every queued job here, as a worker would."""
    service = app.state.service
    while (claimed := service.store.claim(os.getpid())) is not None:
        job, lease = claimed
        run_job(service.store, job, lease, service.settings)


# -- the page --------------------------------------------------------------------------------------
def test_page_and_its_assets(client):
    r = client.get("/")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    assets = re.findall(r'(?:src|href)="(static/[^"]+)"', r.text)
    assert sorted(assets) == ["static/app.js", "static/style.css"]
    for path, kind in (("/static/app.js", "javascript"), ("/static/style.css", "css")):
        a = client.get(path)
        assert a.status_code == 200 and kind in a.headers["content-type"], path
        assert a.content == (STATIC / path.rsplit("/", 1)[1]).read_bytes()
    for bad in ("/static/nothere.js", "/static/index.html", "/static/..%2Fapp.py"):
        r = client.get(bad)
        assert r.status_code == 404 and "error" in r.json(), bad


def test_page_works_offline():
    """No CDN, no external font or script: every URL the page loads is relative (the SVG
    namespace, a name that is never loaded, is the one absolute URL it may write)."""
    for name in ("index.html", "app.js", "style.css"):
        text = (STATIC / name).read_text().replace('"http://www.w3.org/2000/svg"', "")
        assert not re.search(r"https?://|//cdn|@import", text), name


def test_page_files_are_package_data():
    """``pip install .`` (not editable) ships every file of api/static: setup.py's globs."""
    text = (ROOT / "setup.py").read_text()
    globs = re.findall(r'"(\*\.\w+)"', re.search(r'"certsolve\.api\.static": \[(.*?)\]', text)[1])
    files = sorted(p.name for p in STATIC.iterdir())
    assert files and all(any(fnmatch(f, g) for g in globs) for f in files), (files, globs)


def test_page_script_parses():
    """A syntax error would leave the page blank; the browser test is opt-in, node is quick."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed: the script's syntax is checked by the browser test")
    r = subprocess.run([node, "--check", str(STATIC / "app.js")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_page_is_not_in_the_openapi_schema_but_pictures_are(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert "/" not in paths and not any(p.startswith("/static") for p in paths)
    for p in ("poses/{index}.png", "poses.png", "map.png", "paving.png"):
        op = paths[f"/v1/jobs/{{job_id}}/{p}"]["get"]
        assert "image/png" in op["responses"]["200"]["content"]
        assert {"404", "409", "501"} <= set(op["responses"])
    assert "/v1/robots" in paths and "/v1/robots/{name}" in paths


def test_api_reference_pages_load_only_local_files(client):
    """/docs and /redoc (Swagger UI, ReDoc) and every file they load come from the service,
    by relative URLs: nothing from a CDN."""
    for page, viewer in (("/docs", "swagger-ui-bundle.js"), ("/redoc", "redoc.standalone.js")):
        r = client.get(page)
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
        assert not re.search(r"https?://|//cdn|@import|<script>", r.text), page
        urls = re.findall(r'(?:src|href|spec-url)="([^"]+)"', r.text)
        assert f"static/docs/{viewer}" in urls, urls
        for url in urls:
            assert not url.startswith(("/", "http")) and ":" not in url, url
            a = client.get("/" + url)
            assert a.status_code == 200 and len(a.content) > 100, url
        assert "static/swagger-init.js" in urls or page == "/redoc"
    schema = client.get("/openapi.json").json()
    assert "/v1/jobs" in schema["paths"]
    assert client.get("/static/docs/nothere.js").status_code == 404
    assert client.get("/static/docs/..%2F..%2Fcore.py").status_code == 404


# -- the bundled robots ----------------------------------------------------------------------------
def test_bundled_robots_are_the_example_files(client):
    """Served from certsolve.robot.presets, they must equal examples/robots/*.json."""
    robots = client.get("/v1/robots").json()["robots"]
    assert sorted(r["name"] for r in robots) == sorted(p.stem for p in ROBOTS.glob("*.json"))
    for r in robots:
        spec = client.get(r["url"]).json()
        assert spec == json.loads((ROBOTS / f"{r['name']}.json").read_text()), r["name"]
        assert (r["dof"], r["wires"]) == (spec["dof"], len(spec["wires"]))
    r = client.get("/v1/robots/no-such-robot")
    assert r.status_code == 404 and "planar" in r.json()["error"]


# -- pictures --------------------------------------------------------------------------------------
def test_fk_pose_pictures(app, client):
    job_id = submit(
        client,
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.8, 1.8, -2.5, -3.6], "tau_max": 60}},
    )
    r = client.get(f"/v1/jobs/{job_id}/poses/0.png")
    assert r.status_code == 409 and "queued" in r.json()["error"]
    run_queued(app)
    result = client.get(f"/v1/jobs/{job_id}/result").json()
    n = len(result["solutions"])
    assert result["status"] == "complete" and n == 2
    for k in range(n):
        r = client.get(f"/v1/jobs/{job_id}/poses/{k}.png")
        assert r.status_code == 200 and r.headers["content-type"] == "image/png"
        assert r.content.startswith(PNG)
    assert client.get(f"/v1/jobs/{job_id}/poses.png").content.startswith(PNG)
    # kept in the data directory: a second request does not draw again
    cached = app.state.service.settings.data_dir / "pictures" / "v1" / job_id / "pose-0.png"
    stamp = cached.stat().st_mtime_ns
    assert client.get(f"/v1/jobs/{job_id}/poses/0.png").content == cached.read_bytes()
    assert cached.stat().st_mtime_ns == stamp
    # what does not exist
    r = client.get(f"/v1/jobs/{job_id}/poses/{n}.png")
    assert r.status_code == 404 and f"has {n} pose(s)" in r.json()["error"]
    r = client.get(f"/v1/jobs/{job_id}/map.png")
    assert r.status_code == 404 and "fk job" in r.json()["error"]
    assert client.get("/v1/jobs/nosuchjob/poses/0.png").status_code == 404
    assert client.get(f"/v1/jobs/{job_id}/poses/-1.png").status_code == 422


def test_map_and_paving_pictures(app, client):
    grid = {"grid": [-90, 90, -100, 50], "nx": 15, "ny": 13}
    map_id = submit(client, {"kind": "isotropic-map", "robot": KRUT3, "params": grid})
    paving = {"min_force": 100, "box": [[-90, 90], [-100, 50]], "eps": 10}
    ws_id = submit(client, {"kind": "workspace", "robot": KRUT3, "params": paving})
    solve_id = submit(client, {"kind": "solve", "system": CIRCLE})
    run_queued(app)
    for job_id, name in ((map_id, "map"), (ws_id, "paving")):
        r = client.get(f"/v1/jobs/{job_id}/{name}.png")
        assert r.status_code == 200 and r.content.startswith(PNG), r.text[:200]
    assert client.get(f"/v1/jobs/{map_id}/paving.png").status_code == 404
    r = client.get(f"/v1/jobs/{solve_id}/poses/0.png")
    assert r.status_code == 404 and "solve job" in r.json()["error"]


def test_a_job_without_result_has_no_picture(client):
    job_id = submit(client, {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0]}})
    assert client.delete(f"/v1/jobs/{job_id}").json()["status"] == "cancelled"
    r = client.get(f"/v1/jobs/{job_id}/poses.png")
    assert r.status_code == 409 and "no result" in r.json()["error"]


def test_pictures_without_matplotlib_name_the_extra(app, client, monkeypatch):
    job_id = submit(client, {"kind": "solve", "system": CIRCLE})
    grid = {"grid": [-9, 9, -9, 9], "nx": 3, "ny": 3}
    map_id = submit(client, {"kind": "isotropic-map", "robot": KRUT3, "params": grid})
    run_queued(app)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    r = client.get(f"/v1/jobs/{map_id}/map.png")
    assert r.status_code == 501
    extra = "a picture needs the 'plot' extra: pip install 'certsolve[plot]'"
    assert r.json()["error"] == extra
    assert client.get(f"/v1/jobs/{job_id}/map.png").status_code == 404  # checked first


def test_a_result_without_what_the_picture_needs_is_404(app, client):
    """A map stored without its values (as ``to_dict(values=False)`` writes it)."""
    from certsolve.jobs.status import JobStatus

    grid = {"grid": [-9, 9, -9, 9], "nx": 3, "ny": 3}
    map_id = submit(client, {"kind": "isotropic-map", "robot": KRUT3, "params": grid})
    store = app.state.service.store
    job, lease = store.claim(os.getpid())
    result = {"robot": "krut-3", "dof": 2, "xs": [-9, 0, 9], "ys": [-9, 0, 9], "summary": {}}
    assert store.finish(job.id, lease, JobStatus.DONE, result=json.dumps(result))
    r = client.get(f"/v1/jobs/{map_id}/map.png")
    assert r.status_code == 404 and "cannot be drawn" in r.json()["error"]
