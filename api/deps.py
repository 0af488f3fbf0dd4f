"""What route functions get injected (FastAPI ``Depends``): the application's settings,
its :class:`~certsolve.jobs.JobService` and its :class:`~certsolve.jobs.quick.QuickCalls`,
all created once by :func:`api.app.create_app` and kept in ``app.state``."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from certsolve.jobs.quick import QuickCalls
from certsolve.jobs.service import JobService
from certsolve.jobs.settings import ServiceSettings

__all__ = ["Quick", "Service", "Settings", "get_quick", "get_service", "get_settings"]


def get_settings(request: Request) -> ServiceSettings:
    return request.app.state.settings


def get_service(request: Request) -> JobService:
    return request.app.state.service


def get_quick(request: Request) -> QuickCalls:
    return request.app.state.quick


Settings = Annotated[ServiceSettings, Depends(get_settings)]
Service = Annotated[JobService, Depends(get_service)]
Quick = Annotated[QuickCalls, Depends(get_quick)]
