"""Helpers shared by the sub-commands: user errors, number lists, JSON output, progress,
and where a search runs (``--workers`` / ``--scheduler``)."""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
from typing import Any

__all__ = [
    "CliError",
    "add_executor_options",
    "check_limits",
    "describe_run",
    "executor_from_args",
    "parse_floats",
    "print_json",
    "progress_reporter",
    "user_errors",
]

SCHEDULER_ENV = "CERTSOLVE_SCHEDULER"


class CliError(Exception):
    """A user mistake on the command line: printed as ``error: ...``, exit status 2."""


def user_errors() -> tuple[type[BaseException], ...]:
    """Exception types that are the user's input, not a bug: no traceback for these."""
    from ..expr.minibex import MinibexError
    from ..robot.schema import RobotFileError

    return (CliError, MinibexError, RobotFileError, ValueError)


def parse_floats(text: str, what: str, count: int | None = None) -> list[float]:
    """``"1,2.5,-3"`` -> ``[1.0, 2.5, -3.0]``, with a clear error naming ``what``."""
    try:
        vals = [float(t) for t in text.replace(" ", "").split(",") if t != ""]
    except ValueError:
        raise CliError(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if count is not None and len(vals) != count:
        raise CliError(f"{what}: expected {count} numbers, got {len(vals)}")
    return vals


def add_executor_options(parser: argparse.ArgumentParser) -> None:
    """``--workers`` and ``--scheduler`` (read by :func:`executor_from_args`)."""
    parser.add_argument(
        "--workers",
        default=None,
        metavar="N|auto",
        help="local worker processes: an integer >= 1, or auto = the available cores "
        "(default: auto; the first 2 s run in this process, so small problems never start "
        "workers)",
    )
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="tcp://HOST:PORT",
        help=f"run on the Dask cluster of this scheduler (default: ${SCHEDULER_ENV} if set; "
        "needs pip install 'certsolve[distributed]')",
    )


def executor_from_args(args: argparse.Namespace) -> str | int:
    """The executor spec for the library: ``"auto"``, a number of processes, or a Dask
    scheduler address.  An explicit ``--workers`` wins over ``$CERTSOLVE_SCHEDULER``."""
    if args.scheduler is not None and args.workers is not None:
        raise CliError(
            "--workers and --scheduler: give one (with --scheduler the cluster's workers run "
            "the search)"
        )
    address = args.scheduler
    if address is None and args.workers is None:
        address = os.environ.get(SCHEDULER_ENV) or None
    if address is not None:
        where = "--scheduler" if args.scheduler is not None else f"${SCHEDULER_ENV}"
        address = address.strip()
        if not address or any(c.isspace() for c in address):
            raise CliError(f"{where}: expected a scheduler address tcp://HOST:PORT")
        if "://" not in address:
            address = "tcp://" + address
        if importlib.util.find_spec("distributed") is None:
            raise CliError(
                f"{where}: running on a Dask cluster needs the optional dependency "
                "'distributed': pip install 'certsolve[distributed]'"
            )
        return address
    text = "auto" if args.workers is None else args.workers.strip()
    if text == "auto":
        return "auto"
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise CliError(f"--workers: expected an integer >= 1 or 'auto', got {args.workers!r}")
    return n


def check_limits(args: argparse.Namespace) -> None:
    """``--timeout`` > 0, ``--max-boxes`` and ``--max-solutions`` >= 1 (those present)."""
    if getattr(args, "timeout", None) is not None and not args.timeout > 0:
        raise CliError("--timeout must be positive (seconds)")
    for name in ("max_boxes", "max_solutions"):
        v = getattr(args, name, None)
        if v is not None and v < 1:
            raise CliError(f"--{name.replace('_', '-')} must be at least 1")


def describe_run(stats) -> str:
    """``serial`` / ``2 processes, 14 tasks`` / ``dask, 2 workers, 14 tasks``."""
    if stats.executor == "serial":
        return "serial"
    if not stats.tasks:
        return f"{stats.executor}: ended in the serial warm-up, no task run"
    if stats.executor == "processes":
        where = f"{stats.workers} processes"
    else:
        where = f"{stats.executor}, {stats.workers} workers"
    lost = f", {stats.resubmitted} resubmitted" if stats.resubmitted else ""
    return f"{where}, {stats.tasks} tasks{lost}"


def print_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=2, allow_nan=False, default=_default)
    sys.stdout.write("\n")


def _default(o):
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def progress_reporter(enabled: bool, label: str = "solving"):
    """A solver progress callback drawing a live line on stderr (rich), or None."""
    if not enabled or not sys.stderr.isatty():
        return None, lambda: None
    from rich.console import Console
    from rich.live import Live
    from rich.text import Text

    console = Console(stderr=True)
    live = Live(Text(""), console=console, refresh_per_second=8, transient=True)
    live.start()

    def update(p):
        live.update(
            Text(
                f"{label}: {p.boxes} boxes, {p.pending} pending, "
                f"{p.solutions} solutions, {p.undecided} undecided, {p.elapsed:.1f} s"
            )
        )

    return update, live.stop
