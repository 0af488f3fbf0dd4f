"""The hidden test kind ``sleep`` (``enable_test_kinds`` only): sleeps, reports progress,
and on request fails, allocates memory (at once, or more at every progress report, as a
search whose memory grows), ignores its limits or crashes the worker.  The hidden quick
call ``sleep`` (no route; :class:`~certsolve.jobs.quick.QuickCalls` tests) sleeps and
allocates with a cost estimate of its own, so that a test can make a call outlast its
estimate."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import Field

from .base import Job, Kind, Params, QuickCall, Request, RunContext

__all__ = ["KIND", "QUICK", "SleepCall", "SleepJob", "SleepParams", "run_sleep"]


class SleepParams(Params):
    seconds: float = Field(default=1.0, ge=0, le=3600)
    crash: bool = Field(default=False, description="exit the worker abruptly halfway")
    fail: str | None = Field(default=None, max_length=200, description="raise this error")
    allocate_mb: int = Field(default=0, ge=0, le=1_000_000, description="allocate memory first")
    grow_mb: int = Field(default=0, ge=0, le=1000, description="allocate more every tick")
    cooperative: bool = Field(default=True, description="report progress, honour limits")


class SleepJob(Job):
    kind: Literal["sleep"]
    params: SleepParams = Field(default_factory=SleepParams)


@dataclass(kw_only=True)
class _SleepProgress:
    boxes: int
    pending: int
    solutions: int
    undecided: int
    elapsed: float


def run_sleep(p: SleepParams, _input: None, ctx: RunContext) -> Any:
    ballast = bytearray(p.allocate_mb * 2**20) if p.allocate_mb else None
    if p.fail:
        raise ValueError(p.fail)
    t0 = time.monotonic()
    ticks = 0
    stopped = None
    grown = []
    while (elapsed := time.monotonic() - t0) < p.seconds:
        if p.crash and elapsed >= p.seconds / 2:
            os._exit(17)
        if not p.cooperative:  # like a library call that never checks its limits
            time.sleep(min(0.02, max(0.0, p.seconds - elapsed)))
            continue
        if ctx.time_limit is not None and elapsed >= ctx.time_limit:
            stopped = "timeout"
            break
        ticks += 1
        if p.grow_mb:
            grown.append(bytearray(p.grow_mb * 2**20))
        progress = _SleepProgress(boxes=ticks, pending=0, solutions=0, undecided=0, elapsed=elapsed)
        if ctx.progress is not None and ctx.progress(progress) is False:
            stopped = "cancelled"
            break
        time.sleep(min(0.02, max(0.0, p.seconds - elapsed)))
    del ballast, grown
    return {"slept": time.monotonic() - t0, "ticks": ticks, "stopped_by": stopped}


KIND = Kind(
    name="sleep",
    model=SleepJob,
    params=SleepParams,
    run=run_sleep,
    function=lambda: time.sleep,
    summary="test kind: sleep, report progress, optionally crash",
    hidden=True,
)


# -- the hidden quick call --------------------------------------------------------------------
class SleepCallParams(Params):
    seconds: float = Field(default=0.0, ge=0, le=3600)
    allocate_mb: int = Field(default=0, ge=0, le=1_000_000)
    estimate: float = Field(default=0.0, ge=0, description="what the cost estimate says (s)")
    fail: str | None = Field(default=None, max_length=200, description="raise ValueError")


class SleepCall(Request):
    params: SleepCallParams = Field(default_factory=SleepCallParams)


def call_sleep(p: SleepCallParams, _input: None) -> Any:
    ballast = bytearray(p.allocate_mb * 2**20) if p.allocate_mb else None
    if p.fail:
        raise ValueError(p.fail)
    time.sleep(p.seconds)
    del ballast
    return {"slept": p.seconds, "pid": os.getpid()}


QUICK = QuickCall(
    name="sleep",
    model=SleepCall,
    run=call_sleep,
    function=lambda: time.sleep,
    cost=lambda req: req.params.estimate,
    job="a sleep job",
    cost_field="params.seconds",
)
