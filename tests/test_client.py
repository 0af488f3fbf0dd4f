"""certsolve.client.ServiceClient against a stub HTTP server: requests, token, errors, wait.

(The client against the real service is covered by tests/test_service_e2e.py through the
``certsolve submit / status / result / cancel`` commands.)
"""

import json
import socket
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from certsolve.client import ClientError, ServiceClient


class Stub(BaseHTTPRequestHandler):
    """Answers from ``server.replies`` (path -> list of (status, body)); records requests."""

    def _answer(self):
        length = int(self.headers.get("Content-Length") or 0)
        body = json.loads(self.rfile.read(length)) if length else None
        self.server.seen.append((self.command, self.path, dict(self.headers), body))
        queue = self.server.replies.get(self.path) or [(404, {"error": "Not Found"})]
        status, reply = queue.pop(0) if len(queue) > 1 else queue[0]
        data = json.dumps(reply).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    do_GET = do_POST = do_DELETE = _answer

    def log_message(self, *args):
        pass


@pytest.fixture
def stub():
    server = ThreadingHTTPServer(("127.0.0.1", 0), Stub)
    server.seen, server.replies = [], {}
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server
    server.shutdown()
    server.server_close()


def url(server) -> str:
    return f"http://127.0.0.1:{server.server_address[1]}"


def record(status: str, result=None) -> dict:
    return {"id": "j1", "kind": "solve", "status": status, "result": result}


def test_submit_sends_json_and_the_bearer_token(stub):
    stub.replies["/v1/jobs"] = [(202, {"id": "j1", "url": "u", "status": "queued"})]
    client = ServiceClient(url(stub), token="s3cret")
    assert client.submit({"kind": "solve", "system": "x"})["id"] == "j1"
    method, path, headers, body = stub.seen[-1]
    assert (method, path, body) == ("POST", "/v1/jobs", {"kind": "solve", "system": "x"})
    assert headers["Authorization"] == "Bearer s3cret"
    assert headers["Content-Type"] == "application/json"
    # no token: no header
    ServiceClient(url(stub)).submit({"kind": "solve", "system": "x"})
    assert "Authorization" not in stub.seen[-1][2]


def test_paths_and_queries(stub):
    client = ServiceClient(url(stub))
    stub.replies["/v1/jobs?limit=5&status=running"] = [(200, {"items": [], "next_cursor": None})]
    assert client.list(status="running", limit=5)["items"] == []
    stub.replies["/v1/jobs/a%2Fb?result=false"] = [(200, record("queued"))]
    assert client.status("a/b")["status"] == "queued"  # ids are quoted
    stub.replies["/v1/jobs/j1"] = [(200, record("cancelled"))]
    assert client.cancel("j1")["status"] == "cancelled"
    assert stub.seen[-1][0] == "DELETE"


def test_errors_carry_status_and_message(stub):
    client = ServiceClient(url(stub))
    with pytest.raises(ClientError) as info:
        client.job("nope")
    assert info.value.status == 404 and str(info.value) == "service answered 404: Not Found"
    stub.replies["/v1/jobs/j1/result"] = [(409, {"error": "job j1 is queued and has no result"})]
    with pytest.raises(ClientError) as info:
        client.result("j1")
    assert info.value.status == 409 and "has no result" in str(info.value)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(ClientError) as info:
        ServiceClient(f"http://127.0.0.1:{port}", timeout=5).health()
    assert info.value.status is None and "cannot reach" in str(info.value)
    with pytest.raises(ValueError, match="server"):
        ServiceClient("localhost:8000")


def test_wait_polls_until_final(stub):
    stub.replies["/v1/jobs/j1"] = [
        (200, record("queued")),
        (200, record("running")),
        (200, record("done", {"status": "complete"})),
    ]
    rec = ServiceClient(url(stub)).wait("j1", poll=0.01)
    assert rec["status"] == "done" and rec["result"] == {"status": "complete"}
    assert sum(1 for s in stub.seen if s[1] == "/v1/jobs/j1") == 3
    stub.replies["/v1/jobs/j2"] = [(200, {**record("running"), "id": "j2"})]
    with pytest.raises(TimeoutError):
        ServiceClient(url(stub)).wait("j2", poll=0.01, timeout=0.1)


def test_cli_sends_the_token_of_token_file(stub, tmp_path, monkeypatch, capsys):
    from certsolve.cli import main

    stub.replies["/v1/jobs?limit=20"] = [(200, {"items": [], "next_cursor": None})]
    monkeypatch.setenv("CERTSOLVE_TOKEN", "from-the-environment")
    token = tmp_path / "token"
    token.write_text("from-the-file-0123456789\n")
    assert main(["status", "--server", url(stub), "--token-file", str(token)]) == 0
    assert stub.seen[-1][2]["Authorization"] == "Bearer from-the-file-0123456789"
    assert main(["status", "--server", url(stub)]) == 0
    assert stub.seen[-1][2]["Authorization"] == "Bearer from-the-environment"
    assert main(["status", "--server", url(stub), "--token-file", str(tmp_path / "no")]) == 2
    assert "--token-file" in capsys.readouterr().err


# -- certsolve submit --wait / result: the local command's report -------------------------------
ROBOT = "examples/robots/planar.json"
U = [0.8, 1.8, -2.5, -3.6]


def _fk_result():
    """A real FK result as the service stores it (a stub serves it)."""
    from certsolve import forward_kinematics, load_robot
    from certsolve.jobs.partial import stored_result

    return stored_result(forward_kinematics(load_robot(ROBOT), U, tau_max=60), 1000)


def test_result_prints_the_report_of_certsolve_fk(stub, capsys):
    from certsolve.cli import main
    from certsolve.cli.fk import format_result

    result = _fk_result()
    stub.replies["/v1/jobs/j1"] = [(200, {**record("done", result), "kind": "fk"})]
    assert main(["result", "j1", "--server", url(stub)]) == 0
    out = capsys.readouterr().out
    assert out == format_result(result) + "\n"
    assert out.startswith(
        "planar: frame-planar-10, u = [ 0.8  1.8 -2.5 -3.6]\ncomplete: 2 certified"
    )
    assert "pose 2 [unique]" in out and "rotation" not in out  # no raw JSON
    # the same report as the local command, timing aside
    assert main(["fk", ROBOT, "--u", ",".join(map(str, U)), "--tau-max", "60"]) == 0
    local = capsys.readouterr().out.splitlines()
    assert [line for k, line in enumerate(local) if k != 1] == [
        line for k, line in enumerate(out.splitlines()) if k != 1
    ]
    # --json: the record as the service sent it
    assert main(["result", "j1", "--server", url(stub), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["result"] == result


def test_submit_wait_prints_the_report_of_certsolve_solve(stub, capsys):
    from certsolve import solve
    from certsolve.cli import main
    from certsolve.cli.solve import format_result
    from certsolve.jobs.partial import stored_result

    mbx = "examples/systems/circle-line.mbx"
    result = stored_result(solve(mbx), 1000)
    stub.replies["/v1/jobs"] = [(202, {"id": "j1", "url": "u", "status": "queued"})]
    stub.replies["/v1/jobs/j1"] = [(200, record("running")), (200, record("done", result))]
    assert (
        main(["submit", "--kind", "solve", "--system", mbx, "--wait", "--server", url(stub)]) == 0
    )
    out = capsys.readouterr().out
    assert out == format_result("job j1", result) + "\n"
    assert out.startswith("job j1: complete, 2 solution(s), 0 undecided, 0 pending\n")
    assert "solution 2 [unique]" in out


def test_report_counts_what_the_service_did_not_list(stub, capsys):
    """A stored result cut to its first items says how many there were (``truncated``)."""
    from certsolve.cli import main

    result = _fk_result()
    cut = {**result, "solutions": result["solutions"][:1], "truncated": {"solutions": 2}}
    stub.replies["/v1/jobs/j1"] = [(200, {**record("done", cut), "kind": "fk"})]
    assert main(["result", "j1", "--server", url(stub)]) == 0
    out = capsys.readouterr().out
    assert "complete: 2 certified pose(s)" in out and "pose 2" not in out


def test_result_of_a_kind_without_a_report_is_json(stub, capsys):
    from certsolve.cli import main

    stub.replies["/v1/jobs/j1"] = [(200, {**record("done", {"x": 1}), "kind": "sleep"})]
    assert main(["result", "j1", "--server", url(stub)]) == 0
    assert json.loads(capsys.readouterr().out) == {"x": 1}


def _untimed(text: str) -> list[str]:
    """The lines of a report with its timings blanked (``0.027 s``, ``0.75 us``)."""
    import re

    return [re.sub(r"\d+(\.\d+)? (s|us)\b", "T", line) for line in text.splitlines()]


KRUT3 = "examples/robots/krut-3.json"
DESIGN_SPEC = "examples/design/krut3-spec.json"


def _workspace():
    from certsolve import certified_workspace, load_robot

    box = [-100, 100, -100, 100]
    return certified_workspace(load_robot(KRUT3), 100, box, eps=4, executor="auto")  # as the CLI


def _design():
    from certsolve import design

    return design(DESIGN_SPEC)


def _map():
    import numpy as np

    from certsolve import load_robot
    from certsolve.force import isotropic_map

    xs, ys = np.linspace(-100, 100, 50), np.linspace(-100, 100, 40)
    return isotropic_map(load_robot(KRUT3), xs, ys)


@pytest.mark.parametrize(
    "kind, compute, argv, format_name",
    [
        (
            "workspace", _workspace,
            ["workspace", KRUT3, "--min-force", "100", "--box", "-100,100,-100,100", "--eps", "4"],
            "force.format_workspace",
        ),
        ("design", _design, ["design", DESIGN_SPEC], "design.format_design"),
        (
            "isotropic-map", _map,
            ["isotropic", KRUT3, "--grid", "-100,100,-100,100,50,40"],
            "force.format_map",
        ),
    ],
)  # fmt: skip
def test_result_of_force_kinds_prints_the_local_report(
    stub, capsys, kind, compute, argv, format_name
):
    import importlib

    from certsolve.cli import main
    from certsolve.jobs.partial import stored_result

    module, name = format_name.split(".")
    report = getattr(importlib.import_module(f"certsolve.cli.{module}"), name)
    result = stored_result(compute(), 1000)  # the boxes are listed, and cut to 1000
    stub.replies["/v1/jobs/j1"] = [(200, {**record("done", result), "kind": kind})]
    assert main(["result", "j1", "--server", url(stub)]) == 0
    out = capsys.readouterr().out
    assert out == report(result) + "\n" and not out.lstrip().startswith("{")
    assert main(argv) == 0
    assert _untimed(capsys.readouterr().out) == _untimed(out)
