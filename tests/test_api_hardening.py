"""What the service does against hostile or careless clients: security headers on every
answer, the Host allow-list of a service without tokens (DNS rebinding), a delay after a
refused token, no query string values in the access log, and slow clients closed (a real
uvicorn with :func:`certsolve.api.server.uvicorn_options`, driven by a raw socket)."""

import json
import logging
import socket
import threading
import time

import pytest
import uvicorn
from fastapi.testclient import TestClient
from test_service_e2e import free_port

from certsolve.api import middleware
from certsolve.api.app import create_app
from certsolve.api.middleware import PAGE_CSP
from certsolve.api.routers.docs import DOCS_CSP
from certsolve.api.server import QueryRedactor, redact_query, uvicorn_options
from certsolve.cli import build_parser
from certsolve.cli.service import _allowed_hosts
from certsolve.jobs import ServiceSettings
from certsolve.jobs.access import load_access

TOKEN = "alice-token-0123456789"
TOKENS = {"alice": {"token": TOKEN}}


def client_for(tmp_path, base_url="http://localhost", **settings):
    s = ServiceSettings(data_dir=tmp_path / "data", workers=0, **settings)
    return TestClient(create_app(s), base_url=base_url)


# -- headers ---------------------------------------------------------------------------------
def test_every_answer_has_the_security_headers(tmp_path):
    tokens = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    settings = ServiceSettings(data_dir=tmp_path, workers=0, access=tokens, max_body_bytes=1000)
    app = create_app(settings)

    @app.get("/v1/boom")
    def boom():
        raise RuntimeError("a bug")

    with TestClient(app, base_url="http://localhost", raise_server_exceptions=False) as c:
        auth = {"Authorization": f"Bearer {TOKEN}"}
        answers = {
            "page": c.get("/"),
            "script": c.get("/static/app.js"),
            "json": c.get("/v1/jobs", headers=auth),
            "422": c.post("/v1/jobs", json={"kind": "fk"}, headers=auth),
            "404": c.get("/v1/jobs/nosuchjob", headers=auth),
            "401": c.get("/v1/jobs"),
            "413": c.post("/v1/jobs", content=b"x" * 2000, headers=auth),
            "docs": c.get("/docs"),
            "schema": c.get("/openapi.json"),
            "500": c.get("/v1/boom", headers=auth),
        }
    for what, r in answers.items():
        assert r.headers["x-content-type-options"] == "nosniff", what
        assert r.headers["x-frame-options"] == "DENY", what
        csp = r.headers["content-security-policy"]
        assert "frame-ancestors 'none'" in csp, what
        assert csp == (DOCS_CSP if what == "docs" else PAGE_CSP), what
    assert answers["413"].status_code == 413 and answers["401"].status_code == 401
    assert answers["500"].status_code == 500


def test_the_page_needs_no_inline_script_or_style():
    """PAGE_CSP allows no inline script or style: the page has none."""
    import re

    from certsolve.api.routers.pages import STATIC

    html = (STATIC / "index.html").read_text()
    assert not re.search(r"<script(?![^>]*\bsrc=)", html) and "<style" not in html
    assert not re.search(r"\sstyle=|\son[a-z]+=", html)
    script = (STATIC / "app.js").read_text()
    assert not re.search(r"innerHTML|\.style\b|setAttribute\(\s*[\"']style|eval\(", script)
    assert "script-src 'self';" in PAGE_CSP and "style-src 'self';" in PAGE_CSP


# -- Host allow-list -----------------------------------------------------------------------
def test_without_tokens_only_loopback_host_names_are_served(tmp_path):
    with client_for(tmp_path) as c:
        for host in ("localhost", "localhost:8000", "127.0.0.1:8000", "[::1]:8000", "LOCALHOST"):
            assert c.get("/v1/jobs", headers={"Host": host}).status_code == 200, host
        for host in ("evil.example", "evil.example:8000", "localhost.evil.example", "127.0.0.2"):
            r = c.get("/v1/jobs", headers={"Host": host})
            assert r.status_code == 400, host
            assert r.json()["detail"][0]["field"] == "Host"
            assert "--allow-host" in r.json()["error"]
        assert c.get("/", headers={"Host": "evil.example"}).status_code == 400


def test_the_allow_list_is_configurable_and_off_with_tokens(tmp_path):
    with client_for(tmp_path / "a", allowed_hosts=("localhost", "box.lan")) as c:
        assert c.get("/v1/jobs", headers={"Host": "box.lan:8000"}).status_code == 200
        assert c.get("/v1/jobs", headers={"Host": "other.lan"}).status_code == 400
    with client_for(tmp_path / "b", allowed_hosts=("*",)) as c:
        assert c.get("/v1/jobs", headers={"Host": "anything"}).status_code == 200
    tokens = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    with client_for(tmp_path / "c", access=tokens) as c:  # the token is the check
        auth = {"Authorization": f"Bearer {TOKEN}", "Host": "box.lan"}
        assert c.get("/v1/jobs", headers=auth).status_code == 200
    env = {"CERTSOLVE_ALLOWED_HOSTS": "a.lan, b.lan"}
    assert ServiceSettings.from_env(env).allowed_hosts == (
        "localhost", "127.0.0.1", "::1", "a.lan", "b.lan",
    )  # fmt: skip


def test_serve_answers_its_own_host_and_the_names_given():
    def hosts(*argv, env=None):
        args = build_parser(["serve"]).parse_args(["serve", *argv])
        return _allowed_hosts(args, env or {})

    assert hosts() == ("localhost", "127.0.0.1", "::1")
    assert hosts("--host", "0.0.0.0", "--allow-host", "Box.lan") == (
        "localhost", "127.0.0.1", "::1", "box.lan",
    )  # fmt: skip
    assert hosts("--host", "10.0.0.5") == ("localhost", "127.0.0.1", "::1", "10.0.0.5")
    assert "c.lan" in hosts(env={"CERTSOLVE_ALLOWED_HOSTS": "c.lan"})


# -- refused tokens wait -----------------------------------------------------------------------
def test_a_refused_token_waits_before_its_401(tmp_path, monkeypatch):
    waits = []
    real_sleep = middleware.asyncio.sleep

    async def sleep(seconds):
        waits.append(seconds)
        await real_sleep(0)

    monkeypatch.setattr(middleware.asyncio, "sleep", sleep)
    tokens = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(TOKENS)})
    with client_for(tmp_path, access=tokens, auth_failure_delay=0.75) as c:
        assert c.get("/v1/jobs", headers={"Authorization": "Bearer wrong"}).status_code == 401
        assert waits == [0.75]
        assert c.get("/v1/jobs", headers={"Authorization": f"Bearer {TOKEN}"}).status_code == 200
        assert c.get("/healthz").status_code == 200
        assert waits == [0.75]  # a valid token, or a public path, does not wait


# -- the access log ----------------------------------------------------------------------------
def test_query_values_are_redacted():
    assert redact_query("/v1/jobs?token=abc&limit=5") == "/v1/jobs?token=...&limit=..."
    assert redact_query("/v1/jobs") == "/v1/jobs"
    assert redact_query("/x?flag&access_token=s3cr3t") == "/x?flag&access_token=..."
    record = logging.LogRecord(
        "uvicorn.access", logging.INFO, "", 0, '%s - "%s %s HTTP/%s" %d',
        ("127.0.0.1:5", "GET", "/v1/jobs?token=s3cr3t", "1.1", 200), None,
    )  # fmt: skip
    assert QueryRedactor().filter(record)
    assert "s3cr3t" not in record.getMessage() and "token=..." in record.getMessage()


class Running:
    """A real uvicorn serving the app in a thread, with ``serve``'s connection options."""

    def __init__(self, settings: ServiceSettings):
        self.port = free_port()
        config = uvicorn.Config(
            create_app(settings),
            host="127.0.0.1",
            port=self.port,
            log_config=None,  # records propagate to pytest's caplog
            log_level="info",
            **uvicorn_options(settings),
        )
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=self.server.run, daemon=True)
        self.thread.start()
        deadline = time.monotonic() + 60
        while not self.server.started:
            assert self.thread.is_alive() and time.monotonic() < deadline, "no server"
            time.sleep(0.05)

    def connect(self) -> socket.socket:
        s = socket.create_connection(("127.0.0.1", self.port), timeout=30)
        return s

    def close(self) -> None:
        self.server.should_exit = True
        self.thread.join(30)


@pytest.fixture
def running(tmp_path):
    settings = ServiceSettings(data_dir=tmp_path / "data", workers=0, request_timeout=0.5)
    r = Running(settings)
    yield r
    r.close()


def read_all(s: socket.socket) -> bytes:
    """Everything until the server closes (socket timeout: 30 s, far past the server's)."""
    out = b""
    while chunk := s.recv(65536):
        out += chunk
    return out


def read_response(s: socket.socket) -> bytes:
    """One response (headers and its Content-Length of body), the connection left open."""
    data = b""
    while b"\r\n\r\n" not in data:
        data += s.recv(65536)
    head, _, body = data.partition(b"\r\n\r\n")
    length = int(next(
        line.split(b":")[1] for line in head.split(b"\r\n")
        if line.lower().startswith(b"content-length:")
    ))  # fmt: skip
    while len(body) < length:
        body += s.recv(65536)
    return head + b"\r\n\r\n" + body


def test_the_access_log_holds_no_token(running, caplog):
    caplog.set_level(logging.INFO, logger="uvicorn.access")
    with running.connect() as s:
        s.sendall(b"GET /healthz?token=s3cr3t-value HTTP/1.1\r\nHost: localhost\r\n"
                  b"Connection: close\r\n\r\n")  # fmt: skip
        assert read_all(s).startswith(b"HTTP/1.1 200")
    logged = [r.getMessage() for r in caplog.records if r.name == "uvicorn.access"]
    assert any("/healthz?token=..." in m for m in logged), logged
    assert "s3cr3t" not in caplog.text


def test_a_half_sent_request_is_closed(running):
    """Headers without their end, then a body shorter than announced: the server closes
    both connections (recv returns b"") long before the test's socket would time out."""
    with running.connect() as s:
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: localhost\r\n")
        assert read_all(s) == b""
    with running.connect() as s:
        s.sendall(
            b"POST /v1/jobs HTTP/1.1\r\nHost: localhost\r\nContent-Type: application/json\r\n"
            b'Content-Length: 100\r\n\r\n{"kind": '
        )
        assert read_all(s) == b""
    with running.connect() as s:  # connected, nothing sent
        assert read_all(s) == b""
    # a whole request on the same server is answered, and its connection kept alive
    with running.connect() as s:
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: localhost\r\n\r\n")
        assert read_response(s).startswith(b"HTTP/1.1 200")
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: localhost\r\n")  # the next one, half
        assert read_all(s) == b""
