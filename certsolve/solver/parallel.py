"""The branch-and-prune search over ``multiprocessing`` worker processes.

The main process keeps the box buffer and the set of solutions; workers run the same
:meth:`Solver.run` loop on slices of the buffer for a bounded number of rounds and send
back what they found (solutions, undecided boxes) and what is left (their remaining
boxes).  Known unicity boxes travel with every task so that workers do not re-prove known
solutions.  Every box handed out comes back either processed or as a remaining box, so
nothing is lost; solutions found twice (in two workers) are merged by the same test as in
the serial search.  The content of the result -- solutions, undecided regions, status --
is that of a serial run; only box boundaries and statistics differ.
"""

from __future__ import annotations

import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context

from .branch_and_prune import Progress, SearchState
from .buffer import BoxStack
from .certify import SolutionSet
from .result import SolveResult, Stats

__all__ = ["solve_parallel"]

_WORKER = {}


def _init(solver) -> None:
    _WORKER["solver"] = solver


def _task(lo, hi, known, max_rounds, timeout):
    """Run the search on some boxes; return (solutions, undecided, remaining, stats)."""
    solver = _WORKER["solver"]
    n = solver.n
    state = SearchState(BoxStack(n), SolutionSet(n), [], Stats())
    state.stack.push(lo, hi)
    for e0, e1, u0, u1, kind in known:
        state.solutions.add(e0, e1, u0, u1, kind)
    before = len(state.solutions)
    solver.run(state, max_rounds=max_rounds, timeout=timeout)
    sols = state.solutions
    found = [
        (sols.E_lo[i], sols.E_hi[i], sols.U_lo[i], sols.U_hi[i], sols.kind[i])
        for i in range(before, len(sols))
    ]
    rlo, rhi = state.stack.snapshot()
    return found, state.undecided, rlo, rhi, state.stats


def solve_parallel(
    solver,
    *,
    workers: int,
    timeout=None,
    max_boxes=None,
    progress=None,
    rounds_per_task: int = 8,
    task_seconds: float = 1.0,
    serial_seconds: float = 2.0,
) -> SolveResult:
    """Parallel search; the first ``serial_seconds`` run in this process.

    Starting worker processes costs 1-2 s (spawn, imports, unpickling the
    compiled system), so a search that ends within ``serial_seconds`` never starts them:
    small problems cost what they cost serially.  Then the buffer is grown until there is
    work for every worker.
    """
    t0 = time.perf_counter()
    n = solver.n
    state = SearchState.start(solver.system.domain, n)
    warm = serial_seconds if timeout is None else min(serial_seconds, timeout)
    solver.run(state, timeout=warm, max_boxes=max_boxes, progress=progress)
    if state.stats.stopped_by not in (None, "timeout") or (
        timeout is not None and time.perf_counter() - t0 >= timeout
    ):
        state.stats.workers = 1  # a limit was hit before the workers were needed
        return solver.result(state)
    state.stats.stopped_by = None
    while 0 < len(state.stack) < 4 * workers:
        solver.round(state)
        if timeout is not None and time.perf_counter() - t0 >= timeout:
            break
    if not len(state.stack):  # done before the workers were needed
        state.stats.workers = 1
        state.stats.time = time.perf_counter() - t0
        return solver.result(state)
    stats = state.stats
    ctx = get_context("spawn")
    running = {}
    stopped = None
    with ProcessPoolExecutor(
        workers, mp_context=ctx, initializer=_init, initargs=(solver,)
    ) as pool:
        while len(state.stack) or running:
            elapsed = time.perf_counter() - t0
            if stopped is None and timeout is not None and elapsed >= timeout:
                stopped = "timeout"
            if stopped is None and max_boxes is not None and stats.boxes >= max_boxes:
                stopped = "max_boxes"
            # hand out slices of the buffer to idle workers
            while stopped is None and len(state.stack) and len(running) < workers:
                share = max(1, len(state.stack) // (workers - len(running)))
                lo, hi = state.stack.pop(min(share, 4 * solver.batch_size))
                known = [
                    (
                        state.solutions.E_lo[i],
                        state.solutions.E_hi[i],
                        state.solutions.U_lo[i],
                        state.solutions.U_hi[i],
                        state.solutions.kind[i],
                    )
                    for i in range(len(state.solutions))
                ]
                left = None if timeout is None else max(timeout - elapsed, 0.01)
                fut = pool.submit(
                    _task,
                    lo,
                    hi,
                    known,
                    rounds_per_task,
                    task_seconds if left is None else min(task_seconds, left),
                )
                running[fut] = (lo, hi)
            if not running:
                break
            done, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for fut in done:
                lo, hi = running.pop(fut)
                found, undecided, rlo, rhi, st = fut.result()
                for e0, e1, u0, u1, kind in found:
                    if kind == "alias":
                        state.solutions.add(e0, e1, u0, u1, "alias")
                    elif not state.solutions.add(e0, e1, u0, u1, kind):
                        stats.duplicates += 1
                state.undecided.extend(undecided)
                state.stack.push(rlo, rhi)
                stats.boxes += st.boxes
                stats.rounds += st.rounds
                stats.bisections += st.bisections
                stats.certified += st.certified
                stats.duplicates += st.duplicates
                stats.max_pending = max(stats.max_pending, len(state.stack))
            if progress is not None and stopped is None:
                p = Progress(
                    stats.boxes,
                    len(state.stack),
                    state.solutions.count("ok"),
                    len(state.undecided),
                    time.perf_counter() - t0,
                )
                if progress(p) is False:
                    stopped = "cancelled"
    stats.stopped_by = stopped
    stats.time = time.perf_counter() - t0
    stats.workers = workers
    result = solver.result(state)
    return result
