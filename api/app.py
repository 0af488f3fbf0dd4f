"""The HTTP API of the solver service (FastAPI).

``create_app(settings)`` builds the application around a :class:`certsolve.jobs.JobService`:
jobs are queued in the service's SQLite store and run by its worker processes; the HTTP
process only validates, stores and reads.  Routes live in one router per resource
(:mod:`.routers.jobs`, :mod:`.routers.sync`, :mod:`.routers.meta`, the pictures of finished
jobs :mod:`.routers.pictures`, the bundled robots :mod:`.routers.examples`, and the web
page at ``/`` :mod:`.routers.pages`) and get the settings and services through FastAPI
dependencies (:mod:`.deps`).  Run it with ``certsolve serve``
or ``uvicorn certsolve.api.app:create_app --factory`` (settings from ``CERTSOLVE_*``
variables).  See ``docs/api.md``.
"""

from __future__ import annotations

import logging
from contextlib import asynccontextmanager

from fastapi import FastAPI

from certsolve.jobs.kinds import job_request_type
from certsolve.jobs.pictures import Pictures
from certsolve.jobs.quick import QuickCalls
from certsolve.jobs.service import JobService
from certsolve.jobs.settings import ServiceSettings

from .errors import install_error_handlers
from .middleware import BodyLimitMiddleware
from .routers import examples, jobs, meta, pages, pictures, sync

__all__ = ["API_VERSION", "create_app"]

log = logging.getLogger("certsolve.api")

API_VERSION = "1"


def create_app(
    settings: ServiceSettings | None = None, service: JobService | None = None
) -> FastAPI:
    """The FastAPI application; the lifespan starts and stops the service's workers."""
    settings = settings or ServiceSettings.from_env()
    service = service or JobService(settings)

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
    app.state.settings = settings
    app.state.service = service
    app.state.quick = QuickCalls(settings)
    app.state.pictures = Pictures(service.store, settings.data_dir / "pictures")
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes)
    install_error_handlers(app)
    app.include_router(meta.router)
    app.include_router(jobs.router(job_request_type(settings.enable_test_kinds)))
    app.include_router(sync.router)
    app.include_router(pictures.router)
    app.include_router(examples.router)
    app.include_router(pages.router)
    return app
