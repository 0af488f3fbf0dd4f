"""The HTTP API of the solver service (FastAPI).

``create_app(settings)`` builds the application around a :class:`certsolve.jobs.JobService`:
jobs are queued in the service's SQLite store and run by its worker processes; the HTTP
process only validates, stores and reads.  Run it with ``certsolve serve`` or
``uvicorn api.app:create_app --factory`` (settings from ``CERTSOLVE_*`` variables).
See ``docs/api.md``.
"""

import logging
import threading
from contextlib import asynccontextmanager
from typing import Annotated, Any, Literal

from fastapi import Body, FastAPI, Path, Query, Request
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from certsolve.jobs import JobService, LimitError, QueueFull, ServiceSettings, job_record
from certsolve.jobs.jsonutil import dumps, plain
from certsolve.jobs.kinds import (
    KINDS,
    MAX_SYSTEM_CHARS,
    IkCall,
    IsotropicCall,
    JobLimits,
    KindUnavailable,
    TrackCall,
    call_ik,
    call_isotropic,
    call_track,
    job_request_type,
    library_function,
    public_kinds,
)
from certsolve.robot.schema import RobotSpec

from .errors import APIError, install_error_handlers, summary, validation_details
from .middleware import BodyLimitMiddleware

__all__ = ["create_app"]

log = logging.getLogger("certsolve.api")

API_VERSION = "1"
_ID = Annotated[str, Path(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_-]+$")]
_ERRORS = {
    404: {"description": "no such job"},
    413: {"description": "request too large"},
    422: {"description": "invalid request: each problem with its field path"},
    429: {"description": "the queue is full, or too many quick calls at once"},
}


# -- response models (documentation) -----------------------------------------------------------
class JobCreated(BaseModel):
    id: str
    url: str
    status: Literal["queued"] = "queued"


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
    status: Literal["queued", "running", "done", "failed", "cancelled"]
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


class BatchRequest(BaseModel):
    """Either ``jobs`` (full job requests) or one ``kind`` + input with a ``params`` list."""

    model_config = ConfigDict(extra="forbid")
    jobs: list[dict[str, Any]] | None = Field(
        default=None, description="job requests, each as for POST /v1/jobs"
    )
    kind: str | None = Field(default=None, max_length=32, description="kind of every job")
    robot: RobotSpec | None = None
    system: str | None = Field(default=None, max_length=MAX_SYSTEM_CHARS)
    limits: JobLimits | None = None
    params: list[dict[str, Any]] | None = Field(
        default=None, description="one params object per job (with kind and robot/system)"
    )


def create_app(settings: ServiceSettings | None = None, service: JobService | None = None):
    """The FastAPI application; the lifespan starts and stops the service's workers."""
    settings = settings or ServiceSettings.from_env()
    service = service or JobService(settings)
    hidden = settings.enable_test_kinds
    JobRequest = job_request_type(hidden)  # noqa: N806
    kinds = public_kinds(hidden)
    sync_slots = threading.BoundedSemaphore(max(1, settings.sync_concurrency))

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        service.start()
        try:
            yield
        finally:
            service.close()

    app = FastAPI(
        title="certsolve",
        version=API_VERSION,
        summary="Certified interval solving for wire-driven parallel robots, as jobs.",
        description=(
            "Submit solver jobs (`POST /v1/jobs`), poll them (`GET /v1/jobs/{id}`), cancel "
            "them (`DELETE /v1/jobs/{id}`). Jobs run in worker processes and survive "
            'restarts. Errors are JSON `{"error": ..., "detail": [...]}`.'
        ),
        lifespan=lifespan,
    )
    app.state.service = service
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes)
    install_error_handlers(app)

    def url_of(request: Request, job_id: str) -> str:
        return str(request.url_for("get_job", job_id=job_id))

    def queue(reqs: list, batch: str | None = None) -> list[str]:
        try:
            return service.submit(reqs, batch=batch)
        except QueueFull as exc:
            raise APIError(429, str(exc)) from None

    def limit_error(exc: LimitError, prefix: tuple = ("body",)) -> APIError:
        d = validation_details(
            [{"loc": (*prefix, *exc.field.split(".")), "msg": exc.message, "type": "limit"}]
        )
        return APIError(422, f"{exc.field}: {exc.message}", d)

    def record_response(request: Request, row, *, result: bool) -> Response:
        rec = job_record(row)
        rec["url"] = url_of(request, row.id)
        text = dumps(rec)
        if result:
            text = text[:-1] + ',"result":' + (row.result or "null") + "}"
        return Response(text, media_type="application/json")

    # -- health -----------------------------------------------------------------------------
    @app.get("/healthz", tags=["service"])
    def healthz() -> dict[str, Any]:
        """Liveness: workers alive and the queue depth."""
        return service.health()

    @app.get("/v1/kinds", tags=["service"])
    def list_kinds() -> dict[str, Any]:
        """The job kinds, their parameters (JSON Schema) and whether this build has them."""
        out = []
        for name in kinds:
            k = KINDS[name]
            try:
                library_function(name, *k.library)
                available = True
            except KindUnavailable:
                available = False
            out.append(
                {
                    "kind": name,
                    "summary": k.summary,
                    "input": "system" if "system" in k.model.model_fields else "robot",
                    "available": available,
                    "params": k.params.model_json_schema(),
                }
            )
        return {"kinds": out}

    # -- jobs -------------------------------------------------------------------------------
    @app.post(
        "/v1/jobs",
        status_code=202,
        response_model=JobCreated,
        responses={k: {"model": ErrorBody, **v} for k, v in _ERRORS.items() if k != 404},
        tags=["jobs"],
    )
    def submit_job(job: Annotated[JobRequest, Body()], request: Request, response: Response):
        """Queue one job; poll its URL for progress and the result."""
        try:
            (job_id,) = queue([job])
        except LimitError as exc:
            raise limit_error(exc) from None
        url = url_of(request, job_id)
        response.headers["Location"] = url
        return {"id": job_id, "url": url, "status": "queued"}

    @app.post(
        "/v1/jobs/batch",
        status_code=202,
        response_model=BatchCreated,
        responses={k: {"model": ErrorBody, **v} for k, v in _ERRORS.items() if k != 404},
        tags=["jobs"],
    )
    def submit_batch(batch: BatchRequest, request: Request):
        """Queue many jobs at once (all or none).

        Either ``{"jobs": [job, ...]}`` or ``{"kind": "fk", "robot": {...}, "params":
        [{"u": [...]}, {"u": [...]}, ...]}`` (one job per params object)."""
        shared = batch.kind is not None or batch.robot is not None or batch.system is not None
        if batch.jobs is not None and (shared or batch.params is not None):
            raise APIError(422, "give either jobs, or kind + robot/system + params (a list)")
        if batch.jobs is None and (batch.kind is None or batch.params is None):
            raise APIError(422, "give jobs (a list), or kind + robot/system + params (a list)")
        items = batch.jobs if batch.jobs is not None else batch.params
        assert items is not None
        if len(items) > settings.max_batch:
            raise APIError(413, f"{len(items)} jobs in one batch; at most {settings.max_batch}")
        if not items:
            raise APIError(422, "the batch is empty")
        reqs, details = [], []
        for i, item in enumerate(items):
            if batch.jobs is not None:
                data, prefix = item, ("body", "jobs", i)
            else:
                data = {"kind": batch.kind, "params": item}
                if batch.robot is not None:
                    data["robot"] = batch.robot.model_dump()
                if batch.system is not None:
                    data["system"] = batch.system
                if batch.limits is not None:
                    data["limits"] = batch.limits.model_dump()
                prefix = ("body",)
            try:
                req = service.validate(data)
                service.limits_for(req)
                reqs.append(req)
            except ValidationError as exc:
                errs = exc.errors()
                if batch.jobs is None:  # params errors belong to params[i]
                    errs = [_to_item(e, i) for e in errs]
                details.extend(validation_details(errs, prefix))
            except LimitError as exc:
                loc = (*prefix, *exc.field.split("."))
                details.extend(
                    validation_details([{"loc": loc, "msg": exc.message, "type": "limit"}])
                )
            if len(details) >= 50:
                break
        if details:
            seen, unique = set(), []
            for d in details:
                key = (d["field"], d["msg"])
                if key not in seen:
                    seen.add(key)
                    unique.append(d)
            raise APIError(422, summary(unique), unique)
        batch_id = service.new_batch_id()
        ids = queue(reqs, batch=batch_id)
        return {
            "batch": batch_id,
            "url": str(request.url_for("get_batch", batch_id=batch_id)),
            "ids": ids,
        }

    @app.get("/v1/jobs", response_model=JobList, tags=["jobs"])
    def list_jobs(
        request: Request,
        status: Literal["queued", "running", "done", "failed", "cancelled"] | None = None,
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
        items = []
        for row in rows:
            rec = job_record(row)
            rec["url"] = url_of(request, row.id)
            items.append(rec)
        return JSONResponse({"items": items, "next_cursor": str(nxt) if nxt else None})

    @app.get(
        "/v1/jobs/{job_id}",
        response_model=JobRecord,
        responses={404: {"model": ErrorBody}},
        tags=["jobs"],
    )
    def get_job(job_id: _ID, request: Request, result: bool = True):
        """Status, progress and (when done, or partial when cancelled) the result."""
        row = service.store.get(job_id, result=result)
        if row is None:
            raise APIError(404, f"no job {job_id}")
        return record_response(request, row, result=result)

    @app.get(
        "/v1/jobs/{job_id}/result",
        responses={404: {"model": ErrorBody}, 409: {"model": ErrorBody}},
        tags=["jobs"],
    )
    def get_result(job_id: _ID):
        """Only the result (the library's JSON); 409 while the job has none."""
        found = service.store.result_text(job_id)
        if found is None:
            raise APIError(404, f"no job {job_id}")
        status, text = found
        if text is None:
            row = service.store.get(job_id, result=False)
            why = f": {row.error}" if row is not None and row.error else ""
            raise APIError(409, f"job {job_id} is {status} and has no result{why}")
        return Response(text, media_type="application/json")

    @app.delete(
        "/v1/jobs/{job_id}",
        response_model=JobRecord,
        responses={404: {"model": ErrorBody}, 409: {"model": ErrorBody}},
        tags=["jobs"],
    )
    def cancel_job(job_id: _ID, request: Request):
        """Cancel: a queued job at once, a running one within about a second."""
        row = service.cancel(job_id)
        if row is None:
            raise APIError(404, f"no job {job_id}")
        if row.status in ("done", "failed"):
            raise APIError(409, f"job {job_id} already finished ({row.status})")
        resp = record_response(request, row, result=False)
        resp.status_code = 202 if row.status == "running" else 200
        return resp

    @app.get(
        "/v1/batches/{batch_id}",
        response_model=BatchStatus,
        responses={404: {"model": ErrorBody}},
        tags=["jobs"],
    )
    def get_batch(batch_id: _ID, request: Request):
        """How many jobs of a batch are in each status."""
        counts = service.store.counts(batch=batch_id)
        total = sum(counts.values())
        if total == 0:
            raise APIError(404, f"no batch {batch_id}")
        return {
            "batch": batch_id,
            "total": total,
            "counts": counts,
            "finished": counts["queued"] + counts["running"] == 0,
            "jobs_url": str(request.url_for("list_jobs").include_query_params(batch=batch_id)),
        }

    # -- quick synchronous calls --------------------------------------------------------------
    def quick(fn, req) -> JSONResponse:
        if not sync_slots.acquire(timeout=30):
            raise APIError(429, "too many quick calls at once; retry, or submit a job")
        try:
            result = fn(req)
        except KindUnavailable as exc:
            raise APIError(501, str(exc).replace("kind ", "", 1)) from None
        except (ValueError, ArithmeticError) as exc:  # the input's fault
            raise APIError(422, str(exc) or type(exc).__name__) from None
        finally:
            sync_slots.release()
        return JSONResponse(plain(result))

    sync_responses = {
        422: {"model": ErrorBody},
        429: {"model": ErrorBody},
        501: {"model": ErrorBody, "description": "not available in this build"},
    }

    @app.post("/v1/ik", responses=sync_responses, tags=["quick"])
    def ik(req: IkCall) -> Any:
        """Inverse kinematics at one pose (synchronous)."""
        return quick(call_ik, req)

    @app.post("/v1/isotropic", responses=sync_responses, tags=["quick"])
    def isotropic(req: IsotropicCall) -> Any:
        """Isotropic force at one pose (synchronous)."""
        return quick(call_isotropic, req)

    @app.post("/v1/fk/track", responses=sync_responses, tags=["quick"])
    def fk_track(req: TrackCall) -> Any:
        """Forward kinematics near a known pose (synchronous tracking step)."""
        return quick(call_track, req)

    return app


def _to_item(e: dict, i: int) -> dict:
    """An error of the i-th job of a sweep batch, placed at ``params[i]``."""
    loc = tuple(e.get("loc", ()))
    if loc[1:2] == ("params",):
        return {**e, "loc": ("params", i, *loc[2:])}
    msg = str(e.get("msg", ""))
    if len(loc) <= 1 and msg.startswith("Value error, params."):
        return {**e, "msg": msg.replace("params.", f"params[{i}].", 1)}
    return e
