"""The quick synchronous calls: ``POST /v1/ik``, ``/v1/isotropic``, ``/v1/fk/track``."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from certsolve.jobs.kinds import IkCall, IsotropicCall, KindUnavailable, TrackCall
from certsolve.jobs.quick import Busy

from ..deps import Quick
from ..errors import APIError
from ..schemas import SYNC_ERRORS

router = APIRouter(tags=["quick"], responses=SYNC_ERRORS)


def _answer(call: Callable[[Any], Any], req: Any) -> JSONResponse:
    """HTTP around one quick call: its result, or 429 / 501 / 422."""
    try:
        return JSONResponse(call(req))
    except Busy as exc:
        raise APIError(429, str(exc)) from None
    except KindUnavailable as exc:
        raise APIError(501, str(exc).replace("kind ", "", 1)) from None
    except (ValueError, ArithmeticError) as exc:  # the input's fault
        raise APIError(422, str(exc) or type(exc).__name__) from None


@router.post("/v1/ik")
def ik(req: IkCall, quick: Quick) -> Any:
    """Inverse kinematics at one pose (synchronous)."""
    return _answer(quick.ik, req)


@router.post("/v1/isotropic")
def isotropic(req: IsotropicCall, quick: Quick) -> Any:
    """Isotropic force at one pose (synchronous)."""
    return _answer(quick.isotropic, req)


@router.post("/v1/fk/track")
def fk_track(req: TrackCall, quick: Quick) -> Any:
    """Forward kinematics near a known pose (synchronous tracking step)."""
    return _answer(quick.track, req)
