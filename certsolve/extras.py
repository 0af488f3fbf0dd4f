"""Optional parts of certsolve and the packages they need (``pip install 'certsolve[X]'``).

The core (solver, robots, kinematics, force indexes, the command line, the Python client)
needs numpy, scipy, mpmath and pydantic only.  The HTTP service and the pictures are
extras; using one without its packages gives :class:`MissingExtra`, a one-line message
naming the extra, instead of a ``ModuleNotFoundError`` from deep inside.
"""

from __future__ import annotations

import importlib

__all__ = ["EXTRAS", "MissingExtra", "require"]

EXTRAS: dict[str, tuple[str, ...]] = {
    "service": ("fastapi", "uvicorn", "fastapi_offline"),  # certsolve serve, certsolve.api
    "plot": ("matplotlib",),  # --plot
}


class MissingExtra(ImportError):
    """A feature was used without the extra that provides its packages."""


def require(extra: str, what: str) -> None:
    """Import the packages of ``extra``; :class:`MissingExtra` naming it if one is missing."""
    for module in EXTRAS[extra]:
        try:
            importlib.import_module(module)
        except ImportError:
            raise MissingExtra(
                f"{what} needs the '{extra}' extra: pip install 'certsolve[{extra}]'"
            ) from None
