"""The solver service from the command line.

* ``certsolve serve``  -- run the HTTP API with its worker processes (``docs/api.md``)
* ``certsolve batch``  -- run a JSON-lines file of jobs offline, resumable
* ``certsolve submit`` / ``status`` / ``result`` / ``cancel`` -- talk to a running server

Jobs are written as for ``POST /v1/jobs``; ``submit`` also builds one from ``--kind``,
``--robot`` / ``--system`` and ``-p key=value`` options, validated locally with the same
models before anything is sent.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path
from typing import Any

from .common import CliError, print_json

DEFAULT_SERVER = "http://127.0.0.1:8000"
_FINAL = ("done", "failed", "cancelled")


def register(sub) -> None:
    _register_serve(sub)
    _register_batch(sub)
    _register_client(sub)


# -- serve --------------------------------------------------------------------------------------
def _register_serve(sub) -> None:
    p = sub.add_parser(
        "serve",
        description="Serve the job API (FastAPI + uvicorn). Jobs run in worker processes and "
        "are kept in DATA_DIR/jobs.sqlite3: a restart loses nothing. API docs at /docs.",
    )
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (127.0.0.1)")
    p.add_argument("--port", type=int, default=8000, help="port (8000)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (cores)")
    p.add_argument("--data-dir", default=None, help="job store directory (./certsolve-data)")
    p.add_argument("--max-attempts", type=int, default=None, help="runs of a crashing job (2)")
    p.add_argument(
        "--default-timeout", type=float, default=None, help="time limit of a job (600 s)"
    )
    p.add_argument("--max-timeout", type=float, default=None, help="ceiling of time limits")
    p.add_argument("--memory-mb", type=int, default=None, help="memory limit of a job (MiB)")
    p.add_argument(
        "--log-level",
        default="info",
        choices=["critical", "error", "warning", "info", "debug"],
        help="server log level (info)",
    )
    p.add_argument("--enable-test-kinds", action="store_true", help=argparse.SUPPRESS)
    p.set_defaults(func=run_serve)


def _settings(args, **extra):
    from ..jobs import ServiceSettings

    try:
        return ServiceSettings.from_env(
            data_dir=Path(args.data_dir) if getattr(args, "data_dir", None) else None,
            workers=args.workers,
            max_attempts=getattr(args, "max_attempts", None),
            default_timeout=getattr(args, "default_timeout", None),
            max_timeout=getattr(args, "max_timeout", None),
            default_memory_mb=getattr(args, "memory_mb", None),
            enable_test_kinds=True if getattr(args, "enable_test_kinds", False) else None,
            **extra,
        )
    except (TypeError, ValueError) as exc:
        raise CliError(str(exc)) from None


def _check_port(host: str, port: int) -> None:
    """A clear error now rather than after the workers have started."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise CliError(f"--host {host}: {exc.strerror}") from None
    family, _, _, _, addr = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(addr)
        except OSError as exc:
            raise CliError(f"cannot listen on {host}:{port} ({exc.strerror})") from None


def run_serve(args: argparse.Namespace) -> int:
    import logging

    import uvicorn

    from api.app import create_app

    from ..jobs import JobService, ServiceError

    if args.workers is not None and args.workers < 0:
        raise CliError("--workers must be >= 0")
    if not 0 <= args.port < 65536:
        raise CliError("--port must be in 0..65535")
    settings = _settings(args)
    _check_port(args.host, args.port)
    try:
        service = JobService(settings)
        service.acquire()
    except ServiceError as exc:
        raise CliError(str(exc)) from None
    logging.basicConfig(
        level=getattr(logging, args.log_level.upper()),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    print(
        f"certsolve: serving http://{args.host}:{args.port} (docs at /docs) with "
        f"{settings.workers} worker(s), jobs in {settings.data_dir.resolve()}",
        file=sys.stderr,
        flush=True,
    )
    uvicorn.run(
        create_app(settings, service),
        host=args.host,
        port=args.port,
        log_level=args.log_level,
        timeout_graceful_shutdown=5,
    )
    return 0


# -- batch --------------------------------------------------------------------------------------
def _register_batch(sub) -> None:
    p = sub.add_parser(
        "batch",
        description="Run every job of FILE (one JSON job per line, as for POST /v1/jobs) on "
        "worker processes and append one JSON result line per job to the output, as jobs "
        "finish. Re-running skips the lines already done.",
    )
    p.add_argument("file", help="jobs, one JSON object per line")
    p.add_argument("--out", default=None, help="results file (FILE.results.jsonl)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (cores)")
    p.add_argument("--json", action="store_true", help="print only a JSON summary")
    p.add_argument("--enable-test-kinds", action="store_true", help=argparse.SUPPRESS)
    p.set_defaults(func=run_batch_cmd)


def run_batch_cmd(args: argparse.Namespace) -> int:
    from ..jobs.batch import run_batch

    if args.workers is not None and args.workers < 1:
        raise CliError("--workers must be at least 1")
    path = Path(args.file)
    if not path.is_file():
        raise CliError(f"{path}: no such file")
    settings = _settings(args)
    live = not args.json and sys.stderr.isatty()

    def progress(s) -> None:
        if live:
            finished = s.done + s.failed + s.cancelled
            print(
                f"\rbatch: {finished}/{s.lines - s.skipped} finished "
                f"({s.failed} failed), {s.elapsed:.1f} s",
                end="",
                file=sys.stderr,
                flush=True,
            )

    summary = run_batch(path, args.out, settings=settings, progress=progress)
    if live:
        print(file=sys.stderr)
    if args.json:
        print_json(summary.to_dict())
    else:
        print(
            f"{path}: {summary.lines} job(s): {summary.done} done, {summary.failed} failed"
            f" ({summary.invalid} invalid), {summary.cancelled} cancelled, "
            f"{summary.skipped} already done; {summary.elapsed:.1f} s -> {summary.output}"
        )
    return 0 if summary.failed == 0 and summary.cancelled == 0 else 1


# -- client -------------------------------------------------------------------------------------
def _server_arg(p) -> None:
    p.add_argument(
        "--server",
        default=os.environ.get("CERTSOLVE_SERVER", DEFAULT_SERVER),
        help=f"service URL ($CERTSOLVE_SERVER or {DEFAULT_SERVER})",
    )
    p.add_argument("--json", action="store_true", help="print JSON only")


def _register_client(sub) -> None:
    p = sub.add_parser(
        "submit",
        description="Submit JOB (a JSON file as for POST /v1/jobs, '-' for stdin; a .jsonl "
        "file is sent as one batch), or a job built from --kind and the options below.",
    )
    p.add_argument("job", nargs="?", help="job file (.json), batch (.jsonl) or '-'")
    p.add_argument("--kind", help="solve, fk, ik, isotropic-map, workspace")
    p.add_argument("--robot", help="robot file (JSON)")
    p.add_argument("--system", help="Minibex file (kind solve)")
    p.add_argument("--params", help="parameters as a JSON object")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="one parameter (VALUE is JSON, or else a string); repeatable",
    )
    p.add_argument("--timeout", type=float, help="time limit of the job (s)")
    p.add_argument("--wait", action="store_true", help="wait for the result and print it")
    _server_arg(p)
    p.set_defaults(func=run_submit)

    p = sub.add_parser("status")
    p.add_argument("id", nargs="?", help="job id (omit to list the latest jobs)")
    p.add_argument("--status", choices=["queued", "running", "done", "failed", "cancelled"])
    p.add_argument("--limit", type=int, default=20, help="jobs listed (20)")
    _server_arg(p)
    p.set_defaults(func=run_status)

    p = sub.add_parser("result")
    p.add_argument("id", help="job id")
    p.add_argument("--wait", action="store_true", help="wait until the job has finished")
    p.add_argument("--poll", type=float, default=0.5, help="seconds between polls (0.5)")
    _server_arg(p)
    p.set_defaults(func=run_result)

    p = sub.add_parser("cancel")
    p.add_argument("id", help="job id")
    _server_arg(p)
    p.set_defaults(func=run_cancel)


class _Client:
    def __init__(self, server: str):
        server = server.rstrip("/")
        u = urllib.parse.urlsplit(server)
        if u.scheme not in ("http", "https") or not u.netloc:
            raise CliError(f"--server: expected http://host:port, got {server!r}")
        self.server = server
        local = (u.hostname or "") in ("localhost", "127.0.0.1", "::1")
        handlers = [urllib.request.ProxyHandler({})] if local else []
        self.opener = urllib.request.build_opener(*handlers)

    def call(self, method: str, path: str, body: Any = None, *, ok=(200, 202)) -> Any:
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(
            self.server + path,
            data=data,
            method=method,
            headers={"Content-Type": "application/json", "Accept": "application/json"},
        )
        try:
            with self.opener.open(req, timeout=60) as resp:
                raw = resp.read()
                status = resp.status
        except urllib.error.HTTPError as exc:
            raw, status = exc.read(), exc.code
        except (urllib.error.URLError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            raise CliError(f"cannot reach the service at {self.server} ({reason})") from None
        try:
            payload = json.loads(raw) if raw else None
        except ValueError:
            payload = None
        if status not in ok:
            msg = payload.get("error") if isinstance(payload, dict) else None
            raise CliError(
                f"service answered {status}: {msg or raw[:200].decode(errors='replace')}"
            )
        return payload


def _load_json(path: str) -> Any:
    try:
        text = sys.stdin.read() if path == "-" else Path(path).read_text()
    except OSError as exc:
        raise CliError(f"{path}: cannot read ({exc.strerror})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise CliError(f"{path}: invalid JSON at line {exc.lineno}: {exc.msg}") from None


def _parse_value(text: str) -> Any:
    try:
        return json.loads(text)
    except ValueError:
        return text


def build_job(args: argparse.Namespace) -> dict:
    """The job request described by ``submit``'s options (not yet validated)."""
    if args.job:
        job = _load_json(args.job)
        if not isinstance(job, dict):
            raise CliError(f"{args.job}: expected a JSON object (a job)")
    else:
        if not args.kind:
            raise CliError("give a job file, or --kind with --robot or --system")
        job = {"kind": args.kind}
    if args.kind:
        job["kind"] = args.kind
    if args.robot:
        job["robot"] = _load_json(args.robot)
    if args.system:
        try:
            job["system"] = Path(args.system).read_text()
        except OSError as exc:
            raise CliError(f"{args.system}: cannot read ({exc.strerror})") from None
    params = dict(job.get("params") or {})
    if args.params:
        extra = _parse_value(args.params)
        if not isinstance(extra, dict):
            raise CliError("--params: expected a JSON object")
        params.update(extra)
    for item in args.param:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise CliError(f"-p {item!r}: expected KEY=VALUE")
        params[key.strip()] = _parse_value(value.strip())
    if params or "params" in job:
        job["params"] = params
    if args.timeout is not None:
        job.setdefault("limits", {})["timeout"] = args.timeout
    return job


def _check(job: dict, where: str = "job") -> None:
    """Validate locally with the service's own models (one-line error)."""
    from pydantic import ValidationError

    from ..jobs.errors import describe_validation_error
    from ..jobs.kinds import request_adapter

    try:
        request_adapter(True).validate_python(job)
    except ValidationError as exc:
        raise CliError(f"{where}: {describe_validation_error(exc)}") from None


def run_submit(args: argparse.Namespace) -> int:
    client = _Client(args.server)
    if args.job and args.job.endswith(".jsonl"):
        try:
            lines = Path(args.job).read_text().splitlines()
        except OSError as exc:
            raise CliError(f"{args.job}: cannot read ({exc.strerror})") from None
        jobs = []
        for n, line in enumerate(lines, 1):
            if line.strip():
                try:
                    jobs.append(json.loads(line))
                except json.JSONDecodeError as exc:
                    raise CliError(f"{args.job}:{n}: invalid JSON: {exc.msg}") from None
                _check(jobs[-1], f"{args.job}:{n}")
        reply = client.call("POST", "/v1/jobs/batch", {"jobs": jobs})
        if args.json:
            print_json(reply)
        else:
            print(f"batch {reply['batch']}: {len(reply['ids'])} job(s) queued")
            for job_id in reply["ids"]:
                print(job_id)
        return 0
    job = build_job(args)
    _check(job)
    reply = client.call("POST", "/v1/jobs", job)
    if not args.wait:
        if args.json:
            print_json(reply)
        else:
            print(reply["id"])
        return 0
    if not args.json:
        print(f"job {reply['id']} queued", file=sys.stderr)
    return _print_result(client, reply["id"], wait=True, poll=0.2, as_json=args.json)


def _line(rec: dict) -> str:
    parts = [rec["id"], rec["kind"], rec["status"]]
    p = rec.get("progress") or {}
    if p:
        bits = [f"{p[k]} {k}" for k in ("boxes", "pending", "solutions") if k in p]
        parts.append(", ".join(bits))
    if rec.get("elapsed") is not None:
        parts.append(f"{rec['elapsed']:.1f} s")
    if rec.get("attempts", 0) > 1:
        parts.append(f"attempt {rec['attempts']}")
    if rec.get("error"):
        parts.append(rec["error"])
    return "  ".join(parts)


def run_status(args: argparse.Namespace) -> int:
    client = _Client(args.server)
    if args.id:
        rec = client.call("GET", f"/v1/jobs/{urllib.parse.quote(args.id)}?result=false")
        if args.json:
            print_json(rec)
        else:
            print(_line(rec))
        return 0
    if not 1 <= args.limit <= 500:
        raise CliError("--limit must be in 1..500")
    query = {"limit": args.limit}
    if args.status:
        query["status"] = args.status
    page = client.call("GET", "/v1/jobs?" + urllib.parse.urlencode(query))
    if args.json:
        print_json(page)
    else:
        for rec in page["items"]:
            print(_line(rec))
    return 0


def _print_result(client: _Client, job_id: str, *, wait: bool, poll: float, as_json: bool) -> int:
    path = f"/v1/jobs/{urllib.parse.quote(job_id)}"
    while True:
        rec = client.call("GET", path)
        if rec["status"] in _FINAL or not wait:
            break
        time.sleep(max(0.05, poll))
    if as_json:
        print_json(rec)
    elif rec.get("result") is not None:
        print_json(rec["result"])
    if rec["status"] == "done":
        return 0
    if rec["status"] in ("queued", "running"):
        if not as_json:
            print(f"error: job {job_id} is {rec['status']} (use --wait)", file=sys.stderr)
        return 1
    if not as_json:
        print(f"error: job {job_id} {rec['status']}: {rec.get('error')}", file=sys.stderr)
    return 1


def run_result(args: argparse.Namespace) -> int:
    client = _Client(args.server)
    return _print_result(client, args.id, wait=args.wait, poll=args.poll, as_json=args.json)


def run_cancel(args: argparse.Namespace) -> int:
    client = _Client(args.server)
    rec = client.call("DELETE", f"/v1/jobs/{urllib.parse.quote(args.id)}")
    if args.json:
        print_json(rec)
    else:
        print(_line(rec))
    return 0
