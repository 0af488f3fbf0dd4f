"""``certsolve solve FILE``: all solutions of a Minibex system, certified."""

from __future__ import annotations

import argparse

from ..expr.minibex import load_minibex
from ..solver import Solver
from .common import (
    CliError,
    add_executor_options,
    check_limits,
    describe_run,
    executor_from_args,
    print_json,
    progress_reporter,
)


def register(sub) -> None:
    p = sub.add_parser(
        "solve",
        help="solve a square system written in Minibex",
        description="Find every solution of a square system in its domain, each certified "
        "unique (Krawczyk); report undecided and pending boxes.",
    )
    p.add_argument("file", help="Minibex file (Variables / Constraints / end)")
    p.add_argument("--eps", type=float, default=1e-8, help="width below which boxes stop")
    p.add_argument("--timeout", type=float, default=None, help="time limit in seconds")
    p.add_argument("--max-boxes", type=int, default=None, help="limit on processed boxes")
    p.add_argument(
        "--max-solutions", type=int, default=None, help="stop after this many certified solutions"
    )
    add_executor_options(p)
    p.add_argument("--verify", action="store_true", help="re-prove solutions with mpmath")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if not args.eps > 0:
        raise CliError("--eps must be positive")
    check_limits(args)
    executor = executor_from_args(args)
    system = load_minibex(args.file)
    solver = Solver(system, eps=args.eps)
    progress, stop = progress_reporter(not args.json)
    try:
        result = solver.solve(
            timeout=args.timeout,
            max_boxes=args.max_boxes,
            max_solutions=args.max_solutions,
            executor=executor,
            verify=args.verify,
            progress=progress,
        )
    finally:
        stop()
    if args.json:
        print_json(result.to_dict())
    else:
        print(format_result(system.name or args.file, result))
    return 0


def format_result(name: str, result) -> str:
    st = result.stats
    lines = [
        f"{name}: {result.status}, {len(result.solutions)} solution(s), "
        f"{len(result.undecided)} undecided, {len(result.pending)} pending",
        f"  {st.boxes} boxes, {st.time:.3f} s, {describe_run(st)}",
    ]
    names = result.variables
    width = max(len(v) for v in names)
    for k, s in enumerate(result.solutions, 1):
        tag = s.certificate + (" (verified)" if s.verified else "")
        lines.append(f"solution {k} [{tag}]")
        for v, (lo, hi) in zip(names, s.box, strict=True):
            lines.append(f"  {v:<{width}} = {0.5 * lo + 0.5 * hi: .15g}   [{lo!r}, {hi!r}]")
    for k, u in enumerate(result.undecided, 1):
        lines.append(
            f"undecided {k} ({u.reason}): "
            + ", ".join(
                f"{v} in [{lo:.6g}, {hi:.6g}]" for v, (lo, hi) in zip(names, u.box, strict=True)
            )
        )
    return "\n".join(lines)
