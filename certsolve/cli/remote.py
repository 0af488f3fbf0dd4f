"""``certsolve submit`` / ``status`` / ``result`` / ``cancel``: talk to a running service.

Argument parsing and printing only; the HTTP calls are :class:`certsolve.client.ServiceClient`.
Jobs are written as for ``POST /v1/jobs``; ``submit`` also builds one from ``--kind``,
``--robot`` / ``--system`` and ``-p key=value`` options, validated locally with the
service's own models before anything is sent.  The server is ``--server`` (default
``$CERTSOLVE_SERVER``); the token is read from ``--token-file`` (default
``$CERTSOLVE_TOKEN_FILE``), else taken from ``$CERTSOLVE_TOKEN``, and sent as
``Authorization: Bearer``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .common import CliError, print_json


def register(sub) -> None:
    from ..client import DEFAULT_SERVER
    from ..jobs.status import JobStatus

    def server_args(p) -> None:
        p.add_argument(
            "--server",
            default=os.environ.get("CERTSOLVE_SERVER", DEFAULT_SERVER),
            help=f"service URL ($CERTSOLVE_SERVER or {DEFAULT_SERVER})",
        )
        p.add_argument(
            "--token-file",
            default=os.environ.get("CERTSOLVE_TOKEN_FILE"),
            help="file holding the API token ($CERTSOLVE_TOKEN_FILE; else $CERTSOLVE_TOKEN)",
        )
        p.add_argument("--json", action="store_true", help="print JSON only")

    p = sub.add_parser(
        "submit",
        description="Submit JOB (a JSON file as for POST /v1/jobs, '-' for stdin; a .jsonl "
        "file is sent as one batch), or a job built from --kind and the options below.",
    )
    p.add_argument("job", nargs="?", help="job file (.json), batch (.jsonl) or '-'")
    p.add_argument("--kind", help="solve, fk, ik, ik-sweep, isotropic-map, workspace, design")
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
    server_args(p)
    p.set_defaults(func=run_submit)

    p = sub.add_parser("status")
    p.add_argument("id", nargs="?", help="job id (omit to list the latest jobs)")
    p.add_argument("--status", choices=[s.value for s in JobStatus])
    p.add_argument("--limit", type=int, default=20, help="jobs listed (20)")
    server_args(p)
    p.set_defaults(func=run_status)

    p = sub.add_parser("result")
    p.add_argument("id", help="job id")
    p.add_argument("--wait", action="store_true", help="wait until the job has finished")
    p.add_argument("--poll", type=float, default=0.5, help="seconds between polls (0.5)")
    server_args(p)
    p.set_defaults(func=run_result)

    p = sub.add_parser("cancel")
    p.add_argument("id", help="job id")
    server_args(p)
    p.set_defaults(func=run_cancel)


def _token(args: argparse.Namespace) -> str | None:
    """The API token: the first line of ``--token-file``, else ``$CERTSOLVE_TOKEN``."""
    if args.token_file:
        try:
            lines = Path(args.token_file).read_text().split()
        except OSError as exc:
            raise CliError(
                f"--token-file {args.token_file}: cannot read ({exc.strerror})"
            ) from None
        if not lines:
            raise CliError(f"--token-file {args.token_file}: the file is empty")
        return lines[0]
    return os.environ.get("CERTSOLVE_TOKEN") or None


def _client(args: argparse.Namespace):
    from ..client import ServiceClient

    try:
        return ServiceClient(args.server, token=_token(args))
    except ValueError as exc:
        raise CliError(f"--{exc}") from None


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


def _check(job: dict, adapter, where: str = "job") -> None:
    """Validate locally with the service's own models (one-line error)."""
    from pydantic import ValidationError

    from ..jobs.errors import describe_validation_error

    try:
        adapter.validate_python(job)
    except ValidationError as exc:
        raise CliError(f"{where}: {describe_validation_error(exc)}") from None


def run_submit(args: argparse.Namespace) -> int:
    from ..jobs.kinds import request_adapter

    client = _client(args)
    adapter = request_adapter(True)
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
                _check(jobs[-1], adapter, f"{args.job}:{n}")
        reply = client.submit_batch(jobs)
        if args.json:
            print_json(reply)
        else:
            print(f"batch {reply['batch']}: {len(reply['ids'])} job(s) queued")
            for job_id in reply["ids"]:
                print(job_id)
        return 0
    job = build_job(args)
    _check(job, adapter)
    reply = client.submit(job)
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
    client = _client(args)
    if args.id:
        rec = client.status(args.id)
        if args.json:
            print_json(rec)
        else:
            print(_line(rec))
        return 0
    if not 1 <= args.limit <= 500:
        raise CliError("--limit must be in 1..500")
    page = client.list(status=args.status, limit=args.limit)
    if args.json:
        print_json(page)
    else:
        for rec in page["items"]:
            print(_line(rec))
    return 0


def _print_result(client, job_id: str, *, wait: bool, poll: float, as_json: bool) -> int:
    from ..jobs.status import JobStatus

    rec = client.wait(job_id, poll=poll) if wait else client.job(job_id)
    status = JobStatus(rec["status"])
    if as_json:
        print_json(rec)
    elif rec.get("result") is not None:
        report = _report(rec)
        if report is None:
            print_json(rec["result"])
        else:
            print(report(rec["result"]))
    if status is JobStatus.DONE:
        return 0
    if not status.final:
        if not as_json:
            print(f"error: job {job_id} is {status} (use --wait)", file=sys.stderr)
        return 1
    if not as_json:
        print(f"error: job {job_id} {status}: {rec.get('error')}", file=sys.stderr)
    return 1


def _report(rec: dict) -> Callable[[Any], str] | None:
    """The report the local command prints for a result of this job's kind (``certsolve
    fk``, ``solve``, ``workspace``, ``design``, ``isotropic --grid``), from the stored
    result; None: the kind has none (``ik`` and ``ik-sweep``, whose reports show the
    robot's limits: the stored result does not hold them), print JSON."""
    from . import design, fk, force, solve

    reports: dict[str, Callable[[Any], str]] = {
        "fk": fk.format_result,
        "solve": lambda result: solve.format_result(f"job {rec['id']}", result),
        "workspace": force.format_workspace,
        "design": design.format_design,
        "isotropic-map": force.format_map,
    }
    return reports.get(rec.get("kind", ""))


def run_result(args: argparse.Namespace) -> int:
    client = _client(args)
    return _print_result(client, args.id, wait=args.wait, poll=args.poll, as_json=args.json)


def run_cancel(args: argparse.Namespace) -> int:
    client = _client(args)
    rec = client.cancel(args.id)
    if args.json:
        print_json(rec)
    else:
        print(_line(rec))
    return 0
