"""The JSON Schema of :class:`.options.SolveOptions` as data (its validating keywords).

:func:`~certsolve.solver.branch_and_prune.solve` checks its options against it with
:func:`certsolve.lazy.surely_valid`, which needs no pydantic: the model (imported with
pydantic, ~0.07 s of CPU) validates only a value the schema does not surely accept, and
its message is the one the caller reads.  ``tests/test_cli_solve_options.py`` keeps
this copy equal to the model's ``model_json_schema()`` without titles, descriptions and
defaults.

:func:`solve_keywords` is the one mapping from the ``solve`` job's params to
:func:`~certsolve.solver.branch_and_prune.solve`'s keywords, shared by the job's operation
and ``certsolve solve`` (which reads the params without importing the job's model).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["SOLVE_OPTIONS_SCHEMA", "solve_keywords"]

SOLVE_OPTIONS_SCHEMA: dict[str, Any] = {
    "additionalProperties": False,
    "properties": {
        "eps": {"exclusiveMinimum": 0, "maximum": 1000000000.0, "type": "number"},
        "timeout": {"anyOf": [{"exclusiveMinimum": 0, "type": "number"}, {"type": "null"}]},
        "max_boxes": {"anyOf": [{"minimum": 1, "type": "integer"}, {"type": "null"}]},
        "max_solutions": {
            "anyOf": [{"maximum": 1000000000, "minimum": 1, "type": "integer"}, {"type": "null"}]
        },
        "verify": {"type": "boolean"},
    },
    "type": "object",
}


def solve_keywords(params: Mapping[str, Any]) -> dict[str, Any]:
    """The keywords of :func:`~certsolve.solver.branch_and_prune.solve` set by the ``solve``
    job's params (a mapping of its fields, validated: ``SolveParams.model_dump()`` or what
    :func:`certsolve.lazy.surely_valid` accepted); ``cid_vars="all"`` is the solver's
    ``None``.  The run's own limits and hooks (time, boxes, progress ...) are the caller's."""
    cid_vars = params["cid_vars"]
    return {
        "eps": params["eps"],
        "verify": params["verify"],
        "max_solutions": params["max_solutions"],
        "max_undecided": params["max_undecided"],
        "max_pending": params["max_pending"],
        "cid_vars": None if cid_vars == "all" else cid_vars,
        "split_at_zero": params["split_at_zero"],
        # the solver's own multistart unless turned off (:mod:`.starts`)
        **({} if params["newton_starts"] else {"starts": None}),
    }
