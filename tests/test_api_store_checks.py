"""A damaged, truncated or foreign job store: ``serve`` refuses it with one ``error:`` line
naming the file, and ``/healthz`` reports a store that fails its check."""

import json
import sqlite3

import pytest
from fastapi.testclient import TestClient
from test_service_e2e import free_port

from certsolve.api.app import create_app
from certsolve.cli import main as cli_main
from certsolve.jobs import ServiceSettings
from certsolve.jobs.store import JobStore, NewJob, StoreError


def filled_store(path, n=300):
    """A store of ``n`` queued jobs (a few hundred KiB), closed."""
    store = JobStore(path)
    request = json.dumps({"kind": "sleep", "pad": "x" * 2000})
    store.add(NewJob(kind="sleep", request=request, limits={}, max_attempts=1) for _ in range(n))
    store.close()
    return path


def overwrite_inside(path, at=20 * 4096, size=3000):
    """Bytes overwritten inside the jobs table's pages (the file keeps its size)."""
    data = bytearray(path.read_bytes())
    assert len(data) > at + size
    data[at : at + size] = b"A" * size
    path.write_bytes(bytes(data))


def damaged(tmp_path):
    overwrite_inside(filled_store(tmp_path / "jobs.sqlite3"))


def truncated(tmp_path):
    path = filled_store(tmp_path / "jobs.sqlite3")
    path.write_bytes(path.read_bytes()[:5000])


def foreign(tmp_path):
    con = sqlite3.connect(tmp_path / "jobs.sqlite3")
    con.execute("CREATE TABLE people (name TEXT)")
    con.commit()
    con.close()


def not_sqlite(tmp_path):
    (tmp_path / "jobs.sqlite3").write_text("name,age\nada,36\n" * 100)


@pytest.mark.parametrize("spoil", [damaged, truncated, foreign, not_sqlite])
def test_serve_refuses_a_bad_store_in_one_line(tmp_path, capsys, spoil):
    data = tmp_path / "data"
    data.mkdir()
    spoil(data)
    before = (data / "jobs.sqlite3").read_bytes()
    argv = ["serve", "--data-dir", str(data), "--port", str(free_port()), "--workers", "0"]
    assert cli_main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert str(data / "jobs.sqlite3") in err[0]
    assert "damaged" in err[0] or "not a certsolve job store" in err[0], err
    if spoil in (foreign, not_sqlite):
        assert (data / "jobs.sqlite3").read_bytes() == before  # nothing written to it


def test_a_foreign_database_is_not_written_to(tmp_path):
    foreign(tmp_path)
    with pytest.raises(StoreError, match="tables people"):
        JobStore(tmp_path / "jobs.sqlite3")
    con = sqlite3.connect(tmp_path / "jobs.sqlite3")
    tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    con.close()
    assert tables == {"people"}


def test_a_sound_store_passes_its_check(tmp_path):
    store = JobStore(filled_store(tmp_path / "jobs.sqlite3", n=20))
    assert store.check() is None
    store.close()


def test_healthz_reports_a_damaged_store(tmp_path):
    """Reads of a few rows (the counts) still work on this file: only the check sees it."""
    data = tmp_path / "data"
    data.mkdir()
    damaged(data)
    app = create_app(ServiceSettings(data_dir=data, workers=0))
    with TestClient(app, base_url="http://localhost") as client:
        r = client.get("/healthz")
        assert r.status_code == 503, r.text
        assert r.json()["error"].startswith("the job store is failing: ")
        assert "malformed" in r.json()["error"]
        health = app.state.service.health()
        assert health["status"] == "failing" and health["store"]["ok"] is False


def test_healthz_is_ok_on_a_sound_store(tmp_path):
    settings = ServiceSettings(data_dir=tmp_path / "data", workers=0)
    with TestClient(create_app(settings), base_url="http://localhost") as client:
        r = client.get("/healthz")
        assert r.status_code == 200 and r.json()["status"] == "ok"
        assert r.json()["store"] == {"ok": True, "error": None}
