"""Jobs: a persistent queue of solver runs executed by supervised worker processes.

* :mod:`.settings` -- :class:`ServiceSettings` (data directory, workers, limits)
* :mod:`.status`   -- :class:`JobStatus` (queued, running, done, failed, cancelled)
* :mod:`.kinds`    -- the job kinds, one module each: request models (shared by HTTP, batch
  files and the CLI) and the runners calling the library
* :mod:`.store`    -- :class:`JobStore`, jobs and results in SQLite (WAL)
* :mod:`.worker`   -- the worker process loop: claim, run with progress and cancellation
* :mod:`.pool`     -- :class:`WorkerPool`, the supervisor (dead workers, time limits)
* :mod:`.service`  -- :class:`JobService`, what the HTTP API and the batch runner use
* :mod:`.batch`    -- :func:`run_batch`, offline JSON-lines batches (resumable)
* :mod:`.pictures` -- :class:`~.pictures.Pictures`, PNG pictures of finished jobs, drawn
  once and kept in the data directory

This package may import the library (solver, robot, kinematics, force) but never ``api``.

Names are imported on first use (:mod:`certsolve.lazy`): the command line validates its
options with one kind's models without loading the service, its store and its pool.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_exports

if TYPE_CHECKING:
    from .kinds import KINDS, KindUnavailable, job_request_type, request_adapter
    from .service import JobService, LimitError, ServiceError, job_record
    from .settings import ServiceSettings
    from .status import FINAL_STATUSES, STATUSES, JobStatus
    from .store import JobRow, JobStore, QueueFull

_WHERE = {
    "KINDS": ".kinds",
    "KindUnavailable": ".kinds",
    "job_request_type": ".kinds",
    "request_adapter": ".kinds",
    "JobService": ".service",
    "LimitError": ".service",
    "ServiceError": ".service",
    "job_record": ".service",
    "ServiceSettings": ".settings",
    "FINAL_STATUSES": ".status",
    "STATUSES": ".status",
    "JobStatus": ".status",
    "JobRow": ".store",
    "JobStore": ".store",
    "QueueFull": ".store",
}

__getattr__, __dir__ = lazy_exports(__name__, _WHERE)

__all__ = [
    "FINAL_STATUSES",
    "JobRow",
    "JobService",
    "JobStatus",
    "JobStore",
    "KINDS",
    "KindUnavailable",
    "LimitError",
    "QueueFull",
    "STATUSES",
    "ServiceError",
    "ServiceSettings",
    "job_record",
    "job_request_type",
    "request_adapter",
]
