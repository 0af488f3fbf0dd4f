"""Expressions, their DAG, batched evaluation, HC4 contraction, and the Minibex parser.

* :mod:`.node`     -- :class:`Expr` and builders (``var``, ``sqr``, ``sin`` ...)
* :mod:`.graph`    -- hash-consed DAG with constant folding and symbolic derivatives
* :mod:`.program`  -- level-grouped batched evaluation (intervals, floats) and HC4-revise
* :mod:`.system`   -- :class:`System`: square equations + extra constraints over a box
* :mod:`.compiled` -- :class:`CompiledSystem`: ``f``, ``J`` and HC4 over batches of boxes
* :mod:`.ops`      -- what each DAG operation computes (forward, backward, float, smoothness)
* :mod:`.minibex`  -- the Minibex parser (IBEX's modelling language, ``docs/minibex.md``)
"""

from .compiled import CompiledSystem
from .graph import Graph
from .node import (
    Expr,
    abs_,
    acos,
    acosh,
    asin,
    asinh,
    atan,
    atan2,
    atanh,
    const,
    cos,
    cosh,
    esum,
    exp,
    log,
    max_,
    min_,
    param,
    pow,
    rpow,
    sign,
    sin,
    sinh,
    sqr,
    sqrt,
    tan,
    tanh,
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
    "acos",
    "acosh",
    "asin",
    "asinh",
    "atan",
    "atan2",
    "atanh",
    "const",
    "cos",
    "cosh",
    "esum",
    "exp",
    "log",
    "max_",
    "min_",
    "param",
    "pow",
    "rpow",
    "sign",
    "sin",
    "sinh",
    "sqr",
    "sqrt",
    "tan",
    "tanh",
    "var",
]
