"""Kernel micro-benchmarks: the solver's hot loops on fixed batches of boxes, CPU time.

    python benchmarks/kernel_bench.py [--batch 256,1024] [--runs 5] [--calls 20] [--search]
                                      [systems...]

For each system (``katsura-6``, ``eco-7`` from ``examples/systems``, ``T-16``: the MARIONET-T
forward-kinematics system at tau <= 60 N, u = 2; or the path of a ``.mbx`` / ``.bch`` file,
its domain clipped to [-1000, 1000]) and batch size ``B``: random boxes inside the search
domain (seeded; widths 1/64 of the domain, so that many straddle zeros), then the median over
``--runs`` runs of the CPU time (``time.process_time``) of ``--calls`` calls of

* ``forward``  -- interval values of every node of the HC4 program,
* ``hc4``      -- one HC4-revise pass (forward + backward projections),
* ``fj``       -- ``f`` and the Jacobian with the domain check,
* ``columns``  -- ``f`` and the first Newton group's Jacobian columns (FK: mixed Jacobian),
* ``mixed``    -- Hansen's mixed Jacobian over the solver's groups (one variable per group,
  FK: its own), one stacked program at small batches,
* ``newton``   -- the interval Newton contractor (linearisation, Krawczyk, Hansen–Sengupta),
  with the solver's groups (FK: its own; a file: the plain Jacobian),
* ``mnewton``  -- the same with Hansen's mixed Jacobian, one variable per group (the solver's
  default on a file: ``f(c)``, the stacked program, Krawczyk, Hansen–Sengupta),
* ``hc4fix``   -- the HC4 contractor: HC4-revise repeated while a box shrinks (up to 4 passes),
* ``round``    -- an HC4 + Newton round as the solver runs it: HC4 (up to 4 passes), then
  interval Newton with the mixed Jacobian on HC4's boxes,
* ``relax``    -- the polytope-hull contractor (X-Taylor rows + batched dual LPs).

``--search``: the boxes are those the polytope hull contracted in the system's own search
(``Solver.default``, one process; FK: the case's search with ``relax=True``), a seeded
sample, the calls cycling through them ``B`` at a time: random boxes are not the hull's (at
batch 1 on Trigexp1-024 its programs stop after 2 pivots on them, ~11 in the search).

Printed per call in milliseconds and per box in microseconds.  The same boxes are used for
every run, so two checkouts can be compared (run each on an idle machine, or interleave).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _minibex(name: str):
    from certsolve.expr.compiled import CompiledSystem
    from certsolve.expr.minibex import load_minibex

    system = load_minibex(ROOT / "examples" / "systems" / f"{name}.mbx")
    return CompiledSystem(system), np.asarray(system.domain, dtype=float), None


def _t16():
    from certsolve.kinematics import FKSolver, with_tau_max
    from certsolve.robot import Robot
    from certsolve.solver.contractors import IntervalNewton
    from certsolve.solver.pipeline import find

    robot = with_tau_max(Robot.load(str(ROOT / "examples" / "robots" / "marionet-t.json")), 60.0)
    fk = FKSolver(robot)
    solver = fk.search(np.full(robot.m, 2.0)).solver  # u = 2 as the system's parameters
    dom = np.asarray(solver.csys.system.domain, dtype=float)
    return solver.csys, dom, find(solver.contractor, IntervalNewton).groups


SYSTEMS = {"katsura-6": lambda: _minibex("katsura-6"), "eco-7": lambda: _minibex("eco-7")}
SYSTEMS["T-16"] = _t16


def _file(path: str):
    from certsolve.expr.compiled import CompiledSystem
    from certsolve.expr.minibex import load_minibex

    system = load_minibex(Path(path))
    dom = np.clip(np.asarray(system.domain, dtype=float), -1000.0, 1000.0)
    return CompiledSystem(system), dom, None


def boxes(dom: np.ndarray, B: int, seed: int = 0):
    """``B`` random boxes of width 1/64 of the (bounded) domain, inside it."""
    rng = np.random.default_rng(seed)
    lo_d, hi_d = dom[:, 0], dom[:, 1]
    w = (hi_d - lo_d) / 64.0
    lo = lo_d + rng.random((B, dom.shape[0])) * (hi_d - lo_d - w)
    return lo, lo + w


def search_boxes(csys, B: int, count: int = 64, seed: int = 0):
    """Up to ``count`` batches of ``B`` boxes the polytope hull contracted in a search of
    ``csys``'s system (a seeded sample of them)."""
    from certsolve.solver import Solver
    from certsolve.solver.pipeline import find
    from certsolve.solver.relaxation import PolytopeHull

    class Recording(PolytopeHull):
        def __init__(self, csys):
            super().__init__(csys)
            self.seen: list = []

        def contract_hinted(self, lo, hi, hints=None):
            self.seen.append((lo.copy(), hi.copy()))
            return super().contract_hinted(lo, hi, hints)

    solver = Solver.default(csys.system)
    hull = find(solver.contractor, PolytopeHull)
    if hull is None:
        raise SystemExit("--search: this search has no polytope hull")
    rec = Recording(solver.csys)
    solver.contractor = solver.contractor.replace(hull, rec)
    solver.solve()
    lo = np.concatenate([b[0] for b in rec.seen])
    hi = np.concatenate([b[1] for b in rec.seen])
    rng = np.random.default_rng(seed)
    pick = rng.permutation(lo.shape[0])[: count * B]
    return [(lo[pick[i : i + B]], hi[pick[i : i + B]]) for i in range(0, pick.size - B + 1, B)]


def kernels(csys, groups):
    """name -> function(lo, hi) running one kernel call."""
    from certsolve.interval.core import midpoint
    from certsolve.solver.contractors import HC4, IntervalNewton
    from certsolve.solver.relaxation import PolytopeHull

    p = csys.hc4
    cols = np.flatnonzero(groups[0]) if groups else np.arange(csys.n)
    newton = IntervalNewton(csys, groups)
    relax = PolytopeHull(csys)
    mixed = groups if groups is not None else list(np.eye(csys.n, dtype=bool))
    hc4 = HC4(csys)
    newton_mixed = IntervalNewton(csys, mixed)
    return {
        "forward": lambda lo, hi: p.eval_interval(lo, hi, csys.param_lo, csys.param_hi),
        "hc4": csys.hc4_revise,
        "fj": lambda lo, hi: csys.eval_fj(lo, hi, check_domain=True),
        "columns": lambda lo, hi: csys.eval_fj_columns(lo, hi, cols),
        "mixed": lambda lo, hi: csys.eval_fj_mixed(lo, hi, midpoint(lo, hi), mixed),
        "newton": newton.contract,
        "mnewton": newton_mixed.contract,
        "hc4fix": hc4.contract,
        "round": lambda lo, hi: newton_mixed.contract(*hc4.contract(lo, hi)[:2]),
        "relax": relax.contract,
    }


def cpu_per_call(fn, batches, calls: int, runs: int) -> float:
    """Median over ``runs`` of the CPU seconds of one call (``calls`` calls per run, cycling
    through ``batches``, a list of ``(lo, hi)``)."""
    fn(*batches[0])  # warm-up: compiled column programs, caches
    times = []
    for _ in range(runs):
        c = time.process_time()
        for i in range(calls):
            fn(*batches[i % len(batches)])
        times.append((time.process_time() - c) / calls)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("systems", nargs="*", help=f"default: {', '.join(SYSTEMS)}")
    ap.add_argument("--batch", default="256,1024", help="batch sizes, comma-separated")
    ap.add_argument("--runs", type=int, default=5, help="runs per median (>= 3)")
    ap.add_argument("--calls", type=int, default=20, help="calls per run")
    ap.add_argument("--kernels", default="", help="comma-separated subset of the kernels")
    ap.add_argument(
        "--search", action="store_true", help="the boxes the hull saw in a search (not FK)"
    )
    args = ap.parse_args()
    if args.runs < 3:
        sys.exit("--runs must be at least 3 (medians)")
    names = args.systems or list(SYSTEMS)
    print(
        f"# {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}, "
        f"numpy {np.__version__}; CPU time, median of {args.runs} runs x {args.calls} calls"
    )
    print(f"{'system':<10} {'kernel':<8} {'B':>5} {'ms/call':>9} {'us/box':>8}")
    for name in names:
        if name in SYSTEMS:
            csys, dom, groups = SYSTEMS[name]()
        else:
            csys, dom, groups = _file(name)
            name = Path(name).stem
        ks = kernels(csys, groups)
        if args.kernels:
            ks = {k: v for k, v in ks.items() if k in args.kernels.split(",")}
        for B in (int(b) for b in args.batch.split(",")):
            batches = search_boxes(csys, B) if args.search else [boxes(dom, B)]
            for kname, fn in ks.items():
                t = cpu_per_call(fn, batches, args.calls, args.runs)
                row = f"{name:<10} {kname:<8} {B:>5} {t * 1e3:>9.3f} {t / B * 1e6:>8.2f}"
                print(row, flush=True)


if __name__ == "__main__":
    main()
