"""The result a job stores: the library's result, bounded, whatever stopped the run.

A search stopped by its time limit, its box limit, its memory or a cancel returns what it
has: the solutions found so far and the boxes it had not explored, which can be millions
(``pending``).  Writing all of them out costs seconds per million boxes -- longer than the
grace the job has before it is killed -- and makes a result nobody can read.
:func:`stored_result` keeps it bounded, in time proportional to what it keeps:

* the solver's pending boxes (``pending_lo`` / ``pending_hi`` of a solve result, also
  inside an FK result) are cut to their first ``max_items`` rows *before* the result is
  converted to JSON data (other results count their boxes from their arrays, so those are
  cut after conversion, below);
* every other top-level list longer than ``max_items`` is then cut too
  (:func:`.jsonutil.truncate_lists`), before the result is made plain JSON data (the
  workspace's and the design's box lists come out of ``to_dict`` in one numpy call);
* ``truncated`` records the full length of each list that was cut, so nothing is dropped
  silently: what is not listed is counted.

Pending boxes are the unexplored part of the domain; the first ``max_items`` of them (in
the search's order) and their count describe a stopped search.  (A workspace or design
result is converted whole before it is cut -- its counts and measures come from its
arrays -- which costs about 2.3 s per million boxes.)  When the solver merges
its pending boxes into hulls itself (a bounded summary with counts), there is nothing left
to cut here and the summary is stored as it is.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .jsonutil import plain, truncate_lists

__all__ = ["stored_result"]


def _cut(obj: Any, max_items: int, counts: dict[str, int], depth: int = 0) -> Any:
    """``obj``, or a shallow copy of it whose pending boxes (``pending_lo`` / ``pending_hi``
    and the ``pending*`` arrays of the same length) have at most ``max_items`` rows; the
    same for the dataclasses it holds (an FK result holds its solver result)."""
    if depth > 2 or not dataclasses.is_dataclass(obj) or isinstance(obj, type):
        return obj
    changes: dict[str, Any] = {}
    lo = getattr(obj, "pending_lo", None)
    if isinstance(lo, np.ndarray) and lo.ndim >= 1 and lo.shape[0] > max_items:
        n = lo.shape[0]
        counts["pending"] = int(n)
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if f.name.startswith("pending") and isinstance(value, np.ndarray):
                if value.ndim >= 1 and value.shape[0] == n:
                    changes[f.name] = value[:max_items]
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if f.name not in changes and dataclasses.is_dataclass(value):
            cut = _cut(value, max_items, counts, depth + 1)
            if cut is not value:
                changes[f.name] = cut
    return dataclasses.replace(obj, **changes) if changes else obj


def stored_result(result: Any, max_items: int) -> Any:
    """The JSON data a job stores for the library's ``result`` (module docstring)."""
    counts: dict[str, int] = {}
    cut = _cut(result, max_items, counts)
    data = cut.to_dict() if hasattr(cut, "to_dict") else cut
    data = plain(truncate_lists(data, max_items))  # cut first: plain() visits every item
    if counts and isinstance(data, dict):
        data["truncated"] = {**counts, **data.get("truncated", {})}
    return data
