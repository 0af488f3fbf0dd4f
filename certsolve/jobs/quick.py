"""The quick synchronous calls (``/v1/ik``, ``/v1/isotropic``, ``/v1/fk/track``): answered
at once, without a job -- but never computed in the HTTP process.

Each call runs in a small pool of worker processes, under a deadline and a memory limit,
so that no request can take the service down for everyone:

* **cost estimate first**: each call has ``cost(request)``, its estimated seconds from the
  request's size (:class:`.kinds.QuickCall`).  Above ``quick_heavy_timeout`` it is refused
  (:class:`TooCostly`, HTTP 422 naming the job to submit instead); above
  :data:`LIGHT_COST` it goes to the *heavy* lane, else to the *light* lane.  The lanes have
  their own processes (``quick_workers``, ``quick_heavy_workers``), so heavy calls never
  starve light ones;
* **a free process or a 429**: a call waits at most ``quick_wait`` seconds for a process of
  its lane, and at most ``quick_queue`` calls wait per lane; otherwise :class:`Busy` (HTTP
  429 with ``Retry-After``);
* **a deadline**: a call still running after ``quick_timeout`` (light) or
  ``quick_heavy_timeout`` (heavy) seconds has its process killed (:class:`TooCostly`);
* **memory**: each process runs under ``RLIMIT_AS`` = ``quick_memory_mb``; a call that runs
  out gets :class:`TooCostly` and the process is replaced;
* **a client that goes away** (``gone()`` turns true while the call runs, checked every
  :data:`CHECK_EVERY` seconds) has its process killed: its computation stops.

A killed process is replaced at once (its imports take about a second, paid by the next
call of that lane).  The processes are started on first use and die with the service
(``PR_SET_PDEATHSIG``).  Results come back as JSON text (strict JSON,
:func:`.jsonutil.plain`), at most :data:`MAX_RESULT_BYTES` -- the HTTP process only passes
bytes on, so its memory does not grow with the calls it serves.

Errors: :class:`.kinds.KindUnavailable` when this build lacks the library function,
:class:`~certsolve.inputs.InputError` (a ``ValueError``; its ``field`` is the one the library
named, ``""`` if none) for input the library refuses, :class:`Busy`, :class:`TooCostly`,
:class:`Gone`, :class:`QuickFailure` (a bug in the call: HTTP 500).
"""

from __future__ import annotations

import logging
import math
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from ..inputs import InputError
from .settings import ServiceSettings

__all__ = [
    "Busy",
    "CHECK_EVERY",
    "Gone",
    "LIGHT_COST",
    "MAX_RESULT_BYTES",
    "QuickCalls",
    "QuickFailure",
    "TooCostly",
]

log = logging.getLogger("certsolve.jobs.quick")

LIGHT_COST = 1.0  # seconds: calls estimated above this go to the heavy lane
CHECK_EVERY = 0.2  # seconds between looks at the process and at the client
MAX_RESULT_BYTES = 8 * 2**20
READY_TIMEOUT = 120.0  # seconds a new process may take to import the library


class Busy(Exception):
    """No process of the call's lane became free in time: retry after ``retry_after``
    seconds, or submit a job."""

    def __init__(self, message: str, retry_after: int):
        super().__init__(message)
        self.retry_after = retry_after


class TooCostly(ValueError):
    """The call needs more time or memory than a quick call has: submit a job.  ``field``
    is the request field its cost grows with (``robot.wires``, ``params.method``)."""

    def __init__(self, message: str, field: str = ""):
        super().__init__(message)
        self.field = field


class Gone(Exception):
    """The client went away; the computation was stopped."""


class QuickFailure(Exception):
    """The call failed in a way that is not the input's fault (a bug, a dead process)."""


# -- the worker process ---------------------------------------------------------------------------
def _serve(conn, memory_mb: int, parent_pid: int) -> None:
    """A quick-call process: import the calls, say ready, answer requests until EOF."""
    from .worker import die_with_parent, set_memory_limit

    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the service's business
    set_memory_limit(memory_mb)
    from ..robot.schema import RobotFileError
    from .jsonutil import dumps, plain
    from .kinds import QUICK_CALLS, KindUnavailable

    available = {}
    for call in QUICK_CALLS.values():  # load the library now, not during the first call
        try:
            call.load()
            available[call.name] = True
        except KindUnavailable:  # reported when the call is made
            available[call.name] = False
    conn.send(("ready", None))
    while True:
        try:
            name, req = conn.recv()
        except (EOFError, OSError):
            return
        exit_after = False
        try:
            call = QUICK_CALLS[name]
            if not available[name]:
                call.load()  # raises KindUnavailable
            text = dumps(plain(call.run(req.params, getattr(req, "robot", None))))
            if len(text) > MAX_RESULT_BYTES:
                reply: tuple[str, Any] = ("costly", f"a result of {len(text)} bytes")
            else:
                reply = ("ok", text)
        except KindUnavailable as exc:
            reply = ("unavailable", str(exc))
        except MemoryError:
            reply, exit_after = ("memory", None), True
        except InputError as exc:  # the input's fault, at a field the library names
            reply = ("invalid", (exc.field, exc.message))
        except RobotFileError as exc:  # the robot's fault (robot.wires.2.k, if known)
            reply = ("invalid", (exc.field, exc.reason) if exc.field else ("", str(exc)))
        except (ValueError, ArithmeticError) as exc:  # the input's fault
            reply = ("invalid", ("", str(exc) or type(exc).__name__))
        except Exception as exc:
            reply = ("failed", f"{type(exc).__name__}: {exc}"[:500])
        try:
            conn.send(reply)
        except (OSError, ValueError):
            return
        if exit_after:
            return


@dataclass(eq=False)
class _Proc:
    """One quick-call process and the parent's end of its pipe."""

    proc: Any
    conn: Any
    ready: bool = False

    @classmethod
    def start(cls, ctx, memory_mb: int) -> _Proc:
        parent, child = ctx.Pipe()
        proc = ctx.Process(
            target=_serve,
            args=(child, memory_mb, os.getpid()),
            name="certsolve-quick",
            daemon=True,
        )
        proc.start()
        child.close()
        return cls(proc=proc, conn=parent)

    def kill(self) -> None:
        try:
            os.kill(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, TypeError):
            pass
        self.proc.join(5)
        self.conn.close()

    def receive(self, deadline: float, gone: Callable[[], bool]) -> tuple[str, Any]:
        """The next message; ``TimeoutError`` past ``deadline``, :class:`Gone`,
        ``EOFError`` if the process died."""
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            if self.conn.poll(min(CHECK_EVERY, left)):
                return self.conn.recv()  # EOFError when the process is gone
            if gone():
                raise Gone("the client went away")


class _Lane:
    """The processes of one lane and the calls waiting for them.

    Processes are started by ``spawner`` (one long-lived thread): ``PR_SET_PDEATHSIG``
    fires when the *thread* that started a process ends, and the threads answering
    requests come and go."""

    def __init__(
        self,
        name: str,
        size: int,
        timeout: float,
        settings: ServiceSettings,
        spawner: Callable[[], _Proc],
    ):
        self.name = name
        self.size = size
        self.timeout = timeout
        self.settings = settings
        self._start = spawner
        self._cond = threading.Condition()
        self._idle: list[_Proc] = []
        self._free = size  # slots not taken by a call
        self._waiting = 0
        self._ends: dict[int, float] = {}  # id(proc) -> deadline of the call it runs
        self._all: set[_Proc] = set()
        self.closed = False
        self.started = 0  # processes started (the first ``size`` and every replacement)

    def _spawn(self) -> _Proc:
        proc = self._start()
        with self._cond:
            self._all.add(proc)
            self.started += 1
        return proc

    def _retry_after(self) -> int:
        soonest = min(self._ends.values(), default=time.monotonic() + 1)
        return max(1, math.ceil(soonest - time.monotonic()))

    def acquire(self) -> _Proc:
        wait = self.settings.quick_wait
        with self._cond:
            if self.closed:
                raise Busy("the service is stopping", 5)
            if self._free == 0 and self._waiting >= self.settings.quick_queue:
                raise Busy(self._busy_message(), self._retry_after())
            self._waiting += 1
            try:
                ok = self._cond.wait_for(lambda: self._free > 0 or self.closed, timeout=wait)
            finally:
                self._waiting -= 1
            if not ok or self.closed:
                raise Busy(self._busy_message(), self._retry_after())
            self._free -= 1
            proc = self._idle.pop() if self._idle else None
        if proc is None:
            try:
                proc = self._spawn()
            except BaseException:
                with self._cond:
                    self._free += 1
                    self._cond.notify()
                raise
        with self._cond:
            self._ends[id(proc)] = time.monotonic() + self.timeout
        return proc

    def _busy_message(self) -> str:
        return f"every {self.name} quick-call process is busy ({self.size}); retry, or submit a job"

    def release(self, proc: _Proc, *, keep: bool) -> None:
        """Give the slot back; a process not kept (killed, dead) is replaced at once."""
        if not keep:
            proc.kill()
        fresh = None
        if not keep and not self.closed:
            try:
                fresh = self._spawn()
            except Exception:  # the next call starts one
                log.exception("cannot start a quick-call process")
        with self._cond:
            self._ends.pop(id(proc), None)
            if not keep:
                self._all.discard(proc)
            new = proc if keep else fresh
            if new is not None:
                if self.closed:
                    self._all.discard(new)
                else:
                    self._idle.append(new)
            self._free += 1
            self._cond.notify()
        if new is not None and self.closed:
            new.kill()

    def close(self) -> None:
        with self._cond:
            self.closed = True
            procs, self._all, self._idle = list(self._all), set(), []
            self._cond.notify_all()
        for proc in procs:
            proc.kill()

    def pids(self) -> list[int]:
        with self._cond:
            return [p.proc.pid for p in self._all if p.proc.pid is not None]

    def stats(self) -> dict[str, Any]:
        with self._cond:
            return {
                "processes": len(self._all),
                "busy": self.size - self._free,
                "waiting": self._waiting,
                "started": self.started,
                "timeout": self.timeout,
            }


class QuickCalls:
    """Runs the quick calls of one service in its lanes (see the module docstring)."""

    def __init__(self, settings: ServiceSettings):
        self.settings = settings
        self._ctx = multiprocessing.get_context("spawn")
        self._spawner = ThreadPoolExecutor(1, thread_name_prefix="certsolve-quick-spawner")
        s = settings
        self.lanes = {
            "light": _Lane("light", s.quick_workers, s.quick_timeout, s, self._start),
            "heavy": _Lane("heavy", s.quick_heavy_workers, s.quick_heavy_timeout, s, self._start),
        }

    def _start(self) -> _Proc:
        """A new process, started from the spawner thread (see :class:`_Lane`)."""
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(name, "1")  # inherited: one BLAS thread per process
        return self._spawner.submit(_Proc.start, self._ctx, self.settings.quick_memory_mb).result()

    def lane_for(self, name: str, req: Any) -> _Lane:
        """The lane of a call by its cost estimate; :class:`TooCostly` above the heavy
        lane's deadline."""
        from .kinds import QUICK_CALLS

        call = QUICK_CALLS[name]
        cost = float(call.cost(req))
        heavy = self.lanes["heavy"]
        if cost > heavy.timeout:
            raise TooCostly(
                f"this call would take about {cost:.3g} s; quick calls stop at "
                f"{heavy.timeout:g} s: submit {call.job}",
                call.cost_field,
            )
        return heavy if cost > LIGHT_COST else self.lanes["light"]

    def run(self, name: str, req: Any, *, gone: Callable[[], bool] = lambda: False) -> str:
        """The call ``name`` (``ik``, ``isotropic``, ``fk/track``) on a validated request:
        the result as JSON text.  Raises as the module docstring says."""
        from .kinds import QUICK_CALLS, KindUnavailable

        call = QUICK_CALLS[name]
        lane = self.lane_for(name, req)
        proc = lane.acquire()
        keep = False
        try:
            if not proc.ready:
                proc.receive(time.monotonic() + READY_TIMEOUT, gone)  # ("ready", None)
                proc.ready = True
            proc.conn.send((name, req))
            what, value = proc.receive(time.monotonic() + lane.timeout, gone)
            keep = what != "memory"
        except TimeoutError:
            raise TooCostly(
                f"this call ran longer than {lane.timeout:g} s, the limit of quick calls "
                f"({lane.name} lane): submit {call.job}",
                call.cost_field,
            ) from None
        except (EOFError, OSError, BrokenPipeError):
            raise QuickFailure(
                f"the quick-call process died ({_exit(proc)}); the call was not answered"
            ) from None
        finally:
            lane.release(proc, keep=keep)
        if what == "ok":
            return value
        if what == "invalid":
            raise InputError(*value)
        if what == "unavailable":
            raise KindUnavailable(value)
        if what in ("memory", "costly"):
            need = f"more than {self.settings.quick_memory_mb} MiB" if what == "memory" else value
            raise TooCostly(
                f"this call needs {need}, too much for a quick call: submit {call.job}",
                call.cost_field,
            )
        raise QuickFailure(value)

    def close(self) -> None:
        for lane in self.lanes.values():
            lane.close()
        self._spawner.shutdown(wait=False)

    def pids(self) -> list[int]:
        return [pid for lane in self.lanes.values() for pid in lane.pids()]

    def stats(self) -> dict[str, Any]:
        """Per lane: processes, calls running and waiting, processes started in all (the
        first ones and every replacement of a killed one), the deadline."""
        return {name: lane.stats() for name, lane in self.lanes.items()}


def _exit(proc: _Proc) -> str:
    from .pool import describe_exit

    proc.proc.join(1)
    return describe_exit(proc.proc.exitcode)
