"""The ``certsolve`` command line.

Each sub-command lives in a module with a ``register(subparsers)`` function that adds its
parser(s) and sets ``func`` (called with the parsed arguments, returns an exit code):

* :mod:`.solve`   -- ``certsolve solve FILE`` (Minibex systems)
* :mod:`.fk`      -- ``certsolve fk ROBOT --u ...`` (forward kinematics, all solutions; tracking)
* :mod:`.ik`      -- ``certsolve ik ROBOT --pose ...``
* :mod:`.track`   -- ``certsolve track ROBOT --trajectory U.csv --start POSE`` (a path)
* :mod:`.force`   -- ``certsolve isotropic`` and ``certsolve workspace``
* :mod:`.design`  -- ``certsolve design SPEC.json`` (certified design of the force index)
* :mod:`.service` -- ``certsolve serve`` and ``batch`` (the job service on this machine)
* :mod:`.remote`  -- ``certsolve submit``, ``status``, ``result``, ``cancel`` (a running service)
* :mod:`.schema`  -- ``certsolve schema robot`` (JSON Schema of robot files)

Start-up is cheap: :data:`COMMANDS` names each command's module and one-line help, and only
the chosen command's module is imported (numpy, scipy, the solver, FastAPI ... come with
it, or later inside its ``run``).  ``certsolve --help`` imports nothing but argparse.

When the process is the command (:func:`main` without ``argv``), the cyclic garbage
collector is off while the command's modules load, and what they hold is then frozen
(:func:`_imports_without_gc`); see its docstring for the figures.

User errors (bad files, bad arguments) print one ``error: ...`` line and exit with status 2,
never a traceback.  That holds for what argparse refuses too (:class:`_Parser`): a missing
option, a bad value, an unknown option -- with the closest of the command's own options
(``error: --tau-mx: unknown option (did you mean --tau-max?)``) -- or an unknown command.
"""

from __future__ import annotations

import time

_STARTED = time.monotonic()  # before the command imports numpy & co.: time limits count it

import argparse  # noqa: E402
import gc  # noqa: E402
import importlib  # noqa: E402
import os  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
from collections.abc import Iterable, Iterator, Sequence  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from typing import NoReturn  # noqa: E402

from .common import CliError, option_names, user_errors  # noqa: E402

__all__ = ["COMMANDS", "Command", "main", "build_parser", "CliError"]

#: OpenBLAS threads of a command's process unless the user sets ``OPENBLAS_NUM_THREADS``:
#: certsolve's parallelism is its worker processes (which inherit it), its matrices are
#: small, and starting OpenBLAS's thread pool costs ~0.05 s of CPU at ``import numpy``
#: (0.11 -> 0.06 s on the project's 2-core machine)
BLAS_THREADS = "1"


@dataclass(frozen=True, kw_only=True)
class Command:
    """A sub-command: its name, the module under :mod:`certsolve.cli` that registers it, and
    the help line of ``certsolve --help`` (the one place it is written)."""

    name: str
    module: str
    help: str


COMMANDS: tuple[Command, ...] = (
    Command(name="solve", module="solve", help="solve a square system written in Minibex"),
    Command(
        name="fk",
        module="fk",
        help="forward kinematics: all certified equilibrium poses for a control vector u",
    ),
    Command(
        name="ik", module="ik", help="inverse kinematics: controls u (and tensions) holding a pose"
    ),
    Command(
        name="track",
        module="track",
        help="follow a control path from a start pose, every step certified and joined",
    ),
    Command(
        name="isotropic",
        module="force",
        help="maximum isotropic force at a pose or over a grid (Krut et al. 2004)",
    ),
    Command(
        name="workspace",
        module="force",
        help="certified workspace where the maximum isotropic force is at least F",
    ),
    Command(
        name="design",
        module="design",
        help="certified design: parameter boxes proven to give isotropic force >= F",
    ),
    Command(name="serve", module="service", help="run the HTTP job service"),
    Command(name="batch", module="service", help="run a JSON-lines file of jobs offline"),
    Command(name="submit", module="remote", help="submit a job to a running service"),
    Command(
        name="status", module="remote", help="status of a job (or the latest jobs) on a service"
    ),
    Command(name="result", module="remote", help="result of a job on a service"),
    Command(name="cancel", module="remote", help="cancel a job on a service"),
    Command(name="schema", module="schema", help="print the JSON Schema of an input format"),
)


def _help_of(name: str) -> str:
    return next(c.help for c in COMMANDS if c.name == name)


class _Formatter(argparse.HelpFormatter):
    """Option help with its default: ``(default: 1e-08)`` unless the text already says it."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            action.option_strings
            and default not in (None, False, argparse.SUPPRESS)
            and str(default) not in text
            and "default" not in text
        ):
            text += " (default: %(default)s)"
        return text


def _did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean --tau-max?)`` for the closest choice (difflib), else ``""``."""
    import difflib  # (an error's hint: not on the way of a run)

    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


class _Parser(argparse.ArgumentParser):
    """argparse's refusals as one line: :class:`CliError` (printed ``error: ...``, exit
    status 2) instead of a usage block and ``SystemExit``.  Sub-command parsers are of
    this class too (argparse gives them their parent's)."""

    _words: list[str] = []  # what parse_known_args was given (for the error)

    def parse_known_args(self, args=None, namespace=None):
        self._words = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> NoReturn:
        raise CliError(self._one_line(message))

    def _takes(self, word: str) -> bool:
        """An option of this parser (or a prefix argparse would expand), or not an option."""
        if not word.startswith("-") or word == "-" or self._negative_number_matcher.match(word):
            return True
        name = word.split("=", 1)[0]
        options = [s for a in self._actions for s in a.option_strings]
        return name in options or any(o.startswith(name) for o in options if len(name) > 2)

    def _one_line(self, message: str) -> str:
        if message.endswith("required") or "are required: " in message:
            # a misspelt required option is reported as unknown, not as missing
            unknown = [w for w in self._words if not self._takes(w)]
            if unknown:
                return str(self.unknown(unknown))
        missing = re.match(r"the following arguments are required: (.+)$", message)
        if missing:
            return f"{missing.group(1)}: required (see {self.prog} --help)"
        command = re.match(r"argument COMMAND: invalid choice: '(.*)' \(choose from", message)
        if command:
            word = command.group(1)
            hint = _did_you_mean(word, (c.name for c in COMMANDS))
            return f"{word}: unknown command{hint or f' (see {self.prog} --help)'}"
        return re.sub(r"^argument ([^:]+): ", r"\1: ", message)

    def unknown(self, extra: Sequence[str]) -> CliError:
        """The error for the first word this parser does not take: an option, with the
        closest of its own options, or a stray argument."""
        word = next((w for w in extra if w.startswith("-") and w != "-"), None)
        if word is None:
            return CliError(f"{extra[0]!r}: unexpected argument (see {self.prog} --help)")
        name = word.split("=", 1)[0]
        options = [s for a in self._actions for s in a.option_strings]
        hint = _did_you_mean(name, options) or f" (see {self.prog} --help)"
        return CliError(f"{name}: unknown option{hint}")


class _Subcommands:
    """What a command module's ``register`` sees: ``add_parser`` with the help of
    :data:`COMMANDS`, so the help line is written once, and defaults in option help."""

    def __init__(self, action):
        self._action = action

    def add_parser(self, name: str, **kw) -> argparse.ArgumentParser:
        kw.setdefault("help", _help_of(name))
        kw.setdefault("formatter_class", _Formatter)
        return self._action.add_parser(name, **kw)


def build_parser(commands: Iterable[str] | None = None) -> _Parser:
    """The argument parser with the full options of ``commands`` (every command if None);
    the other commands are listed with their help only (their modules are not imported)."""
    parser = _Parser(
        prog="certsolve",
        description="Certified interval solving for wire-driven parallel robots.",
    )
    action = parser.add_subparsers(dest="command", metavar="COMMAND")
    action.required = True
    wanted = {c.name for c in COMMANDS} if commands is None else set(commands)
    modules = list(dict.fromkeys(c.module for c in COMMANDS if c.name in wanted))
    done: set[str] = set()
    for cmd in COMMANDS:
        if cmd.name in done:
            continue
        if cmd.module in modules:
            importlib.import_module(f".{cmd.module}", __name__).register(_Subcommands(action))
            modules.remove(cmd.module)
            done.update(action.choices)
        else:
            action.add_parser(cmd.name, help=cmd.help)
            done.add(cmd.name)
    return parser


def _chosen(argv: Sequence[str]) -> list[str]:
    """The command named on the command line (the first word that is not an option)."""
    names = {c.name for c in COMMANDS}
    for word in argv:
        if not word.startswith("-"):
            return [word] if word in names else []
    return []


def _parse(parser: _Parser, argv: list[str]) -> argparse.Namespace:
    """``parser.parse_args(argv)``; what argparse refuses raises :class:`CliError`, an
    unknown option with the closest option of the command it was given to."""
    args, extra = parser.parse_known_args(argv)
    if extra:
        sub = _subparser(parser, args.command)
        raise (sub if isinstance(sub, _Parser) else parser).unknown(extra)
    return args


def _subparser(parser: argparse.ArgumentParser, command: str | None):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(command) if command else None
    return None


@contextmanager
def _imports_without_gc(process: bool) -> Iterator[None]:
    """Load the command's modules with the cyclic garbage collector off, then freeze what
    they hold (``gc.freeze``: the collector no longer walks it), when ``process`` (this
    process is the command; a caller's process, a test's, is left as it is).

    The objects an import makes (functions, classes, numpy's and certsolve's tables) live
    until the process ends, so the collections that ran while they were made found
    nothing, and every later full collection walked them again, the last one as the
    interpreter exits.  ``certsolve solve`` (2026-11-28, CPU of the whole process): the
    collector took ~8 ms of each call (5 in ``import numpy``, 2-3 in certsolve's imports,
    <1 in the search), and the exit's collection of the ~24,000 objects another ~15-20 ms.
    Only the collection of cycles is deferred: reference counting frees as before, the
    collector runs again once the modules are loaded (on what is made from then on), and
    the interpreter's exit is the usual one (``atexit``, files flushed and closed).
    """
    if not process:
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        gc.enable()


def main(argv: list[str] | None = None) -> int:
    process = argv is None
    if process:  # this process is the command: before any command imports numpy
        os.environ.setdefault("OPENBLAS_NUM_THREADS", BLAS_THREADS)
    argv = sys.argv[1:] if argv is None else list(argv)
    with _imports_without_gc(process):
        parser = build_parser(_chosen(argv))
    try:
        args = _parse(parser, argv)
    except CliError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    args.options = option_names(parser, args.command)
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
