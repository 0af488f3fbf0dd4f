"""What is imported on first use: package names (PEP 562) and the validation models.

A package whose ``__init__`` re-exports names from its modules would import them all on
``import package.module``; with :func:`lazy_exports` the names are looked up when first
used, so ``certsolve fk`` does not pay for the IK modules (scipy) nor the job service for
its HTTP layer.  Static tools see the names through ``if TYPE_CHECKING:`` imports.

Options are validated by their pydantic model, the one validation of every front end
(:mod:`certsolve.inputs`); importing pydantic and building a first model costs ~0.07 s of
CPU, a third of ``certsolve solve``'s start-up.  :func:`surely_valid` reads the model's
JSON Schema, kept as data beside its user and checked against the model by a test, and
says when every value is certainly one the model accepts: then the model is not needed.
Otherwise the model validates, and its message is the one a user reads.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports", "surely_valid"]


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


#: the keywords :func:`surely_valid` reads; a property with any other one is not judged
_JUDGED = {"type", "anyOf", "enum", "minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"}


def surely_valid(schema: Mapping[str, Any], values: Mapping[str, Any]) -> bool:
    """True when the object JSON Schema ``schema`` (a strict pydantic model's:
    ``additionalProperties`` false, no NaN or infinity) accepts every item of ``values``
    -- so the model does too.  Sufficient, not necessary: False (an unknown field, a
    keyword not judged here, a string the model might convert) means *ask the model*.

    Judged: ``type`` (``number``: a finite int or float; ``integer``: an int;
    ``boolean``, ``null``, ``string``), ``anyOf``, ``enum`` and the numeric bounds.
    """
    props = schema.get("properties", {})
    return all(k in props and _accepts(props[k], v) for k, v in values.items())


def _accepts(prop: Mapping[str, Any], value: Any) -> bool:
    if "anyOf" in prop:
        return any(_accepts(p, value) for p in prop["anyOf"])
    if set(prop) - _JUDGED - {"default", "description", "title"}:
        return False
    kind = prop.get("type")
    if kind == "null":
        return value is None
    if kind == "boolean":
        return isinstance(value, bool)
    if kind == "string":
        return isinstance(value, str) and value in prop.get("enum", (value,))
    if kind == "integer":
        ok = type(value) is int
    elif kind == "number":
        ok = type(value) in (int, float) and _finite(value)
    else:
        return False
    return ok and _within(prop, value)


def _finite(value: int | float) -> bool:
    try:
        return math.isfinite(value)
    except OverflowError:  # an int too large for a float
        return False


def _within(prop: Mapping[str, Any], value: int | float) -> bool:
    """``value`` inside the numeric bounds of ``prop`` (an ``enum`` on numbers: not judged)."""
    if "enum" in prop:
        return False
    checks = (
        ("minimum", lambda b: value >= b),
        ("maximum", lambda b: value <= b),
        ("exclusiveMinimum", lambda b: value > b),
        ("exclusiveMaximum", lambda b: value < b),
    )
    return all(check(prop[key]) for key, check in checks if key in prop)
