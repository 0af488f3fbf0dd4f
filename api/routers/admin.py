"""Administration: ``POST /v1/admin/purge`` (admin tokens only; anyone on a service
without tokens, which listens on loopback)."""

from __future__ import annotations

from fastapi import APIRouter

from certsolve.jobs.service import NotAllowed

from ..deps import Caller, Service
from ..errors import APIError
from ..schemas import PurgeRequest, PurgeResult, errors

router = APIRouter(tags=["admin"])


@router.post(
    "/v1/admin/purge", response_model=PurgeResult, responses=errors(400, 401, 403, 413, 422, 429)
)
def purge(req: PurgeRequest, service: Service, caller: Caller) -> PurgeResult:
    """Delete every finished job (done, failed, cancelled) that finished more than
    ``older_than_days`` ago, then truncate the store's write-ahead log."""
    try:
        return PurgeResult(**service.purge(req.older_than_days, caller))
    except NotAllowed as exc:
        raise APIError(403, str(exc), loc=("header", "Authorization"), type="forbidden") from None
