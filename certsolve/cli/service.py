"""The job service on this machine, from the command line.

* ``certsolve serve``  -- run the HTTP API with its worker processes, or with its jobs on a
  Dask cluster (``--scheduler``; ``docs/api.md``, ``docs/distributed.md``)
* ``certsolve batch``  -- run a JSON-lines file of jobs offline, resumable

The client commands (``submit``, ``status``, ``result``, ``cancel``) are in :mod:`.remote`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import SCHEDULER_ENV, CliError, print_json, scheduler_from_args


def register(sub) -> None:
    _register_serve(sub)
    _register_batch(sub)


# -- serve --------------------------------------------------------------------------------------
def _register_serve(sub) -> None:
    p = sub.add_parser(
        "serve",
        description="Serve the job API (FastAPI + uvicorn). Jobs run in worker processes "
        "(or on a Dask cluster: --scheduler) and are kept in DATA_DIR/jobs.sqlite3: a restart "
        "loses nothing. The web page is at /, the API docs at /docs.",
    )
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (127.0.0.1)")
    p.add_argument("--port", type=int, default=8000, help="port (8000)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (cores)")
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="tcp://HOST:PORT",
        help="run the jobs on the Dask cluster of this scheduler, one job per worker thread, "
        f"instead of local worker processes (default: ${SCHEDULER_ENV} if set and --workers "
        "is not given; needs pip install 'certsolve[distributed]')",
    )
    p.add_argument("--data-dir", default=None, help="job store directory (./certsolve-data)")
    p.add_argument("--max-attempts", type=int, default=None, help="runs of a crashing job (2)")
    p.add_argument(
        "--default-timeout", type=float, default=None, help="time limit of a job (600 s)"
    )
    p.add_argument("--max-timeout", type=float, default=None, help="ceiling of time limits")
    p.add_argument("--memory-mb", type=int, default=None, help="memory limit of a job (4096 MiB)")
    p.add_argument(
        "--tokens",
        metavar="FILE",
        default=None,
        help='API tokens: a JSON object {client: {"token": ..., "admin": false}} '
        "($CERTSOLVE_TOKENS holds the same JSON); every /v1/ request then needs "
        "'Authorization: Bearer <token>' (default: no tokens, loopback only)",
    )
    p.add_argument(
        "--allow-host",
        action="append",
        metavar="NAME",
        default=None,
        help="without tokens, answer requests for this Host name too (repeatable; '*' for "
        "any; default: localhost, 127.0.0.1, ::1 and a specific --host; against DNS "
        "rebinding; $CERTSOLVE_ALLOWED_HOSTS, comma-separated)",
    )
    p.add_argument(
        "--request-timeout",
        type=float,
        default=None,
        help="seconds a client may take to send a whole request before it is closed (10)",
    )
    p.add_argument(
        "--insecure",
        action="store_true",
        help="allow a non-loopback --host without tokens (anyone who reaches the port can "
        "submit, read and cancel every job)",
    )
    p.add_argument(
        "--keep-days",
        type=float,
        default=None,
        help="purge finished jobs older than this many days, hourly checks (default: keep all)",
    )
    p.add_argument(
        "--log-level",
        default="info",
        choices=["critical", "error", "warning", "info", "debug"],
        help="server log level (info)",
    )
    p.add_argument("--enable-test-kinds", action="store_true", help=argparse.SUPPRESS)
    p.set_defaults(func=run_serve)


def _settings(args, **extra):
    """The service settings of a command's options and the ``CERTSOLVE_*`` variables; a
    Dask scheduler only from ``--scheduler`` / ``$CERTSOLVE_SCHEDULER`` of a command that
    has the option (:func:`.common.scheduler_from_args`)."""
    import os

    from ..jobs import ServiceSettings
    from ..jobs.access import AccessError, load_access

    environ = {k: v for k, v in os.environ.items() if k != SCHEDULER_ENV}
    if hasattr(args, "scheduler"):
        if args.scheduler is not None and args.workers is not None:
            raise CliError(
                "--workers and --scheduler: give one (the cluster's workers run the jobs)"
            )
        extra["scheduler"] = scheduler_from_args(args)
    try:
        if getattr(args, "tokens", None):
            extra["access"] = load_access(args.tokens)
        if hasattr(args, "allow_host"):
            extra["allowed_hosts"] = _allowed_hosts(args, environ)
        if getattr(args, "request_timeout", None) is not None:
            extra["request_timeout"] = args.request_timeout
        if getattr(args, "keep_days", None) is not None:
            extra["keep_days"] = args.keep_days
            extra["housekeeping_interval"] = min(3600.0, args.keep_days * 86400.0 / 4)
        return ServiceSettings.from_env(
            environ,
            data_dir=Path(args.data_dir) if getattr(args, "data_dir", None) else None,
            workers=args.workers,
            max_attempts=getattr(args, "max_attempts", None),
            default_timeout=getattr(args, "default_timeout", None),
            max_timeout=getattr(args, "max_timeout", None),
            default_memory_mb=getattr(args, "memory_mb", None),
            enable_test_kinds=True if getattr(args, "enable_test_kinds", False) else None,
            **extra,
        )
    except AccessError as exc:
        raise CliError(f"--tokens {exc}" if getattr(args, "tokens", None) else str(exc)) from None
    except (TypeError, ValueError) as exc:
        raise CliError(str(exc)) from None


def _allowed_hosts(args, environ) -> tuple[str, ...]:
    """The Host names a service without tokens answers: the loopback names, those of
    ``$CERTSOLVE_ALLOWED_HOSTS`` and ``--allow-host``, and the ``--host`` it listens on
    (unless that is every interface)."""
    from ..jobs.settings import LOOPBACK_HOSTS

    env = environ.get("CERTSOLVE_ALLOWED_HOSTS", "").split(",")
    names = [*LOOPBACK_HOSTS, *env, *(args.allow_host or [])]
    if args.host not in ("0.0.0.0", "::", ""):
        names.append(args.host)
    return tuple(dict.fromkeys(n.strip().lower() for n in names if n.strip()))


def _is_loopback(host: str) -> bool:
    """Every address ``host`` names is a loopback address (127.0.0.0/8, ::1)."""
    import ipaddress
    import socket

    try:
        infos = socket.getaddrinfo(host, None)
    except socket.gaierror:
        return False
    addrs = {str(info[4][0]).split("%")[0] for info in infos}
    return bool(addrs) and all(ipaddress.ip_address(a).is_loopback for a in addrs)


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


def _check_scheduler(address: str) -> None:
    """A clear error now if the Dask scheduler cannot be reached (not a traceback from
    the server's start-up)."""
    from ..jobs.dask_runner import check_scheduler

    try:
        check_scheduler(address)
    except (OSError, TimeoutError) as exc:
        raise CliError(f"--scheduler {address}: cannot reach the Dask scheduler ({exc})") from None


def run_serve(args: argparse.Namespace) -> int:
    import logging

    from ..extras import require

    require("service", "the service")
    import uvicorn

    from ..api.app import create_app
    from ..api.server import uvicorn_options
    from ..jobs import JobService, ServiceError

    if args.workers is not None and args.workers < 0:
        raise CliError("--workers must be >= 0")
    if not 0 <= args.port < 65536:
        raise CliError("--port must be in 0..65535")
    if args.keep_days is not None and not args.keep_days > 0:
        raise CliError("--keep-days must be > 0")
    if args.request_timeout is not None and not args.request_timeout > 0:
        raise CliError("--request-timeout must be > 0 (seconds)")
    settings = _settings(args)
    if settings.access is None and not args.insecure and not _is_loopback(args.host):
        raise CliError(
            f"--host {args.host} is reachable from other machines and the service has no "
            "tokens: anyone could submit, read and cancel every job. Give --tokens FILE "
            "(or $CERTSOLVE_TOKENS), or --insecure to serve without them"
        )
    _check_port(args.host, args.port)
    if settings.scheduler is not None:
        _check_scheduler(settings.scheduler)
    service = None
    try:
        service = JobService(settings)
        service.acquire()
        service.check_store()
    except ServiceError as exc:
        if service is not None:
            service.close()
        raise CliError(str(exc)) from None
    logging.basicConfig(
        level=getattr(logging, args.log_level.upper()),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    access = settings.access
    who = "no tokens" if access is None else f"tokens of {len(access.clients)} client(s)"
    where = f"{settings.workers} worker(s)"
    if settings.scheduler is not None:
        where = f"jobs on the Dask cluster at {settings.scheduler}"
    print(
        f"certsolve: serving http://{args.host}:{args.port} (web page at /, docs at /docs) with "
        f"{where}, {who}, jobs in {settings.data_dir.resolve()}",
        file=sys.stderr,
        flush=True,
    )
    uvicorn.run(
        create_app(settings, service),
        host=args.host,
        port=args.port,
        log_level=args.log_level,
        timeout_graceful_shutdown=5,
        **uvicorn_options(settings),
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
