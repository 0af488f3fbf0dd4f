"""Parser for the Minibex subset used by IBEX benchmark files (and Realpaver's ``==``).

::

    // comments with '//' or '#'
    Constants
      a = 2.5;
      r = [0.1, 0.2];          // interval constants are allowed
    Variables
      x in [-1, 1];
      y, z in [-a, a];
    Constraints
      x^2 + y^2 = 1;           // '=' or '==': an equation of the square system
      x*y - z == 0;
      x + y <= 2;              // '<=' / '>=': extra constraints (contraction only)
    end

Expressions: numbers, constants, variables, ``+ - * / ^`` (integer exponents), unary
minus, parentheses, ``[lo, hi]``, ``pi`` and the functions ``sqr sqrt exp log sin cos abs
min max``.  Decimal literals that no binary float equals (``0.1``) become the tightest
enclosing interval, so the parsed system contains the written one; variable domains are
rounded outward in the same way.  The parser is a hand-written recursive descent: nothing
in the file is ever evaluated as Python.  Errors raise :class:`MinibexError` naming the line
and column.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from . import node as N
from .graph import Graph
from .node import Expr
from .system import Constraint, System

__all__ = ["MinibexError", "parse_minibex", "load_minibex", "load_system", "decimal_enclosure"]


class MinibexError(ValueError):
    """A syntax or semantic error in a Minibex file, with its position."""

    def __init__(self, message: str, line: int, col: int):
        super().__init__(f"line {line}, column {col}: {message}")
        self.line = line
        self.col = col
        self.reason = message


@dataclass
class Token:
    kind: str  # NUM, ID, OP, EOF
    text: str
    line: int
    col: int


_TOKEN_RE = re.compile(
    r"""
    (?P<ws>[ \t\r\f\v]+)
  | (?P<nl>\n)
  | (?P<comment>(?://|\#)[^\n]*)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<id>[A-Za-z_][A-Za-z_0-9]*)
  | (?P<op>==|<=|>=|[-+*/^()\[\],;=<>:])
    """,
    re.VERBOSE,
)

_FUNCS1 = {
    "sqr": N.sqr,
    "sqrt": N.sqrt,
    "exp": N.exp,
    "log": N.log,
    "ln": N.log,
    "sin": N.sin,
    "cos": N.cos,
    "abs": N.abs_,
}
_FUNCS2 = {"min": N.min_, "max": N.max_}
_SECTIONS = {"constants", "variables", "constraints", "end"}


def decimal_enclosure(text: str) -> tuple[float, float]:
    """Tightest float interval containing the exact decimal ``text``.

    Raises ``OverflowError`` for a decimal beyond the float range.
    """
    exact = Fraction(text)
    f = float(exact)  # OverflowError beyond ~1.8e308
    fx = Fraction(f)
    if fx == exact:
        return f, f
    if fx < exact:
        return f, float(np.nextafter(f, np.inf))
    return float(np.nextafter(f, -np.inf)), f


def _tokenize(text: str) -> list[Token]:
    toks: list[Token] = []
    pos, line, line_start = 0, 1, 0
    while pos < len(text):
        m = _TOKEN_RE.match(text, pos)
        col = pos - line_start + 1
        if not m:
            raise MinibexError(f"unexpected character {text[pos]!r}", line, col)
        kind = m.lastgroup
        if kind == "nl":
            line += 1
            line_start = m.end()
        elif kind == "num":
            toks.append(Token("NUM", m.group(), line, col))
        elif kind == "id":
            toks.append(Token("ID", m.group(), line, col))
        elif kind == "op":
            toks.append(Token("OP", m.group(), line, col))
        pos = m.end()
    toks.append(Token("EOF", "", line, pos - line_start + 1))
    return toks


class _Parser:
    def __init__(self, text: str):
        self.toks = _tokenize(text)
        self.i = 0
        self.constants: dict[str, Expr] = {"pi": N.const(np.pi, float(np.nextafter(np.pi, np.inf)))}
        self.variables: dict[str, tuple[float, float]] = {}
        self.var_exprs: dict[str, Expr] = {}
        self.equations: list[Expr] = []
        self.constraints: list[Constraint] = []

    # -- token helpers ------------------------------------------------------------------
    @property
    def tok(self) -> Token:
        return self.toks[self.i]

    def error(self, msg: str, tok: Token | None = None):
        t = tok or self.tok
        raise MinibexError(msg, t.line, t.col)

    def next(self) -> Token:
        t = self.tok
        self.i += 1
        return t

    def at(self, text: str) -> bool:
        return self.tok.kind in ("OP", "ID") and self.tok.text == text

    def at_keyword(self, word: str) -> bool:
        return self.tok.kind == "ID" and self.tok.text.lower() == word

    def expect(self, text: str, what: str):
        if not self.at(text):
            found = self.tok.text or "end of file"
            self.error(f"expected {text!r} {what}, found {found!r}", self._after_previous())
        return self.next()

    def _after_previous(self) -> Token:
        """Where a missing terminator belongs: just after the previous token."""
        if self.i == 0:
            return self.tok
        prev = self.toks[self.i - 1]
        return Token(prev.kind, prev.text, prev.line, prev.col + len(prev.text))

    # -- grammar --------------------------------------------------------------------------
    def parse(self) -> System:
        if self.at_keyword("constants"):
            self.next()
            while self.tok.kind == "ID" and self.tok.text.lower() not in _SECTIONS:
                self.constant_decl()
        if not self.at_keyword("variables"):
            self.error("expected the 'Variables' section")
        self.next()
        while self.tok.kind == "ID" and self.tok.text.lower() not in _SECTIONS:
            self.variable_decl()
        if not self.variables:
            self.error("no variables declared")
        if not self.at_keyword("constraints"):
            self.error("expected the 'Constraints' section")
        self.next()
        while not (self.at_keyword("end") or self.tok.kind == "EOF"):
            self.constraint()
        if self.at_keyword("end"):
            self.next()
        if self.tok.kind != "EOF":
            self.error(f"unexpected {self.tok.text!r} after 'end'")
        names = list(self.variables)
        n, m = len(names), len(self.equations)
        if m != n:
            raise MinibexError(
                f"the system is not square: {m} equations for {n} variables", self.tok.line, 1
            )
        domain = np.array([self.variables[v] for v in names])
        return System(names, domain, self.equations, self.constraints)

    def constant_decl(self):
        name_tok = self.next()
        self.check_new_name(name_tok)
        if not (self.at("=") or self.at(":=")):
            self.error(f"expected '=' after constant {name_tok.text!r}")
        self.next()
        e = self.expr()
        if e.variables():
            self.error("a constant cannot depend on variables", name_tok)
        self.constants[name_tok.text] = e
        self.expect(";", f"after constant {name_tok.text!r}")

    def check_new_name(self, tok: Token):
        if tok.kind != "ID":
            self.error(f"expected a name, found {tok.text!r}", tok)
        name = tok.text
        if name.lower() in _SECTIONS or name in _FUNCS1 or name in _FUNCS2 or name == "in":
            self.error(f"{name!r} is a reserved word", tok)
        if name in self.constants or name in self.variables:
            self.error(f"{name!r} is already declared", tok)

    def variable_decl(self):
        names = [self.next()]
        self.check_new_name(names[0])
        while self.at(","):
            self.next()
            t = self.next()
            self.check_new_name(t)
            names.append(t)
        if self.at("["):
            self.error("vector variables are not supported; declare each component")
        if not self.at_keyword("in"):
            self.error(f"expected 'in [lo, hi]' after variable {names[-1].text!r}")
        self.next()
        open_tok = self.expect("[", "to start the domain")
        lo_e = self.expr()
        self.expect(",", "between the domain bounds")
        hi_e = self.expr()
        self.expect("]", "to close the domain")
        self.expect(";", "after the variable declaration")
        lo = self.constant_value(lo_e, open_tok)[0]
        hi = self.constant_value(hi_e, open_tok)[1]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            self.error("variable domains must be bounded", open_tok)
        if lo > hi:
            self.error(f"empty domain [{lo}, {hi}]", open_tok)
        for t in names:
            self.variables[t.text] = (lo, hi)
            self.var_exprs[t.text] = N.var(t.text)

    def constant_value(self, e: Expr, tok: Token) -> tuple[float, float]:
        if e.variables():
            self.error("domain bounds must be constants", tok)
        g = Graph([])
        try:
            nid = g.add_expr(e)
        except ValueError as exc:
            self.error(str(exc), tok)
        return g.param[nid]

    def constraint(self):
        lhs = self.expr()
        if self.at("=") or self.at("=="):
            self.next()
            rhs = self.expr()
            self.equations.append(lhs - rhs)
        elif self.at("<=") or self.at(">="):
            op = self.next().text
            rhs = self.expr()
            diff = lhs - rhs if op == "<=" else rhs - lhs
            self.constraints.append(Constraint(diff, -np.inf, 0.0))
        elif self.at("<") or self.at(">"):
            self.error("strict inequalities are not supported; use <= or >=")
        else:
            found = self.tok.text or "end of file"
            self.error(f"expected '=', '==', '<=' or '>=' in constraint, found {found!r}")
        if self.at(";"):
            self.next()
        elif not (self.at_keyword("end") or self.tok.kind == "EOF"):
            self.error("expected ';' after the constraint", self._after_previous())

    # expression := term (('+'|'-') term)*
    def expr(self) -> Expr:
        e = self.term()
        while self.at("+") or self.at("-"):
            op = self.next().text
            r = self.term()
            e = e + r if op == "+" else e - r
        return e

    # term := unary (('*'|'/') unary)*
    def term(self) -> Expr:
        e = self.unary()
        while self.at("*") or self.at("/"):
            op = self.next().text
            r = self.unary()
            e = e * r if op == "*" else e / r
        return e

    # unary := '-' unary | '+' unary | power
    def unary(self) -> Expr:
        if self.at("-"):
            self.next()
            return -self.unary()
        if self.at("+"):
            self.next()
            return self.unary()
        return self.power()

    # power := atom ('^' exponent)?   (exponent: optional sign, integer, or parenthesised)
    def power(self) -> Expr:
        base = self.atom()
        if self.at("^"):
            tok = self.next()
            sign = 1
            if self.at("-"):
                self.next()
                sign = -1
            if self.tok.kind == "NUM":
                t = self.next()
                val = Fraction(t.text)
            elif self.at("("):
                self.next()
                ex = self.expr()
                self.expect(")", "after the exponent")
                lo, hi = self.constant_value(ex, tok)
                if lo != hi:
                    self.error("the exponent must be an exact integer", tok)
                val = Fraction(lo)
            else:
                self.error("expected an integer exponent after '^'")
            val *= sign
            if val.denominator != 1:
                self.error("only integer exponents are supported (use exp(a*log(x)))", tok)
            return N.pow(base, int(val))
        return base

    def atom(self) -> Expr:
        t = self.tok
        if t.kind == "NUM":
            self.next()
            try:
                return N.const(*decimal_enclosure(t.text))
            except OverflowError:
                self.error(f"number {t.text} is beyond the double-precision range", t)
        if self.at("("):
            self.next()
            e = self.expr()
            self.expect(")", "to close the parenthesis")
            return e
        if self.at("["):
            self.next()
            lo_e = self.expr()
            self.expect(",", "in the interval constant")
            hi_e = self.expr()
            self.expect("]", "to close the interval constant")
            lo = self.constant_value(lo_e, t)[0]
            hi = self.constant_value(hi_e, t)[1]
            if lo > hi:
                self.error(f"empty interval [{lo}, {hi}]", t)
            return N.const(lo, hi)
        if t.kind == "ID":
            self.next()
            name = t.text
            if name in _FUNCS1 or name in _FUNCS2:
                self.expect("(", f"after {name}")
                args = [self.expr()]
                while self.at(","):
                    self.next()
                    args.append(self.expr())
                self.expect(")", f"to close {name}(...)")
                want = 1 if name in _FUNCS1 else 2
                if len(args) != want:
                    self.error(f"{name} takes {want} argument(s), got {len(args)}", t)
                fn = _FUNCS1.get(name) or _FUNCS2[name]
                return fn(*args)
            if name in self.var_exprs:
                return self.var_exprs[name]
            if name in self.constants:
                return self.constants[name]
            self.error(f"unknown name {name!r}", t)
        found = t.text or "end of file"
        self.error(f"expected an expression, found {found!r}")


def parse_minibex(text: str, name: str = "") -> System:
    """Parse Minibex text into a :class:`System` (raises :class:`MinibexError`)."""
    system = _Parser(text).parse()
    system.name = name
    return system


def load_minibex(path) -> System:
    from pathlib import Path

    p = Path(path)
    return parse_minibex(p.read_text(), name=p.stem)


def load_system(source, name: str = "") -> System:
    """A system from Minibex text or a file path (text is recognised by its sections:
    it contains ``Variables``).  Raises :class:`MinibexError`, or ``OSError`` for a file
    that cannot be read."""
    from pathlib import Path

    text = str(source)
    if isinstance(source, Path) or "\n" not in text and "Variables" not in text:
        return load_minibex(source)
    return parse_minibex(text, name=name)
