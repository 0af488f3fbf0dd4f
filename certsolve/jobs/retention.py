"""Keeping the job store bounded: a housekeeping thread of the service.

Every ``settings.housekeeping_interval`` seconds (and once at start) it

* purges the finished jobs (done, failed, cancelled) that finished more than
  ``settings.keep_days`` ago, when that is set (:meth:`.JobStore.purge`), and
* checkpoints the write-ahead log into the database and truncates it (``PRAGMA
  wal_checkpoint(TRUNCATE)``): without it the log of a busy store grows as long as some
  reader is always active.

Queued and running jobs are never purged.  An admin can purge at any time with
``POST /v1/admin/purge`` (:meth:`.JobService.purge`).
"""

from __future__ import annotations

import logging
import sqlite3
import threading
import time

from .settings import ServiceSettings
from .store import JobStore

__all__ = ["Housekeeper"]

log = logging.getLogger("certsolve.jobs")


class Housekeeper:
    """The thread described in the module docstring."""

    def __init__(self, store: JobStore, settings: ServiceSettings):
        self.store = store
        self.settings = settings
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.purged = 0  # jobs deleted so far
        self.passes = 0

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="certsolve-housekeeper", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def run_once(self) -> int:
        """One pass: purge (if ``keep_days`` is set) and checkpoint; jobs deleted."""
        deleted = 0
        keep = self.settings.keep_days
        if keep is not None:
            deleted = self.store.purge(time.time() - keep * 86400.0)
            if deleted:
                log.info("purged %d job(s) finished more than %g day(s) ago", deleted, keep)
        else:
            self.store.checkpoint()
        self.purged += deleted
        self.passes += 1
        return deleted

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.run_once()
            except sqlite3.Error as exc:  # busy: next time
                log.warning("housekeeping pass failed: %s", exc)
            except Exception:  # never let the thread die
                log.exception("housekeeping pass failed")
            self._stop.wait(self.settings.housekeeping_interval)
