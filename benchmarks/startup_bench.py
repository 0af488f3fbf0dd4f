"""Start-up cost of the command line: whole-process wall time of short commands.

Targets (issue 10): ``certsolve --help`` <= 0.3 s; ``certsolve fk examples/robots/planar.json
--u 0.5,0.5,0.5,0.5 --tau-max 10`` <= 0.5 s for the whole process; (issue 30) ``certsolve
solve`` to the first box <= 0.15 s (``--max-boxes 1``: imports, parsing, the compiled
system and the solver's programs, one round).  Each command runs ``--repeat`` times as a
fresh process (``python -m certsolve.cli``, the console script's code path); the median,
min and max wall times, and the median CPU time of the process (user + system: steadier on
a shared machine), are printed beside the bare interpreter's start-up.  ``--imports`` adds
the largest cumulative import costs of each command (``python -X importtime``), which is
where start-up time goes.

The commands run with Python's bytecode caches (``__pycache__``), as an installed package
runs: ``PYTHONDONTWRITEBYTECODE`` is removed from their environment (the warm-up run writes
the caches), since without them every run compiles certsolve's ~100 modules again (about
0.08 s of CPU more for ``solve``); ``--no-bytecode`` keeps the variable as it is set.  Two
floors are printed beside: ``import numpy``, and numpy with pydantic's first model (the
shared validation of the command line's options is pydantic's; its first model imports
pydantic's schema machinery, ~0.07 s of CPU).  ``solve`` does not pay the second when its
options are surely valid (:func:`certsolve.lazy.surely_valid`): its floor is ``import numpy``.

Usage::

    python benchmarks/startup_bench.py [--repeat 7] [--imports] [--no-bytecode]
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "certsolve.cli"]
COMMANDS: dict[str, list[str]] = {
    "python -c pass": [sys.executable, "-c", "pass"],
    "import numpy": [sys.executable, "-c", "import numpy"],
    "numpy + a pydantic model": [
        sys.executable,
        "-c",
        "import numpy, pydantic\nclass M(pydantic.BaseModel):\n    x: float = 0",
    ],
    "certsolve --help": [*CLI, "--help"],
    "certsolve fk --help": [*CLI, "fk", "--help"],
    "certsolve fk planar (tau <= 10)": [
        *CLI,
        "fk",
        "examples/robots/planar.json",
        "--u",
        "0.5,0.5,0.5,0.5",
        "--tau-max",
        "10",
    ],
    "certsolve solve circle-line": [*CLI, "solve", "examples/systems/circle-line.mbx"],
    "solve katsura-6, first box": [
        *CLI,
        "solve",
        "examples/systems/katsura-6.mbx",
        "--max-boxes",
        "1",
    ],
    "solve kin2-6r, first box": [*CLI, "solve", "examples/systems/kin2-6r.mbx", "--max-boxes", "1"],
}


def wall(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """Wall time and CPU time (user + system) of one run of ``cmd``."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, env=env)
    t = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return t, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def top_imports(
    cmd: list[str], env: dict[str, str] | None = None, n: int = 8
) -> list[tuple[float, str]]:
    """The ``n`` top-level imports with the largest cumulative time (seconds)."""
    out = subprocess.run(
        [cmd[0], "-X", "importtime", *cmd[1:]],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    costs = []
    for line in out.stderr.splitlines():
        m = re.match(r"import time:\s+\d+ \|\s+(\d+) \| ( *)(\S+)", line)
        if m and len(m.group(2)) <= 2:  # imported by the program itself, not nested
            costs.append((int(m.group(1)) / 1e6, m.group(3)))
    return sorted(costs, reverse=True)[:n]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="runs per command (7)")
    ap.add_argument("--imports", action="store_true", help="also show the largest imports")
    ap.add_argument(
        "--no-bytecode",
        action="store_true",
        help="keep PYTHONDONTWRITEBYTECODE as set (runs without bytecode caches compile)",
    )
    args = ap.parse_args()
    env = dict(os.environ)
    if not args.no_bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    print(f"bytecode caches: {'not written' if env.get('PYTHONDONTWRITEBYTECODE') else 'used'}")
    head = f"{'command':<34} {'median':>8} {'min':>8} {'max':>8} {'cpu':>8}"
    print(f"{head}   ({args.repeat} runs)")
    for name, cmd in COMMANDS.items():
        wall(cmd, env)  # warm the file cache (and write the bytecode caches)
        runs = [wall(cmd, env) for _ in range(args.repeat)]
        times = [t for t, _ in runs]
        cpu = statistics.median(c for _, c in runs)
        print(
            f"{name:<34} {statistics.median(times):8.3f} {min(times):8.3f} {max(times):8.3f}"
            f" {cpu:8.3f}"
        )
        if args.imports and name.startswith("certsolve"):
            for seconds, module in top_imports(cmd, env):
                print(f"    {seconds:6.3f} s  import {module}")


if __name__ == "__main__":
    main()
