"""Strict JSON for results: numpy values become plain ones, non-finite floats ``null``."""

from __future__ import annotations

import json
import math
from typing import Any

__all__ = ["plain", "dumps", "truncate_lists"]


def plain(obj: Any) -> Any:
    """A copy of ``obj`` made of dict / list / str / int / float (finite) / bool / None."""
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [plain(v) for v in obj]
    if hasattr(obj, "to_dict"):
        return plain(obj.to_dict())
    if hasattr(obj, "tolist"):  # numpy arrays and scalars
        return plain(obj.tolist())
    if hasattr(obj, "__float__"):
        return plain(float(obj))
    return str(obj)


def truncate_lists(obj: dict, max_items: int) -> dict:
    """Cut top-level lists longer than ``max_items``; ``truncated`` records the full lengths.

    A solve stopped by its time limit may leave millions of pending boxes: the job keeps
    the first ``max_items`` of them and says how many there were.
    """
    if not isinstance(obj, dict):
        return obj
    cut = {}
    out = {}
    for k, v in obj.items():
        if isinstance(v, list) and len(v) > max_items:
            cut[k] = len(v)
            v = v[:max_items]
        out[k] = v
    if cut:
        out["truncated"] = cut
    return out


def dumps(obj: Any) -> str:
    return json.dumps(obj, allow_nan=False, separators=(",", ":"))
