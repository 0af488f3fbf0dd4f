"""The quick synchronous calls: ``POST /v1/ik``, ``/v1/isotropic``, ``/v1/fk/track``.

Each runs in a quick-call process of the service (:mod:`certsolve.jobs.quick`), never in
the HTTP process; while it runs, the route checks that the client is still there, and a
client that went away has its computation stopped.  The body is checked against its
robot off the event loop (:func:`..deps.checked_body`).
"""

from __future__ import annotations

from typing import Annotated, Any

import anyio.from_thread
from fastapi import APIRouter, Depends, Request
from fastapi.responses import Response

from certsolve.inputs import InputError
from certsolve.jobs.kinds import IkCall, IsotropicCall, KindUnavailable, TrackCall
from certsolve.jobs.kinds.base import deferred
from certsolve.jobs.quick import Busy, Gone, QuickFailure, TooCostly

from ..deps import Quick, checked_body
from ..errors import APIError, problem
from ..schemas import errors

router = APIRouter(
    tags=["quick"],
    responses=errors(
        400,
        401,
        413,
        422,
        429,
        501,
        e422="invalid request, or a call too costly for a quick call (submit a job)",
    ),
)


def _answer(quick: Any, name: str, req: Any, request: Request) -> Response:
    """HTTP around one quick call: its result, or 429 / 501 / 422."""

    def gone() -> bool:
        return anyio.from_thread.run(request.is_disconnected)

    try:
        text = quick.run(name, req, gone=gone)
    except Busy as exc:
        raise APIError(
            429, str(exc), type="busy", headers={"Retry-After": str(exc.retry_after)}
        ) from None
    except KindUnavailable as exc:
        raise APIError(501, str(exc).replace("kind ", "", 1)) from None
    except TooCostly as exc:
        loc = ("body", *exc.field.split(".")) if exc.field else ("body",)
        raise APIError(422, str(exc), loc=loc, type="too_costly") from None
    except Gone:
        return Response(status_code=499)  # nobody reads it
    except QuickFailure as exc:
        raise RuntimeError(str(exc)) from None  # a 500, logged
    except InputError as exc:  # the input's fault
        raise _input_error(exc, req) from None
    except (ValueError, ArithmeticError) as exc:  # pragma: no cover - quick.run sends InputError
        raise _input_error(InputError("", str(exc) or type(exc).__name__), req) from None
    return Response(text, media_type="application/json")


def _input_error(exc: InputError, req: Any) -> APIError:
    """The library refused the input: a 422 at the field it named (``exc.field``, a path
    among the call's arguments: ``pose`` is ``params.pose``, ``robot.wires.2.k`` is
    itself), else at the body."""
    path = [int(p) if p.isdigit() else p for p in exc.field.split(".")] if exc.field else []
    if not path:
        loc: tuple = ("body",)
    elif path[0] == "robot" or path[0] not in type(req.params).model_fields:
        loc = ("body", *path)
    else:
        loc = ("body", "params", *path)
    return APIError(422, str(exc), [problem(exc.message if path else str(exc), loc)])


IkBody = Annotated[IkCall, Depends(checked_body(deferred(IkCall)))]
IsotropicBody = Annotated[IsotropicCall, Depends(checked_body(deferred(IsotropicCall)))]
TrackBody = Annotated[TrackCall, Depends(checked_body(deferred(TrackCall)))]


@router.post("/v1/ik")
def ik(req: IkBody, quick: Quick, request: Request) -> Any:
    """Inverse kinematics at one pose (synchronous)."""
    return _answer(quick, "ik", req, request)


@router.post("/v1/isotropic")
def isotropic(req: IsotropicBody, quick: Quick, request: Request) -> Any:
    """Isotropic force at one pose (synchronous)."""
    return _answer(quick, "isotropic", req, request)


@router.post("/v1/fk/track")
def fk_track(req: TrackBody, quick: Quick, request: Request) -> Any:
    """Forward kinematics near a known pose (synchronous tracking step)."""
    return _answer(quick, "fk/track", req, request)
