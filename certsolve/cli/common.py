"""Helpers shared by the sub-commands: user errors, number lists, JSON output, progress."""

from __future__ import annotations

import json
import sys
from typing import Any

__all__ = ["CliError", "user_errors", "parse_floats", "print_json", "progress_reporter"]


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
