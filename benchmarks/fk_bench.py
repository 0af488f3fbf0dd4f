"""Forward-kinematics benchmark: all-solutions searches, tracking steps, IK Algorithm 2.

    python benchmarks/fk_bench.py [--runs 3] [--workers 1,2] [--timeout 300] [--cases ...]
                                  [--formulation auto|general-19|T-16|...]

For each system (robot file, tau_max, control vector u) it prints the median wall and CPU
time of a complete all-solutions search with 1 and 2 worker processes, the status, number of
certified poses and boxes; then the median time of a certified tracking step (Newton +
Krawczyk in a ±1 mm box) and of IK Algorithm 2, over a trajectory.  Compare with
../shared/TARGETS.md; run on an idle machine and note it.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

from certsolve.kinematics import FKSolver, Tracker, inverse_kinematics, with_tau_max
from certsolve.robot import Pose, Robot

R = "examples/robots"
CASES = {
    "planar-10 tau<=10": ("planar", 10.0, [0.5, 0.5, 0.5, 0.5]),
    "planar-10 tau<=60": ("planar", 60.0, [0.8, 1.8, -2.5, -3.6]),
    "almost-planar-13 tau<=10": ("almost-planar", 10.0, [0.0, 0.0, 0.0, 0.0]),
    "T-16 tau<=10": ("marionet-t", 10.0, [0.0] * 7),
    "T-16 tau<=60": ("marionet-t", 60.0, [2.0] * 7),
    "general-19 tau<=10": ("marionet", 10.0, [0.0] * 7),
}
TRACK = {
    "general-19": ("marionet", (111, 58, 107, 0, 0, 0)),
    "T-16": ("marionet-t", (115, 60, 118, 0, 0, 0)),
    "planar-10": ("planar", (90, 60, 0)),
}


def bench_fk(args) -> None:
    print(
        f"{'case':<26} {'w':>2} {'status':<10} {'poses':>5} {'boxes':>8} {'wall s':>8} {'cpu s':>8}"
    )
    for name in args.cases or CASES:
        robot_name, tau, u = CASES[name]
        robot = with_tau_max(Robot.load(f"{R}/{robot_name}.json"), tau)
        for w in args.workers:
            walls, cpus, res = [], [], None
            for _ in range(args.runs):
                fk = FKSolver(robot, args.formulation)
                t, c = time.perf_counter(), time.process_time()
                res = fk.solve(u, timeout=args.timeout, workers=w)
                walls.append(time.perf_counter() - t)
                cpus.append(time.process_time() - c)
            print(
                f"{name:<26} {w:>2} {res.status:<10} {len(res.solutions):>5} "
                f"{res.stats.boxes:>8} {statistics.median(walls):>8.3f} "
                f"{statistics.median(cpus):>8.3f}",
                flush=True,
            )


def trajectory(robot, start, n, seed=0):
    rng = np.random.default_rng(seed)
    p = np.array(start, dtype=float)
    out = []
    for _ in range(n):
        p = p + rng.normal(0, 0.02, p.size)  # ~0.2 mm and ~0.02 deg per step
        out.append(Pose.from_params(robot.dof, p))
    return out


def bench_realtime(args) -> None:
    print(f"\n{'tracking / IK':<26} {'steps':>6} {'certified':>9} {'median ms':>10} {'p90 ms':>8}")
    for name, (robot_name, start) in TRACK.items():
        robot = Robot.load(f"{R}/{robot_name}.json")
        poses = trajectory(robot, start, args.steps)
        us = [np.asarray(inverse_kinematics(robot, p).u, dtype=float) for p in poses]
        tr = Tracker(robot)
        prev = Pose.from_params(robot.dof, start)
        times, ok = [], 0
        for u in us:
            t = time.perf_counter()
            res = tr.step(u, prev)
            times.append(time.perf_counter() - t)
            ok += res.certified
            if res.certified:
                prev = res.pose
        print(
            f"{'track ' + name:<26} {len(us):>6} {ok:>9} {1e3 * np.median(times):>10.3f} "
            f"{1e3 * np.percentile(times, 90):>8.3f}",
            flush=True,
        )
        if robot.dof == 6 and robot.m == 7:
            times, ok = [], 0
            for p in poses:
                t = time.perf_counter()
                r = inverse_kinematics(robot, p, method="alg2")
                times.append(time.perf_counter() - t)
                ok += r.certificate.kind == "unique-in-box"
            print(
                f"{'IK alg2 ' + robot_name:<26} {len(poses):>6} {ok:>9} "
                f"{1e3 * np.median(times):>10.3f} {1e3 * np.percentile(times, 90):>8.3f}",
                flush=True,
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--cases", nargs="*", choices=list(CASES), default=None)
    ap.add_argument(
        "--formulation", default="auto", help="auto (platform frame) or a paper system name"
    )
    ap.add_argument("--skip-fk", action="store_true")
    args = ap.parse_args()
    args.workers = [int(w) for w in args.workers.split(",")]
    print(
        f"# {platform.machine()}, {os.cpu_count()} cores, python "
        f"{platform.python_version()}; median of {args.runs} runs; "
        f"formulation {args.formulation}"
    )
    if not args.skip_fk:
        bench_fk(args)
    bench_realtime(args)


if __name__ == "__main__":
    main()
