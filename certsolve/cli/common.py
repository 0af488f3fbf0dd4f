"""Helpers shared by the sub-commands: user errors, number lists, JSON output, progress, and
time limits on a whole command."""

from __future__ import annotations

import json
import sys
import time
from typing import Any

__all__ = [
    "CliError",
    "Deadline",
    "user_errors",
    "parse_floats",
    "print_json",
    "progress_reporter",
]


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


def print_json(obj: Any) -> None:
    """Strict JSON on stdout: numpy values become plain ones, an infinite bound ``null``."""
    from ..jobs.jsonutil import plain

    json.dump(plain(obj), sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


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

    def mark(self, stats) -> None:
        """A search stopped by this deadline was stopped by time, not cancelled."""
        if self.hit and stats.stopped_by == "cancelled":
            stats.stopped_by = "timeout"
