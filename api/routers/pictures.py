"""Pictures of finished jobs, as PNG: ``/v1/jobs/{id}/poses/{k}.png`` (certified pose k
of an ``fk`` job, 0-based), ``/v1/jobs/{id}/poses.png`` (all of them overlaid),
``/v1/jobs/{id}/map.png`` (``isotropic-map``), ``/v1/jobs/{id}/paving.png``
(``workspace``) and ``/v1/jobs/{id}/path.png`` (``trajectory``).

Drawing and caching are :class:`certsolve.jobs.pictures.Pictures`' (``app.state.pictures``);
the routes are plain functions, so FastAPI runs them in its thread pool and the event loop
keeps answering while matplotlib draws.  404: no such job, or no such picture for it; 409:
the job has no result yet (or never will: failed); 501: matplotlib is missing (the
``plot`` extra).  A job belongs to the client that submitted it: another client's job is a
404, as on ``GET /v1/jobs/{id}``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Path, Request
from fastapi.responses import FileResponse

from certsolve.extras import MissingExtra
from certsolve.jobs.pictures import NoPicture, Pictures
from certsolve.jobs.service import JobService, NoResult, NoSuchJob

from ..deps import Caller, Service
from ..errors import APIError
from ..schemas import errors
from .jobs import _ID as JobId

__all__ = ["get_pictures", "router"]


def get_pictures(request: Request) -> Pictures:
    return request.app.state.pictures


PicturesDep = Annotated[Pictures, Depends(get_pictures)]

_RESPONSES: dict[int | str, dict] = {
    200: {"content": {"image/png": {}}, "description": "the picture (PNG)"},
    **errors(
        401,
        404,
        409,
        422,
        429,
        501,
        e404="no such job (or another client's), or no such picture of it",
        e409="the job has no result (yet)",
        e501="pictures need the 'plot' extra (matplotlib)",
    ),
}

_CACHE = {"Cache-Control": "private, max-age=86400"}

router = APIRouter(tags=["pictures"])


def _png(
    pictures: Pictures,
    service: JobService,
    caller,
    job_id: str,
    name: str,
    index: int | None = None,
) -> FileResponse:
    try:
        service.job(job_id, caller, result=False)  # the caller's own job, or 404
        path = pictures.png(job_id, name, index)
    except (NoSuchJob, NoPicture) as exc:
        raise APIError(404, str(exc)) from None
    except NoResult as exc:
        raise APIError(409, str(exc)) from None
    except MissingExtra as exc:
        raise APIError(501, str(exc)) from None
    # a finished job's pictures never change
    return FileResponse(path, media_type="image/png", headers=_CACHE)


@router.get(
    "/v1/jobs/{job_id}/poses/{index}.png", response_class=FileResponse, responses=_RESPONSES
)
def pose_picture(
    job_id: JobId,
    index: Annotated[int, Path(ge=0, le=10**9)],
    pictures: PicturesDep,
    service: Service,
    caller: Caller,
):
    """Certified pose ``index`` (0-based, as in ``result.solutions``) of an ``fk`` job: the
    robot with its wires coloured by tension, and a close-up of the platform."""
    return _png(pictures, service, caller, job_id, "pose", index)


@router.get("/v1/jobs/{job_id}/poses.png", response_class=FileResponse, responses=_RESPONSES)
def poses_picture(job_id: JobId, pictures: PicturesDep, service: Service, caller: Caller):
    """Every certified pose of an ``fk`` job overlaid (the title says when the search left
    boxes undecided or pending)."""
    return _png(pictures, service, caller, job_id, "poses")


@router.get("/v1/jobs/{job_id}/map.png", response_class=FileResponse, responses=_RESPONSES)
def map_picture(job_id: JobId, pictures: PicturesDep, service: Service, caller: Caller):
    """The heat map of an ``isotropic-map`` job (white: outside the wrench-feasible
    workspace)."""
    return _png(pictures, service, caller, job_id, "map")


@router.get("/v1/jobs/{job_id}/paving.png", response_class=FileResponse, responses=_RESPONSES)
def paving_picture(job_id: JobId, pictures: PicturesDep, service: Service, caller: Caller):
    """The certified paving of a ``workspace`` job (dof 6: the slice at mid-height)."""
    return _png(pictures, service, caller, job_id, "paving")


@router.get("/v1/jobs/{job_id}/path.png", response_class=FileResponse, responses=_RESPONSES)
def path_picture(job_id: JobId, pictures: PicturesDep, service: Service, caller: Caller):
    """The pose components and tensions along a ``trajectory`` job's path, the lost step
    marked in red."""
    return _png(pictures, service, caller, job_id, "path")
