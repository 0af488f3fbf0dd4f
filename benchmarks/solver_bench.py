"""Solver benchmark: every system of ``examples/systems`` (or those named), serial and with
worker processes.

    python benchmarks/solver_bench.py [--runs 3] [--workers 1,2] [--timeout 300]
                                      [--cid-vars 1,auto,all] [--affine on,off]
                                      [--reduce on,off] [--bisector mix,smear]
                                      [--dir DIR] [names...]

``--dir`` reads ``*.mbx`` and ``*.bch`` files of another folder (IBEX's benchmarks);
``--cid-vars`` compares settings of :class:`~certsolve.solver.Solver`'s ``cid_vars`` (1,
K, ``all``, ``auto``); ``--affine`` the relaxation with and without the affine-form rows
(:class:`~certsolve.solver.relaxation.PolytopeHull`'s ``affine``); ``--reduce`` the
solver's ``reduce_degree`` (:func:`~certsolve.expr.polynomial.reduce_degree`); ``--bisector``
the default :class:`~certsolve.solver.bisectors.SmearCurvatureMix` (``mix``) and
:class:`~certsolve.solver.bisectors.SmearSumRelative` (``smear``).  Prints one row per
system, setting and worker count: variables, status, solutions, undecided, boxes, median
wall time and CPU time (of the main process) over ``--runs`` runs.  Run it on an otherwise
idle machine; note the machine in any report.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

from certsolve.expr.minibex import load_minibex
from certsolve.solver import Solver
from certsolve.solver.bisectors import SmearCurvatureMix, SmearSumRelative
from certsolve.solver.pipeline import find
from certsolve.solver.relaxation import PolytopeHull

BISECTORS = {"mix": SmearCurvatureMix, "smear": SmearSumRelative}

HERE = Path(__file__).resolve().parent.parent / "examples" / "systems"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="system names (default: all)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--eps", type=float, default=1e-8)
    ap.add_argument("--cid-vars", default="auto", help="comma-separated: auto, 1, K, all")
    ap.add_argument("--affine", default="on", help="comma-separated: on, off")
    ap.add_argument("--reduce", default="on", help="comma-separated: on, off")
    ap.add_argument("--bisector", default="mix", help="comma-separated: mix, smear")
    ap.add_argument("--dir", type=Path, default=HERE, help="folder of Minibex files")
    args = ap.parse_args()
    files = sorted(p for p in args.dir.iterdir() if p.suffix in (".mbx", ".bch"))
    if args.names:
        files = [f for f in files if f.stem in args.names]
    workers = [int(w) for w in args.workers.split(",")]
    settings = {"all": None, "auto": "auto"}
    cids = [(c, settings.get(c) if c in settings else int(c)) for c in args.cid_vars.split(",")]
    affines = [a == "on" for a in args.affine.split(",")]
    reduces = [r == "on" for r in args.reduce.split(",")]
    bisectors = args.bisector.split(",")
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}; median of {args.runs} runs"
    )
    print(
        f"{'system':<20} {'vars':>4} {'cid':>4} {'aff':>3} {'red':>3} {'bis':>5} {'w':>2} "
        f"{'status':<10} "
        f"{'sols':>4} {'und':>4} "
        f"{'boxes':>8} {'wall s':>8} {'cpu s':>8}"
    )
    for f in files:
        system = load_minibex(f)
        settings_ = (
            (c, a, r, b, w)
            for c in cids
            for a in affines
            for r in reduces
            for b in bisectors
            for w in workers
        )
        for (cid_name, cid), affine, reduce, bis, w in settings_:
            walls, cpus, res = [], [], None
            for _ in range(args.runs):
                solver = Solver.default(
                    system,
                    eps=args.eps,
                    cid_vars=cid,
                    reduce_degree=reduce,
                    bisector=BISECTORS[bis](),
                )
                relax = find(solver.contractor, PolytopeHull)
                if relax is not None:
                    relax.affine = affine
                t, c = time.perf_counter(), time.process_time()
                res = solver.solve(workers=w, timeout=args.timeout)
                walls.append(time.perf_counter() - t)
                cpus.append(time.process_time() - c)
            print(
                f"{f.stem:<20} {system.n:>4} {cid_name:>4} {'on' if affine else 'off':>3} "
                f"{'on' if reduce else 'off':>3} {bis:>5} {w:>2} "
                f"{res.status:<10} "
                f"{len(res.solutions):>4} {len(res.undecided):>4} {res.stats.boxes:>8} "
                f"{statistics.median(walls):>8.3f} {statistics.median(cpus):>8.3f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
