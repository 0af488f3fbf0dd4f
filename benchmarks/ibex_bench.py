"""IBEX's satisfaction benchmarks through ``certsolve solve``, as a user runs them.

    python benchmarks/ibex_bench.py DIR [--timeout 30] [--runs 3] [--eps 1e-8] [--csv OUT]
                                        [--cid-vars auto] [--workers N]

For every ``.bch`` / ``.mbx`` file in ``DIR``: parse it (a parse error is reported, with its
line and column), then run the whole ``certsolve solve FILE --timeout T --json`` subprocess
``--runs`` times with the CLI's default settings (start-up included) and print the status,
number of certified solutions, undecided boxes (total, and hulls listed), boxes processed and
the median wall time.  Box counts are deterministic; times are medians on a possibly shared
machine.

The files are IBEX's (ibex-team/ibex-lib, LGPL), not part of this repository.  The set used
for issue 11 -- 30 files with 3 to 22 variables, polynomial and transcendental -- can be
fetched from GitHub (``raw.githubusercontent.com/ibex-team/ibex-lib/<commit>/<path>``):

``benchs/benchs-satisfaction/benchs-coprin/``::

    Biggs-exp6.bch                     83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Brent-10.bch                       83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Brent-8.bch                        1c2dd35f912f9d2cba0026b7c479dea2b49ec690
    Brown-05.bch                       83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Brown-10.bch                       83db242af78a7b2bc8e9fecddb9faa6d9620e582
    BroydenBanded-010.bch              83db242af78a7b2bc8e9fecddb9faa6d9620e582
    BroydenTri-0020.bch                1c2dd35f912f9d2cba0026b7c479dea2b49ec690
    Butcher8-a.bch                     83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Caprasse.bch                       83db242af78a7b2bc8e9fecddb9faa6d9620e582
    CountercurrentReactors2-6.bch      83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Discrete-Integral-6.bch            1c2dd35f912f9d2cba0026b7c479dea2b49ec690
    DiscreteBoundary-0020.bch          83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Eco9.bch                           83db242af78a7b2bc8e9fecddb9faa6d9620e582
    ExtendedFreud-0010.bch             1c2dd35f912f9d2cba0026b7c479dea2b49ec690
    ExtendedWood-08.bch                83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Geneig-icse.bch                    1c2dd35f912f9d2cba0026b7c479dea2b49ec690
    I5-1.bch                           83db242af78a7b2bc8e9fecddb9faa6d9620e582
    Katsura-14.bch                     83db242af78a7b2bc8e9fecddb9faa6d9620e582

``benchs/benchs-satisfaction/benchlib2/``::

    kolev36.bch                        83db242af78a7b2bc8e9fecddb9faa6d9620e582
    transistor.bch                     b32859a6fb3977d25d0f5874f20dbcec8c0f7a6c

``benchs/solver/polynom/``::

    Bellido.bch                        9dc5c59bb87923feba86e1a67e8994dd38f157f3
    Dietmaier.bch                      9dc5c59bb87923feba86e1a67e8994dd38f157f3
    Pramanik.bch                       2880b55256c78988aea36f89f7209a5c9bd63b84
    Rose.bch                           94856ca3bc52dc7e3f6ae30557c144d98e636dd2

``benchs/solver/non-polynom/``::

    AOL-legentil.bch                   237734e907b3395804e3aaa89e83d7465c4ff691
    SjirkBoon.bch                      237734e907b3395804e3aaa89e83d7465c4ff691
    Trigo1-0005.bch                    2880b55256c78988aea36f89f7209a5c9bd63b84
    Trigo1-0010m1.bch                  2880b55256c78988aea36f89f7209a5c9bd63b84
    Trigo1-0012.bch                    9dc5c59bb87923feba86e1a67e8994dd38f157f3
    Troesch20.bch                      d81762932b940ff040aedab1fe2d06b762559c4e

``benchs/solver/`` holds IBEX's curated solver set: Dietmaier (the 12-variable Stewart-platform
system), Bellido, Pramanik, Rose and the trigonometric / exponential files are there, not under
``benchs-satisfaction/``.  Files of the issue's list that this index of the repository did not
show (Kin1, Hayes, Reimer, Puma, Redeco, Trigexp) are not in the set.

``--eps`` defaults to the CLI's 1e-8; ``ibexsolve``'s ``--eps-min`` is 1e-3 (see
``docs/minibex.md``).  On the 2-core machine of this project (2026-11-26, ``--timeout 30
--runs 3``) all 30 parse and 28 complete.  AOL-legentil was the third that did not: ``tan``
took every interval within 1e-9 (relative) of a pole for one containing it, and the domain
ends 1e-10 before ``π/2``; with the poles located exactly, HC4 inverting ``sin`` and
``cos``, and the bisector splitting the variable widest *relative to its domain* where the
Jacobian is infinite (not ``z`` in ``[-1e8, 1e8]`` alone), it completes in 27 boxes: no
solution.  The two that do not finish, measured in-process (one worker,
``Solver(...).solve``):

* **Biggs-exp6** (fitting three exponentials ``x3 e^{-t x1} - x4 e^{-t x2} + x6 e^{-t x5}`` to
  six samples): six isolated solutions, the permutations of the three terms, with a Jacobian
  so ill-conditioned that a box of half-width 0.1 around one of them takes 2,156 boxes to
  settle (0.5: 17,647; 2: 110,643).  On ``[-20, 20]^6``: no solution found after 300 s and
  3.05 million boxes (nor in 30 s at ``eps`` 1e-3).
* **Butcher8-a**: one solution (``a = -1.11411...``) after 59 s and 362,780 boxes; the
  pending boxes follow the curve of the last equation (in ``a`` and ``b`` only) with
  ``b1 .. b3`` still wide.
"""

from __future__ import annotations

import argparse
import csv
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

from certsolve.expr.minibex import MinibexError, load_minibex


def run_once(
    path: Path, timeout: float, eps: float, cid_vars: str = "auto", workers: str | None = None
) -> tuple[float, dict | None, str]:
    cmd = [sys.executable, "-m", "certsolve", "solve", str(path), "--json",
           "--timeout", str(timeout), "--eps", str(eps), "--cid-vars", cid_vars]  # fmt: skip
    if workers is not None:
        cmd += ["--workers", workers]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout * 3 + 60)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return wall, None, proc.stderr.strip().splitlines()[-1] if proc.stderr else "failed"
    return wall, json.loads(proc.stdout), ""


def main() -> None:
    ap = argparse.ArgumentParser(description="Run certsolve on a directory of Minibex files.")
    ap.add_argument("dir", type=Path)
    ap.add_argument("--timeout", type=float, default=30.0, help="per run (default 30 s)")
    ap.add_argument("--runs", type=int, default=3, help="runs per file (median wall time)")
    ap.add_argument("--eps", type=float, default=1e-8, help="the CLI's default, 1e-8")
    ap.add_argument("--csv", type=Path, default=None, help="also write the table as CSV")
    ap.add_argument(
        "--cid-vars", default="auto", help="certsolve solve --cid-vars (auto, 1, K or all)"
    )
    ap.add_argument(
        "--workers", default=None, help="certsolve solve --workers (default: the CLI's, auto)"
    )
    args = ap.parse_args()
    files = sorted(p for p in args.dir.iterdir() if p.suffix in (".bch", ".mbx"))
    header = ["file", "n", "status", "solutions", "undecided", "hulls", "boxes", "wall_s"]
    print(f"{'file':32s} {'n':>3s} {'status':10s} {'sols':>5s} {'undec':>7s} {'hulls':>5s} "
          f"{'boxes':>9s} {'wall s':>7s}")  # fmt: skip
    rows = []
    parsed = complete = 0
    for path in files:
        try:
            system = load_minibex(path)
        except MinibexError as exc:
            print(f"{path.name:32s} parse error: {exc}")
            rows.append([path.name, "", "parse error", "", "", "", "", ""])
            continue
        parsed += 1
        walls, result, error = [], None, ""
        for _ in range(args.runs):
            wall, result, error = run_once(
                path, args.timeout, args.eps, args.cid_vars, args.workers
            )
            walls.append(wall)
            if result is None:
                break
        wall = statistics.median(walls)
        if result is None:
            print(f"{path.name:32s} {system.n:3d} error: {error}")
            rows.append([path.name, system.n, "error", "", "", "", "", f"{wall:.2f}"])
            continue
        complete += result["status"] == "complete"
        row = [
            path.name,
            system.n,
            result["status"],
            len(result["solutions"]),
            result["undecided_total"],
            len(result["undecided"]),
            result["stats"]["boxes"],
            f"{wall:.2f}",
        ]
        rows.append(row)
        print(f"{row[0]:32s} {row[1]:3d} {row[2]:10s} {row[3]:5d} {row[4]:7d} {row[5]:5d} "
              f"{row[6]:9d} {row[7]:>7s}", flush=True)  # fmt: skip
    print(f"\n{parsed} of {len(files)} parse; {complete} of {len(files)} complete within "
          f"{args.timeout:g} s (median of {args.runs} run(s) per file)")  # fmt: skip
    if args.csv:
        with args.csv.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header)
            w.writerows(rows)


if __name__ == "__main__":
    main()
