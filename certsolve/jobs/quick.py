"""The quick synchronous calls (``/v1/ik``, ``/v1/isotropic``, ``/v1/fk/track``): cheap
library calls answered at once, without a job.

At most ``settings.sync_concurrency`` run at the same time; a call that finds no free slot
within ``wait`` seconds gets :class:`Busy` (HTTP 429).  The result is plain JSON data
(:func:`.jsonutil.plain`).  Errors: :class:`.kinds.KindUnavailable` when this build lacks
the library function, ``ValueError`` / ``ArithmeticError`` for input the library refuses.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from .jsonutil import plain
from .kinds import IkCall, IsotropicCall, TrackCall, call_ik, call_isotropic, call_track
from .settings import ServiceSettings

__all__ = ["Busy", "QuickCalls"]


class Busy(Exception):
    """Every slot for quick calls stayed taken: retry, or submit a job."""


class QuickCalls:
    """Runs the quick calls of one service, a bounded number at a time."""

    def __init__(self, settings: ServiceSettings, *, wait: float = 30.0):
        self._slots = threading.BoundedSemaphore(max(1, settings.sync_concurrency))
        self.wait = wait

    def ik(self, req: IkCall) -> Any:
        return self._run(call_ik, req)

    def isotropic(self, req: IsotropicCall) -> Any:
        return self._run(call_isotropic, req)

    def track(self, req: TrackCall) -> Any:
        return self._run(call_track, req)

    def _run(self, fn: Callable[[Any], Any], req: Any) -> Any:
        if not self._slots.acquire(timeout=self.wait):
            raise Busy("too many quick calls at once; retry, or submit a job")
        try:
            return plain(fn(req))
        finally:
            self._slots.release()
