"""IBEX's solver benchmarks through ``certsolve solve`` and ``ibexsolve``, side by side.

    python benchmarks/ibex_bench.py DIR [--timeout 30] [--runs 3] [--eps 1e-8]
        [--solvers certsolve,ibexsolve] [--ibexsolve PATH] [--workers N] [--cid-vars auto]
        [--only REGEX] [--both-complete DIR [--ibex-below S]] [--results DIR]
        [--markdown docs/ibex-benchs.md] [--csv OUT]

Every ``.bch`` / ``.mbx`` file under ``DIR`` (recursively) is first read by the Minibex parser
in this process: it parses (its variables ``n`` and equations ``m`` are noted; ``m != n`` is
refused by certsolve's solver, not the parser), or it is refused with the line, column and
construct named.  Then each solver runs it ``--runs`` times as a user
runs it, one subprocess per run, start-up included:

* ``certsolve solve FILE --json --timeout T --eps EPS`` (the CLI's defaults otherwise);
* ``ibexsolve --timeout=T --eps-min=EPS --trace -o TMP.cov FILE`` (IBEX 2.9.1; its default
  ``--eps-min`` is 1e-3, so the comparison is made at certsolve's 1e-8).  Its ``--timeout``
  counts CPU time, so it is also stopped at ``T + 1`` s of wall time, as certsolve's is wall
  time.  Its solutions are read from the COV file it writes (or, when stopped, from what
  ``--trace`` printed) and, for a square system, **de-duplicated**: ibexsolve can report one
  solution twice, in adjacent boxes, so solution boxes that overlap or lie within 1e-6 of
  each other (in every variable) are counted once.

certsolve runs with Python's bytecode caches, as an installed package does: its modules are
compiled once (``compileall``) before the first run, and ``PYTHONDONTWRITEBYTECODE`` is not
passed on; without them every run compiles its ~100 modules again (0.1-0.2 s of CPU on a
2-core VM, the whole of ibexsolve's time on the small files).  ``--no-bytecode`` runs it as
the environment says (``benchmarks/startup_bench.py`` measures the same two ways).

Reported per file and solver: the status (``complete``: nothing pending; ``timeout``;
``refused``: the solver did not run it, with its message), the certified solutions, the
undecided boxes (certsolve's undecided, ibexsolve's unknown), the boxes processed
(ibexsolve's cells) and the median wall time of the runs.  Counts come from the last run
(certsolve's are deterministic; ibexsolve's are with its fixed random seed).

Runs are stored as they finish in ``--results DIR`` (one JSON file per solver, time limit
and eps), so an interrupted run resumes where it stopped, the two solvers can run in two
processes, and ``--markdown`` alone re-renders the table from what is stored
(``--solvers none``; notes after the file's ``<!-- notes ... -->`` line are kept).  The table
is ``docs/ibex-benchs.md``; its summary counts the files
that parse, the files each solver completes, and the median of certsolve's time over
ibexsolve's on the files both complete.

The files are IBEX's (ibex-team/ibex-lib, LGPL), not part of this repository.  The whole
directory of issue 30 is ``benchs/solver`` of IBEX 2.9 (264 files in ``polynom/`` with
``yamamura/``, ``non-polynom/`` and ``others/``).  The set of issue 11 runs the same way
(``--solvers certsolve``, or both) on a directory of these 30 files with 3 to 22 variables,
polynomial and transcendental, fetched from GitHub
(``raw.githubusercontent.com/ibex-team/ibex-lib/<commit>/<path>``):

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
import datetime
import json
import os
import re
import resource
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from certsolve.expr.minibex import MinibexError, load_model

HERE = Path(__file__).resolve().parent
IBEXSOLVE = HERE.parent.parent / "shared" / "tools" / "ibexsolve"
SOLVERS = ("certsolve", "ibexsolve")
#: ibexsolve's search status (the last integer of its COV file) -> ours
IBEX_STATUS = {0: "complete", 1: "complete", 2: "complete", 3: "timeout", 4: "max_boxes",
               5: "cancelled"}  # fmt: skip
DUPLICATE_GAP = 1e-6
WALL_STOP = "stopped at the wall-time limit"
#: what follows this line in the Markdown file is written by hand, and kept when regenerated
NOTES = "<!-- notes: kept when the table is regenerated -->"


@dataclass(kw_only=True)
class Run:
    """One run of one solver on one file.

    ``status``: ``complete`` (nothing pending), a limit (``timeout``...), ``refused`` (the
    solver did not take the file; ``message`` says why) or ``error`` (it failed).
    ``solutions``: certified solutions (ibexsolve's de-duplicated; ``raw_solutions`` before);
    ``undecided``: boxes neither proven nor refuted; ``boxes``: boxes processed (-1: not
    known, for an ibexsolve stopped at the wall limit).
    """

    status: str
    wall: float
    solutions: int = 0
    raw_solutions: int = 0
    undecided: int = 0
    boxes: int = 0
    message: str = ""
    cpu: float = 0.0  # CPU seconds of the subprocess and its children (user + system)
    runs: int = 1  # in a summary: the number of runs whose median ``wall`` is


@dataclass(kw_only=True)
class Parsed:
    """What the Minibex parser made of a file: ``n`` variables and ``m`` equations, or the
    refusal (``error``, with its line and column)."""

    n: int = 0
    m: int = 0
    error: str = ""


@dataclass(kw_only=True)
class Row:
    path: str
    parsed: Parsed
    runs: dict[str, list[Run]] = field(default_factory=dict)


def parse_file(path: Path) -> Parsed:
    try:
        model = load_model(path)
    except MinibexError as exc:
        return Parsed(error=str(exc))
    return Parsed(n=len(model.variables), m=len(model.equations))


def children_cpu() -> float:
    """CPU seconds (user + system) of the finished subprocesses of this process so far."""
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


# -- certsolve --------------------------------------------------------------------------------
def certsolve_env(args: argparse.Namespace) -> dict[str, str]:
    """The environment of certsolve's runs: without ``PYTHONDONTWRITEBYTECODE`` unless
    ``--no-bytecode`` (the module docstring)."""
    env = dict(os.environ)
    if not args.no_bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def compile_certsolve() -> None:
    """Write the bytecode caches of the certsolve package (as ``pip install`` does)."""
    import compileall

    import certsolve

    compileall.compile_dir(Path(certsolve.__file__).parent, quiet=1)


def run_certsolve(path: Path, args: argparse.Namespace, square: bool = True) -> Run:
    cmd = [sys.executable, "-m", "certsolve", "solve", str(path), "--json", "--timeout",
           str(args.timeout), "--eps", str(args.eps), "--cid-vars", args.cid_vars]  # fmt: skip
    if args.workers is not None:
        cmd += ["--workers", args.workers]
    t0, c0 = time.perf_counter(), children_cpu()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout * 3 + 60,
                              env=certsolve_env(args))  # fmt: skip
    except subprocess.TimeoutExpired:
        return Run(status="error", wall=time.perf_counter() - t0, message="killed: no answer",
                   cpu=children_cpu() - c0)  # fmt: skip
    wall, cpu = time.perf_counter() - t0, children_cpu() - c0
    if proc.returncode != 0:
        lines = proc.stderr.strip().splitlines()
        message = lines[-1] if lines else f"exit {proc.returncode}"
        status = "refused" if message.startswith("error:") else "error"
        return Run(status=status, wall=wall, message=message.removeprefix("error: "), cpu=cpu)
    out = json.loads(proc.stdout)
    return Run(status=out["status"], wall=wall, solutions=len(out["solutions"]),
               raw_solutions=len(out["solutions"]), undecided=out["undecided_total"],
               boxes=out["stats"]["boxes"], cpu=cpu)  # fmt: skip


# -- ibexsolve --------------------------------------------------------------------------------
def read_cov(data: bytes) -> tuple[np.ndarray, int, bool]:
    """The solution boxes (shape (k, n, 2)), the search status of ibexsolve's COV file and
    whether the system is square (as many equations as variables).

    The layout is ``ibexsolve --format``'s (CovSolverData, format version 1 1 1 1 1 2).  With
    no equation (inequalities only) the solutions are the inner boxes, as ibexsolve counts.
    """
    pos = 20  # the signature "IBEX COVERING FILE \0"

    def ints(k: int) -> tuple[int, ...]:
        nonlocal pos
        out = struct.unpack_from(f"<{k}I", data, pos)
        pos += 4 * k
        return out

    def reals(k: int) -> np.ndarray:
        nonlocal pos
        out = np.frombuffer(data, dtype="<f8", count=k, offset=pos)
        pos += 8 * k
        return out

    (level,) = ints(1)
    ints(2 * (level + 1))  # format identifier and version
    (n,) = ints(1)
    (total,) = ints(1)
    boxes = reals(2 * n * total).reshape(total, n, 2)
    (inner,) = ints(1)
    inner_index = list(ints(inner))
    ints(1)  # boundary type
    (boundary,) = ints(1)
    ints(boundary)
    m, _inequalities, _btype = ints(3)
    index: list[int] = []
    if m > 0:
        (count,) = ints(1)
        for _ in range(count):
            index.append(ints(1)[0])
            if m < n:
                ints(n - m)
            reals(2 * n)
    (nbb,) = ints(1)
    for _ in range(nbb):
        ints(1)
        if 0 < m < n:
            ints(n - m)
    for _ in range(n):
        pos = data.index(b"\0", pos) + 1
    (status,) = ints(1)
    return boxes[index if m > 0 else inner_index], status, m == n


def distinct(boxes: np.ndarray, gap: float = DUPLICATE_GAP) -> int:
    """The number of groups of boxes, two boxes being in one group when they overlap or lie
    within ``gap`` of each other in every variable (linked transitively)."""
    k = len(boxes)
    group = np.arange(k)
    lo, hi = boxes[:, :, 0], boxes[:, :, 1]
    for i in range(k):  # one row of the k x k relation per turn, vectorized over j
        near = np.all((lo[i] - hi <= gap) & (lo - hi[i] <= gap), axis=1)
        roots = np.unique(group[near])
        group[np.isin(group, roots)] = roots.min()
    return len(np.unique(group))


def _ibex_figure(text: str, label: str) -> int:
    m = re.search(rf"number of {label}:\s*(\d+)", text)
    return int(m.group(1)) if m else 0


_TRACED = re.compile(r"^\s*\[solution\] \((.*)\)\s*$", re.M)


def traced_solutions(text: str) -> np.ndarray:
    """The solution boxes ``--trace`` printed (6 significant digits), shape (k, n, 2)."""
    boxes = [[[float(b) for b in comp.strip(" []").split(",")] for comp in m.split(";")]
             for m in _TRACED.findall(text)]  # fmt: skip
    return np.array(boxes, dtype=float).reshape(len(boxes), -1, 2) if boxes else np.zeros((0, 0, 2))


def run_ibexsolve(path: Path, args: argparse.Namespace, square: bool = True) -> Run:
    """One ``ibexsolve`` run under the same *wall* limit as certsolve's ``--timeout``.

    ibexsolve's own ``--timeout`` counts CPU time, which on a loaded machine is several times
    less than the wall time (5 s of CPU took 25 s of wall here).  So it is also stopped at
    ``timeout + 1`` s of wall time; it writes no COV file then, and its solutions are those
    it printed with ``--trace`` as it found them (6 significant digits: enough to tell
    solutions 1e-6 apart on the files here), its cells unknown.  Solutions are de-duplicated
    only for a ``square`` system (elsewhere they pave a manifold: every box counts).
    """
    with tempfile.TemporaryDirectory() as tmp:
        cov = Path(tmp) / "out.cov"
        cmd = ["stdbuf", "-oL", str(args.ibexsolve), f"--timeout={args.timeout:g}",
               f"--eps-min={args.eps:g}", "--trace", "-o", str(cov), str(path)]  # fmt: skip
        t0, c0 = time.perf_counter(), children_cpu()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, cwd=tmp)  # fmt: skip
        try:
            out, _ = proc.communicate(timeout=args.timeout + 1)
            killed = False
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
            killed = True
        wall, cpu = time.perf_counter() - t0, children_cpu() - c0
        text = re.sub(r"\x1b\[[0-9;]*m", "", out)
        if killed:
            sols = traced_solutions(text)
            count = distinct(sols) if square else len(sols)
            return Run(status="timeout", wall=wall, solutions=count,
                       raw_solutions=len(sols), undecided=-1, boxes=-1,
                       message=WALL_STOP, cpu=cpu)  # fmt: skip
        if proc.returncode != 0 or not cov.exists():
            errors = [ln.strip() for ln in text.splitlines() if "rror" in ln or "xception" in ln]
            message = errors[-1] if errors else f"exit {proc.returncode}"
            return Run(status="refused" if "rror" in message else "error", wall=wall,
                       message=message, cpu=cpu)  # fmt: skip
        try:
            sols, status, square = read_cov(cov.read_bytes())
        except (struct.error, ValueError) as exc:
            return Run(status="error", wall=wall, message=f"unreadable COV file: {exc}",
                       cpu=cpu)  # fmt: skip
    return Run(status=IBEX_STATUS.get(status, f"status {status}"), wall=wall,
               solutions=distinct(sols) if square else len(sols), raw_solutions=len(sols),
               undecided=_ibex_figure(text, "unknown boxes"),
               boxes=_ibex_figure(text, "cells"), cpu=cpu)  # fmt: skip


RUNNERS = {"certsolve": run_certsolve, "ibexsolve": run_ibexsolve}


# -- the store of runs ------------------------------------------------------------------------
def store_path(args: argparse.Namespace, solver: str) -> Path:
    return args.results / f"{solver}-t{args.timeout:g}-eps{args.eps:g}.json"


def load_store(path: Path) -> dict[str, list[dict]]:
    return json.loads(path.read_text()) if path.exists() else {}


def save_store(path: Path, store: dict[str, list[dict]]) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(store, indent=1, sort_keys=True))
    os.replace(tmp, path)


def both_complete(args: argparse.Namespace) -> set[str]:
    """The files whose last stored run in ``--both-complete`` is complete for both solvers;
    with ``--ibex-below S``, only those where ibexsolve's median wall time there is below
    ``S`` seconds (the small files, where start-up and a few rounds are the whole call)."""
    where = argparse.Namespace(**{**vars(args), "results": args.both_complete})
    stores = {s: load_store(store_path(where, s)) for s in SOLVERS}
    done = [{f for f, runs in stores[s].items() if runs[-1]["status"] == "complete"}
            for s in SOLVERS]  # fmt: skip
    if not any(done):
        raise SystemExit(f"--both-complete: no stored runs in {args.both_complete}")
    both = set.intersection(*done)
    below = getattr(args, "ibex_below", None)
    if below is None:
        return both
    ibex = stores["ibexsolve"]
    return {f for f in both if statistics.median(r["wall"] for r in ibex[f]) < below}


def summary_of(runs: list[Run]) -> Run:
    """The last run's counts with the median wall and CPU times of all."""
    last = runs[-1]
    wall = statistics.median(r.wall for r in runs)
    cpu = statistics.median(r.cpu for r in runs)
    return Run(**{**asdict(last), "wall": wall, "cpu": cpu, "runs": len(runs)})


# -- the table ----------------------------------------------------------------------------------
def _cell(run: Run | None) -> list[str]:
    if run is None:
        return ["", "", "", "", "", ""]
    if run.status in ("refused", "error"):
        return [f"{run.status}: {run.message}"[:90].replace("|", "\\|"), "", "", "", "", ""]
    sols = str(run.solutions)
    if run.raw_solutions > run.solutions:  # de-duplicated
        sols += f" ({run.raw_solutions})"
    known = [
        str(k) if k >= 0 and run.message != WALL_STOP else "?" for k in (run.undecided, run.boxes)
    ]
    wall = f"{run.wall:.2f}" if run.runs == 1 else f"{run.wall:.2f} ({run.runs})"
    cpu = f"{run.cpu:.2f}" if run.cpu else ""
    return [run.status, sols, *known, wall, cpu]


def markdown(rows: list[Row], args: argparse.Namespace, command: str) -> str:
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    summ = {s: {r.path: summary_of(r.runs[s]) for r in rows if r.runs.get(s)} for s in SOLVERS}
    parsed = sum(not r.parsed.error for r in rows)
    square = sum(not r.parsed.error and r.parsed.n == r.parsed.m for r in rows)
    done = {s: {p for p, run in summ[s].items() if run.status == "complete"} for s in SOLVERS}
    both = sorted(done["certsolve"] & done["ibexsolve"])
    ratios = [summ["certsolve"][p].wall / summ["ibexsolve"][p].wall for p in both]
    cpu_ratios = [summ["certsolve"][p].cpu / summ["ibexsolve"][p].cpu for p in both
                  if summ["certsolve"][p].cpu and summ["ibexsolve"][p].cpu]  # fmt: skip
    ran = {s: len(summ[s]) for s in SOLVERS}
    differ = [p for p in both if summ["certsolve"][p].solutions != summ["ibexsolve"][p].solutions]
    only = {s: sorted(done[s] - done[t]) for s, t in (SOLVERS, SOLVERS[::-1])}
    lines = [
        "# IBEX's solver benchmarks: certsolve beside ibexsolve",
        "",
        "Generated by `benchmarks/ibex_bench.py` (do not edit by hand); its docstring says what",
        "each column means.  Regenerate with:",
        "",
        f"    {command}",
        "",
        f"Written {date} from runs on the project's shared 2-core machine (other work beside),",
        f"wall-time limit {args.timeout:g} s per run for both solvers, `--eps` / `--eps-min`",
        f"{args.eps:g}; the time is the median wall time of the runs (their number in parentheses",
        "when more than one) of the whole subprocess, start-up included"
        + (" (certsolve without bytecode caches)" if args.no_bytecode else "")
        + ", and `cpu` its median CPU",
        "time (user + system, children included): the machine is shared by other work, so wall",
        f"times there carry its load; CPU times less so.  A file is run again (up to {args.runs}",
        "runs) only while its runs complete under `--repeat-below` seconds (default 5).",
        "ibexsolve is 2.9.1 (filib, no LP); its own `--timeout` counts CPU time, so it is also",
        "stopped at the wall limit, and its solutions are then those it printed (`--trace`; its",
        "unknown boxes and cells are then not known: `?`).  Its solutions are de-duplicated",
        "(boxes that overlap or lie within 1e-6 counted once; its raw count in parentheses when",
        "it differs).",
        "",
        "## Summary",
        "",
        f"* **{parsed} of {len(rows)} files parse**: {square} square systems, and "
        f"{parsed - square} with more or fewer equations than variables (certsolve solves an "
        "over-determined one through a square subsystem and paves an under-determined one, "
        "`docs/minibex.md`: their counts are not ibexsolve's kind of solution).",
    ]
    if len(rows) > parsed:
        lines.append("* Refused by the parser: " + "; ".join(
            f"`{r.path}` ({r.parsed.error})" for r in rows if r.parsed.error) + ".")  # fmt: skip
    for s in SOLVERS:
        lines.append(f"* **{s}** completes {len(done[s])} of the {ran[s]} files it ran"
                     f" ({len(only[s])} that the other does not).")  # fmt: skip
    if ratios:
        cpu_median = f"{statistics.median(cpu_ratios):.1f}x" if cpu_ratios else "not measured"
        lines.append(
            f"* On the {len(both)} files both complete: certsolve's wall time over ibexsolve's has "
            f"median **{statistics.median(ratios):.1f}x** (min {min(ratios):.2f}x, max "
            f"{max(ratios):.0f}x), target 2x; its CPU time over ibexsolve's **{cpu_median}**; "
            f"the solution counts agree on {len(both) - len(differ)} of them"
            + (": not on " + ", ".join(f"`{p}`" for p in differ) if differ else "")
            + "."
        )
    neither = [p for p in summ["certsolve"].keys() & summ["ibexsolve"].keys()
               if p not in done["certsolve"] | done["ibexsolve"]
               and summ["certsolve"][p].status not in ("refused", "error")]  # fmt: skip
    if neither:
        found = {s: sum(summ[s][p].solutions for p in neither) for s in SOLVERS}
        ahead = sum(
            summ["certsolve"][p].solutions >= summ["ibexsolve"][p].solutions for p in neither
        )
        lines.append(
            f"* On the {len(neither)} files neither completes, solutions found by the limit: "
            f"certsolve {found['certsolve']}, ibexsolve {found['ibexsolve']}; certsolve found "
            f"at least as many on {ahead} of them (target: all of them)."
        )
    lines += ["", "## Per file", "",
              "| file | n | m | certsolve | sols | undec | boxes | s | cpu | ibexsolve | sols "
              "| unknown | cells | s | cpu | ratio |",
              "|---|--:|--:|---|--:|--:|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|"]  # fmt: skip
    for r in rows:
        c, i = summ["certsolve"].get(r.path), summ["ibexsolve"].get(r.path)
        ratio = f"{c.wall / i.wall:.1f}" if r.path in both and c and i else ""
        nm = ["", ""] if r.parsed.error else [str(r.parsed.n), str(r.parsed.m)]
        error = Run(status="error", wall=0, message=f"parse error: {r.parsed.error}")
        cert = _cell(c if c or not r.parsed.error else error)
        lines.append("| " + " | ".join([f"`{r.path}`", *nm, *cert, *_cell(i), ratio]) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description="certsolve beside ibexsolve on Minibex files.")
    ap.add_argument("dir", type=Path)
    ap.add_argument("--timeout", type=float, default=30.0, help="per run (default 30 s)")
    ap.add_argument("--runs", type=int, default=3, help="runs per file (median wall time)")
    ap.add_argument("--repeat-below", type=float, default=5.0,
                    help="run a file again only while its runs complete in less (s)")  # fmt: skip
    ap.add_argument("--eps", type=float, default=1e-8, help="certsolve --eps, ibexsolve --eps-min")
    ap.add_argument("--solvers", default="certsolve,ibexsolve", help="which to run, or 'none'")
    ap.add_argument("--ibexsolve", type=Path, default=IBEXSOLVE, help="the ibexsolve binary")
    ap.add_argument("--only", default="", help="run only files whose path matches this regex")
    ap.add_argument("--both-complete", type=Path, default=None, metavar="DIR",
                    help="run only files both solvers complete in the runs stored in DIR "
                    "(same --timeout and --eps): the subset of the time ratio")  # fmt: skip
    ap.add_argument("--ibex-below", type=float, default=None, metavar="S",
                    help="with --both-complete: only files where ibexsolve's stored median "
                    "wall time is below S seconds")  # fmt: skip
    ap.add_argument("--results", type=Path, default=Path("ibex-bench-results"),
                    help="directory of stored runs (resumed)")  # fmt: skip
    ap.add_argument("--markdown", type=Path, default=None, help="write the table here")
    ap.add_argument("--csv", type=Path, default=None, help="also write the table as CSV")
    ap.add_argument("--cid-vars", default="auto", help="certsolve solve --cid-vars")
    ap.add_argument("--workers", default=None, help="certsolve solve --workers (default auto)")
    ap.add_argument("--no-bytecode", action="store_true",
                    help="run certsolve without its bytecode caches")  # fmt: skip
    args = ap.parse_args()
    solvers = [s for s in args.solvers.split(",") if s and s != "none"]
    for s in solvers:
        if s not in RUNNERS:
            ap.error(f"--solvers: unknown solver {s!r} (certsolve, ibexsolve or none)")
    args.results.mkdir(parents=True, exist_ok=True)
    only = re.compile(args.only)
    if args.ibex_below is not None and args.both_complete is None:
        ap.error("--ibex-below: with --both-complete DIR (ibexsolve's stored times)")
    keep = None if args.both_complete is None else both_complete(args)
    files = sorted(p for p in args.dir.rglob("*") if p.suffix in (".bch", ".mbx"))
    stores = {s: load_store(store_path(args, s)) for s in SOLVERS}
    if "certsolve" in solvers and not args.no_bytecode:
        compile_certsolve()
    rows = []
    for path in files:
        rel = path.relative_to(args.dir).as_posix()
        row = Row(path=rel, parsed=parse_file(path))
        rows.append(row)
        chosen = bool(only.search(rel)) and (keep is None or rel in keep)
        for s in solvers:
            if not chosen:
                continue
            runs = [Run(**r) for r in stores[s].get(rel, [])]
            while len(runs) < args.runs and all(
                r.status == "complete" and r.wall < args.repeat_below for r in runs
            ):
                square = row.parsed.n == row.parsed.m or bool(row.parsed.error)
                runs.append(RUNNERS[s](path, args, square))
                stores[s][rel] = [asdict(r) for r in runs]
                save_store(store_path(args, s), stores[s])
                if runs[-1].status in ("refused", "error"):
                    break
            c = _cell(summary_of(runs))
            print(f"{rel:44s} {s:9s} {' '.join(c)}", flush=True)
        for s in SOLVERS:
            if chosen and stores[s].get(rel):
                row.runs[s] = [Run(**r) for r in stores[s][rel]]
    argv = sys.argv[1:]
    if "--solvers" in argv:  # the table is of both solvers, whichever this call ran
        k = argv.index("--solvers")
        argv = argv[:k] + argv[k + 2 :]
    command = "python benchmarks/ibex_bench.py " + " ".join(
        a if " " not in a and "|" not in a else repr(a) for a in argv
    )
    if args.markdown:
        old = args.markdown.read_text() if args.markdown.exists() else ""
        notes = old[old.index(NOTES) :] if NOTES in old else ""
        args.markdown.write_text(markdown(rows, args, command) + ("\n" + notes if notes else ""))
    if args.csv:
        with args.csv.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["file", "n", "m", "solver", "status", "solutions", "raw_solutions",
                        "undecided", "boxes", "wall_s", "cpu_s", "message"])  # fmt: skip
            for r in rows:
                for s, runs in r.runs.items():
                    u = summary_of(runs)
                    w.writerow([r.path, r.parsed.n, r.parsed.m, s, u.status, u.solutions,
                                u.raw_solutions, u.undecided, u.boxes, f"{u.wall:.3f}",
                                f"{u.cpu:.3f}", u.message])  # fmt: skip


if __name__ == "__main__":
    main()
