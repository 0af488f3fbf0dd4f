"""``certsolve solve FILE``: all solutions of a Minibex system, certified.

The options are the ``solve`` job's params (:class:`~certsolve.jobs.kinds.solve.
SolveParams`), refused as the job refuses them.  The model is imported (with pydantic and
the job kinds: ~0.08 s of CPU, a third of the start-up) only when :data:`PARAMS_SCHEMA`
does not surely accept them (:func:`certsolve.lazy.surely_valid`); otherwise they are the
model's own values.  The search is the call of :func:`certsolve.solve` that the job's
operation, :func:`~certsolve.jobs.kinds.solve.run_solve`, makes: both take the params'
keywords from :func:`~certsolve.solver.options_schema.solve_keywords`
(``tests/test_cli_solve_options.py`` checks the two calls are the same).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping
from typing import Any

from ..lazy import surely_valid
from ..solver.options_schema import SOLVE_OPTIONS_SCHEMA, solve_keywords
from ..solver.summary import MAX_LISTED
from .common import (
    Deadline,
    add_checkpoint_options,
    add_executor_options,
    checkpointing,
    count_of,
    describe_run,
    executor_from_args,
    print_report,
    progress_reporter,
    validated,
)

#: the JSON Schema of ``SolveParams``, its validating keywords: the library's options and
#: the answer's sizes (``tests/test_cli_solve_options.py`` keeps it equal to the model's)
PARAMS_SCHEMA: dict[str, Any] = {
    **SOLVE_OPTIONS_SCHEMA,
    "properties": {
        **SOLVE_OPTIONS_SCHEMA["properties"],
        "max_undecided": {"maximum": 100000, "minimum": 0, "type": "integer"},
        "max_pending": {"maximum": 100000, "minimum": 1, "type": "integer"},
        "cid_vars": {
            "anyOf": [
                {"maximum": 100, "minimum": 1, "type": "integer"},
                {"enum": ["all", "auto"], "type": "string"},
            ]
        },
        "split_at_zero": {"type": "boolean"},
        "newton_starts": {"type": "boolean"},
    },
}


def register(sub) -> None:
    p = sub.add_parser(
        "solve",
        description="Find every solution of a square system in its domain, each certified "
        "unique (Krawczyk); report undecided and pending boxes (as hulls with box counts). "
        "More equations than variables: solutions of a square subsystem, the others "
        "satisfied within their enclosure; fewer: a paving of the solution set "
        "(docs/minibex.md).",
    )
    p.add_argument("file", help="Minibex file (Variables / Constraints / end)")
    p.add_argument("--eps", type=float, default=1e-8, help="width below which boxes stop")
    p.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="time limit (s) of the whole command, writing the answer included",
    )
    p.add_argument("--max-boxes", type=int, default=None, help="limit on processed boxes")
    p.add_argument(
        "--max-undecided",
        type=int,
        default=MAX_LISTED,
        help="undecided hulls listed (default %(default)s); past it the answer is incomplete",
    )
    p.add_argument(
        "--max-pending",
        type=int,
        default=MAX_LISTED,
        help="hulls listing the boxes left by a limit (default %(default)s)",
    )
    p.add_argument(
        "--max-solutions", type=int, default=None, help="stop after this many certified solutions"
    )
    p.add_argument(
        "--cid-vars",
        default="auto",
        metavar="K|all|auto",
        help="variables shaved by CID before each bisection: the chosen one (1), the first "
        "K by smear score, all (fewer boxes, more time per box), or auto (default: the count "
        "learnt during the search, as IBEX's ACID)",
    )
    p.add_argument(
        "--split-at-zero",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="split the variables that multiply others at 0 while 0 is well inside their "
        "interval (default: on; --no-split-at-zero: at the bisector's ratio everywhere)",
    )
    p.add_argument(
        "--newton-starts",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="certify solutions early: float Newton from random points of the pending "
        "boxes, each point proven as the search proves its solutions (default: on; "
        "--no-newton-starts: the search alone)",
    )
    add_executor_options(p)
    add_checkpoint_options(p)
    p.add_argument("--verify", action="store_true", help="re-prove solutions with mpmath")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--stream",
        action="store_true",
        help='print JSON lines: {"solution": ...} for each certified solution as it is '
        'proven, then {"result": ...}, the whole answer',
    )
    p.set_defaults(func=run)


def params_of(args: argparse.Namespace) -> dict[str, Any]:
    """The ``solve`` job's params from the options, as a dict: as given when
    :data:`PARAMS_SCHEMA` surely accepts them (each option's default is the model's),
    else validated by ``SolveParams`` (a refusal raises the :class:`CliError` naming the
    option)."""
    given = {k: getattr(args, k) for k in PARAMS_SCHEMA["properties"]}
    if surely_valid(PARAMS_SCHEMA, given):
        return given
    from ..jobs.kinds.solve import SolveParams

    return validated(SolveParams, args).model_dump()


def run(args: argparse.Namespace) -> int:
    from ..expr.minibex import load_minibex
    from ..solver.branch_and_prune import solve

    params = params_of(args)  # the solve job's own checks (eps, timeout, ...)
    executor = executor_from_args(args)
    deadline = Deadline(params["timeout"], args.started)
    system = load_minibex(args.file)
    show, stop = progress_reporter(not (args.json or args.stream))
    if args.stream:
        show = _streamer(show)
    saving = checkpointing(args, "solve")
    try:
        with saving as (checkpoint, cancel):
            result = solve(  # as the solve job's operation, run_solve, calls it
                system,
                timeout=deadline.solver_timeout(),
                max_boxes=params["max_boxes"],
                executor=executor,
                cancel=cancel,
                progress=deadline.progress(show),
                checkpoint=checkpoint,
                **solve_keywords(params),
            )
            saving.status = str(result.status)
    finally:
        stop()
    deadline.mark(result)
    name = system.name or args.file
    if args.stream:
        _json_line({"result": result.to_dict()})
    else:
        print_report(args.json, result.to_dict(), lambda data: format_result(name, data))
    return saving.exit_code


def _json_line(obj: object) -> None:
    """One line of strict JSON on stdout, flushed (a reader sees it at once)."""
    import json
    import sys

    from ..jobs.jsonutil import plain

    sys.stdout.write(json.dumps(plain(obj), separators=(",", ":"), allow_nan=False) + "\n")
    sys.stdout.flush()


def _streamer(inner: Callable[[Any], None] | None) -> Callable[[Any], None]:
    """A progress callback printing each solution of ``p.found`` as a JSON line
    (:attr:`certsolve.solver.search.Progress.found`), then calling ``inner``."""

    def stream(p: Any) -> None:
        for solution in p.found:
            _json_line({"solution": solution.to_dict()})
        if inner is not None:
            inner(p)

    return stream


def format_result(name: str, result: Mapping) -> str:
    """The report of a solve result from its JSON form: :meth:`SolveResult.to_dict` here,
    the stored result of a ``solve`` job for ``certsolve result``."""
    st = result["stats"]
    listed_und, listed_pend = len(result["undecided"]), len(result["pending"])
    und = f"{listed_und} undecided"
    if result["undecided_total"] != listed_und or result["undecided_dropped"]:
        und += f" hull(s) of {result['undecided_total']} box(es)"
        if result["undecided_dropped"]:
            und += f", {result['undecided_dropped']} box(es) not listed"
    pend = f"{result['pending_total']} pending"
    if result["pending_total"] > listed_pend:
        pend += f" box(es) in {listed_pend} hull(s)"
    lines = [
        f"{name}: {result['status']}, {count_of(result, 'solutions')} solution(s), {und}, {pend}",
        f"  {st['boxes']} boxes, {st['time']:.3f} s, {describe_run(st)}"
        + (f", stopped by {st['stopped_by']}" if st.get("stopped_by") else ""),
    ]
    names = result["variables"]
    width = max(len(v) for v in names)
    for k, s in enumerate(result["solutions"], 1):
        tag = s["certificate"] + (" (verified)" if s.get("verified") else "")
        if s.get("parameters"):
            tag += f": every value of {', '.join(s['parameters'])} in the box"
        lines.append(f"solution {k} [{tag}]")
        for v, (lo, hi) in zip(names, s["box"], strict=True):
            lines.append(f"  {v:<{width}} = {0.5 * lo + 0.5 * hi: .15g}   [{lo!r}, {hi!r}]")
    for k, u in enumerate(result["undecided"], 1):
        count = f", {u['boxes']} boxes" if u["boxes"] > 1 else ""
        lines.append(
            f"undecided {k} ({u['reason']}{count}): "
            + ", ".join(
                f"{v} in [{lo:.6g}, {hi:.6g}]" for v, (lo, hi) in zip(names, u["box"], strict=True)
            )
        )
    return "\n".join(lines)
