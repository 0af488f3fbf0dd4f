"""Helpers shared by the sub-commands: user errors, option validation, number lists, JSON
output, progress lines, time limits on a whole command, and where a search runs (``--workers`` /
``--scheduler``).

Options that the job service also takes are validated by the service's own pydantic models
(:func:`validated`), so ``certsolve fk --tau-max -5`` is refused exactly as
``POST /v1/jobs`` refuses ``"tau_max": -5``; the error names the option (``--tau-max``)
instead of the field (``params.tau_max``).  The field -> option map is argparse's own:
each option's ``dest`` is the model's field name (:func:`option_names`).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

__all__ = [
    "CliError",
    "Deadline",
    "add_checkpoint_options",
    "add_executor_options",
    "checkpointing",
    "count_of",
    "describe_run",
    "executor_from_args",
    "scheduler_from_args",
    "user_errors",
    "option_names",
    "validated",
    "parse_floats",
    "print_json",
    "print_report",
    "print_result",
    "progress_reporter",
]

M = TypeVar("M")

SCHEDULER_ENV = "CERTSOLVE_SCHEDULER"


class CliError(Exception):
    """A user mistake on the command line: printed as ``error: ...``, exit status 2."""


def user_errors() -> tuple[type[BaseException], ...]:
    """Exception types that are the user's input, not a bug: no traceback for these."""
    from ..client import ClientError
    from ..expr.minibex import MinibexError
    from ..extras import MissingExtra
    from ..robot.schema import RobotFileError

    return (CliError, ClientError, MinibexError, MissingExtra, RobotFileError, ValueError)


def option_names(parser: argparse.ArgumentParser, command: str) -> dict[str, str]:
    """``{dest: "--option"}`` of a sub-command's parser (the longest spelling of each)."""
    sub = None
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            sub = action.choices.get(command)
    if sub is None:
        return {}
    names = {}
    for action in sub._actions:
        if action.option_strings:
            names[action.dest] = max(action.option_strings, key=len)
        else:
            names[action.dest] = action.dest.upper()
    return names


def _option_of(field: str, args: argparse.Namespace, option: Mapping[str, str]) -> str:
    """The command-line spelling of a model field: ``tau_max`` -> ``--tau-max``."""
    dest = option.get(field, field)
    return getattr(args, "options", {}).get(dest) or "--" + dest.replace("_", "-")


def _where(path: list, args, option: Mapping[str, str]) -> str:
    if not path:
        return ""
    head = _option_of(str(path[0]), args, option)
    rest = path[1:]
    if len(rest) == 1 and isinstance(rest[0], int):
        return f"{head}, number {rest[0] + 1}"
    return head + "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in rest)


def validated(
    model: type[M],
    args: argparse.Namespace,
    values: Mapping[str, Any] | None = None,
    *,
    robot: Any = None,
    option: Mapping[str, str] | None = None,
) -> M:
    """The service's parameter model built from the parsed options (one validation for CLI
    and HTTP).

    Fields are read from ``args`` (same ``dest``) unless ``values`` gives them (parsed
    lists, poses ...); unset (None) options take the model's defaults.  With ``robot``
    (a :class:`~certsolve.robot.schema.RobotSpec`), the checks against the robot run too
    (``u`` has one value per wire, ...).  ``option`` maps a field to the ``dest`` of the
    option it came from when they differ (``{"pose": "at"}``).  Errors become one
    :class:`CliError` naming the option.
    """
    from pydantic import ValidationError

    option = option or {}
    data = {}
    for name in model.model_fields:  # type: ignore[attr-defined]
        value = getattr(args, option.get(name, name), None)
        if value is not None:
            data[name] = value
    for name, value in (values or {}).items():
        if value is None:
            data.pop(name, None)
        else:
            data[name] = value
    try:
        params = model.model_validate(data)  # type: ignore[attr-defined]
        if robot is not None:
            params.check_robot(robot)
    except ValidationError as exc:
        from ..jobs.errors import validation_details  # (imports every kind: errors only)

        details = validation_details(exc.errors())
        parts = [f"{_where(d['loc'], args, option)}: {d['msg']}" for d in details[:3]]
        raise CliError("; ".join(parts)) from None
    except ValueError as exc:  # check_robot: "field: message"
        field, sep, msg = str(exc).partition(": ")
        if sep and field.isidentifier():
            raise CliError(f"{_option_of(field, args, option)}: {msg}") from None
        raise CliError(str(exc)) from None
    return params


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


def scheduler_from_args(args: argparse.Namespace) -> str | None:
    """The Dask scheduler address of ``--scheduler``, else of ``$CERTSOLVE_SCHEDULER``
    unless ``--workers`` was given (``tcp://`` added when missing); None: no cluster."""
    address = args.scheduler
    if address is None and args.workers is None:
        address = os.environ.get(SCHEDULER_ENV) or None
    if address is None:
        return None
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


def executor_from_args(args: argparse.Namespace) -> str | int:
    """The executor spec for the library: ``"auto"``, a number of processes, or a Dask
    scheduler address.  An explicit ``--workers`` wins over ``$CERTSOLVE_SCHEDULER``."""
    if args.scheduler is not None and args.workers is not None:
        raise CliError(
            "--workers and --scheduler: give one (with --scheduler the cluster's workers run "
            "the search)"
        )
    address = scheduler_from_args(args)
    if address is not None:
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


def add_checkpoint_options(parser: argparse.ArgumentParser) -> None:
    """``--checkpoint FILE`` and ``--checkpoint-interval S`` (read by :func:`checkpointing`)."""
    parser.add_argument(
        "--checkpoint",
        default=None,
        metavar="FILE",
        help="save the search to FILE as it goes (and when it stops: time limit, Ctrl-C); "
        "if FILE exists, resume from it: run the same command again until it is complete",
    )
    parser.add_argument(
        "--checkpoint-interval",
        type=float,
        default=30.0,
        metavar="S",
        help="seconds between two saves (a kill -9 loses at most this much work)",
    )


class checkpointing:  # noqa: N801 - a context manager used like a function
    """``with checkpointing(args, "solve") as (checkpoint, cancel):`` -- the search's
    :class:`~certsolve.solver.checkpoint.Checkpoint` (None without ``--checkpoint``) and a
    cancel event: while the block runs, a first Ctrl-C sets it (the search stops after
    its batch and writes the checkpoint), a second one interrupts at once.  On leaving,
    says on stderr what was resumed and saved.  ``interrupted`` tells whether Ctrl-C
    stopped the search."""

    def __init__(self, args: argparse.Namespace, command: str):
        self.path = getattr(args, "checkpoint", None)
        self.interval = getattr(args, "checkpoint_interval", 30.0)
        self.command = command
        self.checkpoint = None
        self.interrupted = False
        self.status: str | None = None  # the command sets the search's status
        self._old = None

    def __enter__(self):
        import signal
        import threading

        if self.path is None:
            return None, None
        from ..solver.checkpoint import Checkpoint

        if not (self.interval >= 0 and self.interval < float("inf")):
            raise CliError(f"--checkpoint-interval: expected seconds >= 0, got {self.interval}")
        folder = os.path.dirname(os.path.abspath(self.path))
        if not os.path.isdir(folder):
            raise CliError(f"--checkpoint: no directory {folder}")
        self.checkpoint = Checkpoint.file(
            self.path, interval=self.interval, key=f"certsolve {self.command}"
        )
        cancel = threading.Event()

        def stop(signum, frame):
            if self.interrupted:
                raise KeyboardInterrupt
            self.interrupted = True
            cancel.set()
            print(
                "\ninterrupted: stopping after this batch and saving the checkpoint "
                "(Ctrl-C again to quit at once)",
                file=sys.stderr,
            )

        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, stop)
        return self.checkpoint, cancel

    def __exit__(self, *exc) -> None:
        import signal

        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
        cp = self.checkpoint
        if cp is None:
            return
        if cp.resumed_from is not None:
            print(
                f"checkpoint: resumed from {self.path} ({cp.resumed_from} boxes done before)",
                file=sys.stderr,
            )
        if cp.error is not None:
            print(f"checkpoint: NOT saved to {self.path}: {cp.error}", file=sys.stderr)
        if cp.writes and exc[0] is None:
            done = self.status in ("complete", "truncated")
            then = "the search is complete" if done else "run the same command again to resume"
            print(
                f"checkpoint: saved to {self.path} ({cp.size / 1e6:.2f} MB, {cp.writes} "
                f"write(s), {cp.write_time:.2f} s); {then}",
                file=sys.stderr,
            )

    @property
    def exit_code(self) -> int:
        """130 when Ctrl-C stopped the search (its partial answer was printed), else 0."""
        return 130 if self.interrupted else 0


def describe_run(stats: Any) -> str:
    """``serial`` / ``2 processes, 14 tasks`` / ``dask, 2 workers, 14 tasks``, from the
    search's :class:`~certsolve.solver.result.Stats` or their JSON form."""
    st = stats if isinstance(stats, Mapping) else vars(stats)
    executor, tasks, workers = st["executor"], st["tasks"], st["workers"]
    if executor == "serial":
        return "serial"
    if not tasks:
        return f"{executor}: ended in the serial warm-up, no task run"
    where = f"{workers} processes" if executor == "processes" else f"{executor}, {workers} workers"
    lost = f", {st['resubmitted']} resubmitted" if st.get("resubmitted") else ""
    return f"{where}, {tasks} tasks{lost}"


def print_json(obj: Any) -> None:
    """Strict JSON on stdout: numpy values become plain ones, an infinite bound ``null``."""
    from ..jobs.jsonutil import plain

    json.dump(plain(obj), sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def print_result(as_json: bool, result: Any, text: Callable[[], str], **extra: Any) -> None:
    """``--json``: ``result.to_dict()`` with the ``extra`` items that are not None (e.g. the
    plot written); otherwise the readable report ``text()``."""
    if as_json:
        out = result.to_dict()
        out.update({k: v for k, v in extra.items() if v is not None})
        print_json(out)
    else:
        print(text())


def count_of(result: Mapping[str, Any], key: str) -> int:
    """How many items the list ``result[key]`` of a result's JSON form had: a job's stored
    result lists the first ones and records the full count under ``truncated``."""
    return int((result.get("truncated") or {}).get(key, len(result[key])))


def print_report(as_json: bool, data: Mapping[str, Any], report: Callable[[Any], str]) -> None:
    """A result's JSON form ``data`` (``to_dict()``): as JSON with ``--json``, else the
    command's readable ``report`` of it -- the function ``certsolve result`` uses for a
    job's stored result of the same kind, so both print the same report."""
    from ..jobs.jsonutil import plain

    if as_json:
        print_json(data)
    else:
        print(report(plain(data)))


def _default(o):
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _solver_line(label: str) -> Callable[[Any], str]:
    def line(p) -> str:
        return (
            f"{label}: {p.boxes} boxes, {p.pending} pending, "
            f"{p.solutions} solutions, {p.undecided} undecided, {p.elapsed:.1f} s"
        )

    return line


def progress_reporter(
    enabled: bool, label: str = "solving", line: Callable[[Any], str] | None = None
) -> tuple[Callable[[Any], None] | None, Callable[[], None]]:
    """``(progress callback, stop)``: one line on stderr redrawn at most 8 times a second
    (a terminal only; otherwise ``(None, no-op)``).  ``line(p)`` writes the line from the
    library's progress object (default: the solver's boxes, pending, solutions ...)."""
    if not enabled or not sys.stderr.isatty():
        return None, lambda: None
    describe = line or _solver_line(label)
    at, width = 0.0, 0  # when the line was last drawn, and how wide it was

    def update(p) -> None:
        nonlocal at, width
        now = time.monotonic()
        if now - at < 0.125:
            return
        text = describe(p)
        sys.stderr.write("\r" + text.ljust(width))
        sys.stderr.flush()
        at, width = now, len(text)

    def stop() -> None:
        if width:
            sys.stderr.write("\r" + " " * width + "\r")
            sys.stderr.flush()

    return update, stop


class Deadline:
    """``--timeout`` for a whole command: start-up, search, building and writing the answer.

    The search is stopped (through its progress callback) as soon as the time used, plus an
    estimate of what building the answer will cost, reaches the limit: a fixed reserve for
    writing (answers are bounded, :mod:`certsolve.solver.summary`) and a cost per undecided and
    per pending box for summarising them (``benchmarks/summary_bench.py``: merging 10^6
    undecided boxes takes 2-8 s, summarising 10^6 pending ones 0.01-0.25 s).  The solver's
    own ``timeout`` is a backstop.
    """

    RESERVE = 1.0  # s: result objects, JSON (up to ~1 MB), printing, exit
    PER_UNDECIDED = 8e-6  # s per undecided box
    PER_PENDING = 3e-7  # s per pending box

    def __init__(self, timeout: float | None, started: float, option: str = "--timeout"):
        if timeout is not None and not (timeout > 0 and timeout < float("inf")):
            raise CliError(f"{option}: expected a positive number of seconds, got {timeout}")
        self.timeout = timeout
        self.started = started
        self.hit = False

    def left(self) -> float | None:
        if self.timeout is None:
            return None
        return self.timeout - (time.monotonic() - self.started)

    def solver_timeout(self) -> float | None:
        """Backstop time limit for the solver (the progress check usually stops it first)."""
        left = self.left()
        return None if left is None else max(left - self.RESERVE, 0.01)

    def progress(self, inner=None):
        """A progress callback: ``inner``'s (if any), stopping the search in time."""
        if self.timeout is None:
            return inner

        def check(p):
            if inner is not None:
                inner(p)
            und, pend = getattr(p, "undecided", 0), getattr(p, "pending", 0)
            cost = self.RESERVE + self.PER_UNDECIDED * und + self.PER_PENDING * pend
            if self.left() <= cost:
                self.hit = True
                return False
            return True

        return check

    def mark(self, result) -> None:
        """A search stopped by this deadline was stopped by time, not cancelled: say so in
        ``result`` (its ``status`` and ``stats.stopped_by``)."""
        from ..solver.search import SearchStatus

        if self.hit and result.status == SearchStatus.CANCELLED:
            result.status = SearchStatus.TIMEOUT
            result.stats.stopped_by = str(SearchStatus.TIMEOUT)
