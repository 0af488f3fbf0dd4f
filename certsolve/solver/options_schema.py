"""The JSON Schema of :class:`.options.SolveOptions` as data (its validating keywords).

:func:`~certsolve.solver.branch_and_prune.solve` checks its options against it with
:func:`certsolve.lazy.surely_valid`, which needs no pydantic: the model (imported with
pydantic, ~0.07 s of CPU) validates only a value the schema does not surely accept, and
its message is the one the caller reads.  ``tests/test_cli_solve_options.py`` keeps
this copy equal to the model's ``model_json_schema()`` without titles, descriptions and
defaults.
"""

from __future__ import annotations

from typing import Any

__all__ = ["SOLVE_OPTIONS_SCHEMA"]

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
