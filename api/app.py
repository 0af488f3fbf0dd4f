"""The HTTP API of the solver service (FastAPI).

``create_app(settings)`` builds the application around a :class:`certsolve.jobs.JobService`:
jobs are queued in the service's SQLite store and run by its worker processes, quick calls
run in the processes of :class:`certsolve.jobs.quick.QuickCalls`; the HTTP process only
validates, stores and reads.  Routes live in one router per resource
(:mod:`.routers.jobs`, :mod:`.routers.sync`, :mod:`.routers.meta`, :mod:`.routers.admin`, the
pictures of finished jobs :mod:`.routers.pictures`, the bundled robots :mod:`.routers.examples`,
the web page at ``/`` :mod:`.routers.pages`, the API reference at ``/docs`` and ``/redoc``
:mod:`.routers.docs`, offline)
and get the settings, services and calling client through FastAPI dependencies
(:mod:`.deps`).  With a token table (``settings.access``) every ``/v1/`` request needs a
bearer token (:class:`.middleware.AccessMiddleware`), and the OpenAPI schema says so.
Run it with ``certsolve serve`` or ``uvicorn certsolve.api.app:create_app --factory``
(settings from ``CERTSOLVE_*`` variables).  See ``docs/api.md``.
"""

from __future__ import annotations

import logging
from contextlib import asynccontextmanager
from typing import Any

from fastapi import FastAPI

from certsolve.jobs.kinds import KINDS, job_request_type, public_kinds
from certsolve.jobs.pictures import Pictures
from certsolve.jobs.quick import QuickCalls
from certsolve.jobs.service import JobService
from certsolve.jobs.settings import ServiceSettings

from .errors import install_error_handlers
from .middleware import (
    AccessMiddleware,
    BodyLimitMiddleware,
    HostMiddleware,
    SecurityHeadersMiddleware,
)
from .routers import admin, docs, examples, jobs, meta, pages, pictures, sync
from .server import ACCESS_LOGGER, QueryRedactor

__all__ = ["API_VERSION", "create_app"]

log = logging.getLogger("certsolve.api")

API_VERSION = "1"


def create_app(
    settings: ServiceSettings | None = None, service: JobService | None = None
) -> FastAPI:
    """The FastAPI application; the lifespan starts and stops the service's workers and
    its quick-call processes."""
    settings = settings or ServiceSettings.from_env()
    service = service or JobService(settings)
    quick = QuickCalls(settings)

    redactor = QueryRedactor()

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        logging.getLogger(ACCESS_LOGGER).addFilter(redactor)
        service.start()
        try:
            yield
        finally:
            quick.close()
            service.close()
            logging.getLogger(ACCESS_LOGGER).removeFilter(redactor)

    app = FastAPI(
        title="certsolve",
        version=API_VERSION,
        summary="Certified interval solving for wire-driven parallel robots, as jobs.",
        description=(
            "Submit solver jobs (`POST /v1/jobs`), poll them (`GET /v1/jobs/{id}`), cancel "
            "them (`DELETE /v1/jobs/{id}`). Jobs run in worker processes and survive "
            'restarts. Every error is JSON `{"error": ..., "detail": [{"loc", "field", '
            '"msg", "type"}, ...]}`.'
        ),
        lifespan=lifespan,
        docs_url=None,  # served offline by .routers.docs
        redoc_url=None,
    )
    app.state.settings = settings
    app.state.service = service
    app.state.quick = quick
    app.state.pictures = Pictures(service.store, settings.data_dir / "pictures")
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes)
    app.add_middleware(
        AccessMiddleware,
        access=settings.access,
        default_rate=settings.quota_requests_per_minute,
        failure_delay=settings.auth_failure_delay,
    )
    app.add_middleware(
        HostMiddleware, allowed=settings.allowed_hosts, active=settings.access is None
    )
    # outside even Starlette's ServerErrorMiddleware, so that a 500 has them too
    build_stack = app.build_middleware_stack
    app.build_middleware_stack = lambda: SecurityHeadersMiddleware(build_stack())  # type: ignore[method-assign]
    install_error_handlers(app)
    app.include_router(meta.router)
    app.include_router(
        jobs.router(
            job_request_type(settings.enable_test_kinds, check=False),
            public_kinds(settings.enable_test_kinds),
        )
    )
    app.include_router(sync.router)
    app.include_router(admin.router)
    app.include_router(pictures.router)
    app.include_router(examples.router)
    app.include_router(pages.router)
    app.include_router(docs.router)
    _finish_openapi(app, settings)
    return app


def _finish_openapi(app: FastAPI, settings: ServiceSettings) -> None:
    """What the OpenAPI schema says of this service: the ceilings of its job limits
    (``timeout`` at most ``max_timeout`` ...), that the ``jobs`` of a batch are job
    requests as ``POST /v1/jobs`` takes them (the service validates each item itself, to
    name it by its index), that the sweep form of a batch (``kind`` + robot or system +
    a ``params`` list) is one variant per variant of each kind's job schema
    (:func:`_sweep_variants`), and, with tokens, that every ``/v1/`` operation needs a
    bearer token."""
    build = app.openapi
    ceilings = {
        "timeout": {"maximum": settings.max_timeout},
        "max_boxes": {"maximum": settings.max_max_boxes},
        "memory_mb": {"minimum": settings.min_memory_mb, "maximum": settings.max_memory_mb},
    }

    def state_ceilings(node: Any) -> None:
        if isinstance(node, list):
            for item in node:
                state_ceilings(item)
            return
        if not isinstance(node, dict):
            return
        for name, prop in (node.get("properties") or {}).items():
            for branch in prop.get("anyOf", [prop]) if isinstance(prop, dict) else ():
                if name in ceilings and branch.get("type") in ("number", "integer"):
                    branch.update(ceilings[name])
        for value in node.values():
            state_ceilings(value)

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            schema = build()
            components = schema.get("components", {}).get("schemas", {})
            state_ceilings(components)
            job = schema["paths"]["/v1/jobs"]["post"]["requestBody"]["content"]
            jobs = components["BatchRequest"]["properties"]["jobs"]
            for branch in jobs.get("anyOf", [jobs]):
                if branch.get("type") == "array":
                    branch["items"] = job["application/json"]["schema"]
            kinds = public_kinds(settings.enable_test_kinds)
            batch = components["BatchRequest"]
            kind = batch["properties"]["kind"]
            for branch in kind.get("anyOf", [kind]):
                if branch.get("type") == "string":
                    branch.pop("maxLength", None)
                    branch["enum"] = kinds
            for form in batch["oneOf"]:
                if "kind" in form.get("required", ()):
                    form.pop("properties", None)
                    form["oneOf"] = _sweep_variants(components, kinds)
            if settings.access is not None:
                schemes = schema.setdefault("components", {}).setdefault("securitySchemes", {})
                schemes["bearer"] = {
                    "type": "http",
                    "scheme": "bearer",
                    "description": "a token of the service's token table (serve --tokens)",
                }
                for path, ops in schema.get("paths", {}).items():
                    if path.startswith("/v1/"):
                        for op in ops.values():
                            op["security"] = [{"bearer": []}]
            app.openapi_schema = schema
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


def _sweep_variants(components: dict[str, Any], kinds: list[str]) -> list[dict[str, Any]]:
    """The sweep form of a batch as JSON Schema: for each variant of each kind's job schema
    (one per robot dof), ``kind`` that kind, its robot (or system) as that variant takes
    it, and ``params`` a list of that variant's params -- the shapes a job of the kind has,
    one params object per job."""
    variants = []
    for name in kinds:
        job = components[KINDS[name].model.__name__]
        for v in job.get("oneOf", [job]):
            props = v["properties"]
            inputs = [i for i in ("robot", "system") if i in props]
            variants.append(
                {
                    "title": f"sweep of {v.get('title', name)}",
                    "properties": {
                        "kind": {"const": name},
                        **{i: props[i] for i in inputs},
                        "params": {"type": "array", "minItems": 1, "items": props["params"]},
                    },
                    "required": ["kind", *inputs, "params"],
                    "not": {
                        "anyOf": [{"required": [i]} for i in ("robot", "system") if i not in inputs]
                    },
                }
            )
    return variants
