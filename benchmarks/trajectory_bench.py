"""Real-time and path benchmark: a reused tracker step, the one-off ``track``, IK
Algorithm 2, and ``track_trajectory`` over a 1000-row path (issue 32).

    python benchmarks/trajectory_bench.py [--runs 3] [--steps 1000] [--robots T-16 general-19]

The path is :func:`fk_bench.trajectory`'s random walk (~0.2 mm and ~0.02° a row) from the
robot's reference pose, its controls from tension-first IK.  For each robot:

* ``step``: the median of :meth:`Tracker.step` over the first 200 rows, each from the
  previous certified pose, reused tracker;
* ``track``: the one-off :func:`certsolve.track` (compiles the system: the cost of one
  call in a control loop that does not keep a tracker), median of 5 calls;
* ``build``: constructing a :class:`Tracker` (the formulation, its compiled system and the
  generated code), median of 5;
* ``IK alg2``: :func:`certsolve.inverse_kinematics` ``method="alg2"`` at each pose of the
  path (dof 6 with 7 wires), median over 200 calls; ``alg2 core``: the same through
  :func:`~certsolve.kinematics.ik_alg2.ik_algorithm2` (the pose a ``Pose``, no input
  model to check); ``alg2 reuse``: :class:`certsolve.Algorithm2` built once, its
  ``solve(pose)`` at each pose (the documented reusable form; the notes say how many of
  the 200 results are certified, each by a Krawczyk test on two nested boxes);
* ``path``: the whole :func:`certsolve.track_trajectory` call (validation, compile, every
  step certified and joined), with its counters.

Each figure is the median of ``--runs`` runs of the median (per call) or of the total
(path), as wall time and as process CPU time: on a shared machine the CPU time is the cost,
the wall time what a user waited.  Run on an idle machine and note it.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np
from fk_bench import TRACK, R, trajectory

import certsolve
from certsolve.kinematics import Tracker, inverse_kinematics
from certsolve.kinematics.ik_alg2 import Algorithm2, ik_algorithm2
from certsolve.robot import Pose, Robot


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def medians(samples) -> tuple[float, float]:
    return statistics.median(s[0] for s in samples), statistics.median(s[1] for s in samples)


def bench_step(robot, start, us) -> tuple[float, float, int]:
    tr = Tracker(robot)
    prev = Pose.from_params(robot.dof, start)
    walls, cpus, ok = [], [], 0
    for u in us[:200]:
        res, w, c = timed(lambda u=u, prev=prev: tr.step(u, prev))
        walls.append(w)
        cpus.append(c)
        ok += res.certified
        if res.certified:
            prev = res.pose
    return statistics.median(walls), statistics.median(cpus), ok


def bench_track(robot, start, us) -> tuple[float, float]:
    out = [timed(lambda: certsolve.track(robot, us[0], list(start)))[1:] for _ in range(5)]
    return medians(out)


def bench_build(robot) -> tuple[float, float]:
    return medians([timed(lambda: Tracker(robot))[1:] for _ in range(5)])


def bench_alg2(robot, poses) -> tuple[float, float]:
    out = [timed(lambda p=p: inverse_kinematics(robot, p, method="alg2"))[1:] for p in poses[:200]]
    return medians(out)


def bench_alg2_core(robot, poses) -> tuple[float, float]:
    return medians([timed(lambda p=p: ik_algorithm2(robot, p))[1:] for p in poses[:200]])


def bench_alg2_reused(robot, poses) -> tuple[float, float, int]:
    alg2 = Algorithm2(robot)
    out = [timed(lambda p=p: alg2.solve(p)) for p in poses[:200]]
    w, c = medians([o[1:] for o in out])
    return w, c, sum(o[0].certificate.kind == "unique-in-box" for o in out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--robots", nargs="*", default=["T-16", "general-19"], choices=list(TRACK))
    args = ap.parse_args()
    print(
        f"# {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}, "
        f"load {os.getloadavg()[0]:.1f}; median of {args.runs} runs (wall / CPU)"
    )
    print(f"{'robot':<12} {'what':<10} {'wall':>10} {'CPU':>10}  notes")
    for name in args.robots:
        robot_name, start = TRACK[name]
        robot = Robot.load(f"{R}/{robot_name}.json")
        poses = trajectory(robot, start, args.steps)
        us = np.array([np.asarray(inverse_kinematics(robot, p).u, dtype=float) for p in poses])
        runs = [bench_step(robot, start, us) for _ in range(args.runs)]
        w, c = medians(runs)
        ok = f"{runs[0][2]}/200 certified"
        print(f"{name:<12} {'step':<10} {1e3 * w:>8.3f}ms {1e3 * c:>8.3f}ms  {ok}")
        w, c = medians([bench_build(robot) for _ in range(args.runs)])
        print(f"{name:<12} {'build':<10} {1e3 * w:>8.1f}ms {1e3 * c:>8.1f}ms  Tracker(robot)")
        w, c = medians([bench_track(robot, start, us) for _ in range(args.runs)])
        print(f"{name:<12} {'track':<10} {1e3 * w:>8.1f}ms {1e3 * c:>8.1f}ms  one-off call")
        if robot.dof == 6 and robot.m == 7:
            w, c = medians([bench_alg2(robot, poses) for _ in range(args.runs)])
            print(f"{name:<12} {'IK alg2':<10} {1e3 * w:>8.3f}ms {1e3 * c:>8.3f}ms  per call")
            w, c = medians([bench_alg2_core(robot, poses) for _ in range(args.runs)])
            print(f"{name:<12} {'alg2 core':<10} {1e3 * w:>8.3f}ms {1e3 * c:>8.3f}ms  per call")
            runs = [bench_alg2_reused(robot, poses) for _ in range(args.runs)]
            w, c = medians([r[:2] for r in runs])
            ok = f"{runs[0][2]}/200 certified"
            print(f"{name:<12} {'alg2 reuse':<10} {1e3 * w:>8.3f}ms {1e3 * c:>8.3f}ms  {ok}")
        samples = []
        for _ in range(args.runs):
            res, w, c = timed(
                lambda r=robot, us=us, s=start: certsolve.track_trajectory(r, us, list(s))
            )
            samples.append((w, c))
        w, c = medians(samples)
        print(
            f"{name:<12} {'path':<10} {w:>9.3f}s {c:>9.3f}s  {len(us)} rows: {res.status}, "
            f"{res.certified} certified; {res.chunks} chunks proven, {res.chunk_failures} "
            f"split, {res.halvings} links cut, {res.own_proofs} steps proven alone",
            flush=True,
        )


if __name__ == "__main__":
    main()
