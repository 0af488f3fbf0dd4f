"""The API reference pages, ``/docs`` (Swagger UI) and ``/redoc`` (ReDoc), served offline.

FastAPI's own pages load Swagger UI and ReDoc from a CDN, so they are blank without a
network.  Here both pages and every file they load come from this service: the two
viewers' files are those the ``fastapi-offline`` package ships (part of the ``service``
extra; its ``static`` folder, served under ``/static/docs/``), the pages are the two small
HTML files below, and Swagger UI is started by ``static/swagger-init.js`` -- no inline
script, so the pages keep the service's Content-Security-Policy except for what the viewers
need: inline styles (both set them from script) and a ``blob:`` worker (ReDoc's search).
Every URL is relative, so the pages work behind a path prefix too.  Not part of the schema.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse, HTMLResponse

from ..errors import APIError

__all__ = ["DOCS_CSP", "VIEWERS", "router"]

VIEWERS = Path(str(files("fastapi_offline") / "static"))
_FILES = {
    "swagger-ui-bundle.js": "text/javascript; charset=utf-8",
    "swagger-ui.css": "text/css; charset=utf-8",
    "redoc.standalone.js": "text/javascript; charset=utf-8",
    "favicon.png": "image/png",
}
DOCS_CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data:; font-src 'self' data:; worker-src 'self' blob:; "
    "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'"
)

_SWAGGER = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>certsolve API - Swagger UI</title>
<link rel="icon" href="static/docs/favicon.png">
<link rel="stylesheet" href="static/docs/swagger-ui.css">
</head>
<body>
<div id="swagger-ui"></div>
<script src="static/docs/swagger-ui-bundle.js"></script>
<script src="static/swagger-init.js"></script>
</body>
</html>
"""

_REDOC = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>certsolve API - ReDoc</title>
<link rel="icon" href="static/docs/favicon.png">
</head>
<body>
<redoc spec-url="openapi.json"></redoc>
<script src="static/docs/redoc.standalone.js"></script>
</body>
</html>
"""

router = APIRouter(include_in_schema=False)


def _page(html: str) -> HTMLResponse:
    return HTMLResponse(html, headers={"Content-Security-Policy": DOCS_CSP})


@router.get("/docs")
def swagger_ui() -> HTMLResponse:
    return _page(_SWAGGER)


@router.get("/redoc")
def redoc() -> HTMLResponse:
    return _page(_REDOC)


@router.get("/static/docs/{name}")
def viewer_file(name: str) -> FileResponse:
    if name not in _FILES:
        raise APIError(404, f"no asset docs/{name}")
    return FileResponse(VIEWERS / name, media_type=_FILES[name])
