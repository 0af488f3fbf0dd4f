"""The search driver with a toy step: limits, status, progress, and that no box is lost.

The toy step bisects intervals of ``[0, 64]``: an interval narrower than 1 is a "solution"
if it holds a marked point, "undecided" if it holds a doubtful point, and proven empty
otherwise (its length is then recorded, so that the test can check that the solutions, the
undecided, the empty parts and the pending boxes cover the domain exactly).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np
import pytest

from certsolve.solver import (
    Limits,
    ProcessExecutor,
    SearchStatus,
    SerialExecutor,
    resolve_executor,
    run_search,
)
from certsolve.solver.buffer import BoxStack
from certsolve.solver.executors import TaskExecutor, TaskPool
from certsolve.solver.search import Tally, run_task

MARKS = np.arange(0.5, 64.0, 4.0)  # 16 solutions
DOUBTS = np.array([10.25, 30.25])  # 2 undecided


@dataclass
class ToyState:
    stack: BoxStack
    solutions: list = field(default_factory=list)
    undecided: list = field(default_factory=list)
    empty: float = 0.0  # total length proven empty


class Bisect1D:
    batch_size = 4

    def start(self, known=None) -> ToyState:
        return ToyState(BoxStack(1))

    def process(self, lo, hi, state: ToyState, *, deadline=None) -> None:
        a, b = lo[:, 0], hi[:, 0]
        small = b - a < 1.0
        for i in np.flatnonzero(small):
            if np.any((MARKS >= a[i]) & (MARKS < b[i])):
                state.solutions.append((a[i], b[i]))
            elif np.any((DOUBTS >= a[i]) & (DOUBTS < b[i])):
                state.undecided.append((a[i], b[i]))
            else:
                state.empty += b[i] - a[i]
        big = ~small
        mid = 0.5 * (a[big] + b[big])
        state.stack.push(
            np.concatenate([a[big], mid])[:, None], np.concatenate([mid, b[big]])[:, None]
        )

    def tally(self, state: ToyState) -> Tally:
        return Tally(solutions=len(state.solutions), undecided=len(state.undecided))

    def known(self, state):
        return None

    def found(self, state):
        return state.solutions, state.undecided, state.empty

    def merge(self, state, found) -> None:
        sols, und, empty = found
        state.solutions.extend(sols)
        state.undecided.extend(und)
        state.empty += empty


def search(**kw):
    return run_search(Bisect1D(), np.array([[0.0]]), np.array([[64.0]]), **kw)


def covered_length(run) -> float:
    st = run.state
    lo, hi = st.stack.snapshot()
    parts = st.solutions + st.undecided
    return st.empty + sum(b - a for a, b in parts) + float(np.sum(hi - lo))


def test_complete_search_finds_everything_and_loses_nothing():
    run = search()
    assert run.status == SearchStatus.COMPLETE == "complete"
    assert len(run.state.solutions) == 16 and len(run.state.undecided) == 2
    assert covered_length(run) == 64.0
    assert run.stats.executor == "serial" and run.stats.tasks == 0
    assert run.stats.boxes == 255  # a full binary tree: 128 leaves of width 1/2
    assert run.stats.batches >= run.stats.boxes / Bisect1D.batch_size


def test_status_enum_is_the_five_words():
    """The five ways a search ends, and ``truncated``: a complete solve whose answer lists
    only part of its undecided boxes (a result status, never a stop)."""
    assert [str(s) for s in SearchStatus] == [
        "complete",
        "truncated",
        "timeout",
        "max_boxes",
        "max_solutions",
        "cancelled",
    ]


@pytest.mark.parametrize(
    "limits, status",
    [
        (Limits(timeout=0.0), "timeout"),
        (Limits(max_boxes=10), "max_boxes"),
        (Limits(max_solutions=3), "max_solutions"),
    ],
)
def test_limits_stop_with_their_status_and_keep_the_rest_pending(limits, status):
    run = search(limits=limits)
    assert run.status == status and run.pending > 0
    assert covered_length(run) == 64.0
    if status == "max_boxes":
        assert 10 <= run.stats.boxes < 10 + Bisect1D.batch_size
    if status == "max_solutions":
        assert 3 <= len(run.state.solutions) < 16


def test_a_limit_reached_on_the_last_batch_is_still_complete():
    full = search()
    run = search(limits=Limits(max_boxes=full.stats.boxes))
    assert run.status == "complete" and run.pending == 0


def test_progress_reports_and_cancels():
    seen = []

    def progress(p):
        seen.append(p)
        return len(seen) < 5

    run = search(progress=progress)
    assert run.status == "cancelled" and len(seen) == 5
    assert [p.boxes for p in seen] == sorted(p.boxes for p in seen)
    last = seen[-1]
    assert last.boxes == run.stats.boxes and last.pending == run.pending
    assert last.solutions == len(run.state.solutions)
    assert covered_length(run) == 64.0


def test_cancel_event():
    event = threading.Event()
    calls = []

    def progress(p):
        calls.append(p.boxes)
        if len(calls) == 2:
            event.set()  # e.g. from another thread: seen before the next batch

    run = search(progress=progress, cancel=event)
    assert run.status == "cancelled" and len(calls) == 2


def test_continuing_a_run_keeps_records_and_counters():
    first = search(limits=Limits(max_boxes=20))
    lo, hi = first.state.stack.snapshot()
    first.state.stack.pop(len(lo))  # hand the pending boxes back as new input
    again = run_search(Bisect1D(), lo, hi, previous=first)
    assert again.status == "complete" and len(again.state.solutions) == 16
    assert again.stats.boxes == 255


def test_limits_are_validated():
    with pytest.raises(ValueError, match="timeout"):
        Limits(timeout=-1)
    with pytest.raises(ValueError, match="max_boxes"):
        Limits(max_boxes=1.5)
    with pytest.raises(ValueError, match="max_solutions"):
        Limits(max_solutions=-2)


def test_a_task_returns_its_records_and_unfinished_boxes():
    step = Bisect1D()
    lo, hi = np.array([[0.0], [32.0]]), np.array([[16.0], [48.0]])
    res = run_task(step, lo, hi, None, Limits(max_boxes=6))
    assert 6 <= res.boxes < 6 + step.batch_size and len(res.lo) > 0
    sols, und, empty = res.found
    total = empty + sum(b - a for a, b in sols + und) + float(np.sum(res.hi - res.lo))
    assert total == 32.0
    # max_solutions counts what the task finds, not what it was given
    res = run_task(step, lo, hi, None, Limits(max_solutions=2))
    assert len(res.found[0]) >= 2 and len(res.lo) > 0


# -- the task loop with an in-process pool that loses tasks -----------------------------------
class WorkerLost(Exception):
    pass


class FlakyPool(TaskPool):
    """Runs tasks here, in submission order; the tasks numbered in ``lose`` are "lost"."""

    def __init__(self, step, lose, slots: int = 3):
        self.step, self.lose = step, lose
        self.workers, self.slots = 2, slots
        self.queue, self.count = [], 0

    def submit(self, lo, hi, known, limits, hints=None):
        self.count += 1
        self.queue.append((self.count, lo, hi, known, limits, hints))
        return self.count

    def next_done(self):
        n, lo, hi, known, limits, hints = self.queue.pop(0)
        if n in self.lose:
            return n, None, WorkerLost()
        return n, run_task(self.step, lo, hi, known, limits, hints), None

    def lost(self, error):
        return isinstance(error, WorkerLost)

    def cancel(self, handles):
        self.queue = [q for q in self.queue if q[0] not in handles]

    def close(self):
        pass


class FlakyExecutor(TaskExecutor):
    name = "flaky"

    def __init__(self, lose=(), *, slice_size=3, task_max_boxes=8, **kw):
        super().__init__(
            warmup=0.0, task_seconds=10.0, slice_size=slice_size, task_max_boxes=task_max_boxes,
            **kw,
        )  # fmt: skip
        self.lose = set(lose)

    def open(self, step):
        return FlakyPool(step, self.lose)


@pytest.mark.parametrize("lose", [(), (2, 3, 7, 8, 9, 20)])
def test_tasks_lost_with_their_worker_are_handed_out_again(lose):
    run = search(executor=FlakyExecutor(lose))
    assert run.status == "complete" and run.stats.executor == "flaky"
    assert sorted(run.state.solutions) == sorted(search().state.solutions)
    assert len(run.state.undecided) == 2 and covered_length(run) == 64.0
    assert run.stats.tasks > 3
    assert run.stats.resubmitted == len(lose)


def test_a_task_lost_too_often_fails_the_search():
    with pytest.raises(RuntimeError, match="failed 2 times"):
        search(executor=FlakyExecutor(range(1, 100), max_attempts=2))


@pytest.mark.parametrize(
    "limits, status",
    [(Limits(max_solutions=4), "max_solutions"), (Limits(max_boxes=30), "max_boxes")],
)
def test_task_executor_honours_limits(limits, status):
    run = search(executor=FlakyExecutor(), limits=limits)
    assert run.status == status and run.pending > 0 and covered_length(run) == 64.0
    if status == "max_solutions":
        assert len(run.state.solutions) >= 4


def test_task_executor_cancels_from_progress():
    calls = []

    def progress(p):
        calls.append(p.tasks)
        return p.tasks < 2

    run = search(executor=FlakyExecutor(), progress=progress)
    assert run.status == "cancelled" and run.pending > 0 and covered_length(run) == 64.0


# -- choosing an executor -------------------------------------------------------------------
def test_resolve_executor():
    assert isinstance(resolve_executor(None), SerialExecutor)
    assert isinstance(resolve_executor(1), SerialExecutor)
    assert isinstance(resolve_executor("serial"), SerialExecutor)
    ex = resolve_executor(3)
    assert isinstance(ex, ProcessExecutor) and ex.workers == 3
    assert isinstance(resolve_executor("auto"), (SerialExecutor, ProcessExecutor))
    assert resolve_executor(ex) is ex
    assert resolve_executor(None, workers=2).workers == 2
    with pytest.raises(ValueError, match="either"):
        resolve_executor(2, workers=2)
    for bad in (0, -1, True, "many", 2.5):
        with pytest.raises(ValueError, match="executor"):
            resolve_executor(bad)
