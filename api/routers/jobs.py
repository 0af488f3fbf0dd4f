"""Jobs and batches: ``/v1/jobs``, ``/v1/jobs/batch``, ``/v1/jobs/{id}``,
``/v1/jobs/{id}/result``, ``/v1/batches/{id}``.

Every route passes the calling client (:data:`..deps.Caller`) to the job service: a
client reads, lists and cancels its own jobs only (another client's job is a 404).

The body of ``POST /v1/jobs`` is the union of the job kinds' models, which depends on the
settings (the hidden test kind), so :func:`router` builds the router for a request type
(and this module keeps its annotations evaluated: no ``from __future__ import annotations``).
"""

from collections.abc import Sequence
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, Query, Request
from fastapi.responses import JSONResponse, Response

from certsolve.jobs.jsonutil import dumps
from certsolve.jobs.service import (
    BatchError,
    LimitError,
    NoResult,
    NoSuchJob,
    job_record,
)
from certsolve.jobs.status import JobStatus
from certsolve.jobs.store import JobRow, QueueFull

from ..deps import Caller, Service, Settings, checked_body
from ..errors import APIError, validation_details
from ..schemas import (
    CROSS_FIELD_RULES,
    BatchCreated,
    BatchRequest,
    BatchStatus,
    JobCreated,
    JobList,
    JobRecord,
    errors,
)

__all__ = ["JOB_STATUS_HEADER", "router"]

_ID = Annotated[str, Path(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_-]+$")]
JOB_STATUS_HEADER = "Certsolve-Job-Status"  # the job's status, beside a bare result

_SUBMIT = errors(400, 401, 413, 422, 429)
_READ = errors(401, 404, 422, 429)


# -- HTTP <-> service translation ---------------------------------------------------------------
def _url(request: Request, job_id: str) -> str:
    return str(request.url_for("get_job", job_id=job_id))


def _record(request: Request, row: JobRow) -> dict[str, Any]:
    return {**job_record(row), "url": _url(request, row.id)}


def _record_response(request: Request, row: JobRow, *, result: bool) -> Response:
    text = dumps(_record(request, row))
    if result:  # the stored JSON text, not parsed again
        text = text[:-1] + ',"result":' + (row.result or "null") + "}"
    return Response(text, media_type="application/json")


def _body(details: list[dict]) -> list[dict]:
    """Validation details of the request body: ``loc`` starts with ``body``."""
    return [{**d, "loc": ["body", *d["loc"]]} for d in details]


def _limit_error(exc: LimitError) -> APIError:
    d = validation_details([{"loc": exc.field.split("."), "msg": exc.message, "type": "limit"}])
    return APIError(422, str(exc), _body(d))


def _queue_error(exc: Exception, retry_after: int) -> APIError:
    if isinstance(exc, QueueFull):
        return APIError(429, str(exc), type="queue_full", headers={"Retry-After": str(retry_after)})
    if isinstance(exc, LimitError):
        return _limit_error(exc)
    if isinstance(exc, BatchError):
        if exc.too_large:
            return APIError(413, exc.message, loc=("body", "jobs"), type="too_large")
        return APIError(422, exc.message, None if exc.details is None else _body(exc.details))
    raise exc


def _missing(exc: NoSuchJob, name: str = "job_id") -> APIError:
    return APIError(404, str(exc), loc=("path", name))


# -- the routes -----------------------------------------------------------------------------------
def router(job_request: Any, kinds: Sequence[str]) -> APIRouter:
    """The jobs router for the request type ``job_request`` (a union of kinds' models,
    deferred: :func:`..deps.checked_body` checks them against their robots) and the names
    of those ``kinds`` (the list's filter)."""
    r = APIRouter(tags=["jobs"])
    job_body = checked_body(job_request, "job")

    @r.post(
        "/v1/jobs",
        status_code=202,
        response_model=JobCreated,
        responses=_SUBMIT,
        description="Queue one job; poll its URL for progress and the result.\n"
        + CROSS_FIELD_RULES,
    )
    def submit_job(
        job: Annotated[Any, Depends(job_body)],
        request: Request,
        response: Response,
        service: Service,
        settings: Settings,
        caller: Caller,
    ):
        """Queue one job; poll its URL for progress and the result."""
        try:
            (job_id,) = service.submit([job], client=caller)
        except (QueueFull, LimitError) as exc:
            raise _queue_error(exc, settings.retry_after) from None
        url = _url(request, job_id)
        response.headers["Location"] = url
        return {"id": job_id, "url": url, "status": JobStatus.QUEUED}

    @r.post(
        "/v1/jobs/batch",
        status_code=202,
        response_model=BatchCreated,
        responses=_SUBMIT,
        description='Queue many jobs at once (all or none): either `{"jobs": [job, ...]}` or '
        '`{"kind": "fk", "robot": {...}, "params": [{"u": [...]}, ...]}` (one job per params '
        "object).\n" + CROSS_FIELD_RULES,
    )
    def submit_batch(
        batch: BatchRequest, request: Request, service: Service, settings: Settings, caller: Caller
    ):
        """Queue many jobs at once (all or none).

        Either ``{"jobs": [job, ...]}`` or ``{"kind": "fk", "robot": {...}, "params":
        [{"u": [...]}, {"u": [...]}, ...]}`` (one job per params object)."""
        try:
            batch_id, ids = service.submit_batch(batch, client=caller)
        except (QueueFull, BatchError) as exc:
            raise _queue_error(exc, settings.retry_after) from None
        url = str(request.url_for("get_batch", batch_id=batch_id))
        return {"batch": batch_id, "url": url, "ids": ids}

    @r.get("/v1/jobs", response_model=JobList, responses=errors(401, 422, 429))
    def list_jobs(
        request: Request,
        service: Service,
        caller: Caller,
        status: JobStatus | None = None,
        kind: Annotated[
            str | None, Query(max_length=32, json_schema_extra={"enum": list(kinds)})
        ] = None,
        batch: Annotated[str | None, Query(max_length=64)] = None,
        limit: Annotated[int, Query(ge=1, le=500)] = 50,
        cursor: Annotated[str | None, Query(pattern=r"^[0-9]{1,18}$")] = None,
    ):
        """The caller's jobs (an admin's: all), newest first, without results; filter by
        status, kind or batch."""
        if kind is not None and kind not in kinds:
            raise APIError(
                422, f"unknown job kind {kind!r}; one of: {', '.join(kinds)}", loc=("query", "kind")
            )
        rows, nxt = service.jobs(
            caller,
            status=status,
            kind=kind,
            batch=batch,
            limit=limit,
            cursor=int(cursor) if cursor else None,
        )
        items = [_record(request, row) for row in rows]
        return JSONResponse({"items": items, "next_cursor": str(nxt) if nxt else None})

    @r.get("/v1/jobs/{job_id}", response_model=JobRecord, responses=_READ)
    def get_job(
        job_id: _ID, request: Request, service: Service, caller: Caller, result: bool = True
    ):
        """Status, progress and the result: when done, and the partial result of a job
        stopped by a limit or a cancel."""
        try:
            row = service.job(job_id, caller, result=result)
        except NoSuchJob as exc:
            raise _missing(exc) from None
        return _record_response(request, row, result=result)

    @r.get(
        "/v1/jobs/{job_id}/result",
        responses={
            200: {
                "description": "the result; the job's status is in the "
                f"{JOB_STATUS_HEADER} header (done, or cancelled with a partial result)",
                "headers": {JOB_STATUS_HEADER: {"schema": {"type": "string"}}},
            },
            **errors(401, 404, 409, 422, 429, e409="the job has no result (yet)"),
        },
    )
    def get_result(job_id: _ID, service: Service, caller: Caller):
        """Only the result (the library's JSON) -- partial when a limit or a cancel stopped
        the job; 409 while the job has none."""
        try:
            status, text = service.result_text(job_id, caller)
        except NoSuchJob as exc:
            raise _missing(exc) from None
        except NoResult as exc:
            raise APIError(409, str(exc), loc=("path", "job_id"), type="no_result") from None
        return Response(text, media_type="application/json", headers={JOB_STATUS_HEADER: status})

    @r.delete(
        "/v1/jobs/{job_id}",
        response_model=JobRecord,
        responses=errors(401, 404, 409, 422, 429, e409="the job has already finished"),
    )
    def cancel_job(job_id: _ID, request: Request, service: Service, caller: Caller):
        """Cancel: a queued job at once, a running one within a few seconds (keeping its
        partial result)."""
        try:
            row = service.cancel(job_id, caller)
        except NoSuchJob as exc:
            raise _missing(exc) from None
        if row.status in (JobStatus.DONE, JobStatus.FAILED):
            raise APIError(
                409,
                f"job {job_id} already finished ({row.status})",
                loc=("path", "job_id"),
                type="conflict",
            )
        resp = _record_response(request, row, result=False)
        resp.status_code = 202 if row.status is JobStatus.RUNNING else 200
        return resp

    @r.get("/v1/batches/{batch_id}", response_model=BatchStatus, responses=_READ)
    def get_batch(batch_id: _ID, request: Request, service: Service, caller: Caller):
        """How many jobs of a batch are in each status."""
        try:
            status = service.batch_status(batch_id, caller)
        except NoSuchJob as exc:
            raise _missing(exc, "batch_id") from None
        jobs_url = request.url_for("list_jobs").include_query_params(batch=batch_id)
        return {**status, "jobs_url": str(jobs_url)}

    return r
