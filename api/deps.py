"""What route functions get injected (FastAPI ``Depends``): the application's settings,
its :class:`~certsolve.jobs.JobService`, its :class:`~certsolve.jobs.quick.QuickCalls`
(all created once by :func:`api.app.create_app` and kept in ``app.state``) and the
calling client (``Caller``: the :class:`~certsolve.jobs.access.Client` of the request's
token, put there by :class:`~.middleware.AccessMiddleware`; None when the service has no
tokens).  A route that reads or changes jobs passes ``Caller`` to the service, which
keeps each client to its own jobs.

A request body is validated once, in two halves: FastAPI parses it on the event loop
into a :func:`~certsolve.jobs.kinds.base.deferred` model (types, ranges, lengths: cheap),
and the sync dependency :func:`checked_body` makes runs the checks against the robot (an FK
formulation built, a design's corner robots: milliseconds) in FastAPI's threadpool,
never on the event loop."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Annotated, Any

from fastapi import Body, Depends, Request

from certsolve.jobs.access import Client
from certsolve.jobs.quick import QuickCalls
from certsolve.jobs.service import JobService
from certsolve.jobs.settings import ServiceSettings

__all__ = [
    "Caller",
    "Quick",
    "Service",
    "Settings",
    "checked_body",
    "get_caller",
    "get_quick",
    "get_service",
    "get_settings",
]


def get_settings(request: Request) -> ServiceSettings:
    return request.app.state.settings


def get_service(request: Request) -> JobService:
    return request.app.state.service


def get_quick(request: Request) -> QuickCalls:
    return request.app.state.quick


def get_caller(request: Request) -> Client | None:
    return request.scope.get("state", {}).get("client")


def checked_body(model: Any, name: str = "req") -> Callable[..., Any]:
    """The sync dependency (FastAPI runs it in its threadpool, off the event loop) that
    takes the request body of type ``model`` (a deferred request model, or a union of
    them) and returns it checked against its robot; a refusal is the 422 the body's own
    validation gives (pydantic's ``ValidationError``, at ``body``).  ``name``: the body
    parameter's name (the title OpenAPI gives a union).  A route takes
    ``Annotated[Model, Depends(checked_body(deferred(Model)))]``."""

    def check(**body: Any) -> Any:
        return body[name].checked()

    body = inspect.Parameter(
        name, inspect.Parameter.KEYWORD_ONLY, annotation=Annotated[model, Body()]
    )
    check.__signature__ = inspect.Signature([body])  # type: ignore[attr-defined]
    return check


Settings = Annotated[ServiceSettings, Depends(get_settings)]
Service = Annotated[JobService, Depends(get_service)]
Quick = Annotated[QuickCalls, Depends(get_quick)]
Caller = Annotated[Client | None, Depends(get_caller)]
