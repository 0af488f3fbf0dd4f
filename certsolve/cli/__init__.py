"""The ``certsolve`` command line.

Each sub-command lives in its own module with a ``register(subparsers)`` function that adds
its parser and sets ``func`` (called with the parsed arguments, returns an exit code):

* :mod:`.solve`   -- ``certsolve solve FILE`` (Minibex systems)
* :mod:`.fk`      -- ``certsolve fk ROBOT --u ...`` (forward kinematics, all solutions; tracking)
* :mod:`.ik`      -- ``certsolve ik ROBOT --pose ...``
* :mod:`.force`   -- ``certsolve isotropic`` and ``certsolve workspace``
* :mod:`.service` -- ``certsolve serve``, ``batch``, ``submit``, ``status``, ``result``
* :mod:`.schema`  -- ``certsolve schema robot`` (JSON Schema of robot files)

User errors (bad files, bad arguments) print one ``error: ...`` line and exit with status 2,
never a traceback.
"""

from __future__ import annotations

import time

_STARTED = time.monotonic()  # before the sub-commands import numpy & co.: time limits count it

import argparse  # noqa: E402
import sys  # noqa: E402

from . import fk, force, ik, schema, service, solve  # noqa: E402
from .common import CliError, user_errors  # noqa: E402

__all__ = ["main", "build_parser", "CliError"]

_MODULES = (solve, fk, ik, force, service, schema)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="certsolve",
        description="Certified interval solving for wire-driven parallel robots.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in _MODULES:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.started = _STARTED if argv is None else time.monotonic()
    try:
        return int(args.func(args) or 0)
    except OSError as exc:
        if isinstance(exc, BrokenPipeError):  # e.g. `certsolve ... | head`
            sys.stderr.close()
            return 0
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except user_errors() as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
