"""A hash-consed expression DAG: shared sub-expressions, constant folding, derivatives.

:class:`Graph` stores nodes in creation order (children always before parents), each as
``(op, args, param)``.  Creating a node that already exists returns the existing id, so
structurally equal sub-expressions are shared across all equations of a system and across
their derivatives.  A few rewrites keep the DAG small and the interval evaluation tight:

* constant sub-expressions are folded with outward-rounded interval arithmetic;
* ``x + c`` and ``c * x`` with a point constant ``c`` become ``cadd`` / ``cmul``;
* ``x + 0``, ``x * 1``, ``x * 0``, ``-(-x)`` are removed; ``x * x`` becomes ``sqr(x)``;
* arguments of commutative operations are put in a canonical order.

Derivatives are symbolic (:meth:`Graph.derivative`) and land in the same DAG, so the
Jacobian and the functions share their common sub-expressions.  For the non-smooth
``abs``, ``min`` and ``max`` the "derivative" is an enclosure of the generalised gradient
(``sign`` and the hull of the branch derivatives); ``sign`` has derivative 0 off its jump.
Boxes containing such a non-smooth point are not certified anyway
(:data:`.ops.SMOOTH`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import cast

import numpy as np

from .node import OPS, Expr
from .ops import FORWARD

__all__ = ["CompileTimeout", "Graph", "check_deadline"]


class CompileTimeout(TimeoutError):
    """Compiling a system passed its ``deadline`` (a :func:`time.monotonic` value):
    ``stage`` names the step it was in.  Raised between units of work (a row of the
    Jacobian, a program), so a system too large for its time limit stops within about one
    unit of the limit instead of after the whole compile."""

    def __init__(self, stage: str):
        super().__init__(f"the time limit passed while {stage}")
        self.stage = stage


def check_deadline(deadline: float | None, stage: str) -> None:
    """Raise :class:`CompileTimeout` naming ``stage`` if ``deadline`` has passed."""
    if deadline is not None and time.monotonic() > deadline:
        raise CompileTimeout(stage)


_COMMUTATIVE = {"add", "mul", "min", "max", "hull"}


def _one_plus_sqr(g: Graph, u: int) -> int:
    return g.node("cadd", (g.node("sqr", (u,)),), 1.0)


def _one_minus_sqr(g: Graph, u: int) -> int:
    return g.node("cadd", (g.node("neg", (g.node("sqr", (u,)),)),), 1.0)


def _recip(g: Graph, u: int) -> int:
    return g.node("div", (g.const(1.0), u))


# d f(a) / d a as a node, for unary f: (graph, node of f(a), node of a) -> node
_CHAIN = {
    "tan": lambda g, x, a: _one_plus_sqr(g, x),
    "sinh": lambda g, x, a: g.node("cosh", (a,)),
    "cosh": lambda g, x, a: g.node("sinh", (a,)),
    "tanh": lambda g, x, a: _one_minus_sqr(g, x),
    "atan": lambda g, x, a: _recip(g, _one_plus_sqr(g, a)),
    "asin": lambda g, x, a: _recip(g, g.node("sqrt", (_one_minus_sqr(g, a),))),
    "acos": lambda g, x, a: g.node("neg", (_recip(g, g.node("sqrt", (_one_minus_sqr(g, a),))),)),
    "asinh": lambda g, x, a: _recip(g, g.node("sqrt", (_one_plus_sqr(g, a),))),
    "acosh": lambda g, x, a: _recip(
        g, g.node("sqrt", (g.node("cadd", (g.node("sqr", (a,)),), -1.0),))
    ),
    "atanh": lambda g, x, a: _recip(g, _one_minus_sqr(g, a)),
}


class Graph:
    """Node table of an expression DAG over fixed, ordered variables and parameters.

    Nodes ``0 .. n-1`` are the variables, nodes ``n .. n+p-1`` the parameters, in order.
    """

    def __init__(self, variables: Sequence[str], parameters: Sequence[str] = ()):
        self.variables = list(variables)
        self.parameters = list(parameters)
        self.var_index = {name: i for i, name in enumerate(self.variables)}
        self.param_index = {name: i for i, name in enumerate(self.parameters)}
        if len(self.var_index) != len(self.variables):
            raise ValueError("duplicate variable names")
        if len(self.param_index) != len(self.parameters) or set(self.var_index) & set(
            self.param_index
        ):
            raise ValueError("parameter names must be distinct from each other and the variables")
        self.op: list[str] = []
        self.args: list[tuple[int, ...]] = []
        self.param: list = []
        self.depends: list[int] = []  # bitmask of variables each node depends on
        self._key: dict = {}
        self._deriv: dict[tuple[int, int], int | None] = {}
        for i in range(len(self.variables)):
            self._make("var", (), i)
        for i in range(len(self.parameters)):
            self._make("param", (), i)

    def __len__(self) -> int:
        return len(self.op)

    # -- node creation ------------------------------------------------------------------
    def _make(self, op: str, args: tuple[int, ...], param) -> int:
        key = (op, args, param)
        nid = self._key.get(key)
        if nid is None:
            nid = len(self.op)
            self.op.append(op)
            self.args.append(args)
            self.param.append(param)
            dep = (1 << param) if op == "var" else 0
            for a in args:
                dep |= self.depends[a]
            self.depends.append(dep)
            self._key[key] = nid
        return nid

    def const(self, lo: float, hi: float | None = None) -> int:
        lo = float(lo)
        hi = lo if hi is None else float(hi)
        return self._make("const", (), (lo, hi))

    def point_value(self, nid: int) -> float | None:
        """The value of a point constant node, else None."""
        if self.op[nid] == "const":
            lo, hi = self.param[nid]
            if lo == hi:
                return lo
        return None

    def node(self, op: str, args: Sequence[int] = (), param=None) -> int:
        """Create (or find) a node, applying the simplifications listed in the module doc."""
        args = tuple(int(a) for a in args)
        if op in ("var", "param", "const"):
            raise ValueError("use the variable / parameter index or Graph.const")
        if len(args) != OPS[op]:
            raise ValueError(f"{op} takes {OPS[op]} arguments")
        if all(self.op[a] == "const" for a in args):
            return self._fold(op, args, param)
        pv = [self.point_value(a) for a in args]
        if op == "add":
            if pv[0] is not None:
                return args[1] if pv[0] == 0.0 else self.node("cadd", (args[1],), pv[0])
            if pv[1] is not None:
                return args[0] if pv[1] == 0.0 else self.node("cadd", (args[0],), pv[1])
        elif op == "sub":
            if pv[1] is not None:
                return args[0] if pv[1] == 0.0 else self.node("cadd", (args[0],), -pv[1])
            if pv[0] is not None:
                n = self.node("neg", (args[1],))
                return n if pv[0] == 0.0 else self.node("cadd", (n,), pv[0])
            if args[0] == args[1]:
                return self.const(0.0)
        elif op == "mul":
            for k in (0, 1):
                c, other = pv[k], args[1 - k]
                if c is not None:
                    if c == 0.0:
                        return self.const(0.0)
                    if c == 1.0:
                        return other
                    if c == -1.0:
                        return self.node("neg", (other,))
                    return self.node("cmul", (other,), c)
            if args[0] == args[1]:
                return self.node("sqr", (args[0],))
        elif op == "div":
            c = pv[1]
            if c is not None and c != 0.0:
                inv = 1.0 / c
                if inv * c == 1.0 and np.frexp(c)[0] in (0.5, -0.5):  # power of two: exact
                    return self.node("cmul", (args[0],), inv)
            if pv[0] == 0.0:
                return self.const(0.0)
        elif op == "neg":
            a = args[0]
            if self.op[a] == "neg":
                return self.args[a][0]
            if self.op[a] == "cmul":
                return self.node("cmul", self.args[a], -self.param[a])
        elif op == "cmul":
            if param == 1.0:
                return args[0]
            if param == 0.0:
                return self.const(0.0)
        elif op == "cadd":
            if param == 0.0:
                return args[0]
        elif op == "pow":
            param = int(param)
            if param == 1:
                return args[0]
            if param == 2:
                return self.node("sqr", args)
            if param == 0:
                return self.const(1.0)
        if op in _COMMUTATIVE and args[0] > args[1]:
            args = (args[1], args[0])
        if param is not None and op in ("cadd", "cmul"):
            param = float(param)
        return self._make(op, args, param)

    def _fold(self, op: str, args: tuple[int, ...], param) -> int:
        vals: list[np.float64 | None] = [np.float64(v) for a in args for v in self.param[a]]
        if len(vals) == 2:
            vals += [None, None]
        with np.errstate(all="ignore"):
            lo, hi = FORWARD[op](*vals, param)
        lo, hi = float(lo), float(hi)
        if not lo <= hi:
            raise ValueError(f"constant expression {op} is undefined (empty)")
        return self.const(lo, hi)

    def add_expr(self, e: Expr) -> int:
        """Insert an :class:`Expr` tree (iteratively, no recursion limit); return its node id."""
        memo: dict[int, int] = {}
        stack: list[tuple[Expr, bool]] = [(e, False)]
        while stack:
            x, ready = stack.pop()
            if id(x) in memo:
                continue
            if x.op == "var":
                if x.param not in self.var_index:
                    raise KeyError(f"unknown variable {x.param!r}")
                memo[id(x)] = self.var_index[x.param]
            elif x.op == "param":
                if x.param not in self.param_index:
                    raise KeyError(f"unknown parameter {x.param!r}")
                memo[id(x)] = len(self.variables) + self.param_index[x.param]
            elif x.op == "const":
                memo[id(x)] = self.const(*x.param)
            elif ready:
                memo[id(x)] = self.node(x.op, [memo[id(a)] for a in x.args], x.param)
            else:
                stack.append((x, True))
                stack.extend((a, False) for a in x.args if id(a) not in memo)
        return memo[id(e)]

    def copy_nodes(self, src: Graph, roots: Sequence[int], var_offset: int = 0) -> dict[int, int]:
        """Copy the nodes ``roots`` of ``src`` need into this graph, as they are (no rewrite).

        Variable ``j`` of ``src`` becomes variable ``var_offset + j`` here; parameters and
        constants are shared (same index, same value).  Returns the map from ``src`` ids to
        ids here.  The copy computes the same operations in the same order of arguments.
        """
        n_src = len(src.variables)
        mapped: dict[int, int] = {}
        for x in src.ancestors(roots):
            op = src.op[x]
            if op == "var":
                mapped[x] = var_offset + src.param[x]
            elif op == "param":
                mapped[x] = len(self.variables) + (x - n_src)
            elif op == "const":
                mapped[x] = self.const(*src.param[x])
            else:
                mapped[x] = self._make(op, tuple(mapped[a] for a in src.args[x]), src.param[x])
        return mapped

    # -- derivatives -----------------------------------------------------------------------
    def derivative(self, nid: int, k: int) -> int | None:
        """Node id of ``∂node/∂x_k`` (``None`` when it is identically zero)."""
        if not (self.depends[nid] >> k) & 1:
            return None
        key = (nid, k)
        if key in self._deriv:
            return self._deriv[key]
        # iterative post-order over the nodes that depend on x_k
        order: list[int] = []
        stack = [(nid, False)]
        seen: set[int] = set()
        while stack:
            x, ready = stack.pop()
            if ready:
                order.append(x)
                continue
            if x in seen or (x, k) in self._deriv or not (self.depends[x] >> k) & 1:
                continue
            seen.add(x)
            stack.append((x, True))
            stack.extend((a, False) for a in self.args[x])
        for x in order:
            self._deriv[(x, k)] = self._d(x, k)
        return self._deriv[key]

    def _dk(self, x: int, k: int) -> int | None:
        if not (self.depends[x] >> k) & 1:
            return None
        return self._deriv[(x, k)]

    def _d(self, x: int, k: int) -> int | None:
        op, args, p = self.op[x], self.args[x], self.param[x]
        N = self.node
        if op == "var":
            return self.const(1.0) if p == k else None
        da = self._dk(args[0], k)
        db = self._dk(args[1], k) if len(args) == 2 else None
        zero = self.const(0.0)

        def mul(u, v):
            return N("mul", (u, v))

        if op in ("add", "sub"):
            if db is None:
                return da
            if da is None:
                return db if op == "add" else N("neg", (db,))
            return N(op, (da, db))
        # a unary node depends on x_k through its argument, so da is set from here on
        du = cast(int, da)
        if op == "neg":
            return N("neg", (du,))
        if op == "cadd":
            return da
        if op == "cmul":
            return N("cmul", (du,), p)
        a = args[0]
        if op == "mul":
            b = args[1]
            terms = []
            if da is not None:
                terms.append(mul(da, b))
            if db is not None:
                terms.append(mul(a, db))
            return terms[0] if len(terms) == 1 else N("add", tuple(terms))
        if op == "div":
            b = args[1]
            # d(a/b) = (da - (a/b) db) / b
            num = da if da is not None else zero
            if db is not None:
                num = N("sub", (num, mul(x, db)))
            return N("div", (num, b))
        if op == "sqr":
            return N("cmul", (mul(a, da),), 2.0)
        if op == "pow":
            return N("cmul", (mul(N("pow", (a,), p - 1), da),), float(p))
        if op == "sqrt":
            return N("div", (du, N("cmul", (x,), 2.0)))
        if op == "exp":
            return mul(x, da)
        if op == "log":
            return N("div", (du, a))
        if op == "sin":
            return mul(N("cos", (a,)), da)
        if op == "cos":
            return N("neg", (mul(N("sin", (a,)), da),))
        if op in _CHAIN:
            return mul(_CHAIN[op](self, x, a), da)
        if op == "atan2":  # atan2(y, x): (x dy - y dx) / (x^2 + y^2)
            y, xx = args
            r2 = N("add", (N("sqr", (y,)), N("sqr", (xx,))))
            terms = []
            if da is not None:
                terms.append(mul(xx, da))
            if db is not None:
                terms.append(N("neg", (mul(y, db),)))
            num = terms[0] if len(terms) == 1 else N("add", tuple(terms))
            return N("div", (num, r2))
        if op == "rpow":  # x^y: y x^(y-1) dx + x^y log(x) dy
            b = args[1]
            terms = []
            if da is not None:
                terms.append(mul(mul(b, N("rpow", (a, N("cadd", (b,), -1.0)))), da))
            if db is not None:
                terms.append(mul(mul(x, N("log", (a,))), db))
            return terms[0] if len(terms) == 1 else N("add", tuple(terms))
        if op == "abs":
            return mul(N("sign", (a,)), da)
        if op == "sign":
            return None  # zero almost everywhere
        if op in ("min", "max", "hull"):
            return N("hull", (da if da is not None else zero, db if db is not None else zero))
        raise NotImplementedError(op)  # pragma: no cover

    def ancestors(self, outputs: Sequence[int]) -> list[int]:
        """The nodes ``outputs`` depend on, themselves included, in topological order."""
        needed: set[int] = set()
        stack = [int(o) for o in outputs]
        while stack:
            x = stack.pop()
            if x not in needed:
                needed.add(x)
                stack.extend(self.args[x])
        return sorted(needed)  # ids are topologically ordered

    def jacobian(
        self, roots: Sequence[int], deadline: float | None = None
    ) -> list[list[int | None]]:
        """``J[i][k] = ∂roots[i]/∂x_k`` as node ids (``None`` for structural zeros).

        ``deadline`` (:func:`time.monotonic`): checked before each row
        (:class:`CompileTimeout`); a dense system's rows cost ``n`` times its equation's DAG.
        """
        rows = []
        for r in roots:
            check_deadline(deadline, "differentiating the equations")
            rows.append([self.derivative(r, k) for k in range(len(self.variables))])
        return rows
