"""Error responses: one shape for every error the API gives, never internals.

Every error answer is JSON ``{"error": message, "detail": [problem, ...]}`` where each
problem is ``{"loc": [...], "field": "dotted.path", "msg": "...", "type": "..."}`` --
with ``line`` and ``column`` when it points into Minibex text or a JSON body that does not
parse.  ``field`` names the request part at fault (``robot.wires.3.tau``, ``job_id``,
``Authorization``, ``body``) and is ``""`` when nothing in the request is (a full queue).

Validation errors (422) list each problem with its ``loc`` (as FastAPI does); the
discriminator tags pydantic puts in the path (``fk``, ``solve``) are removed, and
model-level messages that name their field (``params.u: expected 4 values``) are moved to
that field (:mod:`certsolve.jobs.errors`).  A body that cannot be read as JSON (not JSON,
not UTF-8, nested too deeply) is a 400 whose problem is at ``body``.
"""

from __future__ import annotations

import json
import logging
import sqlite3
from collections.abc import Mapping, Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from certsolve.jobs.errors import field_of, summary, validation_details

__all__ = [
    "APIError",
    "error_body",
    "error_response",
    "install_error_handlers",
    "problem",
    "summary",
    "validation_details",
]

log = logging.getLogger("certsolve.api")

# the problem type of an error answer that has no more specific one
_TYPES = {
    400: "body_invalid",
    401: "unauthorized",
    403: "forbidden",
    404: "not_found",
    405: "method_not_allowed",
    409: "conflict",
    413: "too_large",
    422: "value_error",
    429: "too_many_requests",
    500: "internal",
    501: "unavailable",
    503: "busy",
}


def problem(msg: str, loc: Sequence[Any] = (), type: str = "value_error", **extra: Any) -> dict:
    """One item of ``detail``: ``loc`` is the path into the request (``("path",
    "job_id")``, ``("body", "params", "u")``); ``field`` drops its first part (``body``
    when the whole body is at fault)."""
    loc = list(loc)
    return {
        "loc": loc,
        "field": field_of(loc),
        "msg": msg,
        "type": type,
        **extra,
    }


class APIError(Exception):
    """Raised by endpoints: ``{"error": message, "detail": detail}`` with ``status``.

    Without ``detail`` the one problem is ``message`` at ``loc`` (nothing by default)."""

    def __init__(
        self,
        status: int,
        message: str,
        detail: list | None = None,
        *,
        loc: Sequence[Any] = (),
        type: str | None = None,
        headers: Mapping[str, str] | None = None,
    ):
        super().__init__(message)
        self.status = status
        self.message = message
        self.detail = detail if detail else [problem(message, loc, type or _TYPES.get(status, ""))]
        self.headers = dict(headers) if headers else None


def error_body(status: int, message: str, detail: list | None = None) -> dict[str, Any]:
    """The JSON body of an error answer (also written by the ASGI middlewares)."""
    return {"error": message, "detail": detail or [problem(message, (), _TYPES.get(status, ""))]}


def error_response(
    status: int,
    message: str,
    detail: list | None = None,
    headers: Mapping[str, str] | None = None,
) -> JSONResponse:
    return JSONResponse(error_body(status, message, detail), status_code=status, headers=headers)


def validation_response(details: list[dict]) -> JSONResponse:
    return error_response(422, summary(details) or "invalid request", details)


def _line_column(text: Any, pos: Any) -> dict[str, int]:
    """1-based line and column of character ``pos`` of ``text`` (when both are known)."""
    if not isinstance(text, (str, bytes)) or not isinstance(pos, int):
        return {}
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="replace")
    line = text.count("\n", 0, pos) + 1
    return {"line": line, "column": pos - (text.rfind("\n", 0, pos) + 1) + 1}


def _unparseable(exc: RequestValidationError) -> JSONResponse | None:
    """A body that is not JSON (FastAPI reports it as a validation error): 400."""
    errors = list(exc.errors())
    if not errors or errors[0].get("type") != "json_invalid":
        return None
    e = errors[0]
    loc = e.get("loc", ())
    pos = loc[1] if len(loc) > 1 else None
    where = _line_column(getattr(exc, "body", None), pos)
    reason = (e.get("ctx") or {}).get("error", e.get("msg", "invalid JSON"))
    at = f" at line {where['line']}, column {where['column']}" if where else ""
    msg = f"the body is not valid JSON{at}: {reason}"
    return error_response(400, f"body: {msg}", [problem(msg, ("body",), "json_invalid", **where)])


def _parse_failure(exc: BaseException | None) -> str:
    """Why FastAPI could not read a body (the cause of its 400)."""
    if isinstance(exc, UnicodeDecodeError):
        return f"the body is not UTF-8 text (byte {exc.start}: {exc.reason})"
    if isinstance(exc, RecursionError):
        return "the body is nested too deeply to be read as JSON"
    if isinstance(exc, ValueError):
        return f"the body cannot be read as JSON ({exc})"
    return "the body cannot be read as JSON"


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, exc: RequestValidationError):
        return _unparseable(exc) or validation_response(validation_details(list(exc.errors())))

    @app.exception_handler(ValidationError)
    async def _pydantic(request: Request, exc: ValidationError):
        return validation_response(validation_details(exc.errors(), ("body",)))

    @app.exception_handler(APIError)
    async def _api(request: Request, exc: APIError):
        return error_response(exc.status, exc.message, exc.detail, exc.headers)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        headers = getattr(exc, "headers", None)
        if exc.status_code == 400:  # FastAPI could not read the body
            msg = _parse_failure(exc.__cause__)
            return error_response(
                400, f"body: {msg}", [problem(msg, ("body",), "body_invalid")], headers
            )
        if exc.status_code == 404 and exc.detail == "Not Found":
            msg = f"no route {request.method} {request.url.path}"
            return error_response(404, msg, [problem(msg, ("path",), "not_found")], headers)
        if exc.status_code == 405:
            msg = f"method {request.method} is not allowed on {request.url.path}"
            return error_response(405, msg, None, headers)
        msg = exc.detail if isinstance(exc.detail, str) else json.dumps(exc.detail, default=str)
        return error_response(exc.status_code, msg, None, headers)

    @app.exception_handler(sqlite3.OperationalError)
    async def _busy(request: Request, exc: sqlite3.OperationalError):
        log.warning("job store unavailable on %s %s: %s", request.method, request.url.path, exc)
        return error_response(503, "the job store is busy; retry", headers={"Retry-After": "1"})

    @app.exception_handler(Exception)
    async def _internal(request: Request, exc: Exception):
        log.error("unhandled error on %s %s", request.method, request.url.path, exc_info=exc)
        return error_response(500, "internal server error")
