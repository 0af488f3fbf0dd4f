"""Expressions built with Python operators: ``x*y + sqr(z) - 1``.

An :class:`Expr` is an immutable tree node; the same Python object used twice, or two
structurally equal sub-trees, become one node of the compiled DAG (:mod:`.graph`).  Leaves
are variables (:func:`var`), parameters (:func:`param`, values supplied at evaluation time)
and constants; a constant is an interval ``[lo, hi]`` so that a
decimal like ``0.1``, which no binary float equals, can be enclosed exactly
(:func:`const`).  Python numbers mixed into expressions are taken as exact binary values.
"""

from __future__ import annotations

from numbers import Real
from typing import SupportsInt, cast

__all__ = [
    "Expr",
    "var",
    "param",
    "const",
    "sqr",
    "sqrt",
    "exp",
    "log",
    "sin",
    "cos",
    "pow",
    "tan",
    "sinh",
    "cosh",
    "tanh",
    "asin",
    "acos",
    "atan",
    "asinh",
    "acosh",
    "atanh",
    "atan2",
    "rpow",
    "sign",
    "abs_",
    "min_",
    "max_",
    "esum",
    "OPS",
    "UNARY_FUNCTIONS",
]

#: operation name -> arity (params: 'var' name, 'const' (lo, hi), 'pow' exponent)
OPS: dict[str, int] = {
    "var": 0,
    "param": 0,
    "const": 0,
    "add": 2,
    "sub": 2,
    "mul": 2,
    "div": 2,
    "min": 2,
    "max": 2,
    "hull": 2,
    "atan2": 2,  # atan2(y, x)
    "rpow": 2,  # x^y = exp(y log x), x > 0
    "neg": 1,
    "sqr": 1,
    "sqrt": 1,
    "pow": 1,
    "exp": 1,
    "log": 1,
    "sin": 1,
    "cos": 1,
    "tan": 1,
    "sinh": 1,
    "cosh": 1,
    "tanh": 1,
    "asin": 1,
    "acos": 1,
    "atan": 1,
    "asinh": 1,
    "acosh": 1,
    "atanh": 1,
    "abs": 1,
    "sign": 1,
    "cadd": 1,
    "cmul": 1,
}


class Expr:
    """A node of an expression tree (immutable)."""

    __slots__ = ("op", "args", "param")

    def __init__(self, op: str, args: tuple = (), param=None):
        if op not in OPS:
            raise ValueError(f"unknown operation {op!r}")
        if len(args) != OPS[op]:
            raise ValueError(f"{op} takes {OPS[op]} arguments, got {len(args)}")
        self.op = op
        self.args = tuple(args)
        self.param = param

    # -- construction helpers -------------------------------------------------------
    @staticmethod
    def wrap(x) -> Expr:
        if isinstance(x, Expr):
            return x
        if isinstance(x, Real):
            return const(float(x))
        raise TypeError(f"cannot use {type(x).__name__} in an expression")

    def __add__(self, o):
        return Expr("add", (self, Expr.wrap(o)))

    def __radd__(self, o):
        return Expr("add", (Expr.wrap(o), self))

    def __sub__(self, o):
        return Expr("sub", (self, Expr.wrap(o)))

    def __rsub__(self, o):
        return Expr("sub", (Expr.wrap(o), self))

    def __mul__(self, o):
        return Expr("mul", (self, Expr.wrap(o)))

    def __rmul__(self, o):
        return Expr("mul", (Expr.wrap(o), self))

    def __truediv__(self, o):
        return Expr("div", (self, Expr.wrap(o)))

    def __rtruediv__(self, o):
        return Expr("div", (Expr.wrap(o), self))

    def __neg__(self):
        return Expr("neg", (self,))

    def __pos__(self):
        return self

    def __pow__(self, n):
        return pow(self, n)

    # -- inspection ------------------------------------------------------------------
    def _leaves(self, op: str) -> set[str]:
        """Names of the leaves of kind ``op`` ("var" or "param") below this node."""
        out: set[str] = set()
        stack = [self]
        seen: set[int] = set()
        while stack:
            e = stack.pop()
            if id(e) in seen:
                continue
            seen.add(id(e))
            if e.op == op:
                out.add(e.param)
            stack.extend(e.args)
        return out

    def variables(self) -> set[str]:
        """Names of the variables this expression depends on."""
        return self._leaves("var")

    def parameters(self) -> set[str]:
        """Names of the parameters this expression depends on."""
        return self._leaves("param")

    def __repr__(self) -> str:
        return to_string(self)

    # Expr objects compare by identity; structural equality is the graph's job.
    __hash__ = object.__hash__


def var(name: str) -> Expr:
    return Expr("var", (), str(name))


def param(name: str) -> Expr:
    """A parameter: a constant whose (interval) value is given when the system is evaluated,
    so one compiled system serves many values (e.g. the control vector of forward kinematics)."""
    return Expr("param", (), str(name))


def const(lo: float, hi: float | None = None) -> Expr:
    """A constant interval ``[lo, hi]`` (a point when ``hi`` is omitted)."""
    lo = float(lo)
    hi = lo if hi is None else float(hi)
    if not lo <= hi:
        raise ValueError(f"constant [{lo}, {hi}] is empty")
    return Expr("const", (), (lo, hi))


def sqr(x) -> Expr:
    return Expr("sqr", (Expr.wrap(x),))


def sqrt(x) -> Expr:
    return Expr("sqrt", (Expr.wrap(x),))


def exp(x) -> Expr:
    return Expr("exp", (Expr.wrap(x),))


def log(x) -> Expr:
    return Expr("log", (Expr.wrap(x),))


def sin(x) -> Expr:
    return Expr("sin", (Expr.wrap(x),))


def cos(x) -> Expr:
    return Expr("cos", (Expr.wrap(x),))


def _unary_builder(op: str):
    def build(x) -> Expr:
        return Expr(op, (Expr.wrap(x),))

    build.__name__ = op
    build.__doc__ = f"``{op}(x)``"
    return build


tan = _unary_builder("tan")
sinh = _unary_builder("sinh")
cosh = _unary_builder("cosh")
tanh = _unary_builder("tanh")
asin = _unary_builder("asin")
acos = _unary_builder("acos")
atan = _unary_builder("atan")
asinh = _unary_builder("asinh")
acosh = _unary_builder("acosh")
atanh = _unary_builder("atanh")
sign = _unary_builder("sign")


def atan2(y, x) -> Expr:
    """The angle of the point ``(x, y)``, in ``(-pi, pi]`` (undefined at the origin)."""
    return Expr("atan2", (Expr.wrap(y), Expr.wrap(x)))


def rpow(x, y) -> Expr:
    """Real power ``x^y = exp(y log x)``: defined for ``x > 0`` (and ``0^y = 0`` for ``y > 0``).

    For an integer exponent and any real ``x`` use :func:`pow`.
    """
    return Expr("rpow", (Expr.wrap(x), Expr.wrap(y)))


def abs_(x) -> Expr:
    return Expr("abs", (Expr.wrap(x),))


def min_(x, y) -> Expr:
    return Expr("min", (Expr.wrap(x), Expr.wrap(y)))


def max_(x, y) -> Expr:
    return Expr("max", (Expr.wrap(x), Expr.wrap(y)))


def pow(x, n) -> Expr:  # noqa: A001 - mirrors the Minibex name
    if isinstance(n, Real) and float(n) == int(cast(SupportsInt, n)):
        n = int(cast(SupportsInt, n))
        if n == 2:
            return sqr(x)
        return Expr("pow", (Expr.wrap(x),), n)
    raise ValueError(f"only integer exponents are supported (got {n!r}); use exp(n*log(x))")


#: one-argument functions by name (the Minibex names; ``ln`` is ``log``)
UNARY_FUNCTIONS = {
    "sqr": sqr,
    "sqrt": sqrt,
    "exp": exp,
    "log": log,
    "ln": log,
    "sin": sin,
    "cos": cos,
    "tan": tan,
    "sinh": sinh,
    "cosh": cosh,
    "tanh": tanh,
    "asin": asin,
    "acos": acos,
    "atan": atan,
    "asinh": asinh,
    "acosh": acosh,
    "atanh": atanh,
    "sign": sign,
    "abs": abs_,
}


def esum(terms) -> Expr:
    """Sum of many terms as a *balanced* tree (depth log2(k) instead of k).

    The evaluator processes one tree level per step, so balanced sums are faster.
    """
    terms = [Expr.wrap(t) for t in terms]
    if not terms:
        return const(0.0)
    while len(terms) > 1:
        nxt = [terms[i] + terms[i + 1] for i in range(0, len(terms) - 1, 2)]
        if len(terms) % 2:
            nxt.append(terms[-1])
        terms = nxt
    return terms[0]


_INFIX = {"add": "+", "sub": "-", "mul": "*", "div": "/"}


def to_string(e: Expr) -> str:
    """Readable infix form (Minibex syntax)."""
    if e.op in ("var", "param"):
        return e.param
    if e.op == "const":
        lo, hi = e.param
        return repr(lo) if lo == hi else f"[{lo!r}, {hi!r}]"
    if e.op in _INFIX:
        return f"({to_string(e.args[0])} {_INFIX[e.op]} {to_string(e.args[1])})"
    if e.op == "neg":
        return f"(-{to_string(e.args[0])})"
    if e.op == "pow":
        return f"{to_string(e.args[0])}^{e.param}"
    if e.op == "cadd":
        return f"({to_string(e.args[0])} + {e.param!r})"
    if e.op == "cmul":
        return f"({e.param!r} * {to_string(e.args[0])})"
    return f"{e.op}({', '.join(to_string(a) for a in e.args)})"
