"""Benchmarks of certsolve.force: isotropic-force maps and certified workspaces.

    python benchmarks/force_bench.py [--repeat 5] [--quick]

Prints medians (and min/max) over ``--repeat`` runs:

* maps: poses per second and microseconds per pose of :func:`isotropic_map` on a grid
  (200 x 200 for the planar robots, 100 x 100 at z = 107 cm for MARIONET), vectorised;
* a single pose: :func:`isotropic_force` (with the polytope's facets and, for dof 6, the
  hull of the force section);
* certified workspaces: time, boxes processed and proven share at two ``eps`` values;
* certified design (krut-3, two parameters): time, pairs, shares at three ``eps`` values.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from certsolve.force import certified_workspace, isotropic_force, isotropic_map
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"


def timed(fn, repeat):
    out, times = None, []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, times


def fmt_times(ts):
    return f"{statistics.median(ts):8.3f} ({min(ts):.3f}-{max(ts):.3f})"


def bench_maps(repeat: int, quick: bool):
    rows = []
    cases = [
        ("krut-3", (-100, 100, -100, 100), None, 200),
        ("krut-4", (-100, 100, -100, 100), None, 200),
        ("krut-6", (-100, 100, -100, 100), None, 200),
        ("planar", (0, 180, 0, 120), None, 200),
        ("marionet", (30, 160, 30, 110), 107.0, 100),
    ]
    for name, (x0, x1, y0, y1), z, n in cases:
        if quick:
            n = n // 2
        robot = Robot.load(ROBOTS / f"{name}.json")
        xs, ys = np.linspace(x0, x1, n), np.linspace(y0, y1, n)
        isotropic_map(robot, xs[:5], ys[:5], z=z)  # warm-up (caches, imports)
        _, ts = timed(lambda r=robot, xs=xs, ys=ys, z=z: isotropic_map(r, xs, ys, z=z), repeat)
        med = statistics.median(ts)
        rows.append((name, f"{n}x{n}", fmt_times(ts), n * n / med, 1e6 * med / (n * n)))
    print("\nisotropic-force maps (vectorised over the grid)")
    print(
        f"{'robot':<10} {'grid':>8} {'time s, median (min-max)':>27} {'poses/s':>11} {'us/pose':>8}"
    )
    for name, grid, t, pps, us in rows:
        print(f"{name:<10} {grid:>8} {t:>27} {pps:11.0f} {us:8.2f}")


def bench_single(repeat: int):
    print("\nsingle pose (polytope facets; dof 6 also the hull of the force section)")
    print(f"{'robot':<10} {'pose':<18} {'ms, median':>10} {'f_min (N)':>12}")
    for name, pose in [
        ("krut-3", [0.0, 0.0]),
        ("krut-6", [10.0, 20.0]),
        ("planar", [90.0, 60.0]),
        ("marionet", [111.0, 58.0, 107.0]),
    ]:
        robot = Robot.load(ROBOTS / f"{name}.json")
        res, ts = timed(lambda r=robot, p=pose: isotropic_force(r, p), repeat * 4)
        print(
            f"{name:<10} {','.join(f'{v:g}' for v in pose):<18} "
            f"{1e3 * statistics.median(ts):10.3f} {res.isotropic_force:12.6f}"
        )


def bench_workspace(repeat: int, quick: bool):
    cases = [
        ("krut-3", 100.0, [-100, 100, -100, 100], (2.0, 0.5), {}),
        ("krut-6", 200.0, [-100, 100, -100, 100], (2.0, 0.5), {}),
        ("planar", 1.0, [0, 180, 0, 120], (2.0, 0.5), {}),
        ("marionet", 1.0, [90, 130, 40, 80, 90, 130], (4.0, 2.0), {}),
    ]
    print("\ncertified workspace {f_min >= F} (2 cores shared; median of runs)")
    print(
        f"{'robot':<10} {'F (N)':>6} {'eps':>5} {'time s, median (min-max)':>27} "
        f"{'boxes':>8} {'inside':>7} {'boundary':>8} {'share %':>8}"
    )
    for name, f_req, box, epss, kw in cases:
        robot = Robot.load(ROBOTS / f"{name}.json")
        for eps in epss[:1] if quick else epss:
            reps = 1 if (name == "marionet" or quick) else repeat
            ws, ts = timed(
                lambda r=robot, f=f_req, b=box, e=eps, k=kw: certified_workspace(r, f, b, e, **k),
                reps,
            )
            print(
                f"{name:<10} {f_req:6g} {eps:5g} {fmt_times(ts):>27} {ws.boxes:8d} "
                f"{len(ws.inside):7d} {len(ws.boundary):8d} {100 * ws.inside_share:8.2f}"
            )


def bench_design(repeat: int, quick: bool):
    """Certified design of Krut's 3-motor robot (examples/design/krut3-spec.json)."""
    from certsolve.force.design import design
    from certsolve.force.design_spec import load_design_spec

    spec = load_design_spec(ROBOTS.parent / "design" / "krut3-spec.json")
    print("\ncertified design, krut-3: base half-width x tau_max, F = 150 N on [-20, 20]^2")
    print(
        f"{'eps':>6} {'ws eps':>7} {'time s, median (min-max)':>27} {'pairs':>8} "
        f"{'boxes':>6} {'good %':>7} {'bad %':>6} {'undec. %':>8}"
    )
    settings = [(1 / 16, 2.5), (1 / 32, 1.25)] + ([] if quick else [(1 / 64, 0.625)])
    for eps, weps in settings:
        res, ts = timed(
            lambda e=eps, w=weps: design(spec.model_copy(update={"eps": e, "workspace_eps": w})),
            1 if quick else 3,
        )
        print(
            f"{eps:6.4f} {weps:7g} {fmt_times(ts):>27} {res.pairs:8d} {res.parameter_boxes:6d} "
            f"{100 * res.share('good'):7.1f} {100 * res.share('bad'):6.1f} "
            f"{100 * res.share('undecided'):8.1f}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per measurement (median)")
    ap.add_argument("--quick", action="store_true", help="smaller grids, one eps")
    args = ap.parse_args()
    print(
        f"certsolve.force benchmarks: python {platform.python_version()}, numpy "
        f"{np.__version__}, {os.cpu_count()} CPU(s) (shared machine: figures vary with load)"
    )
    bench_maps(args.repeat, args.quick)
    bench_single(args.repeat)
    bench_workspace(args.repeat, args.quick)
    bench_design(args.repeat, args.quick)


if __name__ == "__main__":
    main()
