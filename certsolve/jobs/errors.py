"""Validation errors as ``{"loc", "field", "msg", "type"}`` dicts with dotted field paths.

Shared by the HTTP API (422 bodies), the batch runner and the CLI: the discriminator tags
pydantic puts in error paths (``fk``, ``solve``) are removed, and model-level messages that
name their field (``params.u: expected 4 values``, ``wires[3].base: ...``) are moved to
that field, so a robot error reads ``robot.wires.3.tau: tau_min must be <= tau_max``.
pydantic's "Input should be ..." reads "must be ..." (``params.eps: must be greater than
0``), which the command line prints after the option (``--eps: must be greater than 0``).
A message that points into Minibex text (``line 4, column 9: ...``) also gives ``line``
and ``column`` as numbers.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

from pydantic import ValidationError

from ..inputs import readable
from .kinds import KINDS

__all__ = ["describe_validation_error", "field_of", "summary", "validation_details"]

_KIND_TAGS = frozenset(KINDS)
_SKIP = ("function-after", "function-before", "function-wrap", "function-plain")
_FIELD_MSG = re.compile(r"^((?:[A-Za-z_]\w*(?:\[\d+\])*)(?:\.[A-Za-z_]\w*(?:\[\d+\])*)*): (.+)$")
_POSITION = re.compile(r"^line (\d+), column (\d+): ")


def _json_safe(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, (str, int, float, bool)) or v is None:
        return v
    return str(v)


def _split_path(text: str) -> list:
    out: list = []
    for part in text.split("."):
        m = re.match(r"^([A-Za-z_]\w*)((?:\[\d+\])*)$", part)
        if not m:
            return [text]
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return out


def _clean_loc(loc) -> list:
    out: list = []
    for part in loc:
        if isinstance(part, str) and (part.startswith(_SKIP) or part in ("tagged-union",)):
            continue
        if (
            isinstance(part, str)
            and part in _KIND_TAGS
            and (not out or out[-1] == "body" or isinstance(out[-1], int))
        ):
            continue  # the discriminated union's tag
        out.append(part)
    return out


def field_of(loc: Sequence[Any]) -> str:
    """The dotted field of a ``loc``: without its ``body`` / ``query`` / ``path`` /
    ``header`` part, unless that is all there is (the whole body is ``body``)."""
    parts = loc[1:] if len(loc) > 1 and loc[0] in ("body", "query", "path", "header") else loc
    return ".".join(str(p) for p in parts)


def validation_details(errors: Sequence[Mapping[str, Any]], prefix: tuple = ()) -> list[dict]:
    """pydantic / FastAPI error dicts -> ``{"loc", "field", "msg", "type"}`` dicts (with
    ``line`` and ``column`` for positions in Minibex text)."""
    out = []
    for e in errors:
        loc = _clean_loc((*prefix, *e.get("loc", ())))
        msg = readable(str(e.get("msg", "invalid value")))
        typ = str(e.get("type", "value_error"))
        if typ == "json_invalid":
            ctx = e.get("ctx") or {}
            msg = f"invalid JSON: {ctx.get('error', msg)}"
            loc = loc[:1]
        pieces = msg.split("; ") if typ == "value_error" else [msg]
        for piece in pieces:
            m = _FIELD_MSG.match(piece)
            ploc = loc
            if m and typ == "value_error":
                sub = _split_path(m.group(1))
                # "params.u: ..." raised at the job level, "wires[3].base: ..." at the robot
                if loc[-1:] == [sub[0]]:
                    sub = sub[1:]
                ploc = [*loc, *sub]
                piece = m.group(2)
            item: dict[str, Any] = {
                "loc": [_json_safe(p) for p in ploc],
                "field": field_of(ploc),
                "msg": piece,
                "type": typ,
            }
            if at := _POSITION.match(piece):
                item["line"], item["column"] = int(at.group(1)), int(at.group(2))
            out.append(item)
    return out


def summary(details: list[dict]) -> str:
    parts = [f"{d['field']}: {d['msg']}" if d["field"] else d["msg"] for d in details[:3]]
    more = len(details) - 3
    return "; ".join(parts) + (f" (and {more} more)" if more > 0 else "")


def describe_validation_error(exc: ValidationError, prefix: tuple = ()) -> str:
    """One line: ``robot.wires.3.tau: tau_min must be <= tau_max; ...``."""
    return summary(validation_details(exc.errors(), prefix))
