"""Forward-kinematics benchmark: all-solutions searches, the cost curve, start-up, tracking
and IK Algorithm 2.

    python benchmarks/fk_bench.py [--runs 3] [--workers 1,2] [--timeout 300] [--cases ...]
                                  [--only PATTERN]
                                  [--formulation auto|general-19|T-16|...] [--curve]
                                  [--startup] [--skip-fk] [--skip-realtime]
                                  [--position-newton on|off] [--relax on|off|default]

Searches: for each case (robot, tau_max, control vector u) the median wall and CPU time of a
complete all-solutions search with each worker count, with the status, certified poses,
boxes and bisections beside them.  Cases marked ``target`` are the targets of issue 10
(../shared/TARGETS.md); ``u~S(seed)`` is u drawn uniformly in the strokes with that seed
(``x0.25``: in the middle quarter of every stroke, issue 29's case of <= 120 s),
``random-general-N`` / ``random-T-N`` the perturbed designs of
:func:`certsolve.robot.presets.random_marionet`; ``u=IK(P)`` the control vector of IK
Algorithm 2 at ``REAL_POSE``, ``u=IK(~,lo-hi)`` IK at a random pose near the middle with
tensions in ``[lo, hi]`` N (:func:`control`); ``stable-only`` cases search for stable
equilibria only.  ``--only PATTERN`` runs the cases whose name matches the regular
expression (``--only stable-only`` the stable-only cases).

``--where CASE``: where a stable-only search's boxes go (:func:`where_boxes`): every box
that reaches the stable-only test, by distance to the nearest equilibrium, by width, by
tension range, each split by the test's outcome (``--max-boxes`` stops the search early).

``--position-newton on|off``: the searches with the position's Newton step on or off
(:mod:`certsolve.kinematics.fk_position`; off by default, as in FKSolver).  ``--relax
on|off``: with or without the polytope hull once a round (``FKSolver(relax=...)``; by
default FKSolver's default: on for spatial robots).  ``--newton-starts on|off``: with or
without the phases of float Newton from random points (``FKSolver(newton_starts=...)``, on
by default; never in the stable-only cases).

``--curve``: how time and boxes grow with tau_max (10, 20, 40, 60 N) and with the stroke
range (u drawn in 1/4, 1/2 and all of the strokes, seed 1), for T-16 and general-19, one
run each: the table a user needs to plan a run.  ``--startup``: the whole ``certsolve fk``
process on the planar example and ``certsolve --help`` (median of 5).  Then the median time
of a certified tracking step (Newton + Krawczyk in a ±1 mm box) and of IK Algorithm 2 over a
trajectory.  Run on an idle machine and note it.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import statistics
import subprocess
import sys
import time

import numpy as np

from certsolve.kinematics import FKSolver, Tracker, inverse_kinematics, with_tau_max
from certsolve.kinematics.stable_only import StableOnly
from certsolve.robot import Pose, Robot
from certsolve.robot.presets import MARIONET_MIDDLE, MARIONET_T_MIDDLE, random_marionet
from certsolve.solver.pipeline import find

R = "examples/robots"
ZERO4, ZERO7 = [0.0] * 4, [0.0] * 7
#: a real pose: ``u = IK(P)`` is computed by IK Algorithm 2 on the robot file (its own
#: tension limits), so the robot is at P (issue 29)
REAL_POSE = (111.0, 58.0, 107.0, 0.0, 0.0, 0.0)
#: a random real pose near the middle of the workspace: up to this many cm and degrees off it
NEAR = (10.0, 10.0)
#: a real control vector comes from a *feasible* IK (every tension within its limits, so
#: the robot is at rest at the drawn pose): up to this many poses are drawn for one seed
FEASIBLE_DRAWS = 50
#: name -> (robot, tau_max, u: a list, ("S", seed, fraction) drawn in the strokes, ("IK",
#: pose) or ("IK~", seed, (tau_lo, tau_hi)): IK at the first random pose near the middle where
#: it is feasible)
CASES = {
    "planar-10 tau<=10": ("planar", 10.0, [0.5, 0.5, 0.5, 0.5]),
    "planar-10 tau<=60": ("planar", 60.0, [0.8, 1.8, -2.5, -3.6]),
    "almost-planar-13 tau<=10": ("almost-planar", 10.0, ZERO4),
    "almost-planar-13 tau<=60 (target)": ("almost-planar", 60.0, ZERO4),
    "T-16 tau<=10 (target)": ("marionet-t", 10.0, ZERO7),
    "T-16 tau<=60 u=2 (target)": ("marionet-t", 60.0, [2.0] * 7),
    "T-16 tau<=60 u~S(1)": ("marionet-t", 60.0, ("S", 1, 1.0)),
    "general-19 tau<=10 (target)": ("marionet", 10.0, ZERO7),
    "general-19 tau<=20 u~S(1)": ("marionet", 20.0, ("S", 1, 1.0)),
    "general-19 tau<=40 u~S(1)": ("marionet", 40.0, ("S", 1, 1.0)),
    "general-19 tau<=60 u~S(1) (target)": ("marionet", 60.0, ("S", 1, 1.0)),
    "general-19 tau<=60 u~S(2) (target)": ("marionet", 60.0, ("S", 2, 1.0)),
    "general-19 tau<=60 u~S(3) (target)": ("marionet", 60.0, ("S", 3, 1.0)),
    "random-T-0 tau<=60 u~S(7)": ("random-T-0", 60.0, ("S", 7, 1.0)),
    "random-general-0 tau<=20 u~S(7)": ("random-general-0", 20.0, ("S", 7, 1.0)),
    "random-general-0 tau<=40 u~S(7)": ("random-general-0", 40.0, ("S", 7, 1.0)),
    "random-general-0 tau<=60 u~S(7)": ("random-general-0", 60.0, ("S", 7, 1.0)),
    "random-general-1 tau<=60 u~S(7)": ("random-general-1", 60.0, ("S", 7, 1.0)),
    # the middle quarter of the strokes (docs/fk-cost.md's curve): u near the reachable set
    "general-19 tau<=60 u~S(1) x0.25 (target)": ("marionet", 60.0, ("S", 1, 0.25)),
    "T-16 tau<=60 u=IK(P)": ("marionet-t", 60.0, ("IK", REAL_POSE)),
    "T-16 tau<=60 u=IK(P) stable-only (target)": ("marionet-t", 60.0, ("IK", REAL_POSE)),
    "general-19 tau<=60 u=IK(P)": ("marionet", 60.0, ("IK", REAL_POSE)),
    "general-19 tau<=60 u=IK(P) stable-only (target)": ("marionet", 60.0, ("IK", REAL_POSE)),
    "random-general-0 tau<=60 u=IK(~,1-9)": ("random-general-0", 60.0, ("IK~", 0, (1.0, 9.0))),
    "random-general-1 tau<=60 u=IK(~,5-40)": ("random-general-1", 60.0, ("IK~", 1, (5.0, 40.0))),
    "random-general-2 tau<=60 u=IK(~,1-9)": ("random-general-2", 60.0, ("IK~", 2, (1.0, 9.0))),
    "random-general-2 tau<=60 u=IK(~,1-9) stable-only": (
        "random-general-2",
        60.0,
        ("IK~", 2, (1.0, 9.0)),
    ),
    "random-T-1 tau<=60 u=IK(~,1-9)": ("random-T-1", 60.0, ("IK~", 1, (1.0, 9.0))),
    "random-T-1 tau<=60 u=IK(~,1-9) stable-only": ("random-T-1", 60.0, ("IK~", 1, (1.0, 9.0))),
}
CURVE_TAUS = (10.0, 20.0, 40.0, 60.0)
CURVE_STROKES = (0.25, 0.5, 1.0)
TRACK = {
    "general-19": ("marionet", (111, 58, 107, 0, 0, 0)),
    "T-16": ("marionet-t", (115, 60, 118, 0, 0, 0)),
    "planar-10": ("planar", (90, 60, 0)),
}


def load(name: str) -> Robot:
    """A bundled example, or ``random-<kind>-<seed>`` (a perturbed MARIONET design)."""
    if name.startswith("random-"):
        _, kind, seed = name.split("-")
        return Robot.load(random_marionet(kind, int(seed)))
    return Robot.load(f"{R}/{name}.json")


def near_pose(robot: Robot, seed: int, draw: int = 0) -> list[float]:
    """A random pose within :data:`NEAR` of the middle of the workspace (the pose the
    robot's strokes are centred on: :func:`random_marionet`); ``draw`` > 0 the next ones."""
    middle = MARIONET_T_MIDDLE if len({tuple(b) for b in robot.B}) == 3 else MARIONET_MIDDLE
    rng = np.random.default_rng(seed if draw == 0 else (seed, draw))
    cm, deg = NEAR
    pose = np.concatenate([np.array(middle) + rng.uniform(-cm, cm, 3), rng.uniform(-deg, deg, 3)])
    return [float(v) for v in pose]


def with_tensions(robot: Robot, lo: float, hi: float) -> Robot:
    """The robot with every wire's tension limits set to ``[lo, hi]``."""
    data = robot.spec.model_dump()
    for w in data["wires"]:
        w["tau"] = [lo, hi]
    return Robot.load(data)


def control(robot: Robot, u, base: Robot | None = None) -> np.ndarray:
    """A control vector: given, ``("IK", pose)``: IK Algorithm 2 at ``pose`` on ``base``
    (the robot file, before ``tau_max``), ``("IK~", seed, (lo, hi))``: IK at a random pose
    near the middle (:func:`near_pose`) with the max-margin tensions in ``[lo, hi]``
    (:func:`inverse_kinematics`'s default method), or ``("S", seed, fraction)``: uniform in
    that share of the strokes around their middle."""
    if isinstance(u, tuple) and u[0] == "IK":
        return inverse_kinematics(base or robot, list(u[1]), method="alg2").u
    if isinstance(u, tuple) and u[0] == "IK~":
        _, seed, (lo, hi) = u
        base = base or robot
        for draw in range(FEASIBLE_DRAWS):  # the first drawn pose whose IK is feasible
            res = inverse_kinematics(with_tensions(base, lo, hi), near_pose(base, seed, draw))
            if res.feasible:
                return np.asarray(res.u, dtype=float)
        raise RuntimeError(f"no feasible pose in {FEASIBLE_DRAWS} draws of seed {seed}")
    if isinstance(u, tuple):
        _, seed, frac = u
        mid = 0.5 * (robot.u_min + robot.u_max)
        half = 0.5 * frac * (robot.u_max - robot.u_min)
        return np.random.default_rng(seed).uniform(mid - half, mid + half)
    return np.asarray(u, dtype=float)


def run_case(robot: Robot, u, args, workers: int, stable_only: bool = False):
    """Median wall and CPU over ``args.runs`` runs, and the last result."""
    walls, cpus, res = [], [], None
    for _ in range(args.runs):
        fk = FKSolver(
            robot,
            args.formulation,
            stable_only=stable_only,
            position_newton=args.position_newton == "on",
            relax=None if args.relax == "default" else args.relax == "on",
            newton_starts=args.newton_starts == "on",
        )
        t, c = time.perf_counter(), time.process_time()
        res = fk.solve(u, timeout=args.timeout, workers=workers)
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return statistics.median(walls), statistics.median(cpus), res


HEAD = (
    f"{'case':<48} {'w':>2} {'status':<10} {'poses':>5} {'boxes':>8} {'bisect':>7} "
    f"{'wall s':>8} {'cpu s':>8} {'all cpu s':>9}"
)


def row(name, w, res, wall, cpu) -> str:
    """One line of the table: ``cpu s`` is this process's (median), ``all cpu s`` the last
    run's search with its workers' tasks (:attr:`.SearchStats.cpu`)."""
    return (
        f"{name:<48} {w:>2} {res.status:<10} {len(res.solutions):>5} {res.stats.boxes:>8} "
        f"{res.stats.bisections:>7} {wall:>8.2f} {cpu:>8.2f} {res.stats.cpu:>9.2f}"
    )


def bench_fk(args) -> None:
    print(HEAD)
    names = args.cases or [c for c in CASES if args.only is None or re.search(args.only, c)]
    for name in names:
        robot_name, tau, u = CASES[name]
        base = load(robot_name)
        robot = with_tau_max(base, tau)
        uu = control(robot, u, base)
        for w in args.workers:
            wall, cpu, res = run_case(robot, uu, args, w, "stable-only" in name)
            print(row(name, w, res, wall, cpu), flush=True)


class RecordBoxes:
    """A stable-only test that keeps, for every box reaching it, its bounds, its tension
    ranges and the outcome: not tested (the tension gate), dropped, or kept."""

    def __init__(self, inner: StableOnly):
        self.inner = inner
        self.rows: list[tuple[np.ndarray, ...]] = []

    def apply(self, batch) -> None:
        lo, hi = batch.lo.copy(), batch.hi.copy()
        self.inner.apply(batch)
        ranges = self.inner.tension_ranges(lo, hi)
        tested = np.all(ranges <= self.inner.max_width, axis=1)
        self.rows.append((lo, hi, ranges.max(axis=1), tested, batch.empty.copy()))

    def describe(self) -> str:
        return self.inner.describe()


def equilibria(fk: FKSolver, search, starts: np.ndarray):
    """The distinct equilibria in the search domain that float Newton reaches from
    ``starts``, with their stability at the point (an experiment's reference, not a proof)."""
    x, ok = search.solver.certifier.newton_point(starts)
    dom = search.domain
    x = x[ok & np.all((x >= dom[:, 0]) & (x <= dom[:, 1]), axis=1)]
    points: list[np.ndarray] = []
    for p in x:
        if all(np.max(np.abs(p - q)) > 1e-6 for q in points):
            points.append(p)
    verdicts = fk.hessian.verdicts(np.array(points) - 1e-9, np.array(points) + 1e-9, search.u)
    return np.array(points).reshape(-1, dom.shape[0]), [str(v.stability) for v in verdicts]


def histogram(title: str, key: np.ndarray, edges, outcome: np.ndarray, names) -> None:
    """A markdown table: the rows of ``key`` binned by ``edges``, split by ``outcome``."""
    print(f"\n| {title} | " + " | ".join(names) + " | all |")
    print("|---" + "|---:" * (len(names) + 1) + "|")
    bins = np.digitize(key, edges)
    labels = [f"< {edges[0]:g}"] + [f"{a:g}-{b:g}" for a, b in zip(edges, edges[1:])]
    for b, label in enumerate([*labels, f">= {edges[-1]:g}"]):
        m = bins == b
        if m.any():
            counts = " | ".join(f"{np.sum(outcome[m] == k):,}" for k in range(len(names)))
            print(f"| {label} | {counts} | {m.sum():,} ({100 * m.mean():.1f} %) |")


def where_boxes(args) -> None:
    """Where a stable-only search's boxes go: every box reaching the stable-only test
    (after HC4 and the partial Newton, each pass of the fixpoint), by distance (cm, max over
    the pose variables) to the nearest equilibrium, by width and by tension range."""
    robot_name, tau, u = CASES[args.where]
    base = load(robot_name)
    robot = with_tau_max(base, tau)
    fk = FKSolver(robot, args.formulation, stable_only=True)
    search = fk.search(control(robot, u, base))
    rec = RecordBoxes(find(search.solver.contractor, StableOnly))
    search.solver.contractor = search.solver.contractor.replace(rec.inner, rec)
    boxes, _ = fk.seeded_boxes(search.u, search.domain)
    t, c = time.perf_counter(), time.process_time()
    res = search.solver.solve(boxes=boxes, max_boxes=args.max_boxes, workers=1)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    lo, hi, ranges, tested, empty = (np.concatenate(a) for a in zip(*rec.rows, strict=True))
    pose = np.setdiff1d(np.arange(lo.shape[1]), fk.form.rho_columns())
    mid = 0.5 * (lo + hi)
    rng = np.random.default_rng(0)
    starts = mid[rng.choice(len(mid), min(40_000, len(mid)), replace=False)]
    points, kinds = equilibria(fk, search, starts)
    print(
        f"{args.where}: {res.status}, {res.stats.boxes:,} boxes, {cpu:.1f} CPU s, "
        f"{wall:.1f} s wall; {len(lo):,} boxes reached the test"
    )
    print("\n| equilibrium (Newton from the boxes) | P1 | stability | nearest of |")
    print("|---|---|---|---:|")
    dist = np.abs(mid[:, None, pose] - points[None, :, pose]).max(axis=2)
    nearest = dist.argmin(axis=1)
    for j, (p, kind) in enumerate(zip(points, kinds, strict=True)):
        print(f"| {j} | {np.round(p[:3], 2).tolist()} | {kind} | {np.sum(nearest == j):,} |")
    neg = np.concatenate(
        [
            np.linalg.eigvalsh(0.5 * np.add(*fk.hessian.enclose(m, m, search.u)))[:, 0] < 0
            for m in np.array_split(mid, max(1, len(mid) // 4096))
        ]
    )
    outcome = np.where(~tested, 0, np.where(empty, 1, np.where(neg, 2, 3)))
    names = ["not tested", "dropped", "kept, indefinite at mid", "kept, PD at mid"]
    width = (hi - lo)[:, pose].max(axis=1)
    histogram("distance (cm)", dist.min(axis=1), [0.5, 2, 5, 10, 20, 50], outcome, names)
    histogram("width (cm)", width, [1, 3, 10, 30], outcome, names)
    histogram("tension range (N)", ranges, [5, 10, 20, 30, 40, 50], outcome, names)


def bench_curve(args) -> None:
    """Time and boxes against tau_max and the stroke range (one run each)."""
    print(f"\ncost curve (u drawn in a share of the strokes, seed 1; 1 run each)\n{HEAD}")
    one = argparse.Namespace(**{**vars(args), "runs": 1})
    for robot_name, label in (("marionet-t", "T-16"), ("marionet", "general-19")):
        for tau in CURVE_TAUS:
            for frac in CURVE_STROKES:
                robot = with_tau_max(load(robot_name), tau)
                uu = control(robot, ("S", 1, frac))
                for w in args.workers:
                    wall, cpu, res = run_case(robot, uu, one, w)
                    name = f"{label} tau<={tau:g} stroke x{frac:g}"
                    print(row(name, w, res, wall, cpu), flush=True)


def bench_startup(args) -> None:
    """The whole ``certsolve`` process: ``--help`` and planar FK (median of 5 runs)."""
    cmds = {
        "certsolve --help": ["--help"],
        "certsolve fk planar (tau<=10)": [
            "fk", f"{R}/planar.json", "--u", "0.5,0.5,0.5,0.5", "--tau-max", "10"
        ],
    }  # fmt: skip
    print(f"\n{'process':<36} {'median s':>9} {'min s':>7}")
    for name, argv in cmds.items():
        times = []
        for _ in range(5):
            t = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "certsolve", *argv], check=True, capture_output=True
            )
            times.append(time.perf_counter() - t)
        print(f"{name:<48} {statistics.median(times):>9.3f} {min(times):>7.3f}", flush=True)


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
    ap.add_argument("--only", default=None, help="the cases whose name matches this regex")
    ap.add_argument("--where", choices=list(CASES), help="where a stable-only search's boxes go")
    ap.add_argument("--max-boxes", type=int, default=None, help="with --where: stop after these")
    ap.add_argument("--curve", action="store_true", help="the cost curve over tau_max, strokes")
    ap.add_argument("--startup", action="store_true", help="whole-process start-up times")
    ap.add_argument("--skip-realtime", action="store_true")
    ap.add_argument(
        "--formulation", default="auto", help="auto (platform frame) or a paper system name"
    )
    ap.add_argument("--skip-fk", action="store_true")
    ap.add_argument(
        "--position-newton",
        choices=("on", "off"),
        default="off",
        help="the searches with FKSolver(position_newton=True / False) "
        "(kinematics/fk_position.py; default off, FKSolver's default)",
    )
    ap.add_argument(
        "--newton-starts",
        choices=("on", "off"),
        default="on",
        help="the searches with FKSolver(newton_starts=True / False): float Newton from "
        "random points of the pending boxes, proven (default on, FKSolver's default)",
    )
    ap.add_argument(
        "--relax",
        choices=("on", "off", "default"),
        default="default",
        help="the searches with FKSolver(relax=True / False): the polytope hull once a round "
        "(default: FKSolver's, on for spatial robots)",
    )
    args = ap.parse_args()
    args.workers = [int(w) for w in args.workers.split(",")]
    print(
        f"# {platform.machine()}, {os.cpu_count()} cores, python "
        f"{platform.python_version()}; median of {args.runs} runs; "
        f"formulation {args.formulation}; position Newton {args.position_newton}; "
        f"relax {args.relax}"
    )
    if args.where:
        where_boxes(args)
        return
    if args.startup:
        bench_startup(args)
    if not args.skip_fk:
        bench_fk(args)
    if args.curve:
        bench_curve(args)
    if not args.skip_realtime:
        bench_realtime(args)


if __name__ == "__main__":
    main()
