"""Package namespaces that import their modules on first use (PEP 562).

A package whose ``__init__`` re-exports names from its modules would import them all on
``import package.module``; with :func:`lazy_exports` the names are looked up when first
used, so ``certsolve fk`` does not pay for the IK modules (scipy) nor the job service for
its HTTP layer.  Static tools see the names through ``if TYPE_CHECKING:`` imports.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, where: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package``: name -> relative module (``".fk"``)."""

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module, package), name)

    def __dir__() -> list[str]:
        return sorted(where)

    return __getattr__, __dir__
