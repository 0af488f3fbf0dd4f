"""Values of Minibex expressions while parsing: exact rationals, expressions, tensors.

A *scalar* is

* a :class:`~fractions.Fraction` -- an exact constant: decimal literals and ``+ - * /``,
  integer powers, ``sqr``, ``abs``, ``sign``, ``min``, ``max`` of exact constants stay exact,
  so indices, loop bounds and dimensions computed from them are exact integers, and a
  constant such as ``1/3`` becomes, at the end, its tightest float enclosure;
* an :class:`~certsolve.expr.node.Expr` -- an expression of the variables, or a constant
  interval ``[lo, hi]``.  An operation whose arguments are all constant is evaluated at once
  (outward rounded, :data:`certsolve.expr.ops.FORWARD`); an operation undefined on its constant
  argument (``1/0``, ``log(0)``, ``sqrt(-1)``) is a parse error at the operator.

A :class:`Tensor` is a vector (shape ``(n,)``, a column), a row vector ``(1, n)``, a matrix
``(m, n)`` or a 3-D array, of scalars in row-major order.  ``oo`` is not a value: it may only be
written as a bound of an interval (:class:`Infinity` marks it until then).

Every function here takes the token to blame for an error (``at``) and raises
:class:`~.lexer.MinibexError` there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import NoReturn

import numpy as np

from ...interval.rounding import rational_enclosure
from .. import node as N
from ..node import Expr
from ..ops import FORWARD
from .lexer import MinibexError, Token

__all__ = [
    "Tensor",
    "Infinity",
    "fail",
    "enclosure",
    "as_expr",
    "make",
    "arith",
    "negate",
    "power",
    "function",
    "transpose",
    "index",
    "stack",
    "components",
    "as_int",
    "interval",
]

_MAX_BITS = 4096  # exact rationals larger than this become intervals
_MAX = float(np.finfo(np.float64).max)


def fail(message: str, at: Token) -> NoReturn:
    raise MinibexError(message, at.line, at.col)


@dataclass(frozen=True)
class Tensor:
    shape: tuple[int, ...]
    items: tuple

    @property
    def is_vector(self) -> bool:
        return len(self.shape) == 1 or (len(self.shape) == 2 and self.shape[0] == 1)

    def describe(self) -> str:
        if len(self.shape) == 1:
            return f"a vector of {self.shape[0]}"
        if self.shape[0] == 1 and len(self.shape) == 2:
            return f"a row vector of {self.shape[1]}"
        return "a " + "x".join(str(d) for d in self.shape) + " array"


@dataclass(frozen=True)
class Infinity:
    sign: int


def _describe(v) -> str:
    if isinstance(v, Tensor):
        return v.describe()
    return "a number"


# -- exact constants ----------------------------------------------------------------------------
def _small(f: Fraction) -> bool:
    return f.numerator.bit_length() <= _MAX_BITS and f.denominator.bit_length() <= _MAX_BITS


def enclosure(f: Fraction, at: Token) -> tuple[float, float]:
    """Tightest float interval containing the exact rational ``f``."""
    try:
        return rational_enclosure(f)
    except OverflowError:
        fail("a constant is beyond the double-precision range", at)


def as_expr(v, at: Token) -> Expr:
    """A scalar as an expression (an exact constant becomes its tightest enclosure)."""
    if isinstance(v, Expr):
        return v
    if isinstance(v, Fraction):
        return N.const(*enclosure(v, at))
    if isinstance(v, Infinity):
        fail("oo (infinity) may only be a bound of an interval, as in [0, +oo]", at)
    fail(f"expected a number, found {_describe(v)}", at)


def _num(v: float) -> str:
    return str(int(v)) if math.isfinite(v) and v == int(v) and abs(v) < 1e15 else repr(v)


def _undefined(op: str, args, at: Token):
    shown = ", ".join(
        _num(a.param[0])
        if a.param[0] == a.param[1]
        else f"[{_num(a.param[0])}, {_num(a.param[1])}]"
        for a in args
    )
    if op == "div":
        fail("division by zero in a constant expression", at)
    name = {"rpow": "^", "pow": "^"}.get(op, op)
    fail(f"undefined constant: {name}({shown}) has no value (outside the domain of {name})", at)


def make(op: str, args: tuple, at: Token, param=None) -> Expr:
    """``Expr(op, args)``, evaluated at once when every argument is a constant."""
    if all(a.op == "const" for a in args):
        vals: list[np.float64 | None] = [np.float64(v) for a in args for v in a.param]
        if len(vals) == 2:
            vals += [None, None]
        with np.errstate(all="ignore"):
            lo, hi = FORWARD[op](*vals, param)
        lo, hi = float(lo), float(hi)
        if not lo <= hi or lo == math.inf or hi == -math.inf:
            _undefined(op, args, at)
        return N.const(lo, hi)
    return Expr(op, args, param)


# -- scalar and tensor arithmetic ---------------------------------------------------------------
def _scalar_arith(op: str, a, b, at: Token):
    if isinstance(a, Infinity) or isinstance(b, Infinity):
        as_expr(a if isinstance(a, Infinity) else b, at)  # raises
    if isinstance(a, Fraction) and isinstance(b, Fraction):
        if op == "+":
            r = a + b
        elif op == "-":
            r = a - b
        elif op == "*":
            r = a * b
        else:
            if b == 0:
                fail("division by zero in a constant expression", at)
            r = a / b
        if _small(r):
            return r
    name = {"+": "add", "-": "sub", "*": "mul", "/": "div"}[op]
    return make(name, (as_expr(a, at), as_expr(b, at)), at)


def _flat_vector(t: Tensor) -> bool:
    return t.is_vector


def _matrix(t: Tensor) -> tuple[int, int]:
    """Shape of ``t`` as a matrix (a vector is a column)."""
    if len(t.shape) == 1:
        return t.shape[0], 1
    if len(t.shape) == 2:
        return t.shape
    raise ValueError


def _from_matrix(rows: int, cols: int, items: list):
    if rows == 1 and cols == 1:
        return items[0]
    if cols == 1:
        return Tensor((rows,), tuple(items))
    return Tensor((rows, cols), tuple(items))


def _same_shape(a: Tensor, b: Tensor) -> bool:
    if a.shape == b.shape:
        return True
    try:
        return _matrix(a) == _matrix(b)
    except ValueError:
        return False


def arith(op: str, a, b, at: Token):
    """``a op b`` for ``op`` in ``+ - * /`` on scalars and tensors (see the module docstring).

    Tensors: ``+``/``-`` elementwise on equal shapes; a scalar times (or a tensor divided by a
    scalar) elementwise; matrix times matrix or vector (a vector is a column), and the dot
    product of two vectors of the same length.
    """
    ta, tb = isinstance(a, Tensor), isinstance(b, Tensor)
    if not ta and not tb:
        return _scalar_arith(op, a, b, at)
    if op in "+-":
        if not (ta and tb):
            fail(
                f"cannot {'add' if op == '+' else 'subtract'} {_describe(a)} and {_describe(b)}", at
            )
        if not _same_shape(a, b):
            fail(
                f"cannot {'add' if op == '+' else 'subtract'} {a.describe()} and {b.describe()}", at
            )
        return Tensor(a.shape, tuple(_scalar_arith(op, x, y, at) for x, y in zip(a.items, b.items)))
    if op == "/":
        if tb:
            fail(f"cannot divide by {b.describe()}", at)
        return Tensor(a.shape, tuple(_scalar_arith("/", x, b, at) for x in a.items))
    # '*'
    if not ta:
        return Tensor(b.shape, tuple(_scalar_arith("*", a, y, at) for y in b.items))
    if not tb:
        return Tensor(a.shape, tuple(_scalar_arith("*", x, b, at) for x in a.items))
    try:
        (m, k), (k2, n) = _matrix(a), _matrix(b)
    except ValueError:
        fail(f"cannot multiply {a.describe()} and {b.describe()}", at)
    if k == k2:
        items = []
        for i in range(m):
            for j in range(n):
                items.append(
                    _dot(
                        [a.items[i * k + t] for t in range(k)],
                        [b.items[t * n + j] for t in range(k)],
                        at,
                    )
                )
        return _from_matrix(m, n, items)
    if a.is_vector and b.is_vector and len(a.items) == len(b.items):
        return _dot(list(a.items), list(b.items), at)
    fail(f"cannot multiply {a.describe()} and {b.describe()}", at)


def _dot(xs: list, ys: list, at: Token):
    terms = [_scalar_arith("*", x, y, at) for x, y in zip(xs, ys)]
    acc = terms[0]
    for t in terms[1:]:
        acc = _scalar_arith("+", acc, t, at)
    return acc


def negate(v, at: Token):
    if isinstance(v, Tensor):
        return Tensor(v.shape, tuple(negate(x, at) for x in v.items))
    if isinstance(v, Infinity):
        return Infinity(-v.sign)
    if isinstance(v, Fraction):
        return -v
    return make("neg", (v,), at)


def power(base, exponent, at: Token):
    """``base ^ exponent``: an exact integer exponent is an integer power (any real base);
    any other exponent is the real power ``exp(e log x)`` (``x > 0``, see ``N.rpow``)."""
    for v in (base, exponent):
        if isinstance(v, Tensor):
            fail(f"cannot raise to a power with {v.describe()}", at)
    if isinstance(exponent, Fraction) and exponent.denominator == 1:
        n = int(exponent)
        if isinstance(base, Fraction):
            if base == 0 and n < 0:
                fail("division by zero in a constant expression (0 to a negative power)", at)
            bits = max(abs(base.numerator).bit_length(), base.denominator.bit_length())
            if abs(n) * max(bits, 1) <= _MAX_BITS:
                return base**n
        if abs(n) > 2**31:
            fail(f"the exponent {n} is too large", at)
        b = as_expr(base, at)
        if n == 0:
            return make("pow", (b,), at, 0) if b.op == "const" else Fraction(1)
        if n == 1:
            return b
        if n == 2:
            return make("sqr", (b,), at)
        return make("pow", (b,), at, n)
    return make("rpow", (as_expr(base, at), as_expr(exponent, at)), at)


_EXACT_UNARY = {
    "sqr": lambda f: f * f,
    "abs": abs,
    "sign": lambda f: Fraction((f > 0) - (f < 0)),
}


def function(name: str, args: list, at: Token):
    """A built-in function applied to scalar arguments (``min``/``max`` take two or more)."""
    for v in args:
        if isinstance(v, Tensor):
            fail(f"{name} takes numbers, not {v.describe()}", at)
    if name in ("min", "max"):
        if len(args) < 2:
            fail(f"{name} takes at least 2 arguments, got {len(args)}", at)
        acc = args[0]
        for v in args[1:]:
            if isinstance(acc, Fraction) and isinstance(v, Fraction):
                acc = min(acc, v) if name == "min" else max(acc, v)
            else:
                acc = make(name, (as_expr(acc, at), as_expr(v, at)), at)
        return acc
    if name == "atan2":
        if len(args) != 2:
            fail(f"atan2 takes 2 arguments, got {len(args)}", at)
        return make("atan2", (as_expr(args[0], at), as_expr(args[1], at)), at)
    if len(args) != 1:
        fail(f"{name} takes 1 argument, got {len(args)}", at)
    (v,) = args
    if isinstance(v, Fraction) and name in _EXACT_UNARY:
        r = _EXACT_UNARY[name](v)
        if _small(r):
            return r
    op = "log" if name == "ln" else name
    return make(op, (as_expr(v, at),), at)


def transpose(v, at: Token):
    if not isinstance(v, Tensor):
        return v
    if len(v.shape) == 1:
        return Tensor((1, v.shape[0]), v.items)
    if len(v.shape) == 2:
        m, n = v.shape
        if m == 1:
            return Tensor((n,), v.items)
        return Tensor((n, m), tuple(v.items[i * n + j] for j in range(n) for i in range(m)))
    fail(f"cannot transpose {v.describe()}", at)


def as_int(v, at: Token, what: str) -> int:
    if isinstance(v, Fraction) and v.denominator == 1:
        return int(v)
    if isinstance(v, Expr) and v.op == "const" and v.param[0] == v.param[1]:
        x = v.param[0]
        if math.isfinite(x) and x == int(x):
            return int(x)
    fail(f"{what} must be an integer constant", at)


def index(v, idx: list, ats: list[Token]):
    """``v(i)``, ``v(i, j)``...: 1-based; one index of a matrix selects a row."""
    if not isinstance(v, Tensor):
        fail("only a vector or a matrix can be indexed", ats[0])
    row = v.is_vector and len(v.shape) == 2 and len(idx) == 1  # x(j) of a row vector
    shape = (v.shape[1],) if row else v.shape
    if len(idx) > len(shape):
        fail(f"{len(idx)} indices for {v.describe()}", ats[len(shape)])
    offset = 0
    stride = len(v.items)
    for k, (i, at) in enumerate(zip(idx, ats)):
        n = shape[k]
        i = as_int(i, at, "an index")
        if not 1 <= i <= n:
            fail(f"index {i} out of range 1..{n}", at)
        stride //= n
        offset += (i - 1) * stride
    rest = shape[len(idx) :]
    if not rest:
        return v.items[offset]
    items = v.items[offset : offset + stride]
    if len(rest) == 1:
        return Tensor((1, rest[0]), items) if len(shape) == 2 else Tensor(rest, items)
    return Tensor(rest, items)


def stack(items: list, sep: str, at: Token):
    """``(e1, e2, ...)`` (``sep = ','``: a row, or columns side by side) or ``(e1; e2; ...)``
    (a column, or rows / matrices stacked)."""
    first = items[0]
    for v in items:
        if isinstance(v, Infinity):
            as_expr(v, at)
    shapes = {v.shape if isinstance(v, Tensor) else () for v in items}
    if len(shapes) != 1:
        fail("the elements of a vector or matrix must all have the same shape", at)
    k = len(items)
    if not isinstance(first, Tensor):
        return Tensor((k,), tuple(items)) if sep == ";" else Tensor((1, k), tuple(items))
    s = first.shape
    if sep == ";":
        if len(s) == 1:  # columns stacked: a longer column
            return Tensor((k * s[0],), tuple(x for v in items for x in v.items))
        if first.is_vector:  # rows stacked: a matrix
            return Tensor((k, s[1]), tuple(x for v in items for x in v.items))
        if len(s) == 2:
            return Tensor((k, *s), tuple(x for v in items for x in v.items))
        fail("arrays of more than 3 dimensions are not supported", at)
    if len(s) == 1:  # columns side by side: a matrix
        m = s[0]
        return Tensor((m, k), tuple(items[j].items[i] for i in range(m) for j in range(k)))
    if first.is_vector:  # rows side by side: a longer row
        return Tensor((1, k * s[1]), tuple(x for v in items for x in v.items))
    fail("matrices can only be stacked with ';'", at)


def components(v) -> list:
    """The scalars of a value, in order."""
    return list(v.items) if isinstance(v, Tensor) else [v]


def interval(lo, hi, at: Token) -> Expr:
    """The constant ``[lo, hi]`` (bounds may be ``oo``)."""

    def bound(v, upper: bool) -> float:
        if isinstance(v, Infinity):
            return math.inf if v.sign > 0 else -math.inf
        if isinstance(v, Tensor):
            fail(f"an interval bound must be a number, not {v.describe()}", at)
        e = as_expr(v, at)
        if e.op != "const":
            fail("interval bounds must be constants", at)
        return e.param[1] if upper else e.param[0]

    a, b = bound(lo, False), bound(hi, True)
    if not a <= b or a == math.inf or b == -math.inf:
        fail(f"empty interval [{a}, {b}]", at)
    return N.const(a, b)
