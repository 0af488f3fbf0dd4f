"""The HTTP API of the certsolve solver service: ``create_app(settings)`` (FastAPI).

Installed as ``certsolve.api`` (the source folder is ``api/``); it needs the ``service``
extra (``pip install 'certsolve[service]'``).
"""

from certsolve.extras import require

require("service", "certsolve.api")

from .app import create_app  # noqa: E402

__all__ = ["create_app"]
