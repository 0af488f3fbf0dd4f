"""Forward kinematics within tolerances (issue 31): time and boxes of the set's FK, and the
tightness of its pose boxes.

    python benchmarks/tolerance_bench.py [--runs 3] [--timeout 120] [--cases t16,general19]
                                         [--samples 12]

For each case (robot, tolerances, tau <= 10 N, u = 0) the median wall and CPU time of
:func:`certsolve.kinematics.forward_kinematics` on the robot with tolerances (the nominal
search, the seeds' proofs and the search of the rest), with its status, pose boxes, the
search's boxes beside them; then the tightness: the largest width of the pose box's
attachment bounds against the spread of the same attachments over ``--samples`` robots
drawn from the set (half at random corners) and solved one by one by the nominal FK.  The
targets (../shared/TARGETS.md, issue 31): T-16 with ±0.05 cm anchors and ±1 % on ``k`` at
10 N in <= 10 s, general-19 in <= 60 s.  Serial (one process).  Run on an idle machine
and note it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

from certsolve.kinematics import forward_kinematics
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
TOLERANCES = [
    {"path": "wires[*].base[*]", "plus_minus": 0.05},
    {"path": "wires[*].k", "relative": 0.01},
]
CASES = {"t16": "marionet-t.json", "general19": "marionet.json"}


def _robot(name: str) -> Robot:
    data = json.loads((ROBOTS / CASES[name]).read_text())
    for w in data["wires"]:
        w["tau"] = [min(w["tau"][0], 10.0), 10.0]
    data["tolerances"] = TOLERANCES
    return Robot.load(data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--cases", default="t16,general19")
    ap.add_argument("--samples", type=int, default=12)
    args = ap.parse_args()
    print(f"load average at the start {os.getloadavg()[0]:.2f}")
    print("case       status    poses  boxes    wall (s)  cpu (s)  box/spread (max)")
    for name in args.cases.split(","):
        robot = _robot(name)
        u = np.zeros(robot.m)
        walls, cpus = [], []
        for _ in range(args.runs):
            t0, c0 = time.perf_counter(), time.process_time()
            res = forward_kinematics(robot, u, timeout=args.timeout, executor=None)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        ratio = "-"
        if res.solutions and args.samples:
            rng = np.random.default_rng(0)
            pts = []
            for i in range(args.samples):
                sample = forward_kinematics(robot.draw(rng, corner=i % 2 == 0), u)
                pts += [s.platform_points for s in sample.solutions]
            spread = np.ptp(np.array(pts), axis=0)
            lo, hi = res.solutions[0].bounds.platform_points
            ratio = f"{np.max((hi - lo) / (spread + 1e-12)):.2f} ({np.max(hi - lo):.3f} cm)"
        print(
            f"{name:10s} {str(res.status):9s} {len(res.solutions):5d}  {res.stats.boxes:7d}  "
            f"{statistics.median(walls):8.2f}  {statistics.median(cpus):7.2f}  {ratio}"
        )
        runs = ", ".join(f"{w:.2f} ({c:.2f})" for w, c in zip(walls, cpus, strict=True))
        print(f"  runs, wall (cpu) s: {runs}; load average {os.getloadavg()[0]:.2f}")
        for note in res.notes:
            print(f"  note: {note}")


if __name__ == "__main__":
    main()
