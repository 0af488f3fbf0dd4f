"""The web page of the service: ``/`` and its assets under ``/static/``.

One HTML page with a small script and a style sheet, shipped inside the package
(``certsolve/api/static``) and working offline: no CDN, no build step.  The script talks
to the same JSON API as any client (``/v1/jobs``, ``/v1/robots``, the pictures), sending
the access token the user typed, if any.  Not part of the OpenAPI schema.
"""

from __future__ import annotations

import re
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse

from ..errors import APIError

__all__ = ["STATIC", "router"]

STATIC = Path(__file__).resolve().parent.parent / "static"
_ASSET = re.compile(r"^[a-z0-9_-]+\.(css|js|svg|png)$")
_TYPES = {
    "css": "text/css; charset=utf-8",
    "js": "text/javascript; charset=utf-8",
    "svg": "image/svg+xml",
    "png": "image/png",
}

router = APIRouter(include_in_schema=False)


@router.get("/")
def index() -> FileResponse:
    return FileResponse(STATIC / "index.html", media_type="text/html; charset=utf-8")


@router.get("/static/{name}")
def asset(name: str) -> FileResponse:
    path = STATIC / name
    if not _ASSET.match(name) or not path.is_file():
        raise APIError(404, f"no asset {name}")
    return FileResponse(path, media_type=_TYPES[name.rsplit(".", 1)[1]])
