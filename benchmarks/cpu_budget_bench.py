"""Solutions certified within a budget of CPU seconds, for several batch sizes.

On a shared machine a wall-clock limit measures the load as much as the solver; this
measures the order of the search at equal CPU time instead.  Each search runs with no time
limit and is cancelled by its progress callback once this process has used ``--cpu``
seconds since the search started (the build outside it; checked between rounds, so a search
may overrun by one round).  Reported per file and batch size: the status, the solutions
certified, the boxes processed, the boxes processed when the first solution was certified,
and the points ``boxes/solutions`` at each of ``--at`` CPU seconds (one search gives them
all).  The table of docs/solver.md, *Why 15 files are still behind ibexsolve at 10 s*:

    python benchmarks/cpu_budget_bench.py --cpu 12 --at 3,6,9,12 --sizes 128,256,512,1024 FILE...

``--dives newton,lower`` compares the dives (which half of a split box the next round takes,
``solver/dive.py``): the table of docs/solver.md, *The dive*.
"""

from __future__ import annotations

import argparse
import time

from certsolve.expr.minibex import load_system
from certsolve.solver import Solver
from certsolve.solver.dive import LowerFirst, NewtonSide

DIVES = {"newton": NewtonSide, "lower": LowerFirst}


def run(
    path: str, batch_size: int, budget: float, dive: str = "newton"
) -> tuple[str, list[tuple[int, int, float]]]:
    """One search of ``path`` cancelled at ``budget`` CPU seconds: its status and the
    ``(boxes, solutions, cpu)`` after every round."""
    solver = Solver.default(load_system(path), batch_size=batch_size, dive=DIVES[dive]())
    points: list[tuple[int, int, float]] = []
    c0 = time.process_time()

    def progress(p) -> bool:
        cpu = time.process_time() - c0
        points.append((p.boxes, p.solutions, cpu))
        return cpu < budget

    result = solver.solve(progress=progress)
    return str(result.status), points


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--cpu", type=float, default=9.0, help="CPU seconds a search may take")
    ap.add_argument("--at", default="3,6,9", help="CPU seconds to report solutions at")
    ap.add_argument("--sizes", default="128,256,512,1024", help="batch sizes to compare")
    ap.add_argument(
        "--dives", default="newton", help=f"dives to compare ({', '.join(DIVES)}; solver/dive.py)"
    )
    args = ap.parse_args()
    at = [float(a) for a in args.at.split(",")]
    cols = " | ".join(f"{a:g} s: boxes/solutions" for a in at)
    print(f"| file | batch | dive | status | solutions | boxes | boxes to 1st | {cols} |")
    print("|---|--:|---|---|--:|--:|--:|" + "--:|" * len(at))
    runs = [(int(s), d) for s in args.sizes.split(",") for d in args.dives.split(",")]
    for path in args.files:
        for size, dive in runs:
            status, points = run(path, size, args.cpu, dive)
            boxes, sols, _ = points[-1] if points else (0, 0, 0.0)
            first = next((b for b, s, _ in points if s), None)
            marks = []
            for a in at:
                done = [(b, s) for b, s, c in points if c <= a]
                b, s = done[-1] if done else (0, 0)
                marks.append(f"{b}/{s}")
            name = path.split("/")[-1]
            print(
                f"| {name} | {size} | {dive} | {status} | {sols} | {boxes} | "
                f"{'-' if first is None else first} | {' | '.join(marks)} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
