"""Jobs and batches: ``/v1/jobs``, ``/v1/jobs/batch``, ``/v1/jobs/{id}``,
``/v1/jobs/{id}/result``, ``/v1/batches/{id}``.

The body of ``POST /v1/jobs`` is the union of the job kinds' models, which depends on the
settings (the hidden test kind), so :func:`router` builds the router for a request type
(and this module keeps its annotations evaluated: no ``from __future__ import annotations``).
"""

from typing import Annotated, Any

from fastapi import APIRouter, Body, Path, Query, Request
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

from ..deps import Service
from ..errors import APIError, validation_details
from ..schemas import (
    SUBMIT_ERRORS,
    BatchCreated,
    BatchRequest,
    BatchStatus,
    ErrorBody,
    JobCreated,
    JobList,
    JobRecord,
)

__all__ = ["router"]

_ID = Annotated[str, Path(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_-]+$")]


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


def _queue_error(exc: Exception) -> APIError:
    if isinstance(exc, QueueFull):
        return APIError(429, str(exc))
    if isinstance(exc, LimitError):
        return _limit_error(exc)
    if isinstance(exc, BatchError):
        if exc.too_large:
            return APIError(413, exc.message)
        return APIError(422, exc.message, None if exc.details is None else _body(exc.details))
    raise exc


# -- the routes -----------------------------------------------------------------------------------
def router(job_request: Any) -> APIRouter:
    """The jobs router for the request type ``job_request`` (a union of kinds' models)."""
    r = APIRouter(tags=["jobs"])

    @r.post("/v1/jobs", status_code=202, response_model=JobCreated, responses=SUBMIT_ERRORS)
    def submit_job(
        job: Annotated[job_request, Body()],
        request: Request,
        response: Response,
        service: Service,
    ):
        """Queue one job; poll its URL for progress and the result."""
        try:
            (job_id,) = service.submit([job])
        except (QueueFull, LimitError) as exc:
            raise _queue_error(exc) from None
        url = _url(request, job_id)
        response.headers["Location"] = url
        return {"id": job_id, "url": url, "status": JobStatus.QUEUED}

    @r.post("/v1/jobs/batch", status_code=202, response_model=BatchCreated, responses=SUBMIT_ERRORS)
    def submit_batch(batch: BatchRequest, request: Request, service: Service):
        """Queue many jobs at once (all or none).

        Either ``{"jobs": [job, ...]}`` or ``{"kind": "fk", "robot": {...}, "params":
        [{"u": [...]}, {"u": [...]}, ...]}`` (one job per params object)."""
        try:
            batch_id, ids = service.submit_batch(batch)
        except (QueueFull, BatchError) as exc:
            raise _queue_error(exc) from None
        url = str(request.url_for("get_batch", batch_id=batch_id))
        return {"batch": batch_id, "url": url, "ids": ids}

    @r.get("/v1/jobs", response_model=JobList)
    def list_jobs(
        request: Request,
        service: Service,
        status: JobStatus | None = None,
        kind: Annotated[str | None, Query(max_length=32)] = None,
        batch: Annotated[str | None, Query(max_length=64)] = None,
        limit: Annotated[int, Query(ge=1, le=500)] = 50,
        cursor: Annotated[str | None, Query(pattern=r"^[0-9]{1,18}$")] = None,
    ):
        """Jobs, newest first, without results; filter by status, kind or batch."""
        rows, nxt = service.store.list(
            status=status,
            kind=kind,
            batch=batch,
            limit=limit,
            cursor=int(cursor) if cursor else None,
        )
        items = [_record(request, row) for row in rows]
        return JSONResponse({"items": items, "next_cursor": str(nxt) if nxt else None})

    @r.get("/v1/jobs/{job_id}", response_model=JobRecord, responses={404: {"model": ErrorBody}})
    def get_job(job_id: _ID, request: Request, service: Service, result: bool = True):
        """Status, progress and (when done, or partial when cancelled) the result."""
        row = service.store.get(job_id, result=result)
        if row is None:
            raise APIError(404, f"no job {job_id}")
        return _record_response(request, row, result=result)

    @r.get(
        "/v1/jobs/{job_id}/result",
        responses={404: {"model": ErrorBody}, 409: {"model": ErrorBody}},
    )
    def get_result(job_id: _ID, service: Service):
        """Only the result (the library's JSON); 409 while the job has none."""
        try:
            text = service.result_text(job_id)
        except NoSuchJob as exc:
            raise APIError(404, str(exc)) from None
        except NoResult as exc:
            raise APIError(409, str(exc)) from None
        return Response(text, media_type="application/json")

    @r.delete(
        "/v1/jobs/{job_id}",
        response_model=JobRecord,
        responses={404: {"model": ErrorBody}, 409: {"model": ErrorBody}},
    )
    def cancel_job(job_id: _ID, request: Request, service: Service):
        """Cancel: a queued job at once, a running one within about a second."""
        row = service.cancel(job_id)
        if row is None:
            raise APIError(404, f"no job {job_id}")
        if row.status in (JobStatus.DONE, JobStatus.FAILED):
            raise APIError(409, f"job {job_id} already finished ({row.status})")
        resp = _record_response(request, row, result=False)
        resp.status_code = 202 if row.status is JobStatus.RUNNING else 200
        return resp

    @r.get(
        "/v1/batches/{batch_id}", response_model=BatchStatus, responses={404: {"model": ErrorBody}}
    )
    def get_batch(batch_id: _ID, request: Request, service: Service):
        """How many jobs of a batch are in each status."""
        try:
            status = service.batch_status(batch_id)
        except NoSuchJob as exc:
            raise APIError(404, str(exc)) from None
        jobs_url = request.url_for("list_jobs").include_query_params(batch=batch_id)
        return {**status, "jobs_url": str(jobs_url)}

    return r
