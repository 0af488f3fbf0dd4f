"""Response models of the HTTP API (documentation in the OpenAPI schema) and the error
answers each kind of route can give.  Request bodies are the job kinds' own models
(:mod:`certsolve.jobs.kinds`) and :class:`certsolve.jobs.service.BatchRequest`."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from certsolve.jobs.service import BatchRequest
from certsolve.jobs.status import JobStatus

__all__ = [
    "BatchCreated",
    "BatchRequest",
    "BatchStatus",
    "ErrorBody",
    "JobCreated",
    "JobList",
    "JobProgress",
    "JobRecord",
    "SUBMIT_ERRORS",
    "SYNC_ERRORS",
]


class JobCreated(BaseModel):
    id: str
    url: str
    status: Literal[JobStatus.QUEUED] = JobStatus.QUEUED


class BatchCreated(BaseModel):
    batch: str
    url: str
    ids: list[str]


class JobProgress(BaseModel):
    model_config = ConfigDict(extra="allow")  # e.g. inside / outside of a workspace job
    boxes: int | None = None
    pending: int | None = None
    solutions: int | None = None
    undecided: int | None = None
    elapsed: float | None = None
    stopped_by: str | None = None


class JobRecord(BaseModel):
    id: str
    url: str
    kind: str
    status: JobStatus
    batch: str | None
    created_at: str
    started_at: str | None
    finished_at: str | None
    elapsed: float | None = Field(description="seconds running (so far)")
    attempts: int
    max_attempts: int
    limits: dict[str, Any]
    progress: JobProgress | None
    cancel_requested: bool
    worker_pid: int | None
    error: str | None
    result: Any = Field(default=None, description="the library's result, when done")


class JobList(BaseModel):
    items: list[JobRecord]
    next_cursor: str | None = Field(description="pass as ?cursor= for the next page")


class BatchStatus(BaseModel):
    batch: str
    total: int
    counts: dict[str, int]
    finished: bool
    jobs_url: str


class ErrorBody(BaseModel):
    error: str
    detail: list[dict[str, Any]] | None = None


_ERRORS = {
    413: {"description": "request too large"},
    422: {"description": "invalid request: each problem with its field path"},
    429: {"description": "the queue is full, or too many quick calls at once"},
}
SUBMIT_ERRORS: dict[int | str, dict[str, Any]] = {
    k: {"model": ErrorBody, **v} for k, v in _ERRORS.items()
}
SYNC_ERRORS: dict[int | str, dict[str, Any]] = {
    422: {"model": ErrorBody},
    429: {"model": ErrorBody},
    501: {"model": ErrorBody, "description": "not available in this build"},
}
