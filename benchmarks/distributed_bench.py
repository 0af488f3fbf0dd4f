"""Executors benchmark: serial vs local processes vs a Dask LocalCluster, and what travels.

    python benchmarks/distributed_bench.py [--runs 3] [--workers 2] [--cases t16-60 katsura-7]
                                           [--executors serial processes dask] [--skip-search]

For each case it prints, per executor, the medians over ``--runs`` of the wall time, the CPU
time (this process plus every task: ``stats.cpu``), the boxes, boxes per wall second and per
CPU second, the tasks, and the status and number of solutions (which must not depend on the
executor).  Then the bytes that travel (the pickled step, scattered once; a task's boxes and
known solutions; a result) and the per-task overhead: the round trip of an empty task,
with and without the known solutions of a finished search.  The Dask cluster is a
``LocalCluster`` of ``--workers`` single-threaded worker processes on this machine.  Compare
with ../shared/TARGETS.md ("Dask cluster, 2 local workers vs serial, T-16 tau <= 60:
>= 1.7x"); note the machine's load: the figures are only as quiet as the machine.
"""

from __future__ import annotations

import argparse
import logging
import os
import pickle
import platform
import statistics
import time

import numpy as np

from certsolve.expr.minibex import load_minibex
from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.robot import Robot
from certsolve.solver import Limits, ProcessExecutor, Solver, run_search
from certsolve.solver.dask_executor import DaskExecutor
from certsolve.solver.search import Search, run_task


def t16_60():
    robot = with_tau_max(Robot.load("examples/robots/marionet-t.json"), 60.0)
    fk = FKSolver(robot)
    u = np.full(7, 2.0)
    return fk.search(u).solver  # u as the parameters, on its search box


def katsura7():
    # katsura-6 (2.4 s since the affine relaxation) ends inside the 2 s serial warm-up
    return Solver.default(load_minibex("benchmarks/systems/katsura-7.mbx"))


CASES = {"t16-60": t16_60, "katsura-7": katsura7}


def domain(step):
    dom = step.domain
    return dom[:, 0][None].copy(), dom[:, 1][None].copy()


def executors(names, workers, client):
    out = {}
    for name in names:
        if name == "serial":
            out[name] = None
        elif name == "processes":
            out[name] = ProcessExecutor(workers)
        elif name == "dask":
            out[name] = DaskExecutor(client)
    return out


def bench_search(args, client) -> None:
    print(
        f"{'case':<10} {'executor':<10} {'status':<9} {'sols':>4} {'boxes':>8} {'wall s':>7} "
        f"{'cpu s':>7} {'boxes/s':>8} {'boxes/cpu-s':>11} {'tasks':>5} {'speedup':>7}"
    )
    for case in args.cases:
        serial_wall = None
        for name, ex in executors(args.executors, args.workers, client).items():
            walls, cpus, boxes, runs = [], [], [], []
            for _ in range(args.runs):
                step = CASES[case]()
                t = time.perf_counter()
                run = run_search(step, *domain(step), executor=ex or None, limits=Limits())
                walls.append(time.perf_counter() - t)
                cpus.append(run.stats.cpu)
                boxes.append(run.stats.boxes)
                runs.append(run)
            w, c, b = statistics.median(walls), statistics.median(cpus), statistics.median(boxes)
            if name == "serial":
                serial_wall = w
            run = runs[-1]
            speed = f"{serial_wall / w:7.2f}" if serial_wall else f"{'-':>7}"
            print(
                f"{case:<10} {name:<10} {run.status!s:<9} "
                f"{run.state.solutions.count('ok'):>4} {b:>8.0f} {w:>7.2f} {c:>7.2f} "
                f"{b / w:>8.0f} {b / c:>11.0f} {run.stats.tasks:>5} {speed}",
                flush=True,
            )


def task_round_trips(pool, step, known, n: int) -> tuple[float, float]:
    """Median wall seconds from submitting an empty task to having its result back, and
    the CPU seconds per task of this process (driver, client; with a LocalCluster also its
    scheduler)."""
    empty = np.empty((0, step.n))
    times = []
    c = time.process_time()
    for _ in range(n):
        t = time.perf_counter()
        pool.submit(empty, empty, known, Limits(timeout=1.0))
        _, res, err = pool.next_done()
        if err is not None:
            raise err
        times.append(time.perf_counter() - t)
    return statistics.median(times), (time.process_time() - c) / n


def bench_travel(args, client) -> None:
    print(f"\n{'case':<10} {'what':<52} {'bytes':>9}")
    for case in args.cases:
        step = CASES[case]()
        # boxes of a task: from a search under way; known solutions: from a finished one
        # (the largest set a task carries)
        early = run_search(step, *domain(step), limits=Limits(max_boxes=20 * step.batch_size))
        lo, hi = early.state.stack.snapshot()
        k = min(len(lo), 2 * step.batch_size)
        step = CASES[case]()
        run = run_search(step, *domain(step), limits=Limits(timeout=args.known_seconds))
        known = step.known(run.state)
        n_sol = run.state.solutions.count("ok")
        rows = [
            ("step, pickled (scattered once)", len(pickle.dumps(step))),
            (f"boxes of a task ({k} boxes)", len(pickle.dumps((lo[:k], hi[:k])))),
            (
                f"known solutions ({n_sol} + {len(run.state.solutions) - n_sol} unicity boxes)",
                len(known),
            ),
        ]
        res = run_task(step, lo[:k], hi[:k], known, Limits(timeout=1.0))
        rows.append((f"a task's result ({len(res.lo)} boxes back)", len(pickle.dumps(res))))
        # the driver's own work per result: merge it, push its boxes, pickle the known set
        search = Search(step, run.state)
        t = time.process_time()
        for _ in range(10):
            search.in_flight += k
            search.absorb(lo[:k], res)
            step.known(run.state)
        merge_ms = 1e3 * (time.process_time() - t) / 10
        for what, size in rows:
            print(f"{case:<10} {what:<52} {size:>9}")
        print(f"{case:<10} {'driver CPU to merge a result (ms)':<52} {merge_ms:>9.2f}")
        for name, ex in executors(["processes", "dask"], args.workers, client).items():
            if name not in args.executors:
                continue
            pool = ex.open(step)
            try:
                task_round_trips(pool, step, None, 3)  # start-up
                bare, bare_cpu = task_round_trips(pool, step, None, args.trips)
                full, full_cpu = task_round_trips(pool, step, known, args.trips)
            finally:
                pool.close()
            for what, (wall, cpu) in (
                ("empty task", (bare, bare_cpu)),
                ("... with the known solutions", (full, full_cpu)),
            ):
                print(
                    f"{case:<10} {name + ' ' + what + ': round trip ms':<52} {1e3 * wall:>9.2f}\n"
                    f"{case:<10} {'  driver CPU ms per task':<52} {1e3 * cpu:>9.2f}"
                )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cases", nargs="*", choices=list(CASES), default=list(CASES))
    ap.add_argument(
        "--executors",
        nargs="*",
        choices=["serial", "processes", "dask"],
        default=["serial", "processes", "dask"],
    )
    ap.add_argument("--trips", type=int, default=30, help="empty tasks timed per executor")
    ap.add_argument("--known-seconds", type=float, default=600.0)
    ap.add_argument("--skip-search", action="store_true")
    ap.add_argument(
        "--dask-malloc-default",
        action="store_true",
        help="keep Dask's MALLOC_TRIM_THRESHOLD_=65536 for the workers",
    )
    args = ap.parse_args()
    print(
        f"# {platform.machine()}, {os.cpu_count()} cores, load average "
        f"{', '.join(f'{v:.1f}' for v in os.getloadavg())}, python "
        f"{platform.python_version()}; median of {args.runs} runs; {args.workers} workers"
    )
    client = cluster = None
    if "dask" in args.executors:
        import dask
        from distributed import Client, LocalCluster

        # Dask's default MALLOC_TRIM_THRESHOLD_=65536 for its workers (and, with a
        # LocalCluster, for this process) doubles the CPU time of the solver's batches
        # (docs/distributed.md); --dask-malloc-default keeps it to measure that
        key = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
        with dask.config.set({} if args.dask_malloc_default else {key: None}):
            cluster = LocalCluster(
                n_workers=args.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
        client = Client(cluster)
    try:
        if not args.skip_search:
            bench_search(args, client)
        bench_travel(args, client)
    finally:
        if client is not None:
            client.close()
            cluster.close()
    print(f"# load average at the end {', '.join(f'{v:.1f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
