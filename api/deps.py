"""What route functions get injected (FastAPI ``Depends``): the application's settings,
its :class:`~certsolve.jobs.JobService`, its :class:`~certsolve.jobs.quick.QuickCalls`
(all created once by :func:`api.app.create_app` and kept in ``app.state``) and the
calling client (``Caller``: the :class:`~certsolve.jobs.access.Client` of the request's
token, put there by :class:`~.middleware.AccessMiddleware`; None when the service has no
tokens).  A route that reads or changes jobs passes ``Caller`` to the service, which
keeps each client to its own jobs."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from certsolve.jobs.access import Client
from certsolve.jobs.quick import QuickCalls
from certsolve.jobs.service import JobService
from certsolve.jobs.settings import ServiceSettings

__all__ = [
    "Caller",
    "Quick",
    "Service",
    "Settings",
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


Settings = Annotated[ServiceSettings, Depends(get_settings)]
Service = Annotated[JobService, Depends(get_service)]
Quick = Annotated[QuickCalls, Depends(get_quick)]
Caller = Annotated[Client | None, Depends(get_caller)]
