"""``certsolve solve FILE``: all solutions of a Minibex system, certified."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping
from typing import Any

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


def run(args: argparse.Namespace) -> int:
    from ..expr.minibex import load_minibex
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.solve import SolveParams, run_solve

    params = validated(SolveParams, args)  # the solve job's own checks (eps, timeout, ...)
    executor = executor_from_args(args)
    deadline = Deadline(params.timeout, args.started)
    system = load_minibex(args.file)
    show, stop = progress_reporter(not (args.json or args.stream))
    if args.stream:
        show = _streamer(show)
    saving = checkpointing(args, "solve")
    try:
        with saving as (checkpoint, cancel):
            ctx = RunContext(
                time_limit=deadline.solver_timeout(),
                max_boxes=params.max_boxes,
                progress=deadline.progress(show),
                checkpoint=checkpoint,
                executor=executor,
                cancel=cancel,
            )
            result = run_solve(params, system, ctx)  # the solve job's operation
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
