"""The HTTP API of the certsolve solver service: ``create_app(settings)`` (FastAPI)."""

from .app import create_app

__all__ = ["create_app"]
