"""Helpers shared by the sub-commands: user errors, number lists, JSON output, progress."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from typing import Any

__all__ = [
    "CliError",
    "user_errors",
    "parse_floats",
    "print_json",
    "print_result",
    "progress_reporter",
    "status_line",
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
    json.dump(obj, sys.stdout, indent=2, allow_nan=False, default=_default)
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


def status_line(enabled: bool, text: Callable[[Any], str]):
    """A progress callback rewriting one line on stderr with ``text(progress)``, and a
    function that clears it; ``(None, no-op)`` when disabled or stderr is not a terminal."""
    if not enabled or not sys.stderr.isatty():
        return None, lambda: None
    width = [0]

    def update(p):
        line = text(p)
        width[0] = max(width[0], len(line))
        sys.stderr.write("\r" + line.ljust(width[0]))
        sys.stderr.flush()

    def stop():
        sys.stderr.write("\r" + " " * width[0] + "\r")
        sys.stderr.flush()

    return update, stop
