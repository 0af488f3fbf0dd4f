"""Forward-kinematics research benchmark: the six reference FK searches.

Runs each case with a per-case timeout and prints boxes, CPU seconds, status, solution
count (and the solutions' first point).  CPU time (``time.process_time``) is reported
because the machine is shared; the timeout itself is wall time (solver limit).

    python benchmarks/fk_research.py [--timeout 60] [--cases planar10,t16] [--repeat 1]
                                     [--formulation auto] [--batch 256]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from certsolve.kinematics.fk import FKSolver, with_tau_max  # noqa: E402
from certsolve.robot import Robot  # noqa: E402

ROBOTS = os.path.join(ROOT, "examples", "robots")

# name -> (robot file, tau_max override or None, u)
CASES = {
    "planar10": ("planar.json", None, [0.0, 0.0, 0.0, 0.0]),
    "planar10-t60": ("planar.json", 60.0, [0.8, 1.8, -2.5, -3.6]),
    "almost13": ("almost-planar.json", None, [0.0] * 4),
    "t16": ("marionet-t.json", None, [0.0] * 7),
    "t16-t60": ("marionet-t.json", 60.0, [0.0] * 7),
    "general19": ("marionet.json", None, [0.0] * 7),
}
DEFAULT = list(CASES)
# intermediate cases for experiments (not run by default)
CASES.update(
    {
        "t16-t20": ("marionet-t.json", 20.0, [0.0] * 7),
        "t16-t30": ("marionet-t.json", 30.0, [0.0] * 7),
        "general19-t20": ("marionet.json", 20.0, [0.0] * 7),
        "almost13-t60": ("almost-planar.json", 60.0, [0.0] * 4),
    }
)


def run_case(name, timeout, formulation="auto", batch=None, **solver_opts):
    fname, tau, u = CASES[name]
    robot = Robot.load(os.path.join(ROBOTS, fname))
    robot = with_tau_max(robot, tau)
    kw = {} if batch is None else {"batch_size": batch}
    fk = FKSolver(robot, formulation, **kw)
    for k, v in solver_opts.items():
        setattr(fk.solver, k, v)
    t0 = time.process_time()
    w0 = time.perf_counter()
    res = fk.solve(np.array(u), timeout=timeout)
    cpu = time.process_time() - t0
    wall = time.perf_counter() - w0
    return fk, res, cpu, wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--cases", default=",".join(DEFAULT))
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--formulation", default="auto")
    ap.add_argument("--batch", type=int, default=None)
    args = ap.parse_args(argv)
    print(f"load average: {os.getloadavg()[0]:.2f}")
    hdr = f"{'case':14s} {'form':18s} {'boxes':>8s} {'cpu s':>7s} {'wall s':>7s} status      sols"
    print(hdr)
    for name in args.cases.split(","):
        for _ in range(args.repeat):
            fk, res, cpu, wall = run_case(name, args.timeout, args.formulation, args.batch)
            st = res.stats
            sols = "; ".join(
                "(" + ", ".join(f"{v:.2f}" for v in s.platform_points[0]) + ")"
                for s in res.solutions
            )
            print(
                f"{name:14s} {fk.formulation:18s} {st.boxes:8d} {cpu:7.2f} {wall:7.2f} "
                f"{res.status:11s} {len(res.solutions)} {sols} "
                f"und={len(res.undecided)}",
                flush=True,
            )


if __name__ == "__main__":
    main()
