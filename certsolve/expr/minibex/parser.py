"""Recursive-descent parser of Minibex, with IBEX's meaning (see ``docs/minibex.md``).

Nothing in the text is ever evaluated as Python.  Constant sub-expressions are evaluated as
they are read (exactly for rationals, outward rounded otherwise), so an undefined one
(``1/0``, ``log(0)``) is reported where it is written.  ``for`` loops re-read their body once
per value of the loop variable; functions are read once, with placeholder arguments, and
inlined by substitution at every call.  The nesting of expressions and the total work
(tokens read, loop bodies and inlined functions included) are bounded by
:class:`~.lexer.Limits`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from .. import node as N
from ..node import Expr
from ..system import Constraint, System
from . import values as V
from .lexer import LIMITS, Limits, MinibexError, Token, tokenize
from .values import Infinity, Tensor, fail

__all__ = ["Model", "parse"]

_SECTIONS = {"constants", "variables", "constraints", "end", "function", "minimize"}
_RESERVED = _SECTIONS | {"return", "for", "in", "oo"}
_BUILTINS = set(N.UNARY_FUNCTIONS) | {"min", "max", "atan2"}
_LITERAL = re.compile(r"(\d*)\.?(\d*)(?:[eE]([+-]?\d+))?$")
_MAX_DIGITS = 400
_MAX_FLOAT = Fraction(float(np.finfo(np.float64).max))
_PI = N.const(float(np.pi), float(np.nextafter(np.pi, np.inf)))


@dataclass(kw_only=True)
class Model:
    """A Minibex text as read: the scalar ``variables`` in order, their ``domain`` (shape
    ``(n, 2)``), the ``equations`` ``f_i(x) = 0`` and the extra ``constraints``.

    The number of equations ``m`` may differ from ``n`` (IBEX reads over- and under-determined
    systems); :meth:`system` is the :class:`System` the solver takes, square or not
    (``certsolve.solver.nonsquare``).
    """

    variables: list[str]
    domain: np.ndarray
    equations: list[Expr]
    constraints: list[Constraint]
    end: Token  # the end of the text: where errors about the whole system point

    def system(self, name: str = "") -> System:
        """The :class:`System` (``m != n``: the solver's non-square searches)."""
        return System(self.variables, self.domain, self.equations, self.constraints, name=name)


@dataclass
class _Function:
    params: list[tuple[str, tuple[int, ...]]]
    placeholders: list  # per parameter: its value (an Expr var or a Tensor of them)
    result: object  # value of the return expression, in the placeholders


def _literal(tok: Token):
    """An exact ``Fraction`` (or, below the float range, the interval ``[0, 2^-1074]``)."""
    m = _LITERAL.match(tok.text)
    assert m is not None  # the lexer only makes NUM tokens of this form
    whole, frac, exp = m.group(1), m.group(2), int(m.group(3) or 0)
    digits = (whole + frac).lstrip("0")
    if len(digits) > _MAX_DIGITS:
        fail(f"number {tok.text[:20]}... has more than {_MAX_DIGITS} digits", tok)
    if not digits:
        return Fraction(0)
    # int(digits) * 10^scale, and 10^(top - 1) <= value < 10^top
    scale = exp - len(frac)
    top = len(digits) + scale
    if top > 310:
        fail(f"number {tok.text} is beyond the double-precision range", tok)
    if top < -330:  # below the smallest subnormal (4.9e-324)
        return N.const(0.0, 5e-324)
    value = Fraction(int(digits)) * Fraction(10) ** scale
    if value > _MAX_FLOAT:
        fail(f"number {tok.text} is beyond the double-precision range", tok)
    return value


class _Parser:
    def __init__(self, text: str, limits: Limits):
        self.limits = limits
        self.toks = tokenize(text, limits)
        self.i = 0
        self.work = 0
        self.depth = 0
        self.constants: dict[str, object] = {"pi": _PI}
        self.variables: dict[str, object] = {}
        self.names: list[str] = []  # scalar variable names, in order
        self.domain: list[tuple[float, float]] = []
        self.functions: dict[str, _Function] = {}
        self.locals: dict[str, object] = {}  # loop variables, or a function's locals
        self.in_function = False
        self.equations: list[Expr] = []
        self.constraints: list[Constraint] = []

    # -- tokens -----------------------------------------------------------------------------------
    @property
    def tok(self) -> Token:
        return self.toks[self.i]

    def next(self) -> Token:
        t = self.toks[self.i]
        if t.kind != "EOF":
            self.i += 1
        self.work += 1
        if self.work > self.limits.max_work:
            fail(
                f"the system is too large: more than {self.limits.max_work} tokens read "
                "(loops and function calls expanded)",
                t,
            )
        return t

    def at(self, text: str) -> bool:
        t = self.toks[self.i]  # (the parser's most frequent call: ~5 a token)
        return t.text == text and t.kind in ("OP", "ID")

    def at_kw(self, word: str) -> bool:
        return self.tok.kind == "ID" and self.tok.text.lower() == word

    def found(self) -> str:
        return repr(self.tok.text) if self.tok.kind != "EOF" else "end of file"

    def expect(self, text: str, what: str) -> Token:
        if not self.at(text):
            where = self.toks[self.i - 1].after() if self.i else self.tok
            fail(f"expected {text!r} {what}, found {self.found()}", where)
        return self.next()

    def end_statement(self, what: str) -> None:
        """A ';' (or ',') ends a declaration; a missing one is reported just after it."""
        if self.at(";") or self.at(","):
            self.next()
        else:
            fail(f"expected ';' after {what}, found {self.found()}", self.toks[self.i - 1].after())

    def skip_semicolons(self) -> None:
        while self.at(";"):
            self.next()

    # -- sections ---------------------------------------------------------------------------------
    def parse(self) -> Model:
        self.skip_semicolons()
        if self.at_kw("constants"):
            self.next()
            self.declarations(self.constant_decl)
        self.function_blocks()
        if not self.at_kw("variables"):
            fail(f"expected the 'Variables' section, found {self.found()}", self.tok)
        self.next()
        self.declarations(self.variable_decl)
        if not self.names:
            fail("no variables declared", self.tok)
        self.function_blocks()
        if self.at_kw("minimize"):
            fail("optimization (Minimize) is not supported: certsolve solves equations", self.tok)
        if not self.at_kw("constraints"):
            fail(f"expected the 'Constraints' section, found {self.found()}", self.tok)
        self.next()
        self.constraints_block()
        if self.tok.kind != "EOF":
            fail(f"unexpected {self.found()} after 'end'", self.tok)
        domain = np.array(self.domain, dtype=float).reshape(len(self.names), 2)
        return Model(variables=self.names, domain=domain, equations=self.equations,
                     constraints=self.constraints, end=self.tok)  # fmt: skip

    def declarations(self, decl) -> None:
        self.skip_semicolons()
        while self.tok.kind == "ID" and self.tok.text.lower() not in _SECTIONS:
            decl()
            self.skip_semicolons()

    def new_name(self, local: bool = False) -> Token:
        """A new name; ``local`` names (function parameters and locals) may shadow globals."""
        t = self.next()
        if t.kind != "ID":
            fail(f"expected a name, found {t.text!r}" if t.kind != "EOF" else
                 "expected a name, found end of file", t)  # fmt: skip
        name = t.text
        if name.lower() in _RESERVED or name in _BUILTINS:
            fail(f"{name!r} is a reserved word", t)
        if name in self.functions or (
            not local and (name in self.constants or name in self.variables)
        ):
            fail(f"{name!r} is already declared", t)
        if name in self.locals:
            fail(f"{name!r} is already used in this scope", t)
        return t

    def dims(self) -> tuple[int, ...]:
        shape: list[int] = []
        while self.at("["):
            open_tok = self.next()
            n = V.as_int(self.expr(), open_tok, "a dimension")
            self.expect("]", "to close the dimension")
            if n < 1:
                fail(f"dimension {n} must be at least 1", open_tok)
            shape.append(n)
            if len(shape) > 3:
                fail("arrays of more than 3 dimensions are not supported", open_tok)
            if math.prod(shape) > self.limits.max_dim:
                fail(f"more than {self.limits.max_dim} components", open_tok)
        if len(shape) == 2 and shape[1] == 1:
            shape = shape[:1]  # x[n][1] is the column vector x[n]
        return tuple(shape)

    @staticmethod
    def component_names(name: str, shape: tuple[int, ...]) -> list[str]:
        out = [name]
        for d in shape:
            out = [f"{p}[{k}]" for p in out for k in range(1, d + 1)]
        return out

    def shaped(self, value, shape: tuple[int, ...], at: Token):
        """``value`` for a declaration of ``shape``: a scalar fills every component."""
        if not shape:
            if isinstance(value, Tensor):
                fail(f"expected a number, found {value.describe()}; declare the dimensions", at)
            return value
        size = math.prod(shape)
        if not isinstance(value, Tensor):
            return Tensor(shape, (value,) * size)
        if len(value.items) != size or not (
            value.shape == shape or (len(shape) == 1 and value.shape == (1, size))
        ):
            fail(f"{value.describe()} given for a declaration of shape {list(shape)}", at)
        return Tensor(shape, value.items)

    def constant_decl(self) -> None:
        name_tok = self.new_name()
        shape = self.dims()
        if not (self.at("=") or self.at(":=") or self.at_kw("in")):
            fail(f"expected '=' or 'in' after constant {name_tok.text!r}, found {self.found()}",
                 self.tok)  # fmt: skip
        eq_tok = self.next()
        value = self.shaped(self.expr(), shape, eq_tok)
        for v in V.components(value):
            if isinstance(v, Infinity):
                V.as_expr(v, eq_tok)
            if isinstance(v, Expr) and v.op != "const":
                fail("a constant cannot depend on variables", eq_tok)
        self.constants[name_tok.text] = value
        self.end_statement(f"constant {name_tok.text!r}")

    def variable_decl(self) -> None:
        name_tok = self.new_name()
        name = name_tok.text
        shape = self.dims()
        comps = self.component_names(name, shape)
        if len(self.names) + len(comps) > self.limits.max_variables:
            fail(f"more than {self.limits.max_variables} variables", name_tok)
        if self.at_kw("in"):
            in_tok = self.next()
            dom = self.shaped(self.expr(), shape, in_tok)
            bounds = [self.bounds(v, in_tok) for v in V.components(dom)]
        else:  # IBEX: a variable declared without a domain is unbounded
            bounds = [(-math.inf, math.inf)] * len(comps)
        exprs = [N.var(c) for c in comps]
        self.variables[name] = Tensor(shape, tuple(exprs)) if shape else exprs[0]
        self.names.extend(comps)
        self.domain.extend(bounds)
        self.end_statement(f"the declaration of {name!r}")

    @staticmethod
    def bounds(v, at: Token) -> tuple[float, float]:
        if isinstance(v, Infinity):
            fail("a domain must be an interval, as in [0, +oo]", at)
        e = V.as_expr(v, at)
        if e.op != "const":
            fail("a domain must be a constant", at)
        lo, hi = e.param
        if not lo <= hi:
            fail(f"empty domain [{lo}, {hi}]", at)
        return lo, hi

    # -- functions --------------------------------------------------------------------------------
    def function_blocks(self) -> None:
        while self.at_kw("function"):
            self.function_block()
            self.skip_semicolons()

    def function_block(self) -> None:
        self.next()
        name_tok = self.new_name()
        fname = name_tok.text
        self.expect("(", f"after the function name {fname!r}")
        params: list[tuple[str, tuple[int, ...]]] = []
        placeholders = []
        saved = self.locals
        self.locals = {}
        self.in_function = True
        try:
            while True:
                p_tok = self.new_name(local=True)
                shape = self.dims()
                comps = self.component_names(f"{fname}#{p_tok.text}", shape)
                exprs = [N.var(c) for c in comps]
                value = Tensor(shape, tuple(exprs)) if shape else exprs[0]
                params.append((p_tok.text, shape))
                placeholders.append(value)
                self.locals[p_tok.text] = value
                if self.at(","):
                    self.next()
                    continue
                self.expect(")", "to close the parameter list")
                break
            self.skip_semicolons()
            while not self.at_kw("return"):
                if self.tok.kind == "EOF" or self.at_kw("end"):
                    fail(f"expected 'return' in function {fname!r}, found {self.found()}", self.tok)
                local_tok = self.new_name(local=True)
                self.expect("=", f"after {local_tok.text!r} (a local definition)")
                self.locals[local_tok.text] = self.expr()
                self.end_statement(f"the definition of {local_tok.text!r}")
                self.skip_semicolons()
            self.next()
            result = self.expr()
            self.skip_semicolons()
            if not self.at_kw("end"):
                fail(f"expected 'end' to close function {fname!r}, found {self.found()}", self.tok)
            self.next()
        finally:
            self.locals = saved
            self.in_function = False
        self.functions[fname] = _Function(params, placeholders, result)

    def call(self, name: str, args: list, at: Token):
        """Inline function ``name``: its result with the placeholders replaced by ``args``."""
        fn = self.functions[name]
        if len(args) != len(fn.params):
            fail(f"{name} takes {len(fn.params)} argument(s), got {len(args)}", at)
        subst: dict[str, Expr] = {}
        for (pname, shape), holder, arg in zip(fn.params, fn.placeholders, args):
            if isinstance(holder, Tensor):
                if not isinstance(arg, Tensor) or len(arg.items) != len(holder.items):
                    fail(f"argument {pname!r} of {name} must be of shape {list(shape)}", at)
                pairs = list(zip(holder.items, arg.items, strict=True))
            else:
                if isinstance(arg, Tensor):
                    fail(f"argument {pname!r} of {name} must be a number, not {arg.describe()}", at)
                pairs = [(holder, arg)]
            for h, a in pairs:
                subst[h.param] = V.as_expr(a, at)
        memo: dict[int, Expr] = {}
        try:
            out = [self.substitute(v, subst, memo, at) for v in V.components(fn.result)]
        except MinibexError as exc:
            raise MinibexError(f"in the call of {name}: {exc.reason}", exc.line, exc.col) from None
        if isinstance(fn.result, Tensor):
            return Tensor(fn.result.shape, tuple(out))
        return out[0]

    def substitute(self, v, subst: dict[str, Expr], memo: dict[int, Expr], at: Token):
        """``v`` with variables renamed by ``subst`` (iterative; constants evaluated)."""
        if not isinstance(v, Expr):
            return v
        stack = [(v, False)]
        while stack:
            e, ready = stack.pop()
            if id(e) in memo:
                continue
            if e.op == "var":
                memo[id(e)] = subst.get(e.param, e)
            elif not e.args:
                memo[id(e)] = e
            elif ready:
                self.work += 1
                args = tuple(memo[id(a)] for a in e.args)
                if all(a is b for a, b in zip(args, e.args)):
                    memo[id(e)] = e
                else:
                    memo[id(e)] = V.make(e.op, args, at, e.param)
            else:
                stack.append((e, True))
                stack.extend((a, False) for a in e.args if id(a) not in memo)
        if self.work > self.limits.max_work:
            fail(f"the system is too large: more than {self.limits.max_work} steps of inlining", at)
        return memo[id(v)]

    # -- constraints ------------------------------------------------------------------------------
    def constraints_block(self) -> None:
        loops: list[list] = []  # [name, value, stop, body start]
        while True:
            if self.tok.kind == "EOF":
                if loops:
                    fail(f"missing 'end' of the loop over {loops[-1][0]!r}", self.tok)
                return
            if self.at_kw("end"):
                self.next()
                if not loops:
                    return
                frame = loops[-1]
                frame[1] += 1
                if frame[1] <= frame[2]:
                    self.locals[frame[0]] = Fraction(frame[1])
                    self.i = frame[3]
                else:
                    del self.locals[frame[0]]
                    loops.pop()
                    self.skip_semicolons()
                continue
            if self.at(";"):
                self.next()
                continue
            if self.at_kw("for"):
                for_tok = self.next()
                var_tok = self.new_name()
                self.expect("=", "after the loop variable")
                start = V.as_int(self.expr(), for_tok, "a loop bound")
                self.expect(":", "between the loop bounds")
                stop = V.as_int(self.expr(), for_tok, "a loop bound")
                self.skip_semicolons()
                if start > stop:
                    self.skip_loop_body(for_tok)
                    continue
                self.locals[var_tok.text] = Fraction(start)
                loops.append([var_tok.text, start, stop, self.i])
                continue
            self.constraint()

    def skip_loop_body(self, for_tok: Token) -> None:
        depth = 1
        while depth:
            t = self.next()
            if t.kind == "EOF":
                fail("missing 'end' of the loop", for_tok)
            if t.kind == "ID" and t.text.lower() == "for":
                depth += 1
            elif t.kind == "ID" and t.text.lower() == "end":
                depth -= 1
        self.skip_semicolons()

    def constraint(self) -> None:
        start = self.tok
        lhs = self.expr()
        if not (self.tok.kind == "OP" and self.tok.text in ("=", "==", "<=", ">=", "<", ">")):
            fail(f"expected '=', '==', '<=' or '>=' in the constraint, found {self.found()}",
                 self.tok)  # fmt: skip
        rel = self.next()
        rhs = self.expr()
        if rel.text in (">=", ">"):
            lhs, rhs = rhs, lhs
        zero = Fraction(0)
        if isinstance(rhs, Fraction) and rhs == zero:
            diff = lhs  # 'f = 0' is f itself, not f - 0
        elif isinstance(lhs, Fraction) and lhs == zero:
            diff = V.negate(rhs, rel)
        else:
            diff = V.arith("-", lhs, rhs, rel)
        for e in V.components(diff):
            e = V.as_expr(e, rel)
            if not e.variables():
                fail("the constraint involves no variable", start)
            if rel.text in ("=", "=="):
                self.equations.append(e)
            else:  # '<' and '>' are read as their closures '<=' and '>='
                self.constraints.append(Constraint(e, -math.inf, 0.0))
        if self.at(";"):
            self.next()
        elif not (self.at_kw("end") or self.tok.kind == "EOF"):
            fail(f"expected ';' after the constraint, found {self.found()}",
                 self.toks[self.i - 1].after())  # fmt: skip

    # -- expressions ------------------------------------------------------------------------------
    def expr(self):
        """additive := term (('+' | '-') term)*"""
        v = self.term()
        while self.at("+") or self.at("-"):
            op = self.next()
            v = V.arith(op.text, v, self.term(), op)
        return v

    def term(self):
        """term := unary (('*' | '/') unary)*"""
        v = self.unary()
        while self.at("*") or self.at("/"):
            op = self.next()
            v = V.arith(op.text, v, self.unary(), op)
        return v

    def unary(self):
        """unary := ('-' | '+') unary | atom postfix* ('^' unary)?"""
        self.depth += 1
        try:
            if self.depth > self.limits.max_depth:
                fail(f"nesting deeper than {self.limits.max_depth}", self.tok)
            if self.at("-"):
                t = self.next()
                return V.negate(self.unary(), t)
            if self.at("+"):
                self.next()
                return self.unary()
            v = self.postfix(self.atom())
            if self.at("^"):
                t = self.next()
                return V.power(v, self.unary(), t)
            return v
        finally:
            self.depth -= 1

    def postfix(self, v):
        while True:
            if self.at("'"):
                v = V.transpose(v, self.next())
            elif self.at("[") and isinstance(v, Tensor):
                t = self.next()
                i = self.expr()
                self.expect("]", "to close the index")
                v = V.index(v, [i], [t])
            elif self.at("(") and isinstance(v, Tensor):
                t = self.next()
                idx, ats = self.arguments(t)
                v = V.index(v, idx, ats)
            else:
                return v

    def arguments(self, open_tok: Token) -> tuple[list, list[Token]]:
        """``e1, e2, ...)`` after an opening parenthesis."""
        args, ats = [], []
        while True:
            ats.append(self.tok)
            args.append(self.expr())
            if self.at(","):
                self.next()
                continue
            self.expect(")", "to close the argument list")
            return args, ats

    def atom(self):
        t = self.tok
        if t.kind == "NUM":
            self.next()
            return _literal(t)
        if self.at("("):
            self.next()
            first = self.expr()
            if not (self.at(",") or self.at(";")):
                self.expect(")", "to close the parenthesis")
                return first
            sep = self.tok.text
            items = [first]
            while self.at(sep):
                self.next()
                items.append(self.expr())
            if self.at(";" if sep == "," else ","):
                fail("mix of ',' and ';' in one vector; nest the rows: ((a, b); (c, d))", self.tok)
            self.expect(")", "to close the vector")
            return V.stack(items, sep, t)
        if self.at("["):
            self.next()
            lo = self.expr()
            self.expect(",", "in the interval")
            hi = self.expr()
            self.expect("]", "to close the interval")
            return V.interval(lo, hi, t)
        if t.kind == "ID":
            self.next()
            name = t.text
            if name == "oo":
                return Infinity(1)
            if name in _BUILTINS or name in self.functions:
                if not self.at("("):
                    fail(f"expected '(' after {name}, found {self.found()}", self.tok)
                args, _ = self.arguments(self.next())
                if name in _BUILTINS:
                    return V.function(name, args, t)
                return self.call(name, args, t)
            return self.lookup(t)
        fail(f"expected an expression, found {self.found()}", t)

    def lookup(self, t: Token):
        name = t.text
        if name in self.locals:
            return self.locals[name]
        if name in self.variables:
            if self.in_function:
                fail(f"variable {name!r} is not visible inside a function; pass it as an "
                     "argument", t)  # fmt: skip
            return self.variables[name]
        if name in self.constants:
            return self.constants[name]
        fail(f"unknown name {name!r}", t)


def parse(text: str, limits: Limits = LIMITS) -> Model:
    """Read Minibex text into a :class:`Model` (square or not).

    Raises :class:`~.lexer.MinibexError` (and nothing else) for any text.
    """
    p = _Parser(text, limits)
    try:
        return p.parse()
    except RecursionError:  # the depth limit is far below Python's: a deep caller
        raise MinibexError("nesting too deep", p.tok.line, p.tok.col) from None
