"""``/healthz`` and ``/v1/kinds``: what the service is and can do."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from certsolve.jobs.kinds import KINDS, KindUnavailable, public_kinds

from ..deps import Quick, Service, Settings
from ..errors import APIError
from ..schemas import errors

router = APIRouter(tags=["service"])


@router.get("/healthz", responses=errors(503))
def healthz(service: Service, quick: Quick) -> dict[str, Any]:
    """Liveness: the job store's check, workers alive, the queue depth and the quick-call
    processes (public: no token needed); 503 naming the problem when the store is damaged
    or cannot be read."""
    health = service.health()
    if health["status"] != "ok":
        problem = health["store"]["error"]
        raise APIError(503, f"the job store is failing: {problem}", loc=("store",))
    return {**health, "quick": quick.stats()}


@router.get("/v1/kinds", responses=errors(401, 429))
def list_kinds(settings: Settings) -> dict[str, Any]:
    """The job kinds, their parameters (JSON Schema) and whether this build has them."""
    out = []
    for name in public_kinds(settings.enable_test_kinds):
        k = KINDS[name]
        try:
            k.load()
            available = True
        except KindUnavailable:
            available = False
        out.append(
            {
                "kind": name,
                "summary": k.summary,
                "input": k.input,
                "available": available,
                "params": k.params.model_json_schema(),
            }
        )
    return {"kinds": out}
