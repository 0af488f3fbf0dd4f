"""Polynomial equations: exact expansion, and an equivalent system of lower degree.

Many systems hold fewer distinct leading monomials than equations.  Dietmaier's Stewart
platform (12 quadratic equations in the 12 coordinates of four points) is the plain case:
every equation is a distance, so its quadratic part is a combination of the 10 Gram
products ``b_i . b_j``, and two combinations of the 12 equations are *linear*.  An interval
solver sees none of that: each equation is contracted alone, and the cancellation happens
only in exact arithmetic.

:func:`expand` writes an expression as ``sum_m c_m x^m`` with exact rational interval
coefficients ``c_m = [lo, hi]`` (a constant of the system is an interval, so its expansion
encloses every polynomial the constants allow).  :func:`reduce_degree` runs Gauss-Jordan
elimination, in exact rationals, on the midpoints of the coefficient matrix (columns ordered
by decreasing degree), so each reduced row ``r = sum_k T_rk f_k`` cancels its leading
monomials exactly.  A row of lower degree than the equations it combines replaces one of
them.  The new system ``g = A f`` (``A`` = identity except the replaced rows, whose entries
are ``T``) has

* the same zeros: ``A`` is nonsingular, checked exactly (the submatrix ``T[rows, replaced]``
  has full rank in rationals);
* a unique zero in a box exactly when ``f`` has one, so Krawczyk's proof on ``g`` certifies
  a solution of ``f``;
* enclosures: each coefficient of ``g`` is ``sum_k T_rk [c_k]`` in exact rational interval
  arithmetic, rounded outward to binary64 -- so ``g``'s expression encloses ``A f`` for
  every value the constants may take.

Equations that are not polynomial in the variables (a parameter, a transcendental
function, a division by a non-constant, more than ``max_terms`` monomials) keep their form
and take no part in the elimination.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..interval.rounding import rational_enclosure
from .node import Expr, const, esum, pow, var
from .system import System

__all__ = ["expand", "degree_reductions", "reduce_degree", "Polynomial"]

#: exact interval [lo, hi] of rationals
Coefficient = tuple[Fraction, Fraction]
#: exponent tuple (one per variable) -> coefficient
Polynomial = dict[tuple[int, ...], Coefficient]

_ONE = (Fraction(1), Fraction(1))
_FLOAT_MAX = Fraction(float(np.finfo(float).max))


def _mul_c(a: Coefficient, b: Coefficient) -> Coefficient:
    if a[0] == a[1] and b[0] == b[1]:
        p = a[0] * b[0]
        return (p, p)
    ps = (a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1])
    return (min(ps), max(ps))


def _add_into(out: Polynomial, m: tuple[int, ...], c: Coefficient) -> None:
    old = out.get(m)
    out[m] = c if old is None else (old[0] + c[0], old[1] + c[1])


def _scale(p: Polynomial, c: Coefficient) -> Polynomial:
    return {m: _mul_c(c, v) for m, v in p.items()}


def _mul(p: Polynomial, q: Polynomial) -> Polynomial:
    out: Polynomial = {}
    for m1, c1 in p.items():
        for m2, c2 in q.items():
            _add_into(out, tuple(a + b for a, b in zip(m1, m2, strict=True)), _mul_c(c1, c2))
    return out


def _constant_value(p: Polynomial) -> Coefficient | None:
    """The value of a polynomial without variables, else ``None``."""
    if any(any(m) for m in p):
        return None
    return next(iter(p.values()), (Fraction(0), Fraction(0)))


def expand(expr: Expr, variables: list[str], max_terms: int = 400) -> Polynomial | None:
    """``expr`` as an exact polynomial in ``variables``, or ``None`` if it is not one.

    Handles variables, finite constants, ``+ - *``, ``neg``, ``sqr``, non-negative integer
    powers and division by a constant interval without zero; anything else (or more than
    ``max_terms`` monomials at any node) gives ``None``.
    """
    index = {v: i for i, v in enumerate(variables)}
    zero = (0,) * len(variables)
    memo: dict[int, Polynomial | None] = {}

    def go(root: Expr) -> Polynomial | None:
        # children before parents with an explicit stack, not recursion: a sum of a few
        # thousand terms is a chain that deep (IBEX's Yamamura1-0400)
        stack = [root]
        while stack:
            e = stack[-1]
            if id(e) in memo:
                stack.pop()
                continue
            todo = [a for a in e.args if id(a) not in memo]
            if todo:
                stack.extend(todo)
                continue
            stack.pop()
            res = _node(e)
            memo[id(e)] = None if res is not None and len(res) > max_terms else res
        return memo[id(root)]

    def product(p: Polynomial, q: Polynomial) -> Polynomial | None:
        # bounds the work as well as the result: at most 16 max_terms products
        return _mul(p, q) if len(p) * len(q) <= 16 * max_terms else None

    def _node(e: Expr) -> Polynomial | None:
        op = e.op
        if op == "var":
            k = index[e.param]
            return {zero[:k] + (1,) + zero[k + 1 :]: _ONE}
        if op == "const":
            lo, hi = e.param
            if not (math.isfinite(lo) and math.isfinite(hi)):
                return None
            return {zero: (Fraction(lo), Fraction(hi))}
        maybe = [memo[id(a)] for a in e.args]  # computed first (go)
        args = [a for a in maybe if a is not None]
        if len(args) < len(maybe):
            return None
        if op in ("add", "sub"):
            out = dict(args[0])
            sign = 1 if op == "add" else -1
            for m, (lo, hi) in args[1].items():
                _add_into(out, m, (lo, hi) if sign == 1 else (-hi, -lo))
            return out
        if op == "neg":
            return {m: (-hi, -lo) for m, (lo, hi) in args[0].items()}
        if op == "mul":
            return product(args[0], args[1])
        if op == "sqr":
            return product(args[0], args[0])
        if op == "pow" and isinstance(e.param, int) and e.param >= 0:
            power: Polynomial | None = {zero: _ONE}
            for _ in range(e.param):
                power = product(power, args[0]) if power is not None else None
                if power is None or len(power) > max_terms:
                    return None
            return power
        if op == "cadd":
            out = dict(args[0])
            c = Fraction(float(e.param))
            _add_into(out, zero, (c, c))
            return out
        if op == "cmul":
            c = Fraction(float(e.param))
            return _scale(args[0], (c, c))
        if op == "div":
            d = _constant_value(args[1])
            if d is None or d[0] <= 0 <= d[1]:
                return None
            return _scale(args[0], (1 / d[1], 1 / d[0]))
        return None

    return go(expr)


def _degree(p: Polynomial) -> int:
    return max((sum(m) for m, (lo, hi) in p.items() if lo != 0 or hi != 0), default=0)


def _to_expr(p: Polynomial, variables: list[str]) -> Expr:
    """``sum_m [c_m] x^m``, each coefficient rounded outward to binary64.

    Terms whose coefficient straddles 0 (``|c_m| <= r_m``: their midpoints cancelled, only
    the constants' uncertainty is left) of even degree ``d`` are bounded together by
    weighted AM-GM, ``|x^m| <= sum_i (m_i / d) x_i^d <= S_d = sum_i x_i^d``::

        sum_m c_m x^m  in  [-R_d, R_d] * S_d,   R_d = sum_m r_m,

    one product per degree instead of one per monomial, and ``S_d`` is the same node in
    every equation over the same variables.
    """
    terms = []
    cancelled: dict[int, tuple[Fraction, set[int]]] = {}
    for m, (lo, hi) in sorted(p.items(), key=lambda t: (-sum(t[0]), t[0])):
        if lo == 0 and hi == 0:
            continue
        d = sum(m)
        if d and d % 2 == 0 and lo < 0 < hi:
            r, used = cancelled.get(d, (Fraction(0), set()))
            cancelled[d] = (r + max(-lo, hi), used | {i for i, k in enumerate(m) if k})
            continue
        c = const(rational_enclosure(lo)[0], rational_enclosure(hi)[1])
        mono = _monomial(m, variables)
        terms.append(c if mono is None else mono if (lo, hi) == _ONE else c * mono)
    for d, (r, used) in sorted(cancelled.items()):
        s_d = esum([pow(var(variables[i]), d) for i in sorted(used)])
        bound = rational_enclosure(r)[1]
        terms.append(const(-bound, bound) * s_d)
    return esum(terms)


def _monomial(m: tuple[int, ...], variables: list[str]) -> Expr | None:
    factors = [var(v) if k == 1 else pow(var(v), k) for v, k in zip(variables, m, strict=True) if k]
    if not factors:
        return None
    mono = factors[0]
    for f in factors[1:]:
        mono = mono * f
    return mono


def gauss_jordan(rows: list[list[Fraction]], cols: int) -> int:
    """Reduce ``rows`` in place (exact rationals) on their first ``cols`` columns: each
    pivot row scaled to a leading 1, its column cleared in every other row.  Returns the
    number of pivots (the rank over those columns)."""
    top = 0
    for j in range(cols):
        piv = next((i for i in range(top, len(rows)) if rows[i][j] != 0), None)
        if piv is None:
            continue
        rows[top], rows[piv] = rows[piv], rows[top]
        rows[top] = [x / rows[top][j] for x in rows[top]]
        for i in range(len(rows)):
            if i != top and rows[i][j] != 0:
                f = rows[i][j]
                rows[i] = [x - f * y for x, y in zip(rows[i], rows[top], strict=True)]
        top += 1
        if top == len(rows):
            break
    return top


def _may_lower(polys: dict[int, Polynomial]) -> bool:
    """Whether some combination may lower a degree (a cheap screen in floating point).

    If ``sum_k T_k f_k`` has degree below ``D``, the largest degree of the ``f_k`` it
    combines, the degree-``D`` monomials of the degree-``D`` equations cancel: their rows
    (over those monomials) are dependent.  So when, for every degree ``D``, those rows are
    clearly independent (smallest singular value above ``1e-6`` of the largest, rows scaled
    to unit norm), nothing lowers a degree and the exact elimination is skipped.
    """
    by_degree: dict[int, list[Polynomial]] = {}
    for p in polys.values():
        by_degree.setdefault(_degree(p), []).append(p)
    for d, group in by_degree.items():
        monos = sorted({m for p in group for m in p if sum(m) == d})
        if len(group) > len(monos):
            return True
        col = {m: j for j, m in enumerate(monos)}
        a = np.zeros((len(group), len(monos)))
        for i, p in enumerate(group):
            for m, (lo, hi) in p.items():
                if sum(m) == d:
                    a[i, col[m]] = float((lo + hi) / 2)
        a /= np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-300)
        sv = np.linalg.svd(a, compute_uv=False)
        if not np.all(np.isfinite(sv)) or sv[-1] <= 1e-6 * sv[0]:
            return True
    return False


def degree_reductions(
    system: System, max_equations: int = 40, max_terms: int = 400
) -> dict[int, dict[int, Fraction]]:
    """The combinations that lower a degree: ``{replaced equation: {equation: T_k}}``.

    Gauss-Jordan elimination, in exact rationals, of the midpoints of the polynomial
    equations' coefficients (columns by decreasing degree, so a reduced row has cancelled
    every leading monomial it could).  A reduced row ``sum_k T_k f_k`` of degree ``d`` below
    that of some ``f_k`` it combines replaces the one of them with the most monomials that
    keeps the submatrix ``T[rows, replaced]`` of full rank (exact), so the new system is
    ``A f`` with ``A`` nonsingular.  Lowest degrees first.  Empty when nothing lowers a
    degree, or with fewer than 2 or more than ``max_equations`` polynomial equations.
    """
    return _reductions(_polynomials(system, max_terms), max_equations)


def _polynomials(system: System, max_terms: int) -> dict[int, Polynomial]:
    """The expansions of the system's polynomial equations, by equation index (those with
    a coefficient beyond the float range left out)."""
    polys = {}
    for k, eq in enumerate(system.equations):
        p = expand(eq, system.variables, max_terms)
        if p is not None and all(max(-lo, hi) <= _FLOAT_MAX for lo, hi in p.values()):
            polys[k] = p
    return polys


def _reductions(polys: dict[int, Polynomial], max_equations: int) -> dict[int, dict[int, Fraction]]:
    """:func:`degree_reductions` of the expanded equations ``polys``."""
    eqs = sorted(polys)
    if not 2 <= len(eqs) <= max_equations or not _may_lower(polys):
        return {}
    monos = sorted({m for p in polys.values() for m in p}, key=lambda m: (-sum(m), m))
    col = {m: j for j, m in enumerate(monos)}
    ne, nm = len(eqs), len(monos)
    # [M_mid | I]: Gauss-Jordan keeps T (the combination) in the right block
    rows = []
    for i, k in enumerate(eqs):
        r = [Fraction(0)] * (nm + ne)
        for m, (lo, hi) in polys[k].items():
            r[col[m]] = (lo + hi) / 2
        r[nm + i] = Fraction(1)
        rows.append(r)
    gauss_jordan(rows, nm)
    degree = [_degree(polys[k]) for k in eqs]
    candidates = []
    for r in rows:
        lead = next((j for j in range(nm) if r[j] != 0), None)
        if lead is None:
            continue  # the equations are dependent here: leave them
        d, t = sum(monos[lead]), r[nm:]
        if any(t[i] != 0 and degree[i] > d for i in range(ne)):
            candidates.append((d, t))
    candidates.sort(key=lambda c: c[0])
    replaced: list[int] = []  # positions in eqs
    chosen: list[list[Fraction]] = []
    for d, t in candidates:
        order = sorted(
            (i for i in range(ne) if t[i] != 0 and degree[i] > d and i not in replaced),
            key=lambda i: (-len(polys[eqs[i]]), -degree[i], i),
        )
        for i in order:
            cols = [*replaced, i]
            block = [[row[c] for c in cols] for row in [*chosen, t]]
            if gauss_jordan(block, len(cols)) == len(cols):
                chosen.append(t)
                replaced.append(i)
                break
    return {
        eqs[i]: {eqs[j]: t[j] for j in range(ne) if t[j] != 0}
        for i, t in zip(replaced, chosen, strict=True)
    }


def reduce_degree(system: System, max_equations: int = 40, max_terms: int = 400) -> System:
    """The equivalent system where :func:`degree_reductions` replace equations.

    Returns ``system`` itself when nothing lowers a degree.  A replaced equation is
    ``sum_k T_k f_k`` expanded, its coefficients computed in exact rational interval
    arithmetic and rounded outward, so it encloses the combination for every value the
    constants allow (see the module docstring).
    """
    polys = _polynomials(system, max_terms)
    reductions = _reductions(polys, max_equations)
    if not reductions:
        return system
    new_eqs = list(system.equations)
    for k, combination in reductions.items():
        total: Polynomial = {}
        for j, t in combination.items():
            for m, v in polys[j].items():
                _add_into(total, m, _mul_c((t, t), v))
        try:
            new_eqs[k] = _to_expr(total, system.variables)
        except OverflowError:
            # a coefficient beyond the float range: keep the given system (replacing only
            # the other rows could leave A singular)
            return system
    return System(
        system.variables,
        system.domain,
        new_eqs,
        list(system.constraints),
        system.name,
        dict(system.parameters),
    )
