"""Anytime behaviour of the solver: what a search stopped by its time limit has certified.

For each file, the search runs with each first batch size of ``--starts`` (``none``, the
default: ``batch_size`` boxes from the first round; a number: rounds start that small and
grow while the per-box time falls, :class:`~certsolve.solver.batching.BatchSizer`),
``--runs`` times each, in this process one after the other: the solutions certified
at the limit, the boxes processed, the boxes processed when the first solution was
certified, the wall and CPU seconds of the search (medians over the runs).  ``--max-boxes``
(with ``--timeout 0``) compares the orders at equal work, whatever the machine's load.  ``--ibex``
also runs ``ibexsolve --timeout=T --eps-min=1e-8`` once per file beside, as
``benchmarks/ibex_bench.py`` does (solutions de-duplicated, the raw count, CPU seconds).

    python benchmarks/anytime_bench.py --timeout 10 --runs 3 FILE...
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from ibex_bench import IBEXSOLVE, run_ibexsolve

from certsolve import solve
from certsolve.expr.minibex import load_system


def one(path: str, timeout: float | None, label: str, max_boxes: int | None) -> dict:
    """One search of ``path``: solutions, boxes, boxes at the first solution, wall, CPU."""
    system = load_system(path)
    first: list[int] = []

    def progress(p) -> None:
        if p.solutions and not first:
            first.append(p.boxes)

    t0, c0 = time.perf_counter(), time.process_time()
    start = None if label == "none" else int(label)
    r = solve(
        system,
        timeout=timeout,
        max_boxes=max_boxes,
        batch_start=start,
        progress=progress,
    )
    return {
        "status": str(r.status),
        "solutions": len(r.solutions),
        "boxes": r.stats.boxes,
        "first": first[0] if first else None,
        "wall": time.perf_counter() - t0,
        "cpu": time.process_time() - c0,
    }


def ibex(path: str, timeout: float) -> str:
    """ibexsolve's solutions at the limit, de-duplicated (raw count), and its CPU seconds
    (:func:`ibex_bench.run_ibexsolve`)."""
    opts = argparse.Namespace(ibexsolve=IBEXSOLVE, timeout=timeout, eps=1e-8)
    run = run_ibexsolve(Path(path), opts)
    return f"{run.solutions} ({run.raw_solutions}), {run.cpu:.1f} s"


def median(values: list) -> float | None:
    vals = [v for v in values if v is not None]
    return statistics.median(vals) if vals else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--timeout", type=float, default=10.0, help="wall seconds (0: none)")
    ap.add_argument("--max-boxes", type=int, default=None, help="stop after this many boxes")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--ibex", action="store_true")
    ap.add_argument(
        "--starts",
        default="none,16",
        help="first batch sizes to compare (none: batch_size)",
    )
    args = ap.parse_args()
    print("| file | batch_start | solutions | boxes | boxes to 1st | wall s | CPU s | ibexsolve |")
    print("|---|---|---|---|---|---|---|---|")
    for path in args.files:
        ib = ibex(path, args.timeout or 10.0) if args.ibex else ""
        for label in args.starts.split(","):
            timeout = args.timeout or None
            runs = [one(path, timeout, label, args.max_boxes) for _ in range(args.runs)]
            row = [
                median([r[k] for r in runs]) for k in ("solutions", "boxes", "first", "wall", "cpu")
            ]
            sols, boxes, first, wall, cpu = row
            name = path.split("/")[-1]
            print(
                f"| {name} | {label} | {sols:g} | {boxes:g} | "
                f"{'-' if first is None else f'{first:g}'} | {wall:.2f} | {cpu:.2f} | {ib} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
