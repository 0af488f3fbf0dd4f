"""User input, checked once for every front end: the error that names its field, the
strict model every options model derives from, and the bounds on single values.

The library's entry points (``certsolve.forward_kinematics``, ``track``, ...), the job
kinds (HTTP bodies, batch lines) and the command line validate the same options with the
same pydantic models (:mod:`certsolve.robot.inputs` holds those of the robot functions;
the job kinds' ``Params`` derive from them), so a value one front end refuses is refused by
all, with the same message.  Where the front ends differ is only in how they *name* the
field: ``tau_max`` in Python, ``params.tau_max`` over HTTP, ``--tau-max`` on the command
line.  In Python the refusal is an :class:`InputError`: a ``ValueError`` whose ``field``
is the dotted path of the value at fault (``u``, ``pose.2``), and whose message is
``"field: what is wrong"``.

This module sits below every layer (it imports pydantic only).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Annotated, Any, TypeVar

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

__all__ = [
    "MAX_COORD",
    "MAX_FORCE",
    "Coord",
    "InputError",
    "StrictModel",
    "check_count",
    "checked",
    "checked_value",
    "readable",
    "value_type",
]

MAX_COORD = 1e6  # cm, the robot schema's bound
MAX_FORCE = 1e9  # N

Coord = Annotated[float, Field(ge=-MAX_COORD, le=MAX_COORD)]

M = TypeVar("M", bound=BaseModel)

_PREFIXES = ("Value error, ", "Assertion failed, ")
_SHOULD = re.compile(r"^(?:Input|String|List|Tuple|Dictionary|Value) should (be|have) ")
_FIELD_MSG = re.compile(r"^([A-Za-z_][\w.\[\]]*): (.+)$")


class InputError(ValueError):
    """A value the library refuses: ``field`` is its dotted path (``tau_max``, ``u``,
    ``pose.2``; ``""`` when no one field is at fault), ``message`` what is wrong;
    ``str(exc)`` is ``"field: message"``."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}" if field else message)
        self.field = field
        self.message = message


class StrictModel(BaseModel):
    """A strict options model: unknown fields and non-finite numbers are refused."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def readable(msg: str) -> str:
    """pydantic's message as the front ends print it: without ``Value error,``, and
    ``Input should be ...`` read as ``must be ...``."""
    for p in _PREFIXES:
        if msg.startswith(p):
            msg = msg[len(p) :]
    return _SHOULD.sub(r"must \1 ", msg)


def _error(exc: ValidationError, prefix: tuple = ()) -> InputError:
    """The first problem of ``exc`` as an :class:`InputError` (a model-level message that
    names its field, ``u: expected 4 values``, is moved to that field)."""
    first = exc.errors()[0]
    loc = [*prefix, *(p for p in first["loc"] if not str(p).startswith("function-"))]
    msg = readable(str(first["msg"]))
    named = _FIELD_MSG.match(msg)
    if named and first["type"] == "value_error":
        loc, msg = [*loc, named.group(1)], named.group(2)
    return InputError(".".join(str(p) for p in loc), msg)


def _plain(value: Any) -> Any:
    """numpy arrays and scalars as the lists and numbers a user would write."""
    tolist = getattr(value, "tolist", None)
    return tolist() if callable(tolist) else value


def checked(model: type[M], values: Mapping[str, Any]) -> M:
    """``model`` built from ``values`` (numpy arrays read as lists); a value of None takes
    the model's default.  The first problem is raised as :class:`InputError` naming its
    field."""
    data = {k: _plain(v) for k, v in values.items() if v is not None}
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise _error(exc) from None


def value_type(kind: Any) -> TypeAdapter:
    """A validator of single values of the type ``kind`` (an ``Annotated`` type with its
    ``Field`` constraints), non-finite numbers refused as in :class:`StrictModel`; build it
    once (a module constant), it costs a fraction of a millisecond."""
    return TypeAdapter(kind, config=ConfigDict(allow_inf_nan=False))


def checked_value(kind: TypeAdapter, value: Any, field: str) -> Any:
    """``value`` validated by ``kind`` (:func:`value_type`); the problem is raised as
    :class:`InputError` at ``field``."""
    try:
        return kind.validate_python(value)
    except ValidationError as exc:
        raise _error(exc, (field,)) from None


def check_count(values: Sequence | None, count: int, name: str, what: str) -> None:
    """``values`` (when given) has ``count`` items; ``what`` says what they are."""
    if values is not None and len(values) != count:
        raise InputError(name, f"expected {count} {what}, got {len(values)}")
