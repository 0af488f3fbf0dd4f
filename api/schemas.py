"""Response models of the HTTP API (documentation in the OpenAPI schema) and the error
answers each kind of route can give.  Request bodies are the job kinds' own models
(:mod:`certsolve.jobs.kinds`) and :class:`certsolve.jobs.service.BatchRequest`."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from certsolve.jobs.service import BatchRequest
from certsolve.jobs.status import JobStatus

__all__ = [
    "CROSS_FIELD_RULES",
    "BatchCreated",
    "BatchRequest",
    "BatchStatus",
    "ErrorBody",
    "JobCreated",
    "JobList",
    "JobProgress",
    "JobRecord",
    "Problem",
    "PurgeRequest",
    "PurgeResult",
    "errors",
]


# what the validation checks beyond the published JSON Schema (which states types, ranges,
# lengths, enums and one variant per robot dof); in the descriptions of the operations that
# take job requests, and in docs/reliability.md
CROSS_FIELD_RULES = """
Rules the JSON Schema cannot state (a request that breaks one is a 422 naming the field):

- every range is `[lo, hi]` with `lo <= hi` (a wire's `tau` and `u`, the robot's domain,
  a workspace `box`, a map's `grid` as `[xmin, xmax, ymin, ymax]`, design `range`s),
  workspace angle ranges at most 360 degrees wide;
- `params.u` has one value per wire of the robot (`fk`, `fk/track`);
- a wire's `tau_max` is below its stiffness `k` (eq. 5 divides by `k - tau`);
- `system` is Minibex text (its grammar, no undefined constant);
- FK: the platform attachment points span the formulation's frame, and the formulation is
  one the robot's geometry admits (`auto` always is);
- no wire of zero length at an IK or force pose;
- tracking (`fk/track`, `trajectory`) takes a robot without `tolerances` (one robot, not a set);
- IK of a robot with `tolerances`: method `tension` or `alg2` with `solve` `tau`, at least as
  many wires as equilibrium equations, and no wire of zero length for any robot of the set;
- IK Algorithm 2: `tau_fixed` below the fixed wire's stiffness `k` (eq. 5);
- IK with `distribution` `closed-form`: one more wire than equations (`m = w + 1`) and a
  wrench matrix of full rank at the pose;
- IK: another method's options keep their defaults (`u_last`, `window` not with `tension`;
  `fixed_wire`, `tau_fixed`, `solve` are alg2's; `distribution`, `check_lp` tension's);
- design parameter `path`s exist in the robot and share no number;
- a map's `nx * ny` is at most 250 000 points;
- a batch in the sweep form (`kind` + robot/system + `params` list): each item of `params`
  is the params object of that kind.
"""


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
    owner: str | None = Field(description="the client that submitted it (None without tokens)")
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


class Problem(BaseModel):
    """One problem of an error answer: where (``loc``, ``field``), what and what kind."""

    loc: list[str | int | None] = Field(description="path into the request, e.g. body.robot")
    field: str = Field(description="dotted path without its first part ('' if none)")
    msg: str
    type: str
    line: int | None = Field(default=None, description="Minibex text / JSON body: line")
    column: int | None = Field(default=None, description="Minibex text / JSON body: column")


class ErrorBody(BaseModel):
    """Every error answer: a one-line message and each problem."""

    error: str
    detail: list[Problem] = Field(min_length=1)


class PurgeRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")
    older_than_days: float = Field(
        ge=0, le=1e5, description="delete finished jobs that finished longer ago than this"
    )


class PurgeResult(BaseModel):
    deleted: int
    older_than_days: float
    db: int = Field(description="bytes of the job store after the purge")
    wal: int = Field(description="bytes of its write-ahead log after the checkpoint")


_WHY = {
    400: "the body cannot be read as JSON (not JSON, not UTF-8, nested too deeply)",
    401: "no valid token (a service started with tokens); see WWW-Authenticate",
    403: "an admin token is needed",
    404: "no such job or batch (or not the caller's)",
    409: "conflict with the job's state",
    413: "request body too large, or too many jobs in one batch",
    422: "invalid request: each problem with its field path",
    429: "the queue or the client's quota is full, too many requests, or no free "
    "quick-call process; retry after Retry-After seconds",
    501: "not available in this build",
    503: "the job store fails its check or cannot be read",
}
_HEADERS = {
    401: {"WWW-Authenticate": {"schema": {"type": "string"}}},
    429: {"Retry-After": {"schema": {"type": "integer"}, "description": "seconds"}},
}


def errors(*codes: int, **why: str) -> dict[int | str, dict[str, Any]]:
    """The ``responses`` of a route for its error ``codes`` (every error answer is an
    :class:`ErrorBody`); ``why`` overrides a description (``e409="..."``)."""
    out: dict[int | str, dict[str, Any]] = {}
    for code in codes:
        entry: dict[str, Any] = {"model": ErrorBody, "description": why.get(f"e{code}", _WHY[code])}
        if code in _HEADERS:
            entry["headers"] = _HEADERS[code]
        out[code] = entry
    return out
