"""Inverse kinematics timings for MARIONET (Merlet 2007, section II.A).

    /tmp/venv/bin/python benchmarks/ik_bench.py [--n 200] [--json]

Poses: ``n`` random poses within ±8 cm / ±4° of the workspace centre (111, 58, 107) for the
"full range" runs, and a trajectory of ``n`` small steps (0.1 mm and 0.005° per axis: a 1 kHz
control loop at 10 cm/s) for the "near the last u" runs, where each call gets the previous
call's controls (Algorithm 1 searches the 1 mm window around them).  Every call includes the whole
``inverse_kinematics`` entry point (geometry, solve, certificate, violations, result object).

References (Merlet 2007, ALIAS on a 2007 laptop): Algorithm 1 14 s (full stroke) and 2 s
(1 mm window); Algorithm 2 12 ms (full range) and 2 ms (near the last u).  Target for
Algorithm 2: <= 0.1 ms median (``../shared/TARGETS.md``), met by its reusable form
:class:`~certsolve.kinematics.ik_alg2.Algorithm2` (the "reused" row: the robot and the
options checked once, ``solve(pose)`` per pose).  The last row is an IK sweep
(:func:`certsolve.kinematics.ik_sweep.ik_sweep`, Merlet's Fig. 3 procedure) of ``n`` points of
``u_1`` in [-1, 1] cm at the centre pose: time per point, median over 5 sweeps.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from certsolve.kinematics.ik import inverse_kinematics  # noqa: E402
from certsolve.kinematics.ik_alg2 import Algorithm2  # noqa: E402
from certsolve.kinematics.ik_sweep import ik_sweep  # noqa: E402
from certsolve.robot import Pose, Robot  # noqa: E402

CENTRE = np.array([111.0, 58.0, 107.0, 0.0, 0.0, 0.0])


def poses_random(n, rng):
    d = np.concatenate([rng.uniform(-8, 8, (n, 3)), rng.uniform(-4, 4, (n, 3))], axis=1)
    return [Pose.from_params(6, list(CENTRE + x)) for x in d]


def poses_trajectory(n, rng):
    step = np.concatenate([np.full(3, 0.01), np.full(3, 0.005)])
    p = CENTRE.copy()
    out = []
    for _ in range(n + 1):
        p = p + step * rng.choice([-1.0, 1.0], 6)
        out.append(Pose.from_params(6, list(p)))
    return out


def timed(robot, poses, method, chain=False, reuse=False, **options):
    """Median/p90/min (ms) over the poses, certified/ok counts.  ``chain``: each call gets
    the previous call's controls (the first pose gives the first ones, not timed);
    ``reuse``: Algorithm 2 by one :class:`Algorithm2` (``method`` "alg2")."""
    if reuse:
        return _stats(poses, Algorithm2(robot, **options).solve)
    if not chain:
        return _stats(poses, lambda pose: inverse_kinematics(robot, pose, method, **options))
    last = [inverse_kinematics(robot, poses[0], method, **options).u]

    def call(pose):
        res = inverse_kinematics(robot, pose, method, u_last=last[0], **options)
        if res.u is not None:
            last[0] = res.u
        return res

    return _stats(poses[1:], call)


def _stats(poses, solve):
    """The figures of :func:`timed` for ``solve(pose)`` over the poses."""
    times, certified, ok = [], 0, 0
    for pose in poses:
        t0 = time.perf_counter()
        res = solve(pose)
        times.append(time.perf_counter() - t0)
        certified += res.certificate.kind != "none"
        ok += res.status == "ok"
    t = np.array(times) * 1e3
    return {
        "median_ms": float(np.median(t)),
        "p90_ms": float(np.percentile(t, 90)),
        "min_ms": float(t.min()),
        "calls": len(t),
        "certified": certified,
        "ok": ok,
    }


def timed_sweep(robot, n, repeat=5):
    """An IK sweep of ``n`` points: time per point (median, min over ``repeat`` sweeps)."""
    per_point = []
    for _ in range(repeat):
        res = ik_sweep(robot, list(CENTRE), joint=1, start=-1.0, stop=1.0, count=n)
        per_point.append(res.time / n * 1e3)
    return {
        "median_ms": float(np.median(per_point)),
        "p90_ms": float(np.percentile(per_point, 90)),
        "min_ms": float(min(per_point)),
        "calls": n,
        "certified": res.counts["certified"],
        "ok": res.counts["certified"],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200, help="poses per row (default 200)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    robot = Robot.load(ROOT / "examples/robots/marionet.json")
    rng = np.random.default_rng(args.seed)
    rand = poses_random(args.n, rng)
    traj = poses_trajectory(args.n, rng)
    for pose in rand[:20]:  # warm up (imports, caches)
        for m in ("tension", "alg1", "alg2"):
            inverse_kinematics(robot, pose, m)
    n_lp = max(20, args.n // 5)
    newton = {"solve": "newton"}
    rows = [
        ("tension-first, closed form", timed(robot, rand, "tension")),
        ("tension-first, LP (HiGHS)", timed(robot, rand[:n_lp], "tension", distribution="lp")),
        ("Alg 1, full stroke [-20, 20]", timed(robot, rand, "alg1")),
        ("Alg 1, 1 mm window around last u", timed(robot, traj, "alg1", True, window=0.1)),
        ("Alg 2, full range (tau solve)", timed(robot, rand, "alg2")),
        ("Alg 2, full range, reused Algorithm2", timed(robot, rand, "alg2", reuse=True)),
        ("Alg 2, full range (Newton from mid-stroke)", timed(robot, rand, "alg2", **newton)),
        ("Alg 2, near last u (Newton from last u)", timed(robot, traj, "alg2", True, **newton)),
        ("Alg 2, near last u (tau solve)", timed(robot, traj, "alg2", True)),
        ("IK sweep of u_1, per point (continuation)", timed_sweep(robot, args.n)),
    ]
    if args.json:
        print(json.dumps({name: r for name, r in rows}, indent=2))
        return 0
    print(f"MARIONET inverse kinematics, {args.n} poses per row (medians of single calls)")
    print(f"{'method':<44} {'median ms':>10} {'p90 ms':>8} {'min ms':>8} {'certified':>10}  ok")
    for name, r in rows:
        print(
            f"{name:<44} {r['median_ms']:>10.3f} {r['p90_ms']:>8.3f} {r['min_ms']:>8.3f} "
            f"{r['certified']:>5}/{r['calls']:<4} {r['ok']:>5}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
