"""Where is the robot?  Time to the first certified stable pose on real control vectors.

For each robot and each of ``--poses`` random poses near the middle of the workspace
(within 10 cm and 10 degrees), ``u`` is computed by inverse kinematics (max-margin tensions
in ``--tensions``, e.g. 1-9 N), and forward kinematics at tau <= ``--tau-max`` is run with
``stable_only=True, max_solutions=1``: the time and boxes until the first certified stable
pose, whether it is the pose ``u`` was computed from, and how many local minima of the
energy the float descent found (:mod:`certsolve.kinematics.energy_minima`).  With
``--no-seeds`` the same searches run without the seeds, with ``--timeout`` each.

    python benchmarks/stable_first_bench.py [--robots marionet,marionet-t,random-general-0]
        [--poses 3] [--tensions 1,9] [--tau-max 60] [--timeout 60] [--no-seeds]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from fk_bench import load, with_tensions

from certsolve import Pose, Robot, inverse_kinematics
from certsolve.kinematics.energy_minima import energy_minima
from certsolve.kinematics.fk_solver import FKSolver, with_tau_max

MIDDLE = {"marionet": (111.0, 58.0, 107.0), "marionet-t": (111.0, 58.0, 107.0)}


def real_u(robot: Robot, rng, tensions) -> tuple[Pose, np.ndarray] | None:
    """u from IK at a random pose near the middle (None if that pose is not feasible)."""
    middle = MIDDLE.get(robot.name, tuple(robot.domain.mean(axis=1)))
    for _ in range(50):
        params = np.r_[np.add(middle, rng.uniform(-10, 10, 3)), rng.uniform(-10, 10, 3)]
        pose = Pose.from_params(6, params)
        res = inverse_kinematics(with_tensions(robot, *tensions), pose, method="tension")
        if res.feasible:
            return pose, np.asarray(res.u, dtype=float)
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", default="marionet,marionet-t,random-general-0,random-T-1")
    ap.add_argument("--poses", type=int, default=3)
    ap.add_argument("--tensions", default="1,9")
    ap.add_argument("--tau-max", type=float, default=60.0)
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--no-seeds", action="store_true")
    args = ap.parse_args()
    tensions = tuple(float(v) for v in args.tensions.split(","))
    print(
        "| robot | pose | minima | status | stable poses | the IK pose | boxes | CPU s | wall s |"
    )
    print("|---|---|---:|---|---:|---|---:|---:|---:|")
    for name in args.robots.split(","):
        robot = with_tau_max(load(name), args.tau_max)
        fk = FKSolver(robot, stable_only=True, seed_minima=not args.no_seeds)
        rng = np.random.default_rng(7)
        for k in range(args.poses):
            drawn = real_u(robot, rng, tensions)
            if drawn is None:
                print(f"| {name} | {k} | no feasible pose drawn |")
                continue
            pose, u = drawn
            minima = len(energy_minima(robot, u))
            t, c = time.perf_counter(), time.process_time()
            res = fk.solve(u, timeout=args.timeout, max_solutions=1, workers=1)
            wall, cpu = time.perf_counter() - t, time.process_time() - c
            target = pose.position + robot.B @ pose.rotation.T
            same = [np.max(np.abs(s.platform_points - target)) < 1e-6 for s in res.solutions]
            print(
                f"| {name} | {k} | {minima} | {res.status} | {len(res.solutions)} | "
                f"{'yes' if any(same) else 'no'} | {res.stats.boxes:,} | {cpu:.2f} | {wall:.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
