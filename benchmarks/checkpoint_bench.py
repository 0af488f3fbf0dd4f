"""Checkpoints: size and cost of a snapshot, and the overhead on a search.

    python benchmarks/checkpoint_bench.py [--runs 3] [--boxes 100000]

1. a solver state on ``katsura-6`` (7 variables) and one of the T-16 forward kinematics
   (16 variables) with ``--boxes`` pending boxes and every solution of the system recorded:
   bytes of the snapshot, CPU seconds to build it, to write it to a file (atomic: temporary
   file, fsync, rename) and to restore it;
2. ``katsura-6`` solved serially without a checkpoint, with one every 30 s (the default: in
   practice the final write only) and after every batch (``interval=0``, the worst case):
   CPU seconds and writes.

Medians of ``--runs`` runs of CPU time (``time.process_time``; the fsync's wait is not
CPU, see the wall column); the machine may be shared.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from certsolve.expr.minibex import load_minibex
from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.robot import Robot
from certsolve.solver import Solver
from certsolve.solver.checkpoint import Checkpoint, write_atomic
from certsolve.solver.search import Search, run_search

ROOT = Path(__file__).resolve().parents[1]


def cpu(fn):
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return time.process_time() - c, time.perf_counter() - w, out


def snapshot_costs(name: str, solver: Solver, boxes: int, runs: int) -> None:
    run = run_search(solver, *[d[None] for d in solver.system.domain.T])  # the records
    state = run.state
    dom = solver.system.domain
    rng = np.random.default_rng(0)
    a = dom[:, 0] + rng.random((boxes, solver.n)) * (dom[:, 1] - dom[:, 0])
    state.stack.push(a, a + 1e-3)
    search = Search(solver, state, stats=run.stats)
    cp = Checkpoint(lambda d: None)
    cp.fingerprint = "bench"
    rows = {"snapshot": [], "write": [], "write wall": [], "restore": []}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.ck"
        for _ in range(runs):
            t, _, data = cpu(lambda: cp.snapshot(search))
            rows["snapshot"].append(t)
            t, w, _ = cpu(lambda: write_atomic(path, data))  # noqa: B023
            rows["write"].append(t)
            rows["write wall"].append(w)
            t, _, _ = cpu(lambda: cp.restore(solver, data))  # noqa: B023
            rows["restore"].append(t)
    sols = state.solutions.count("ok")
    print(f"{name}: {boxes} pending boxes of {solver.n} variables, {sols} solutions recorded")
    print(f"  snapshot size {len(data) / 1e6:.2f} MB")
    for k, v in rows.items():
        print(f"  {k:<10} {1e3 * statistics.median(v):8.1f} ms")


def overhead(runs: int) -> None:
    system = load_minibex(str(ROOT / "examples/systems/katsura-6.mbx"))
    rows: dict[str, list] = {"none": [], "every 30 s": [], "every batch": []}
    writes = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(runs):
            for label, interval in (("none", None), ("every 30 s", 30.0), ("every batch", 0.0)):
                path = Path(tmp) / f"k6-{interval}-{len(rows[label])}.ck"
                cp = None if interval is None else Checkpoint.file(path, interval=interval)
                t, _, res = cpu(lambda cp=cp: Solver.default(system).solve(checkpoint=cp))
                rows[label].append(t)
                writes[label] = (0 if cp is None else cp.writes, res.stats.boxes)
    print("katsura-6 solved serially (CPU s, median):")
    for label, v in rows.items():
        w, b = writes[label]
        print(f"  {label:<12} {statistics.median(v):7.2f} s   {w} writes, {b} boxes")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--boxes", type=int, default=100_000)
    args = ap.parse_args()
    k6 = Solver.default(load_minibex(str(ROOT / "examples/systems/katsura-6.mbx")))
    snapshot_costs("katsura-6", k6, args.boxes, args.runs)
    robot = with_tau_max(Robot.load(ROOT / "examples/robots/marionet-t.json"), 10.0)
    fk = FKSolver(robot)
    snapshot_costs("T-16 FK", fk.search(np.zeros(7)).solver, args.boxes, args.runs)
    overhead(args.runs)


if __name__ == "__main__":
    main()
