"""The registry of job kinds: ``KINDS`` (name -> :class:`.base.Kind`) and the request
type, a union of the kinds' job models discriminated by ``kind``; and of the quick calls,
``QUICK_CALLS`` (name -> :class:`.base.QuickCall`)."""

from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import Field, TypeAdapter

from . import design, fk, ik, ik_sweep, isotropic_map, sleep, solve, trajectory, workspace
from .base import Kind, QuickCall, deferred

__all__ = ["KINDS", "QUICK_CALLS", "job_request_type", "public_kinds", "request_adapter"]

KINDS: dict[str, Kind] = {
    module.KIND.name: module.KIND
    for module in (solve, fk, ik, ik_sweep, isotropic_map, workspace, design, trajectory, sleep)
}
QUICK_CALLS: dict[str, QuickCall] = {
    module.QUICK.name: module.QUICK for module in (ik, isotropic_map, fk, sleep)
}  # "sleep" has no route: tests of the quick-call processes


def public_kinds(include_hidden: bool = False) -> list[str]:
    return [k.name for k in KINDS.values() if include_hidden or not k.hidden]


def job_request_type(include_hidden: bool = False, *, check: bool = True) -> Any:
    """The request type: a union of the kinds' models, discriminated by ``kind``.
    ``check=False``: the :func:`.base.deferred` models (checked later by
    :meth:`.base.Request.checked`)."""
    models = tuple(
        KINDS[name].model if check else deferred(KINDS[name].model)
        for name in public_kinds(include_hidden)
    )
    return Annotated[Union[models], Field(discriminator="kind")]  # noqa: UP007


def request_adapter(include_hidden: bool = False) -> TypeAdapter:
    """Validates a job request (dict or JSON) into the kind's model.  Building one costs a
    few milliseconds: a long-lived caller (the service, a worker) keeps its own."""
    return TypeAdapter(job_request_type(include_hidden))
