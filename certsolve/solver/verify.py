"""Independent re-proof of certified solutions with ``mpmath.iv`` (``verify=True``).

The numpy path proves each solution with float64 interval arithmetic and a priori rounding
bounds.  As an independent check, this module re-runs the Krawczyk test on every unicity
box with mpmath's interval arithmetic at a higher precision (default 100 bits), evaluating
the expression DAG node by node with mpmath (no code shared with the numpy evaluator) and
forming ``K(U) = c - Y f(c) + (I - Y J(U))(U - c)`` with mpmath interval matrices.
``Solution.verified`` is then True when ``K(U) ⊂ int U`` holds again and the existence box
is confirmed inside the unicity box.
"""

from __future__ import annotations

from typing import Any

import mpmath

from ..expr.compiled import CompiledSystem

__all__ = ["verify_solutions", "iv_eval"]


def _ivl(ctx, lo, hi):
    return ctx.mpf([lo, hi])


def _exact(x) -> mpmath.mpf:
    """The exact lower end point of an ``mpmath.iv`` value, as an ``mpf``."""
    return mpmath.mpf(x._mpi_[0])


def _monotone(ctx, fn, a, increasing=True, dlo=None, dhi=None):
    """Enclosure of a monotone real function over ``a`` (restricted to ``[dlo, dhi]``).

    The end points are evaluated 40 bits beyond the working precision and widened by one
    unit of it: mpmath's real elementary functions are accurate to the last bit there.
    """
    with mpmath.workprec(ctx.prec + 40):
        lo, hi = mpmath.mpf(a._mpi_[0]), mpmath.mpf(a._mpi_[1])
        if dlo is not None:
            lo = max(lo, dlo)
        if dhi is not None:
            hi = min(hi, dhi)
        if lo > hi:
            raise ValueError("argument outside the domain")
        ends = (fn(lo), fn(hi)) if increasing else (fn(hi), fn(lo))
        eps = mpmath.mpf(2) ** (-ctx.prec)
        tiny = mpmath.mpf(2) ** (-10 * ctx.prec)
        rlo = ends[0] - abs(ends[0]) * eps - tiny
        rhi = ends[1] + abs(ends[1]) * eps + tiny
    return ctx.mpf([rlo, rhi])


# ops evaluated through a monotone real function: (function, increasing, domain)
_MONOTONE = {
    "sinh": (mpmath.sinh, True, None, None),
    "tanh": (mpmath.tanh, True, None, None),
    "atan": (mpmath.atan, True, None, None),
    "asinh": (mpmath.asinh, True, None, None),
    "asin": (mpmath.asin, True, -1, 1),
    "acos": (mpmath.acos, False, -1, 1),
    "acosh": (mpmath.acosh, True, 1, None),
    "atanh": (mpmath.atanh, True, -1, 1),
}


def iv_eval(csys: CompiledSystem, nodes: list[int], lo, hi, ctx):
    """mpmath interval values of ``nodes`` for the box ``[lo, hi]`` (node by node)."""
    g = csys.graph
    n = csys.n
    val = {}
    for v in g.ancestors(nodes):
        op, args, p = g.op[v], g.args[v], g.param[v]
        if op == "var":
            val[v] = _ivl(ctx, lo[p], hi[p])
            continue
        if op == "param":
            k = v - n
            val[v] = _ivl(ctx, csys.param_lo[k], csys.param_hi[k])
            continue
        if op == "const":
            val[v] = _ivl(ctx, p[0], p[1])
            continue
        a = val[args[0]]
        b: Any = val[args[1]] if len(args) == 2 else None  # mpmath interval (binary ops)
        if op == "add":
            r = a + b
        elif op == "sub":
            r = a - b
        elif op == "mul":
            r = a * b
        elif op == "div":
            r = a / b
        elif op == "neg":
            r = -a
        elif op == "sqr":
            r = a**2
        elif op == "pow":
            r = a**p
        elif op == "sqrt":
            r = ctx.sqrt(a)
        elif op == "exp":
            r = ctx.exp(a)
        elif op == "log":
            r = ctx.log(a)
        elif op == "sin":
            r = ctx.sin(a)
        elif op == "cos":
            r = ctx.cos(a)
        elif op == "tan":
            r = ctx.tan(a)
        elif op == "cosh":
            r = (ctx.exp(a) + ctx.exp(-a)) / 2
        elif op in _MONOTONE:
            fn, inc, dlo, dhi = _MONOTONE[op]
            r = _monotone(ctx, fn, a, inc, dlo, dhi)
        elif op == "atan2":
            r = ctx.atan2(a, b)
        elif op == "rpow":
            r = ctx.exp(b * ctx.log(a)) if _exact(a) > 0 else ctx.mpf([0, "+inf"])
        elif op == "abs":
            r = abs(a)
        elif op == "cadd":
            r = a + ctx.mpf(p)
        elif op == "cmul":
            r = a * ctx.mpf(p)
        elif op == "min":
            r = ctx.mpf([min(a.a, b.a), min(a.b, b.b)])
        elif op == "max":
            r = ctx.mpf([max(a.a, b.a), max(a.b, b.b)])
        elif op == "hull":
            r = ctx.mpf([min(a.a, b.a), max(a.b, b.b)])
        elif op == "sign":
            r = ctx.mpf(
                [
                    -1 if a.a < 0 else (0 if a.a == 0 else 1),
                    -1 if a.b < 0 else (0 if a.b == 0 else 1),
                ]
            )
        else:  # pragma: no cover
            raise NotImplementedError(op)
        val[v] = r
    return [val[v] for v in nodes]


def _krawczyk_mp(csys: CompiledSystem, ulo, uhi, ctx) -> bool:
    n = csys.n
    f_nodes = csys.f.global_ids[csys.f.outputs].tolist()
    fj_nodes = csys.fj.global_ids[csys.fj.outputs].tolist()
    jac = fj_nodes[n:]
    c = [(ctx.mpf(a) + ctx.mpf(b)) / 2 for a, b in zip(ulo, uhi, strict=True)]
    c = [ci.mid for ci in c]  # exact-enough point inside U
    fc = iv_eval(csys, f_nodes, c, c, ctx)
    jv = iv_eval(csys, jac, ulo, uhi, ctx)
    J = [[ctx.mpf(0) for _ in range(n)] for _ in range(n)]
    flat = csys.jac_structure.ravel().nonzero()[0]
    for k, pos in enumerate(flat):
        J[pos // n][pos % n] = jv[k]
    # point preconditioner: inverse of the midpoint matrix, in ordinary mpmath
    with mpmath.workprec(ctx.prec):
        Jm = mpmath.matrix([[J[i][j].mid for j in range(n)] for i in range(n)])
        try:
            Ym = Jm**-1
        except ZeroDivisionError:
            return False
    Y = [[ctx.mpf(Ym[i, j]) for j in range(n)] for i in range(n)]
    U = [ctx.mpf([ulo[i], uhi[i]]) for i in range(n)]
    D = [U[j] - c[j] for j in range(n)]
    for i in range(n):
        yf = sum((Y[i][k] * fc[k] for k in range(n)), ctx.mpf(0))
        acc = ctx.mpf(0)
        for j in range(n):
            yj = sum((Y[i][k] * J[k][j] for k in range(n)), ctx.mpf(0))
            m = (ctx.mpf(1) if i == j else ctx.mpf(0)) - yj
            acc = acc + m * D[j]
        K = c[i] - yf + acc
        if not (K.a > U[i].a and K.b < U[i].b):
            return False
    return True


def verify_solutions(csys: CompiledSystem, solutions, prec: int = 100) -> None:
    """Set ``verified`` on each solution by an independent mpmath Krawczyk proof."""
    ctx = mpmath.iv
    old = ctx.prec
    ctx.prec = prec
    try:
        for s in solutions:
            inside = bool(all(s.ulo <= s.lo) and all(s.hi <= s.uhi))
            s.verified = inside and _krawczyk_mp(csys, s.ulo.tolist(), s.uhi.tolist(), ctx)
    finally:
        ctx.prec = old
