"""Error responses: always JSON ``{"error": message, "detail": [...]?}``, never internals.

Validation errors (422) list each problem with its ``loc`` (as FastAPI does), a dotted
``field`` path into the request body (``robot.wires.3.tau``) and a message; the
discriminator tags pydantic puts in the path (``fk``, ``solve``) are removed, and
model-level messages that name their field (``params.u: expected 4 values``) are moved to
that field.
"""

from __future__ import annotations

import json
import logging
import sqlite3
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from certsolve.jobs.errors import summary, validation_details

__all__ = [
    "APIError",
    "error_response",
    "install_error_handlers",
    "summary",
    "validation_details",
]

log = logging.getLogger("certsolve.api")


class APIError(Exception):
    """Raised by endpoints: becomes ``{"error": message}`` with ``status``."""

    def __init__(self, status: int, message: str, detail: list | None = None):
        super().__init__(message)
        self.status = status
        self.message = message
        self.detail = detail


def error_response(
    status: int, message: str, detail: list | None = None, headers: dict | None = None
) -> JSONResponse:
    body: dict[str, Any] = {"error": message}
    if detail is not None:
        body["detail"] = detail
    return JSONResponse(body, status_code=status, headers=headers)


def validation_response(details: list[dict]) -> JSONResponse:
    return error_response(422, summary(details) or "invalid request", details)


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, exc: RequestValidationError):
        return validation_response(validation_details(list(exc.errors())))

    @app.exception_handler(ValidationError)
    async def _pydantic(request: Request, exc: ValidationError):
        return validation_response(validation_details(exc.errors(), ("body",)))

    @app.exception_handler(APIError)
    async def _api(request: Request, exc: APIError):
        return error_response(exc.status, exc.message, exc.detail)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        msg = exc.detail if isinstance(exc.detail, str) else json.dumps(exc.detail, default=str)
        return error_response(exc.status_code, msg, headers=getattr(exc, "headers", None))

    @app.exception_handler(sqlite3.OperationalError)
    async def _busy(request: Request, exc: sqlite3.OperationalError):
        log.warning("job store unavailable on %s %s: %s", request.method, request.url.path, exc)
        return error_response(503, "the job store is busy; retry", headers={"Retry-After": "1"})

    @app.exception_handler(Exception)
    async def _internal(request: Request, exc: Exception):
        log.error("unhandled error on %s %s", request.method, request.url.path, exc_info=exc)
        return error_response(500, "internal server error")
