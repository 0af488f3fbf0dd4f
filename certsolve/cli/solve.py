"""``certsolve solve FILE``: all solutions of a Minibex system, certified."""

from __future__ import annotations

import argparse

from .common import CliError, print_json, progress_reporter, validated


def register(sub) -> None:
    p = sub.add_parser(
        "solve",
        description="Find every solution of a square system in its domain, each certified "
        "unique (Krawczyk); report undecided and pending boxes.",
    )
    p.add_argument("file", help="Minibex file (Variables / Constraints / end)")
    p.add_argument("--eps", type=float, default=1e-8, help="width below which boxes stop")
    p.add_argument("--timeout", type=float, default=None, help="time limit in seconds")
    p.add_argument("--max-boxes", type=int, default=None, help="limit on processed boxes")
    p.add_argument("--workers", type=int, default=1, help="worker processes")
    p.add_argument("--verify", action="store_true", help="re-prove solutions with mpmath")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..expr.minibex import load_minibex
    from ..jobs.kinds.solve import SolveParams
    from ..solver import Solver

    params = validated(SolveParams, args)  # the solve job's own checks (eps, timeout, ...)
    if args.workers < 1:
        raise CliError("--workers must be at least 1")
    system = load_minibex(args.file)
    solver = Solver(system, eps=params.eps)
    progress, stop = progress_reporter(not args.json)
    try:
        result = solver.solve(
            timeout=params.timeout,
            max_boxes=params.max_boxes,
            workers=args.workers,
            verify=params.verify,
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
        f"  {st.boxes} boxes, {st.time:.3f} s, {st.workers} worker(s)"
        + (f", stopped by {st.stopped_by}" if st.stopped_by else ""),
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
