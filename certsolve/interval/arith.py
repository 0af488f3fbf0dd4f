"""Interval arithmetic with outward rounding: ``+ - * /``, powers, ``sqrt``, ``abs``, min/max.

Every function takes bounds ``(alo, ahi[, blo, bhi])`` as numpy arrays (broadcastable) and
returns a new pair ``(lo, hi)`` that encloses ``{a ∘ b : a ∈ [a], b ∈ [b]}``.  Bounds of
the exact result are computed in round-to-nearest and then moved one float outward
(:mod:`.rounding`), which is sound because these operations are correctly rounded.

Partial functions follow IBEX's *domain restriction* convention: the image of an interval
is the image of its intersection with the function's domain.

* ``div``: divisor points equal to 0 are not in the domain.  With ``0`` strictly inside
  the divisor the quotient set is two half-lines and its hull, ``(-inf, inf)``, is
  returned; with the divisor ``[0, d]`` or ``[c, 0]`` one half-line; ``x / [0, 0]`` is
  empty.  (:func:`certsolve.interval.projections.mul_inverse` keeps the gap when it
  matters for contraction.)
* ``sqrt``: the negative part of the argument is ignored; an entirely negative argument
  gives the empty interval.
* ``pow`` with a negative exponent is ``1 / x**n`` with the same rule as ``div``.

Operands are normally non-empty.  Empty operands give empty results, or NaN bounds
from ``inf - inf``; a NaN bound only ever comes from an empty operand, so callers may
treat ``not (lo <= hi)`` as empty.  Mapping an empty operand to a non-empty result is
sound (it only loses information); the reverse never happens.
"""

from __future__ import annotations

import numpy as np

from .core import Pair
from .rounding import down, up

__all__ = [
    "add",
    "sub",
    "neg",
    "mul",
    "scale",
    "shift",
    "div",
    "div_nonzero",
    "recip",
    "sqr",
    "sqrt",
    "pow_int",
    "iabs",
    "imin",
    "imax",
]

_INF = np.inf


def _keep_empty(lo: np.ndarray, hi: np.ndarray, *operands: np.ndarray) -> Pair:
    """Propagate emptiness: where any operand pair is empty, make the result empty."""
    emp = None
    for k in range(0, len(operands), 2):
        e = operands[k] > operands[k + 1]
        emp = e if emp is None else (emp | e)
    if emp is not None and np.any(emp):
        lo = np.where(emp, _INF, lo)
        hi = np.where(emp, -_INF, hi)
    return lo, hi


def add(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    return down(alo + blo), up(ahi + bhi)


def sub(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    return down(alo - bhi), up(ahi - blo)


def neg(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    return -ahi, -alo  # exact


def shift(alo: np.ndarray, ahi: np.ndarray, c: np.ndarray | float) -> Pair:
    """``[a] + c`` for a float (array) ``c``."""
    return down(alo + c), up(ahi + c)


def scale(alo: np.ndarray, ahi: np.ndarray, c: np.ndarray | float) -> Pair:
    """``c * [a]`` for a float (array) ``c``."""
    with np.errstate(over="ignore"):  # overflow to ±inf is a valid bound
        p = c * alo
        q = c * ahi
    return down(np.minimum(p, q)), up(np.maximum(p, q))


def mul(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    """Product; ``0 * inf`` counts as 0 (``fmin``/``fmax`` ignore the NaN it produces)."""
    with np.errstate(invalid="ignore", over="ignore"):
        p1 = alo * blo
        p2 = alo * bhi
        p3 = ahi * blo
        p4 = ahi * bhi
    lo = np.fmin(np.fmin(p1, p2), np.fmin(p3, p4))
    hi = np.fmax(np.fmax(p1, p2), np.fmax(p3, p4))
    lo = np.where(np.isnan(lo), 0.0, lo)
    hi = np.where(np.isnan(hi), 0.0, hi)
    return _keep_empty(down(lo), up(hi), alo, ahi, blo, bhi)


def div_nonzero(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    """Quotient by a divisor free of 0: the hull of the four corner quotients, rounded out.

    The quotient is monotone in each argument on such a box, so its extremes are corners.
    (Where the divisor holds 0 the result means nothing; :func:`div` replaces it there.)
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q1 = alo / blo
        q2 = alo / bhi
        q3 = ahi / blo
        q4 = ahi / bhi
    return (
        down(np.fmin(np.fmin(q1, q2), np.fmin(q3, q4))),
        up(np.fmax(np.fmax(q1, q2), np.fmax(q3, q4))),
    )


def div(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    """Quotient with IBEX semantics for divisors containing 0 (see module docstring)."""
    alo, ahi, blo, bhi = np.broadcast_arrays(alo, ahi, blo, bhi)
    lo, hi = div_nonzero(alo, ahi, blo, bhi)
    zb = (blo <= 0.0) & (bhi >= 0.0)
    if np.any(zb):
        a_pos = alo >= 0.0
        a_neg = ahi <= 0.0
        a_zero = a_pos & a_neg  # a == [0, 0]
        b_pos = zb & (blo == 0.0) & (bhi > 0.0)  # [0, d]
        b_neg = zb & (bhi == 0.0) & (blo < 0.0)  # [c, 0]
        b_zero = zb & (blo == 0.0) & (bhi == 0.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # b = [0, d]: a >= 0 -> [a.lo/d, inf); a <= 0 -> (-inf, a.hi/d]
            bp_lo = np.where(a_pos, down(alo / bhi), -_INF)
            bp_hi = np.where(a_neg, up(ahi / bhi), _INF)
            # b = [c, 0]: a >= 0 -> (-inf, a.lo/c]; a <= 0 -> [a.hi/c, inf)
            bn_lo = np.where(a_neg, down(ahi / blo), -_INF)
            bn_hi = np.where(a_pos, up(alo / blo), _INF)
        zlo = np.where(b_pos, bp_lo, np.where(b_neg, bn_lo, -_INF))
        zhi = np.where(b_pos, bp_hi, np.where(b_neg, bn_hi, _INF))
        zlo = np.where(a_zero & ~b_zero, 0.0, zlo)
        zhi = np.where(a_zero & ~b_zero, 0.0, zhi)
        zlo = np.where(b_zero, _INF, zlo)
        zhi = np.where(b_zero, -_INF, zhi)
        lo = np.where(zb, zlo, lo)
        hi = np.where(zb, zhi, hi)
    return _keep_empty(lo, hi, alo, ahi, blo, bhi)


def recip(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    one = np.ones_like(alo)
    return div(one, one, alo, ahi)


def sqr(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``{a**2}``: tighter than ``a*a`` (the dependency problem)."""
    p = alo * alo
    q = ahi * ahi
    lo = np.where((alo <= 0.0) & (ahi >= 0.0), 0.0, down(np.minimum(p, q)))
    hi = up(np.maximum(p, q))
    return _keep_empty(lo, hi, alo, ahi)


def sqrt(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """Square root of the non-negative part (empty if there is none)."""
    lo = np.maximum(alo, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        rlo = np.maximum(down(np.sqrt(lo)), 0.0)
        rhi = up(np.sqrt(ahi))
    neg_only = ahi < 0.0
    rlo = np.where(neg_only, _INF, rlo)
    rhi = np.where(neg_only, -_INF, rhi)
    return _keep_empty(rlo, rhi, alo, ahi)


def _pow_pos(alo: np.ndarray, ahi: np.ndarray, n: int) -> Pair:
    """``x**n`` for n >= 2 by repeated rounded multiplication of non-negative bounds.

    For 0 <= x the map is increasing, so bounds are ``lo**n`` rounded down and ``hi**n``
    rounded up; repeated squaring with rounding at each step keeps the enclosure.
    """
    rlo = np.ones_like(alo)
    rhi = np.ones_like(ahi)
    blo, bhi = alo, ahi
    k = n
    with np.errstate(over="ignore"):  # overflow to inf is a valid upper bound
        while k:
            if k & 1:
                rlo = down(rlo * blo)
                rhi = up(rhi * bhi)
            k >>= 1
            if k:
                blo = down(blo * blo)
                bhi = up(bhi * bhi)
    return np.maximum(rlo, 0.0), rhi


def pow_int(alo: np.ndarray, ahi: np.ndarray, n: int) -> Pair:
    """``x**n`` for an integer ``n`` (``n < 0`` is ``1/x**|n|`` with :func:`div` semantics)."""
    n = int(n)
    if n == 0:
        lo, hi = np.ones_like(alo), np.ones_like(ahi)
        return _keep_empty(lo, hi, alo, ahi)
    if n == 1:
        return alo.copy(), ahi.copy()
    if n == 2:
        return sqr(alo, ahi)
    if n < 0:
        plo, phi = pow_int(alo, ahi, -n)
        return recip(plo, phi)
    if n % 2 == 0:
        mlo = np.where(ahi < 0.0, -ahi, np.where(alo > 0.0, alo, 0.0))  # mignitude
        mhi = np.maximum(np.abs(alo), np.abs(ahi))  # magnitude
        lo, hi = _pow_pos(mlo, mhi, n)
    else:
        # odd powers are increasing: bound sign(x)|x|**n at each end (both ends at once)
        ends = np.abs(np.stack((alo, ahi)))
        pl, ph = _pow_pos(ends, ends, n)
        lo = np.where(alo >= 0.0, pl[0], -ph[0])
        hi = np.where(ahi >= 0.0, ph[1], -pl[1])
    return _keep_empty(lo, hi, alo, ahi)


def iabs(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    lo = np.where(alo >= 0.0, alo, np.where(ahi <= 0.0, -ahi, 0.0))
    hi = np.maximum(-alo, ahi)
    return _keep_empty(lo, hi, alo, ahi)


def imin(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    return _keep_empty(np.minimum(alo, blo), np.minimum(ahi, bhi), alo, ahi, blo, bhi)


def imax(alo: np.ndarray, ahi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> Pair:
    return _keep_empty(np.maximum(alo, blo), np.maximum(ahi, bhi), alo, ahi, blo, bhi)
