"""Expressions, their DAG, batched evaluation, HC4 contraction, and the Minibex parser.

* :mod:`.node`     -- :class:`Expr` and builders (``var``, ``sqr``, ``sin`` ...)
* :mod:`.graph`    -- hash-consed DAG with constant folding and symbolic derivatives
* :mod:`.program`  -- level-grouped batched evaluation (intervals, floats) and HC4-revise
* :mod:`.system`   -- :class:`System`: square equations + extra constraints over a box
* :mod:`.compiled` -- :class:`CompiledSystem`: ``f``, ``J`` and HC4 over batches of boxes
* :mod:`.minibex`  -- parser for the Minibex subset of IBEX benchmark files
"""

from .compiled import CompiledSystem
from .graph import Graph
from .node import (
    Expr,
    abs_,
    const,
    cos,
    esum,
    exp,
    log,
    max_,
    min_,
    param,
    pow,
    sin,
    sqr,
    sqrt,
    var,
)
from .program import Program
from .system import Constraint, System

__all__ = [
    "CompiledSystem",
    "Constraint",
    "Expr",
    "Graph",
    "Program",
    "System",
    "abs_",
    "const",
    "cos",
    "esum",
    "exp",
    "log",
    "max_",
    "min_",
    "param",
    "pow",
    "sin",
    "sqr",
    "sqrt",
    "var",
]
