"""``/v1/robots``: the robots that come with certsolve, as robot files.

They are the robots of the two papers (MARIONET and its T-platform, the almost-planar and
planar 4-wire robots, Krut's planar robots with 3 to 6 motors), built by
:mod:`certsolve.robot.presets` -- the same code that writes ``examples/robots/*.json``, so
an installed package serves them without shipping copies of the files.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Request

from ..errors import APIError
from ..schemas import errors

__all__ = ["router"]

router = APIRouter(tags=["robots"])

_NAME = Annotated[str, Path(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")]


def _bundled() -> dict[str, dict[str, Any]]:
    from certsolve.robot.presets import all_presets

    return {file.removesuffix(".json"): spec for file, spec in all_presets().items()}


@router.get("/v1/robots", responses=errors(401, 429))
def list_robots(request: Request) -> dict[str, Any]:
    """The bundled robots: name, dof, number of wires and the URL of the robot file."""
    items = [
        {
            "name": name,
            "dof": spec["dof"],
            "wires": len(spec["wires"]),
            "url": str(request.url_for("get_robot", name=name)),
        }
        for name, spec in _bundled().items()
    ]
    return {"robots": items}


@router.get("/v1/robots/{name}", responses=errors(401, 404, 422, 429))
def get_robot(name: _NAME) -> dict[str, Any]:
    """One bundled robot file (the JSON of ``examples/robots/<name>.json``)."""
    robots = _bundled()
    spec = robots.get(name.removesuffix(".json"))
    if spec is None:
        raise APIError(404, f"no bundled robot {name}; there are: {', '.join(robots)}")
    return spec
