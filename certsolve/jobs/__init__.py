"""Jobs: a persistent queue of solver runs executed by supervised worker processes.

* :mod:`.settings` -- :class:`ServiceSettings` (data directory, workers, limits)
* :mod:`.kinds`    -- the job kinds: request models (shared by HTTP, batch files and the
  CLI) and the runners calling the library
* :mod:`.store`    -- :class:`JobStore`, jobs and results in SQLite (WAL)
* :mod:`.worker`   -- the worker process loop: claim, run with progress and cancellation
* :mod:`.pool`     -- :class:`WorkerPool`, the supervisor (dead workers, time limits)
* :mod:`.service`  -- :class:`JobService`, what the HTTP API and the batch runner use
* :mod:`.batch`    -- :func:`run_batch`, offline JSON-lines batches (resumable)

This package may import the library (solver, robot, kinematics, force) but never ``api``.
"""

from .kinds import KINDS, KindUnavailable, job_request_type, request_adapter
from .service import JobService, LimitError, ServiceError, job_record
from .settings import ServiceSettings
from .store import FINAL_STATUSES, STATUSES, JobRow, JobStore, QueueFull

__all__ = [
    "FINAL_STATUSES",
    "KINDS",
    "STATUSES",
    "JobRow",
    "JobService",
    "JobStore",
    "KindUnavailable",
    "LimitError",
    "QueueFull",
    "ServiceError",
    "ServiceSettings",
    "job_record",
    "job_request_type",
    "request_adapter",
]
