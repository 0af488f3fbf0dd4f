"""The operations of the expression DAG, one table per use: the one place that says what each
operation computes.

* :data:`FORWARD` -- interval enclosure ``(alo, ahi, blo, bhi, param) -> (lo, hi)`` (domain
  restriction as in :mod:`certsolve.interval`); used for constant folding (:mod:`.graph`),
  batched evaluation (:mod:`.program`) and as the fallback of the per-box code (:mod:`.scalar`).
* :data:`BACKWARD` -- HC4 projections ``(zlo, zhi, alo, ahi, blo, bhi, param)`` returning the
  narrowed argument bounds; an operation without an entry contracts nothing (sound).
* :data:`FLOAT` -- approximate values at points (Newton iterations; NaN outside the domain).
* :data:`SMOOTH` -- where an operation is *defined, continuous and differentiable* on a whole
  box: ``(alo, ahi, blo, bhi, zlo, zhi, param) -> mask``.  Interval Newton and Krawczyk are
  applied only to boxes on which every node passes (:meth:`.program.Program.defined_mask`):
  no ``sqrt``/``log`` of a non-positive part, no pole of ``tan``, no division by an interval
  containing 0, ``asin``/``acos``/``atanh`` strictly inside ``(-1, 1)``, ``acosh`` above 1,
  ``x^y`` with ``x > 0``, ``atan2`` away from the half-line ``{y = 0, x <= 0}``, and no
  non-differentiable point of ``abs``, ``sign``, ``min`` or ``max``.  Operations not listed
  are smooth everywhere.

Binary operations take ``(a, b)`` in the order of :class:`~.node.Expr` arguments;
``atan2(y, x)`` has ``a = y``, ``b = x``; ``rpow(x, y)`` is ``x^y``.
"""

from __future__ import annotations

import numpy as np

from ..interval import arith, elementary
from ..interval import inplace as IP
from ..interval import projections as P

__all__ = ["FORWARD", "BACKWARD", "FLOAT", "SMOOTH"]


def _sign(lo, hi):
    return np.sign(lo), np.sign(hi)


def _hull(alo, ahi, blo, bhi):
    return np.minimum(alo, blo), np.maximum(ahi, bhi)


def _unary(fn):
    return lambda a, b, c, d, p: fn(a, b)


FORWARD = {
    "add": lambda a, b, c, d, p: arith.add(a, b, c, d),
    "sub": lambda a, b, c, d, p: arith.sub(a, b, c, d),
    "mul": lambda a, b, c, d, p: arith.mul(a, b, c, d),
    "div": lambda a, b, c, d, p: arith.div(a, b, c, d),
    "min": lambda a, b, c, d, p: arith.imin(a, b, c, d),
    "max": lambda a, b, c, d, p: arith.imax(a, b, c, d),
    "hull": lambda a, b, c, d, p: _hull(a, b, c, d),
    "atan2": lambda a, b, c, d, p: elementary.atan2(a, b, c, d),
    "rpow": lambda a, b, c, d, p: elementary.rpow(a, b, c, d),
    "neg": lambda a, b, c, d, p: (-b, -a),
    "sqr": _unary(arith.sqr),
    "sqrt": _unary(arith.sqrt),
    "pow": lambda a, b, c, d, p: arith.pow_int(a, b, p),
    "exp": _unary(elementary.exp),
    "log": _unary(elementary.log),
    "sin": _unary(elementary.sin),
    "cos": _unary(elementary.cos),
    "tan": _unary(elementary.tan),
    "sinh": _unary(elementary.sinh),
    "cosh": _unary(elementary.cosh),
    "tanh": _unary(elementary.tanh),
    "asin": _unary(elementary.asin),
    "acos": _unary(elementary.acos),
    "atan": _unary(elementary.atan),
    "asinh": _unary(elementary.asinh),
    "acosh": _unary(elementary.acosh),
    "atanh": _unary(elementary.atanh),
    "abs": _unary(arith.iabs),
    "sign": _unary(_sign),
    "cadd": lambda a, b, c, d, p: arith.shift(a, b, p),
    "cmul": lambda a, b, c, d, p: arith.scale(a, b, p),
}


def _bwd_unary(fn):
    return lambda z0, z1, a, b, c, d, p: fn(z0, z1, a, b)


BACKWARD = {
    "add": lambda z0, z1, a, b, c, d, p: IP.bwd_add(z0, z1, a, b, c, d),
    "sub": lambda z0, z1, a, b, c, d, p: IP.bwd_sub(z0, z1, a, b, c, d),
    "mul": lambda z0, z1, a, b, c, d, p: IP.bwd_mul(z0, z1, a, b, c, d),
    "div": lambda z0, z1, a, b, c, d, p: P.bwd_div(z0, z1, a, b, c, d),
    "min": lambda z0, z1, a, b, c, d, p: P.bwd_min(z0, z1, a, b, c, d),
    "max": lambda z0, z1, a, b, c, d, p: P.bwd_max(z0, z1, a, b, c, d),
    "rpow": lambda z0, z1, a, b, c, d, p: P.bwd_rpow(z0, z1, a, b, c, d),
    "neg": _bwd_unary(P.bwd_neg),
    "sqr": _bwd_unary(P.bwd_sqr),
    "sqrt": _bwd_unary(P.bwd_sqrt),
    "pow": lambda z0, z1, a, b, c, d, p: P.bwd_pow(z0, z1, a, b, p),
    "exp": _bwd_unary(P.bwd_exp),
    "log": _bwd_unary(P.bwd_log),
    "abs": _bwd_unary(P.bwd_abs),
    "sign": _bwd_unary(P.bwd_sign),
    "sin": _bwd_unary(P.bwd_sin),
    "cos": _bwd_unary(P.bwd_cos),
    "tan": _bwd_unary(P.bwd_tan),
    "sinh": _bwd_unary(P.bwd_sinh),
    "cosh": _bwd_unary(P.bwd_cosh),
    "tanh": _bwd_unary(P.bwd_tanh),
    "asin": _bwd_unary(P.bwd_asin),
    "acos": _bwd_unary(P.bwd_acos),
    "atan": _bwd_unary(P.bwd_atan),
    "asinh": _bwd_unary(P.bwd_asinh),
    "acosh": _bwd_unary(P.bwd_acosh),
    "atanh": _bwd_unary(P.bwd_atanh),
    "cadd": lambda z0, z1, a, b, c, d, p: P.bwd_shift(z0, z1, a, b, p),
    "cmul": lambda z0, z1, a, b, c, d, p: P.bwd_scale(z0, z1, a, b, p),
    # atan2, hull: no contraction of the arguments (sound)
}

FLOAT = {
    "add": lambda x, y, p: x + y,
    "sub": lambda x, y, p: x - y,
    "mul": lambda x, y, p: x * y,
    "div": lambda x, y, p: x / y,
    "min": lambda x, y, p: np.minimum(x, y),
    "max": lambda x, y, p: np.maximum(x, y),
    "hull": lambda x, y, p: 0.5 * (x + y),
    "atan2": lambda x, y, p: np.arctan2(x, y),
    "rpow": lambda x, y, p: np.power(x, y),
    "neg": lambda x, y, p: -x,
    "sqr": lambda x, y, p: x * x,
    "sqrt": lambda x, y, p: np.sqrt(x),
    "pow": lambda x, y, p: x**p,
    "exp": lambda x, y, p: np.exp(x),
    "log": lambda x, y, p: np.log(x),
    "sin": lambda x, y, p: np.sin(x),
    "cos": lambda x, y, p: np.cos(x),
    "tan": lambda x, y, p: np.tan(x),
    "sinh": lambda x, y, p: np.sinh(x),
    "cosh": lambda x, y, p: np.cosh(x),
    "tanh": lambda x, y, p: np.tanh(x),
    "asin": lambda x, y, p: np.arcsin(x),
    "acos": lambda x, y, p: np.arccos(x),
    "atan": lambda x, y, p: np.arctan(x),
    "asinh": lambda x, y, p: np.arcsinh(x),
    "acosh": lambda x, y, p: np.arccosh(x),
    "atanh": lambda x, y, p: np.arctanh(x),
    "abs": lambda x, y, p: np.abs(x),
    "sign": lambda x, y, p: np.sign(x),
    "cadd": lambda x, y, p: x + p,
    "cmul": lambda x, y, p: x * p,
}


def _no_zero(lo, hi):
    return (lo > 0.0) | (hi < 0.0)


def _open_unit(lo, hi):
    return (lo > -1.0) & (hi < 1.0)


SMOOTH = {
    "sqrt": lambda a, b, c, d, z0, z1, p: a >= 0.0,
    "log": lambda a, b, c, d, z0, z1, p: a > 0.0,
    "div": lambda a, b, c, d, z0, z1, p: _no_zero(c, d),
    "pow": lambda a, b, c, d, z0, z1, p: _no_zero(a, b) if p < 0 else np.ones(a.shape, bool),
    "tan": lambda a, b, c, d, z0, z1, p: np.isfinite(z0) & np.isfinite(z1),
    "asin": lambda a, b, c, d, z0, z1, p: _open_unit(a, b),
    "acos": lambda a, b, c, d, z0, z1, p: _open_unit(a, b),
    "atanh": lambda a, b, c, d, z0, z1, p: _open_unit(a, b),
    "acosh": lambda a, b, c, d, z0, z1, p: a > 1.0,
    "rpow": lambda a, b, c, d, z0, z1, p: a > 0.0,
    "atan2": lambda a, b, c, d, z0, z1, p: (c > 0.0) | (a > 0.0) | (b < 0.0),
    "abs": lambda a, b, c, d, z0, z1, p: _no_zero(a, b),
    "sign": lambda a, b, c, d, z0, z1, p: _no_zero(a, b),
    "min": lambda a, b, c, d, z0, z1, p: (b < c) | (d < a),
    "max": lambda a, b, c, d, z0, z1, p: (b < c) | (d < a),
}
