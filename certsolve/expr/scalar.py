"""Straight-line Python code for one box at a time: the fast path for real-time use.

The level-grouped :class:`~.program.Program` pays a few microseconds of numpy overhead per
group, which dominates when a single box is evaluated (tracking, one Krawczyk test).  A
:class:`ScalarProgram` instead generates, from the same DAG, a Python function that
evaluates every node with Python floats and ``math.nextafter`` -- the same outward-rounding
rules as :mod:`certsolve.interval` (one ulp for correctly rounded operations, a wider margin
for libm functions) -- plus a float-only function for Newton steps.  The source is built
from our own graph (node numbers and ``repr`` of floats, never user text) and compiled
with ``exec`` once per system.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from ..interval.rounding import EPS, LIBM_ULPS
from .graph import Graph
from .ops import FLOAT, FORWARD

__all__ = ["ScalarProgram"]

_INF = math.inf
_NINF = -math.inf
_nd = math.nextafter


def _down(x):
    return _nd(x, -_INF)


def _up(x):
    return _nd(x, _INF)


def _mul(a, b, c, d):
    p = (a * c, a * d, b * c, b * d)
    p = [0.0 if v != v else v for v in p]  # 0*inf -> 0
    return _down(min(p)), _up(max(p))


def _div(a, b, c, d):
    if c > 0.0 or d < 0.0:
        q = (a / c, a / d, b / c, b / d)
        return _down(min(q)), _up(max(q))
    if c == 0.0 and d == 0.0:
        return _INF, -_INF
    if a >= 0.0 and b <= 0.0:
        return 0.0, 0.0
    if c < 0.0 < d:
        return -_INF, _INF
    if c == 0.0:  # (0, d]
        if a >= 0.0:
            return _down(a / d), _INF
        if b <= 0.0:
            return -_INF, _up(b / d)
        return -_INF, _INF
    if a >= 0.0:  # [c, 0)
        return -_INF, _up(a / c)
    if b <= 0.0:
        return _down(b / c), _INF
    return -_INF, _INF


def _sqr(a, b):
    p, q = a * a, b * b
    lo = 0.0 if a <= 0.0 <= b else _down(min(p, q))
    return lo, _up(max(p, q))


def _sqrt(a, b):
    if b < 0.0:
        return _INF, -_INF
    return max(_down(math.sqrt(max(a, 0.0))), 0.0), _up(math.sqrt(b))


def _ipow(a, b, n):
    if n < 0:
        lo, hi = _ipow(a, b, -n)
        return _div(1.0, 1.0, lo, hi)
    if n == 0:
        return 1.0, 1.0
    if n % 2 == 0:
        m_lo = 0.0 if a <= 0.0 <= b else min(abs(a), abs(b))
        m_hi = max(abs(a), abs(b))
        return _pos_pow(m_lo, n)[0], _pos_pow(m_hi, n)[1]
    la, ha = _pos_pow(abs(a), n)
    lb, hb = _pos_pow(abs(b), n)
    lo = la if a >= 0.0 else -ha
    hi = hb if b >= 0.0 else -lb
    return lo, hi


def _pos_pow(x, n):
    lo = hi = 1.0
    blo = bhi = x
    k = n
    while k:
        if k & 1:
            lo, hi = _down(lo * blo), _up(hi * bhi)
        k >>= 1
        if k:
            blo, bhi = _down(blo * blo), _up(bhi * bhi)
    return max(lo, 0.0), hi


_W = LIBM_ULPS * EPS


def _wd(x):
    return _down(x - (abs(x) * _W + 2.0**-1020)) if math.isfinite(x) else x


def _wu(x):
    return _up(x + (abs(x) * _W + 2.0**-1020)) if math.isfinite(x) else x


def _exp(a, b):
    try:
        lo = max(_wd(math.exp(a)), 0.0)
    except OverflowError:
        lo = 1.7976931348623157e308
    try:
        hi = _wu(math.exp(b))
    except OverflowError:
        hi = _INF
    return lo, hi


def _log(a, b):
    if b <= 0.0:
        return _INF, -_INF
    lo = -_INF if a <= 0.0 else _wd(math.log(a))
    return lo, _wu(math.log(b)) if b < _INF else _INF


def _has(a, b, off):
    slack = 1e-9 * max(1.0, abs(a), abs(b))
    k = math.ceil((a - slack - off) / (2 * math.pi))
    return off + k * 2 * math.pi <= b + slack


def _trig(fn, a, b, max_at, min_at):
    if not (b - a < 2 * math.pi) or max(abs(a), abs(b)) >= 1e8:
        return -1.0, 1.0
    fa, fb = fn(a), fn(b)
    lo = -1.0 if _has(a, b, min_at) else max(_wd(min(fa, fb)), -1.0)
    hi = 1.0 if _has(a, b, max_at) else min(_wu(max(fa, fb)), 1.0)
    return lo, hi


def _sin(a, b):
    return _trig(math.sin, a, b, 0.5 * math.pi, -0.5 * math.pi)


def _cos(a, b):
    return _trig(math.cos, a, b, 0.0, math.pi)


def _abs(a, b):
    lo = a if a >= 0.0 else (-b if b <= 0.0 else 0.0)
    return lo, max(-a, b)


def _sign(a, b):
    return float((a > 0) - (a < 0)), float((b > 0) - (b < 0))


def _scale(a, b, c):
    p, q = c * a, c * b
    return _down(min(p, q)), _up(max(p, q))


def _fmul(a0, a1, b0, b1):
    """``[a0, a1]·[b0, b1]`` for finite bounds (the fast variant): the two corner products
    that are the bounds, picked by the operands' signs."""
    if a0 >= 0.0:
        if b0 >= 0.0:
            return _nd(a0 * b0, _NINF), _nd(a1 * b1, _INF)
        if b1 <= 0.0:
            return _nd(a1 * b0, _NINF), _nd(a0 * b1, _INF)
        return _nd(a1 * b0, _NINF), _nd(a1 * b1, _INF)
    if a1 <= 0.0:
        if b0 >= 0.0:
            return _nd(a0 * b1, _NINF), _nd(a1 * b0, _INF)
        if b1 <= 0.0:
            return _nd(a1 * b1, _NINF), _nd(a0 * b0, _INF)
        return _nd(a0 * b1, _NINF), _nd(a0 * b0, _INF)
    if b0 >= 0.0:
        return _nd(a0 * b1, _NINF), _nd(a1 * b1, _INF)
    if b1 <= 0.0:
        return _nd(a1 * b0, _NINF), _nd(a0 * b0, _INF)
    return _nd(min(a0 * b1, a1 * b0), _NINF), _nd(max(a0 * b0, a1 * b1), _INF)


def _fsqr(a0, a1):
    """``[a0, a1]²`` for finite bounds (the fast variant)."""
    if a0 > 0.0:
        return _nd(a0 * a0, _NINF), _nd(a1 * a1, _INF)
    if a1 < 0.0:
        return _nd(a1 * a1, _NINF), _nd(a0 * a0, _INF)
    return 0.0, _nd(max(a0 * a0, a1 * a1), _INF)


def _fdiv(a0, a1, b0, b1):
    """``[a0, a1]/[b0, b1]`` for finite bounds (the fast variant): by the signs when the
    divisor is away from 0, else the helper's IBEX cases."""
    if b0 > 0.0:
        if a0 >= 0.0:
            return _nd(a0 / b1, _NINF), _nd(a1 / b0, _INF)
        if a1 <= 0.0:
            return _nd(a0 / b0, _NINF), _nd(a1 / b1, _INF)
        return _nd(a0 / b0, _NINF), _nd(a1 / b0, _INF)
    if b1 < 0.0:
        if a0 >= 0.0:
            return _nd(a1 / b1, _NINF), _nd(a0 / b0, _INF)
        if a1 <= 0.0:
            return _nd(a1 / b0, _NINF), _nd(a0 / b1, _INF)
        return _nd(a1 / b1, _NINF), _nd(a0 / b1, _INF)
    return _div(a0, a1, b0, b1)


def _fwd(op, a, b, c=None, d=None):
    """Any operation without inline code: its batched enclosure (:data:`.ops.FORWARD`) on
    numpy scalars -- the same bounds as the batched evaluator, at numpy's per-call cost."""
    f = np.float64
    with np.errstate(all="ignore"):
        lo, hi = FORWARD[op](
            f(a), f(b), None if c is None else f(c), None if d is None else f(d), None
        )
    return float(lo), float(hi)


def _flt(op, x, y=None):
    """Float value of an operation without inline code (NaN outside its domain)."""
    with np.errstate(all="ignore"):
        return float(FLOAT[op](np.float64(x), None if y is None else np.float64(y), None))


_HELPERS = {
    "_fwd": _fwd,
    "_flt": _flt,
    "_down": _down,
    "_up": _up,
    "_mul": _mul,
    "_div": _div,
    "_sqr": _sqr,
    "_sqrt": _sqrt,
    "_ipow": _ipow,
    "_exp": _exp,
    "_log": _log,
    "_sin": _sin,
    "_cos": _cos,
    "_abs": _abs,
    "_sign": _sign,
    "_scale": _scale,
    "_fmul": _fmul,
    "_fsqr": _fsqr,
    "_fdiv": _fdiv,
    "math": math,
    "inf": _INF,
}

_CALL = {
    "mul": "_mul({a0}, {a1}, {b0}, {b1})",
    "div": "_div({a0}, {a1}, {b0}, {b1})",
    "sqr": "_sqr({a0}, {a1})",
    "sqrt": "_sqrt({a0}, {a1})",
    "exp": "_exp({a0}, {a1})",
    "log": "_log({a0}, {a1})",
    "sin": "_sin({a0}, {a1})",
    "cos": "_cos({a0}, {a1})",
    "abs": "_abs({a0}, {a1})",
    "sign": "_sign({a0}, {a1})",
    "min": "min({a0}, {b0}), min({a1}, {b1})",
    "max": "max({a0}, {b0}), max({a1}, {b1})",
    "hull": "min({a0}, {b0}), max({a1}, {b1})",
    "neg": "-{a1}, -{a0}",
    "add": "_down({a0} + {b0}), _up({a1} + {b1})",
    "sub": "_down({a0} - {b1}), _up({a1} - {b0})",
}

_FLOAT = {
    "add": "{a} + {b}",
    "sub": "{a} - {b}",
    "mul": "{a} * {b}",
    "div": "{a} / {b}",
    "min": "min({a}, {b})",
    "max": "max({a}, {b})",
    "hull": "0.5 * ({a} + {b})",
    "neg": "-{a}",
    "sqr": "{a} * {a}",
    "sqrt": "math.sqrt({a})",
    "exp": "math.exp({a})",
    "log": "math.log({a})",
    "sin": "math.sin({a})",
    "cos": "math.cos({a})",
    "abs": "abs({a})",
    "sign": "float(({a} > 0) - ({a} < 0))",
}


def _call(op: str, fmt: dict) -> str:
    """Source of the interval call of ``op`` (inline helper, or the generic fallback)."""
    if op in _CALL:
        return _CALL[op].format(**fmt)
    if "b0" in fmt:
        return f"_fwd({op!r}, {fmt['a0']}, {fmt['a1']}, {fmt['b0']}, {fmt['b1']})"
    return f"_fwd({op!r}, {fmt['a0']}, {fmt['a1']})"


class _Bail(Exception):
    """Raised by the fast interval function when a value is not finite."""


# code of the fast interval function (finite values only; see ScalarProgram).  Products
# and quotients pick their two bounds by the operands' signs (a comparison costs ~10 ns in
# CPython, ``min``/``max`` of four products ~150 ns); as rounding to nearest is monotone,
# the rounded product that is the bound is the minimum (maximum) of the four rounded
# products, so the bounds are the same floats as the helpers'.  They are functions, not
# inline code: the inline branches doubled the source and ``compile()``'s time (general-19's
# Jacobian 18 -> 40 ms), most of building a tracker
_FAST = {
    "add": "{lo} = nd({a0} + {b0}, NI); {hi} = nd({a1} + {b1}, PI)",
    "sub": "{lo} = nd({a0} - {b1}, NI); {hi} = nd({a1} - {b0}, PI)",
    "neg": "{lo} = -{a1}; {hi} = -{a0}",
    "mul": "{lo}, {hi} = _fmul({a0}, {a1}, {b0}, {b1})",
    "sqr": "{lo}, {hi} = _fsqr({a0}, {a1})",
    "div": "{lo}, {hi} = _fdiv({a0}, {a1}, {b0}, {b1})",
}


class ScalarProgram:
    """Generated per-box evaluators of the nodes needed for ``outputs``.

    ``interval(xlo, xhi, plo, phi) -> (lo, hi)`` takes sequences of variable and parameter
    bounds and returns lists of output bounds; ``floats(x, p) -> values`` the float version.

    ``interval`` first runs a *fast* variant in which ``+ -``, negations and scalings are
    inline code and products, quotients and squares take the bounds their operands' signs
    pick (:func:`_fmul`, :func:`_fdiv`, :func:`_fsqr`).  Both are only sound without
    infinities (``inf * 0`` gives NaN, and a sign test or Python's ``min`` of a NaN goes
    either way), so the inputs of those operations and the outputs are checked to be
    finite, and the fast variant bails out to the helper-based one otherwise.
    """

    def __init__(self, graph: Graph, outputs: Sequence[int]):
        n = len(graph.variables)
        order = graph.ancestors(outputs)
        self._fast_source = self._fast(graph, order, outputs, n)
        ilines = ["def interval_safe(xlo, xhi, plo, phi):"]
        flines = ["def floats(x, p):"]
        for v in order:
            op, args, p = graph.op[v], graph.args[v], graph.param[v]
            lo, hi, fv = f"l{v}", f"h{v}", f"f{v}"
            if op == "var":
                ilines.append(f"    {lo} = xlo[{p}]; {hi} = xhi[{p}]")
                flines.append(f"    {fv} = x[{p}]")
                continue
            if op == "param":
                k = v - n
                ilines.append(f"    {lo} = plo[{k}]; {hi} = phi[{k}]")
                flines.append(f"    {fv} = p[{k}]")
                continue
            if op == "const":
                ilines.append(f"    {lo} = {p[0]!r}; {hi} = {p[1]!r}")
                flines.append(f"    {fv} = {0.5 * p[0] + 0.5 * p[1]!r}")
                continue
            a = args[0]
            fmt = {"a0": f"l{a}", "a1": f"h{a}"}
            if len(args) == 2:
                fmt.update(b0=f"l{args[1]}", b1=f"h{args[1]}")
            if op == "cadd":
                rhs, frhs = f"_down(l{a} + {p!r}), _up(h{a} + {p!r})", f"f{a} + {p!r}"
            elif op == "cmul":
                rhs, frhs = f"_scale(l{a}, h{a}, {p!r})", f"f{a} * {p!r}"
            elif op == "pow":
                rhs, frhs = f"_ipow(l{a}, h{a}, {int(p)})", f"f{a} ** {int(p)}"
            else:
                rhs = _call(op, fmt)
                fb = f"f{args[1]}" if len(args) == 2 else "None"
                frhs = (
                    _FLOAT[op].format(a=f"f{a}", b=fb)
                    if op in _FLOAT
                    else f"_flt({op!r}, f{a}, {fb})"
                )
            ilines.append(f"    {lo}, {hi} = {rhs}")
            flines.append(f"    {fv} = {frhs}")
        outs = [int(o) for o in outputs]
        ilines.append(
            f"    return [{', '.join(f'l{o}' for o in outs)}], [{', '.join(f'h{o}' for o in outs)}]"
        )
        flines.append(f"    return [{', '.join(f'f{o}' for o in outs)}]")
        namespace = dict(_HELPERS)
        namespace.update(nd=math.nextafter, NI=-_INF, PI=_INF, _Bail=_Bail)
        # each variant is compiled at its first call (compile() is most of the cost of
        # building a program, and most users call one or two of the three)
        self._namespace = namespace
        self._sources = {
            "interval_safe": ("\n".join(ilines), "<certsolve-scalar-interval>"),
            "interval_fast": (self._fast_source, "<certsolve-scalar-fast>"),
            "floats": ("\n".join(flines), "<certsolve-scalar-float>"),
        }
        self.n_nodes = len(order)

    def prepare(self, *, interval: bool = False, floats: bool = False) -> None:
        """Compile now what :meth:`interval` (its fast variant) or :attr:`floats` will call,
        instead of at the first call (a real-time loop's first step)."""
        if interval:
            self._interval_fast  # noqa: B018  (the cached property compiles it)
        if floats:
            self.floats  # noqa: B018

    def _compiled(self, name: str):
        source, filename = self._sources[name]
        exec(compile(source, filename, "exec"), self._namespace)
        return self._namespace[name]

    @functools.cached_property
    def interval_safe(self):
        return self._compiled("interval_safe")

    @functools.cached_property
    def _interval_fast(self):
        return self._compiled("interval_fast")

    @functools.cached_property
    def floats(self):
        return self._compiled("floats")

    def interval(self, xlo, xhi, plo, phi):
        try:
            return self._interval_fast(xlo, xhi, plo, phi)
        except _Bail:
            return self.interval_safe(xlo, xhi, plo, phi)

    @staticmethod
    def _fast(graph: Graph, order, outputs, n) -> str:
        lines = ["def interval_fast(xlo, xhi, plo, phi):"]
        guard = "    if not (NI < {lo} and {hi} < PI): raise _Bail"
        # Only the inputs of min/max-based operations and the outputs need the guard: the
        # NaN that an infinite bound can cause (inf - inf, 0 * inf) passes unchanged
        # through + - neg and scalings (and nextafter) until it reaches a guarded node,
        # and an overflowed bound stays a valid, if loose, bound through them.
        passthrough = {"add", "sub", "neg", "cadd", "cmul"}
        guarded = {int(o) for o in outputs}
        for v in order:
            if graph.op[v] not in passthrough:
                guarded.update(int(a) for a in graph.args[v])
        for v in order:
            op, args, p = graph.op[v], graph.args[v], graph.param[v]
            lo, hi = f"l{v}", f"h{v}"
            if op == "var":
                lines.append(f"    {lo} = xlo[{p}]; {hi} = xhi[{p}]")
            elif op == "param":
                lines.append(f"    {lo} = plo[{v - n}]; {hi} = phi[{v - n}]")
            elif op == "const":
                lines.append(f"    {lo} = {p[0]!r}; {hi} = {p[1]!r}")
            else:
                a = args[0]
                fmt = {"lo": lo, "hi": hi, "a0": f"l{a}", "a1": f"h{a}"}
                if len(args) == 2:
                    fmt.update(b0=f"l{args[1]}", b1=f"h{args[1]}")
                if op in _FAST:
                    lines.append("    " + _FAST[op].format(**fmt))
                elif op == "cadd":
                    lines.append(f"    {lo} = nd(l{a} + {p!r}, NI); {hi} = nd(h{a} + {p!r}, PI)")
                elif op == "cmul":
                    if p >= 0.0:
                        lines.append(
                            f"    {lo} = nd({p!r} * l{a}, NI); {hi} = nd({p!r} * h{a}, PI)"
                        )
                    else:
                        lines.append(
                            f"    {lo} = nd({p!r} * h{a}, NI); {hi} = nd({p!r} * l{a}, PI)"
                        )
                elif op == "pow":
                    lines.append(f"    {lo}, {hi} = _ipow(l{a}, h{a}, {int(p)})")
                else:
                    lines.append(f"    {lo}, {hi} = " + _call(op, fmt))
            if v in guarded:
                lines.append(guard.format(lo=lo, hi=hi))
        outs = [int(o) for o in outputs]
        lines.append(
            f"    return [{', '.join(f'l{o}' for o in outs)}], [{', '.join(f'h{o}' for o in outs)}]"
        )
        return "\n".join(lines)
