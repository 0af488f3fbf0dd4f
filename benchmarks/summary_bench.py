"""Bounded answers: cost of summarising many boxes, and the whole-run time limit of the CLI.

    python benchmarks/summary_bench.py [--runs 3] [--boxes 1000000]

1. :func:`certsolve.solver.summary.merge_touching` on ``N`` undecided-like boxes (half along a
   curve, where they touch, half scattered) in 2 and 10 dimensions, and
   :func:`~certsolve.solver.summary.chunk_hulls` on ``N`` pending boxes;
2. ``certsolve solve`` on the issue-13 system (a line of solutions, ``x - y = 0; 2x - 2y = 0``
   over [-1e6, 1e6]^2, ``--eps 1e-12 --timeout 20 --json``): wall time of the whole subprocess
   and size of its output.

Medians of ``--runs`` runs; the machine may be shared, so read times with care.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from certsolve.solver.summary import chunk_hulls, merge_touching

LINE = """Variables
  x in [-1e6, 1e6];
  y in [-1e6, 1e6];
Constraints
  x - y = 0;
  2*x - 2*y = 0;
end
"""


def boxes(N: int, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 1, N)
    c = np.stack([np.cos(6 * t) * (1 + 0.1 * k) for k in range(n)], axis=1)
    c[: N // 2] = rng.uniform(-5, 5, (N // 2, n))
    return c - 1e-3, c + 1e-3


def timed(fn, runs: int):
    times = []
    out = None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--boxes", type=int, default=1_000_000)
    ap.add_argument("--timeout", type=float, default=20.0)
    args = ap.parse_args()
    for n in (2, 10):
        lo, hi = boxes(args.boxes, n)
        t, (_, _, cnt) = timed(lambda lo=lo, hi=hi: merge_touching(lo, hi), args.runs)
        print(f"merge_touching  N={args.boxes} n={n}: {t:.2f} s -> {cnt.size} hulls, "
              f"largest {cnt[:3].tolist()}")  # fmt: skip
        t, _ = timed(lambda lo=lo, hi=hi: chunk_hulls(lo, hi, 1000), args.runs)
        print(f"chunk_hulls     N={args.boxes} n={n}: {t:.3f} s -> 1000 hulls")
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "line.mbx"
        f.write_text(LINE)
        walls, sizes = [], []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-m", "certsolve", "solve", str(f), "--eps", "1e-12",
                 "--timeout", str(args.timeout), "--json"],
                capture_output=True, check=True,
            ).stdout  # fmt: skip
            walls.append(time.perf_counter() - t0)
            sizes.append(len(out))
        runs = [round(w, 2) for w in walls]
        print(f"certsolve solve line.mbx --eps 1e-12 --timeout {args.timeout:g} --json: "
              f"median wall {statistics.median(walls):.2f} s (runs {runs}), "
              f"output {statistics.median(sizes) / 1e3:.0f} kB")  # fmt: skip


if __name__ == "__main__":
    main()
