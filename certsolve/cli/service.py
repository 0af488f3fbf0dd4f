"""The job service on this machine, from the command line.

* ``certsolve serve``  -- run the HTTP API with its worker processes (``docs/api.md``)
* ``certsolve batch``  -- run a JSON-lines file of jobs offline, resumable

The client commands (``submit``, ``status``, ``result``, ``cancel``) are in :mod:`.remote`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import CliError, print_json


def register(sub) -> None:
    _register_serve(sub)
    _register_batch(sub)


# -- serve --------------------------------------------------------------------------------------
def _register_serve(sub) -> None:
    p = sub.add_parser(
        "serve",
        description="Serve the job API (FastAPI + uvicorn). Jobs run in worker processes and "
        "are kept in DATA_DIR/jobs.sqlite3: a restart loses nothing. The web page is at /, "
        "the API docs at /docs.",
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

    from ..extras import require

    require("service", "the service")
    import uvicorn

    from ..api.app import create_app
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
        f"certsolve: serving http://{args.host}:{args.port} (web page at /, docs at /docs) with "
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
