"""Backward projections (inverse images) used by forward-backward contraction (HC4-revise).

For a node ``z = op(x[, y])`` and current enclosures ``[z], [x], [y]``, ``bwd_op`` returns
narrowed ``[x'] ⊆ [x]`` (and ``[y'] ⊆ [y]``) such that every ``(x, y)`` in the old boxes with
``op(x, y) ∈ [z]`` is still in the new ones.  An empty result proves that no such point
exists.  All bounds are outward rounded, so the projections never lose a solution.

Naming follows IBEX (``bwd_add``, ``bwd_mul``, ...).  ``bwd_mul`` and ``bwd_div`` keep the
gap of the extended division (:func:`mul_inverse`) before taking the hull, as IBEX does.
The other elementary functions are inverted on their monotone branches: ``bwd_sinh``,
``bwd_tanh``, ``bwd_asinh``, ``bwd_atanh``, ``bwd_atan``, ``bwd_asin``, ``bwd_acos``,
``bwd_acosh`` (one branch), ``bwd_cosh`` (two, ``±acosh(z)``), ``bwd_sin`` and ``bwd_cos``
(the two monotone branches ``[x]`` meets first, split where they join; an argument wider than
about π is left unchanged), ``bwd_tan`` (when the argument lies between two consecutive poles;
otherwise no contraction), ``bwd_rpow`` (``x = z^(1/y)``
for an exponent away from 0, and ``x >= 0`` always) and ``bwd_sign``.  ``atan2`` has no
projection (no contraction of its arguments: sound).
"""

from __future__ import annotations

import numpy as np

from . import arith, elementary
from .core import Pair, Quad
from .rounding import down, up, widen_down, widen_up

__all__ = [
    "mul_inverse",
    "bwd_add",
    "bwd_sub",
    "bwd_neg",
    "bwd_shift",
    "bwd_scale",
    "bwd_mul",
    "bwd_div",
    "bwd_sqr",
    "bwd_sqrt",
    "bwd_pow",
    "bwd_exp",
    "bwd_log",
    "bwd_abs",
    "bwd_min",
    "bwd_max",
    "bwd_tan",
    "bwd_sin",
    "bwd_cos",
    "bwd_sinh",
    "bwd_cosh",
    "bwd_tanh",
    "bwd_atan",
    "bwd_asin",
    "bwd_acos",
    "bwd_asinh",
    "bwd_acosh",
    "bwd_atanh",
    "bwd_rpow",
    "bwd_sign",
]

_INF = np.inf
_HALF_PI = 0.5 * np.pi  # the float below π/2
_PI = float(np.pi)  # the float below π
_HALF_PI_UP = float(np.nextafter(0.5 * np.pi, np.inf))
_PI_LO = _PI
_PI_HI = float(np.nextafter(np.pi, np.inf))


def _meet(alo, ahi, blo, bhi):
    return np.maximum(alo, blo), np.minimum(ahi, bhi)


def _hull_of_meets(xlo, xhi, p1lo, p1hi, p2lo, p2hi):
    """hull((x ∩ p1) ∪ (x ∩ p2)), empty if both are empty."""
    alo, ahi = _meet(xlo, xhi, p1lo, p1hi)
    blo, bhi = _meet(xlo, xhi, p2lo, p2hi)
    a_ok = alo <= ahi
    b_ok = blo <= bhi
    lo = np.where(a_ok, np.where(b_ok, np.minimum(alo, blo), alo), np.where(b_ok, blo, _INF))
    hi = np.where(a_ok, np.where(b_ok, np.maximum(ahi, bhi), ahi), np.where(b_ok, bhi, -_INF))
    return lo, hi


def mul_inverse(
    zlo: np.ndarray,
    zhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
) -> Pair:
    """Narrow ``[x]`` to the hull of ``{t ∈ [x] : ∃ y ∈ [y], t*y ∈ [z]}``.

    * ``0 ∉ [y]``: the ordinary quotient ``[z] / [y]`` (four corner quotients; this is
      the common case and is computed for the whole batch at once);
    * ``0 ∈ [y]`` and ``0 ∈ [z]``: any ``t`` works (take ``y = 0``): no contraction;
    * ``0 ∈ [y]``, ``0 ∉ [z]``: the quotient set is two half-lines, one per sign of ``y``;
      each is intersected with ``[x]`` before the hull is taken (only these entries are
      computed, on the compressed subset).
    """
    zlo, zhi, ylo, yhi, xlo, xhi = np.broadcast_arrays(zlo, zhi, ylo, yhi, xlo, xhi)
    shape = zlo.shape
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q1 = zlo / ylo
        q2 = zlo / yhi
        q3 = zhi / ylo
        q4 = zhi / yhi
        qlo = np.minimum(np.minimum(q1, q2), np.minimum(q3, q4))
        qhi = np.maximum(np.maximum(q1, q2), np.maximum(q3, q4))
    out_lo = np.maximum(xlo, down(qlo))
    out_hi = np.minimum(xhi, up(qhi))
    y0 = (ylo <= 0.0) & (yhi >= 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        indeterminate = np.isnan(np.sum(out_lo) + np.sum(out_hi))
    if not indeterminate and not np.any(y0):
        return out_lo, out_hi
    out_lo = np.array(out_lo, copy=True).reshape(-1)
    out_hi = np.array(out_hi, copy=True).reshape(-1)
    if indeterminate:
        _fix_indeterminate(out_lo, out_hi, zlo, zhi, ylo, yhi, xlo, xhi)
    k = np.flatnonzero(y0)
    glo, ghi = _mul_inverse_zero(*(np.ravel(a)[k] for a in (zlo, zhi, ylo, yhi, xlo, xhi)))
    out_lo[k] = glo
    out_hi[k] = ghi
    return out_lo.reshape(shape), out_hi.reshape(shape)


def _fix_indeterminate(lo, hi, zlo, zhi, ylo, yhi, xlo, xhi) -> None:
    """Redo, in place, the entries of ``lo, hi`` (flat views) where a corner quotient is ``∞/∞``.

    With ``0 ∉ [y]`` the quotient set ``[z]/[y]`` is the hull of its corner *limits*; a
    corner ``±∞/±∞`` has no single limit, but the two corners next to it (a finite bound
    over ``∞``, and ``∞`` over a finite bound) bound every quotient near it, so it can be
    left out: ``fmin``/``fmax`` skip it.  ``np.minimum`` would make the bound NaN, which the
    evaluator reads as an *empty* box: a lost solution.  Entries with a NaN operand (an
    empty interval) stay NaN.  (Entries with ``0 ∈ [y]`` are redone by the caller anyway.)
    """
    k = np.flatnonzero(np.isnan(lo) | np.isnan(hi))
    z0, z1, y0, y1, x0, x1 = (np.take(a, k) for a in (zlo, zhi, ylo, yhi, xlo, xhi))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q = (z0 / y0, z0 / y1, z1 / y0, z1 / y1)
        qlo = np.fmin(np.fmin(q[0], q[1]), np.fmin(q[2], q[3]))
        qhi = np.fmax(np.fmax(q[0], q[1]), np.fmax(q[2], q[3]))
        nlo = np.maximum(x0, down(qlo))
        nhi = np.minimum(x1, up(qhi))
    operand_nan = np.isnan(z0) | np.isnan(z1) | np.isnan(y0) | np.isnan(y1)
    operand_nan |= np.isnan(x0) | np.isnan(x1)
    np.put(lo, k, np.where(operand_nan, np.take(lo, k), nlo))
    np.put(hi, k, np.where(operand_nan, np.take(hi, k), nhi))


def _mul_inverse_zero(zlo, zhi, ylo, yhi, xlo, xhi):
    """:func:`mul_inverse` where ``0 ∈ [y]`` (1-D arrays).

    With ``0 ∉ [z]`` the quotient set is two half-lines, both bounded by a quotient of the
    same endpoint ``e`` of ``[z]`` nearest 0 (``e = z̲`` when ``z > 0``, ``z̄`` when ``z < 0``):

    * ``y ∈ (0, ȳ]``: ``[e/ȳ, ∞)`` if ``z > 0``, ``(-∞, e/ȳ]`` if ``z < 0``;
    * ``y ∈ [y̲, 0)``: ``(-∞, e/y̲]`` if ``z > 0``, ``[e/y̲, ∞)`` if ``z < 0``.

    Each half-line is met with ``[x]`` (the infinite end leaves that bound of ``[x]``), then
    the hull of the non-empty meets is taken; ``0 ∈ [z]`` gives ``[x]`` (take ``y = 0``).
    Where that holds for every entry (most calls of HC4), ``[x]`` is returned at once.
    """
    z0 = (zlo <= 0.0) & (zhi >= 0.0)
    if z0.all():
        return xlo, xhi
    zpos = zlo > 0.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        e = np.where(zpos, zlo, zhi)
        qp = e / yhi
        qn = e / ylo
        # meet of [x] with the y > 0 half-line (a) and with the y < 0 one (b)
        alo = np.where(zpos, np.maximum(xlo, down(qp)), xlo)
        ahi = np.where(zpos, xhi, np.minimum(xhi, up(qp)))
        blo = np.where(zpos, xlo, np.maximum(xlo, down(qn)))
        bhi = np.where(zpos, np.minimum(xhi, up(qn)), xhi)
    a_ok = alo <= ahi
    a_ok &= yhi > 0.0
    b_ok = blo <= bhi
    b_ok &= ylo < 0.0
    glo = np.where(a_ok, np.where(b_ok, np.minimum(alo, blo), alo), np.where(b_ok, blo, _INF))
    ghi = np.where(a_ok, np.where(b_ok, np.maximum(ahi, bhi), ahi), np.where(b_ok, bhi, -_INF))
    return np.where(z0, xlo, glo), np.where(z0, xhi, ghi)


def bwd_add(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x + y."""
    xlo, xhi = _meet(xlo, xhi, *arith.sub(zlo, zhi, ylo, yhi))
    ylo, yhi = _meet(ylo, yhi, *arith.sub(zlo, zhi, xlo, xhi))
    return xlo, xhi, ylo, yhi


def bwd_sub(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x - y."""
    xlo, xhi = _meet(xlo, xhi, *arith.add(zlo, zhi, ylo, yhi))
    ylo, yhi = _meet(ylo, yhi, *arith.sub(xlo, xhi, zlo, zhi))
    return xlo, xhi, ylo, yhi


def bwd_neg(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = -x."""
    return _meet(xlo, xhi, -zhi, -zlo)


def bwd_shift(
    zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray, c: np.ndarray | float
) -> Pair:
    """z = x + c."""
    return _meet(xlo, xhi, down(zlo - c), up(zhi - c))


def bwd_scale(
    zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray, c: np.ndarray | float
) -> Pair:
    """z = c*x for a float c (no contraction where c == 0)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        p = zlo / c
        q = zhi / c
    lo = np.where(c == 0.0, -_INF, down(np.minimum(p, q)))
    hi = np.where(c == 0.0, _INF, up(np.maximum(p, q)))
    return _meet(xlo, xhi, lo, hi)


def bwd_mul(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x * y."""
    xlo, xhi = mul_inverse(zlo, zhi, ylo, yhi, xlo, xhi)
    ylo, yhi = mul_inverse(zlo, zhi, xlo, xhi, ylo, yhi)
    return xlo, xhi, ylo, yhi


def bwd_div(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x / y, i.e. x = z*y with y != 0."""
    xlo, xhi = _meet(xlo, xhi, *arith.mul(zlo, zhi, ylo, yhi))
    ylo, yhi = mul_inverse(xlo, xhi, zlo, zhi, ylo, yhi)
    return xlo, xhi, ylo, yhi


def bwd_sqr(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = x**2: x ∈ ±sqrt(z ∩ [0, inf))."""
    rlo, rhi = arith.sqrt(zlo, zhi)
    return _hull_of_meets(xlo, xhi, rlo, rhi, -rhi, -rlo)


def bwd_sqrt(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = sqrt(x): x ∈ (z ∩ [0, inf))**2 and x >= 0."""
    zlo = np.maximum(zlo, 0.0)
    slo, shi = arith.sqr(zlo, zhi)
    slo = np.where(zlo > zhi, _INF, slo)
    xlo, xhi = _meet(xlo, xhi, slo, shi)
    return np.maximum(xlo, 0.0), xhi


def _root(zlo, zhi, n):
    """Enclosure of the real n-th root (n >= 3) of z ∩ [0, inf), widened by 1e-12 relative.

    ``z**(1/n)`` uses an inexactly rounded exponent and libm ``pow``; their combined relative
    error is below 1e-13 over the whole float range, so a 1e-12 margin is safe.
    """
    zlo = np.maximum(zlo, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        rlo = np.power(zlo, 1.0 / n)
        rhi = np.power(np.maximum(zhi, 0.0), 1.0 / n)
    rlo = np.maximum(down(rlo * (1.0 - 1e-12)), 0.0)
    rhi = up(rhi * (1.0 + 1e-12) + 1e-300)
    return rlo, rhi


def bwd_pow(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray, n: int) -> Pair:
    """z = x**n for an integer n."""
    n = int(n)
    if n == 1:
        return _meet(xlo, xhi, zlo, zhi)
    if n == 2:
        return bwd_sqr(zlo, zhi, xlo, xhi)
    if n <= 0:
        return xlo, xhi  # sound: no contraction
    if n % 2 == 0:
        rlo, rhi = _root(zlo, zhi, n)
        rlo = np.where(zhi < 0.0, _INF, rlo)
        rhi = np.where(zhi < 0.0, -_INF, rhi)
        return _hull_of_meets(xlo, xhi, rlo, rhi, -rhi, -rlo)
    # odd: x = sign(z) |z|**(1/n), increasing
    plo, phi = _root(np.maximum(zlo, 0.0), zhi, n)  # root of the positive part
    nlo, nhi = _root(np.maximum(-zhi, 0.0), -zlo, n)  # root of |negative part|
    lo = np.where(zlo >= 0.0, plo, -nhi)
    hi = np.where(zhi <= 0.0, -nlo, phi)
    return _meet(xlo, xhi, lo, hi)


def bwd_exp(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = exp(x): x ∈ log(z)."""
    return _meet(xlo, xhi, *elementary.log(zlo, zhi))


def bwd_log(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = log(x): x ∈ exp(z)."""
    return _meet(xlo, xhi, *elementary.exp(zlo, zhi))


def bwd_abs(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = |x|: x ∈ ±(z ∩ [0, inf))."""
    zlo = np.maximum(zlo, 0.0)
    return _hull_of_meets(xlo, xhi, zlo, zhi, -zhi, -zlo)


def bwd_min(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = min(x, y): both >= z.lo; the operand that must be the minimum is <= z.hi."""
    nxlo = np.maximum(xlo, zlo)
    nylo = np.maximum(ylo, zlo)
    nxhi = np.where(ylo > zhi, np.minimum(xhi, zhi), xhi)
    nyhi = np.where(xlo > zhi, np.minimum(yhi, zhi), yhi)
    return nxlo, nxhi, nylo, nyhi


def bwd_max(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = max(x, y): both <= z.hi; the operand that must be the maximum is >= z.lo."""
    nxhi = np.minimum(xhi, zhi)
    nyhi = np.minimum(yhi, zhi)
    nxlo = np.where(yhi < zlo, np.maximum(xlo, zlo), xlo)
    nylo = np.where(xhi < zlo, np.maximum(ylo, zlo), ylo)
    return nxlo, nxhi, nylo, nyhi


def bwd_sinh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = sinh(x): x = asinh(z)."""
    return _meet(xlo, xhi, *elementary.asinh(zlo, zhi))


def bwd_asinh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = asinh(x): x = sinh(z)."""
    return _meet(xlo, xhi, *elementary.sinh(zlo, zhi))


def bwd_tanh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = tanh(x) ∈ (-1, 1): x = atanh(z)."""
    return _meet(xlo, xhi, *elementary.atanh(zlo, zhi))


def bwd_atanh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = atanh(x): x = tanh(z) ∈ [-1, 1]."""
    return _meet(xlo, xhi, *elementary.tanh(zlo, zhi))


def bwd_cosh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = cosh(x) >= 1: x ∈ ±acosh(z)."""
    rlo, rhi = elementary.acosh(zlo, zhi)
    return _hull_of_meets(xlo, xhi, rlo, rhi, -rhi, -rlo)


def bwd_acosh(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = acosh(x) >= 0: x = cosh(z ∩ [0, inf)) >= 1."""
    dead = zhi < 0.0
    clo, chi = elementary.cosh(np.maximum(zlo, 0.0), zhi)
    lo, hi = _meet(xlo, xhi, np.maximum(clo, 1.0), chi)
    return np.where(dead, _INF, lo), np.where(dead, -_INF, hi)


def _branch_inverse(fn, zlo, zhi, rlo, rhi, at_lo, at_hi, increasing=True):
    """Image by ``fn`` of ``z ∩ [rlo, rhi]`` where ``fn`` is monotone on the branch.

    ``rlo, rhi`` are floats *inside* the branch (the float below π/2, ...); a ``z`` bound beyond
    them maps to ``at_lo`` / ``at_hi``, the value of the inverse at the branch's real end (or
    beyond it), so the result is sound even though the float end is not the real one.
    """
    with np.errstate(all="ignore"):
        a = np.clip(zlo, rlo, rhi)
        b = np.clip(zhi, rlo, rhi)
        fa = fn(a)
        fb = fn(b)
    if increasing:
        lo = np.where(zlo <= rlo, at_lo, widen_down(fa))
        hi = np.where(zhi >= rhi, at_hi, widen_up(fb))
    else:
        lo = np.where(zhi >= rhi, at_lo, widen_down(fb))
        hi = np.where(zlo <= rlo, at_hi, widen_up(fa))
    return lo, hi


def bwd_atan(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = atan(x) ∈ (-π/2, π/2): x = tan(z)."""
    lo, hi = _branch_inverse(np.tan, zlo, zhi, -_HALF_PI, _HALF_PI, -_INF, _INF)
    dead = (zhi < -_HALF_PI_UP) | (zlo > _HALF_PI_UP)
    lo, hi = _meet(xlo, xhi, lo, hi)
    return np.where(dead, _INF, lo), np.where(dead, -_INF, hi)


def bwd_asin(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = asin(x) ∈ [-π/2, π/2]: x = sin(z) ∈ [-1, 1]."""
    lo, hi = _branch_inverse(np.sin, zlo, zhi, -_HALF_PI, _HALF_PI, -1.0, 1.0)
    dead = (zhi < -_HALF_PI_UP) | (zlo > _HALF_PI_UP)
    lo, hi = _meet(xlo, xhi, np.maximum(lo, -1.0), np.minimum(hi, 1.0))
    return np.where(dead, _INF, lo), np.where(dead, -_INF, hi)


def bwd_acos(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = acos(x) ∈ [0, π]: x = cos(z) ∈ [-1, 1] (decreasing)."""
    lo, hi = _branch_inverse(np.cos, zlo, zhi, 0.0, _PI, -1.0, 1.0, increasing=False)
    dead = (zhi < 0.0) | (zlo > _PI_HI)
    lo, hi = _meet(xlo, xhi, np.maximum(lo, -1.0), np.minimum(hi, 1.0))
    return np.where(dead, _INF, lo), np.where(dead, -_INF, hi)


def bwd_tan(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = tan(x): x ∈ atan(z) + kπ when ``[x]`` lies between the poles around ``kπ``.

    ``k`` is taken from the midpoint; the branch test and ``kπ`` use outward-rounded bounds
    of π, so a box touching a pole is left unchanged (sound).
    """
    with np.errstate(all="ignore"):
        k = np.round((0.5 * xlo + 0.5 * xhi) / _PI_LO)
        k = np.where(np.abs(k) < 1e8, k, 0.0)  # also NaN / inf midpoints
        klo, khi = elementary.half_pi_multiple(2.0 * k)  # ∋ kπ
        half = 0.5 * _PI_LO  # <= π/2 (exact halving)
        inside = (xlo > up(khi - half)) & (xhi < down(klo + half))
        alo, ahi = elementary.atan(zlo, zhi)
        blo, bhi = arith.add(alo, ahi, klo, khi)
    lo, hi = _meet(xlo, xhi, blo, bhi)
    return np.where(inside, lo, xlo), np.where(inside, hi, xhi)


def _sine_branches(zlo, zhi, xlo, xhi, parity: int):
    """Preimage in ``[x]`` of ``[z]`` by ``sin`` (``parity`` 0) or ``cos`` (``parity`` 1).

    Both are monotone on the branches ``B_m = [c_m - π/2, c_m + π/2]`` centred at
    ``c_m = m π/2`` with ``m ≡ parity (mod 2)``, where ``f(c_m + t) = σ_m sin t``
    (``σ_m = ±1``, and ``σ_{m+2} = -σ_m``): so ``x ∈ B_m`` and ``f(x) ∈ [z]`` give
    ``x ∈ c_m + asin(σ_m [z])``.  The branch ``B_m`` of ``x̲`` and the next one ``B_{m+2}``
    are inverted, each on its part of ``[x]`` (split at the common end ``c_m + π/2``), and the
    hull of the two pieces is kept.  ``[x]`` reaching past ``B_{m+2}`` (wider than about π),
    or not provably inside the two branches, is left unchanged (sound).  The centres and the
    common end are outward-rounded enclosures; ``asin`` is the outward-rounded one of
    :mod:`.elementary`, and ``-asin(s)`` encloses ``asin(-s)`` (an odd function).
    """
    with np.errstate(all="ignore"):
        k = np.floor((xlo - parity * _HALF_PI) / _PI_LO + 0.5)  # x̲ ∈ B_m, m = 2k + parity
        k = np.where(np.abs(k) < 1e8, k, 0.0)  # also NaN / inf bounds
        c0lo, c0hi = elementary.half_pi_multiple(2.0 * k + parity)
        c1lo, c1hi = down(c0lo + _PI_LO), up(c0hi + _PI_HI)  # c_{m+2} = c_m + π
        half = 0.5 * _PI_LO  # <= π/2 (exact halving)
        inside = (xlo > up(c0hi - half)) & (xhi < down(c1lo + half))
        if not np.any(inside):  # every [x] wider than the two branches: nothing to do
            return xlo, xhi
        odd = (k - 2.0 * np.floor(0.5 * k)) != parity  # σ_m = -1
        slo, shi = np.where(odd, -zhi, zlo), np.where(odd, -zlo, zhi)  # σ_m [z]
        alo, ahi = elementary.asin(slo, shi)
        p0lo, p0hi = down(c0lo + alo), np.minimum(up(c0hi + ahi), up(c0hi + 0.5 * _PI_HI))
        p1lo, p1hi = np.maximum(down(c1lo - ahi), down(c0lo + half)), up(c1hi - alo)
        lo, hi = _hull_of_meets(xlo, xhi, p0lo, p0hi, p1lo, p1hi)
    return np.where(inside, lo, xlo), np.where(inside, hi, xhi)


def bwd_sin(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = sin(x): x ∈ mπ + (-1)^m asin(z) on the branch around mπ (two branches at most)."""
    return _sine_branches(zlo, zhi, xlo, xhi, 0)


def bwd_cos(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = cos(x): x ∈ (m+1/2)π - (-1)^m asin(z) on the branch around (m+1/2)π (two at most)."""
    return _sine_branches(zlo, zhi, xlo, xhi, 1)


def bwd_rpow(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x^y (x > 0, or x = 0 < y): x >= 0, and x = z^(1/y) when 0 ∉ [y]; y unchanged."""
    xlo = np.maximum(xlo, 0.0)
    zlo = np.maximum(zlo, 0.0)
    away = (ylo > 0.0) | (yhi < 0.0)
    one = np.ones_like(ylo)
    with np.errstate(all="ignore"):
        rlo, rhi = arith.div(one, one, ylo, yhi)
        plo, phi = elementary.rpow(zlo, zhi, rlo, rhi)
    nlo, nhi = _meet(xlo, xhi, plo, phi)
    nlo = np.where(away, nlo, xlo)
    nhi = np.where(away, nhi, xhi)
    dead = zhi < 0.0
    return np.where(dead, _INF, nlo), np.where(dead, -_INF, nhi), ylo, yhi


def bwd_sign(zlo: np.ndarray, zhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """z = sign(x) ∈ {-1, 0, 1}: x keeps the signs whose value lies in ``[z]``."""
    neg = (zlo <= -1.0) & (zhi >= -1.0)
    zero = (zlo <= 0.0) & (zhi >= 0.0)
    pos = (zlo <= 1.0) & (zhi >= 1.0)
    lo = np.where(neg, -_INF, np.where(zero, 0.0, np.where(pos, 0.0, _INF)))
    hi = np.where(pos, _INF, np.where(zero, 0.0, np.where(neg, 0.0, -_INF)))
    return _meet(xlo, xhi, lo, hi)
