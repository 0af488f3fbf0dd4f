"""The life cycle of a job: ``queued -> running -> done | failed | cancelled``.

A running job whose worker died goes back to ``queued`` while it has attempts left
(:meth:`.store.JobStore.release`); a queued job can be cancelled at once.  ``done`` means
the library call returned (its result may still be ``incomplete``: that is the search's
own status, not the job's); ``failed`` comes with an ``error``; ``cancelled`` keeps the
partial result when the search stopped cooperatively.
"""

from __future__ import annotations

from enum import StrEnum

__all__ = ["FINAL_STATUSES", "STATUSES", "JobStatus"]


class JobStatus(StrEnum):
    QUEUED = "queued"
    RUNNING = "running"
    DONE = "done"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def final(self) -> bool:
        """The job will not change any more."""
        return self in FINAL_STATUSES


STATUSES: tuple[JobStatus, ...] = tuple(JobStatus)
FINAL_STATUSES = frozenset({JobStatus.DONE, JobStatus.FAILED, JobStatus.CANCELLED})
