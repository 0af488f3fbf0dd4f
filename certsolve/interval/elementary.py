"""Elementary functions on intervals: exponential, logarithm, trigonometric, hyperbolic, their
inverses, ``atan2`` and real powers.

libm results are not correctly rounded, so bounds are widened by
:data:`~certsolve.interval.rounding.LIBM_ULPS` ulps (:func:`widen_down` / :func:`widen_up`)
instead of one.  Partial functions follow IBEX's *domain restriction* convention: the image of
an interval is the image of its intersection with the function's domain (``log([-1, 1]) =
[-inf, 0]``, ``asin([0, 2]) = [0, pi/2]``), and an interval with no point in the domain
(``log([-2, -1])``) gives the empty interval.

* Monotone functions (``exp log sinh tanh atan asin acos asinh acosh atanh``) map the end
  points; a bound that overflows stays a valid (finite) bound.
* ``sin``, ``cos`` and ``cosh`` are monotone between critical points.  A bound is the extreme
  value (``±1``, or ``cosh(0) = 1``) whenever a critical point may lie in the interval; for
  ``sin``/``cos`` the critical points ``kπ/2`` are tested with outward-rounded enclosures
  (:func:`half_pi_multiple`), so the inexact value of π in floating point can never hide one
  (a false positive, within an ulp or so, only loses tightness).  Intervals wider than ``2π``,
  or with huge bounds, map to ``[-1, 1]``.
* ``tan`` is increasing between its poles ``π/2 + kπ``; an interval that may contain a pole (same
  test) maps to ``(-inf, inf)``, the hull of the two half-lines.  (A relative slack of 1e-9
  once stood for the enclosure: every box within 1e-9 of a pole then got ``(-inf, inf)``, and
  IBEX's AOL-legentil, whose domain ends 1e-10 before ``π/2``, could not be decided there.)
* ``atan2(y, x)`` (the angle of the point ``(x, y)``, in ``(-π, π]``, undefined at the origin) is
  continuous off the half-line ``{y = 0, x < 0}``; on a box that does not cross it, the angle is
  extreme at a corner, since a box is convex and the directions of a convex set seen from a point
  outside it form an arc ending at the directions of vertices.  A box crossing the half-line maps
  to ``[-π, π]``.
* ``rpow(x, y) = x^y = exp(y log x)`` (IBEX's real power) on the domain ``x > 0``, extended by
  its limits ``0^y = 0`` for ``y > 0``.  For fixed ``y`` it is monotone in ``x``, and for fixed
  ``x`` monotone in ``y``, so over a box it is extreme at a corner (limits at ``x = 0`` or
  ``x = inf`` included: ``0^y`` is ``inf, 1, 0`` and ``inf^y`` is ``0, 1, inf`` for ``y < 0, = 0,
  > 0``, which are monotone in ``y`` too).
"""

from __future__ import annotations

import numpy as np

from .core import Pair
from .rounding import down, up, widen_down, widen_up

__all__ = [
    "exp",
    "log",
    "sin",
    "cos",
    "tan",
    "sinh",
    "cosh",
    "tanh",
    "asin",
    "acos",
    "atan",
    "asinh",
    "acosh",
    "atanh",
    "atan2",
    "rpow",
    "half_pi_multiple",
]

_INF = np.inf
_TWO_PI = 2.0 * np.pi
_HUGE = 1e8  # beyond this, return [-1, 1] for sin/cos ((-inf, inf) for tan)
_MAX = float(np.finfo(np.float64).max)
_HALF_PI_UP = float(np.nextafter(0.5 * np.pi, np.inf))  # > π/2 (float(π/2) is below it)
_PI_UP = float(np.nextafter(np.pi, np.inf))  # > π
_PI_LO = float(np.pi)  # < π


def exp(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    with np.errstate(over="ignore"):
        lo = np.maximum(widen_down(np.exp(alo)), 0.0)
        hi = widen_up(np.exp(ahi))
    lo = np.minimum(lo, np.finfo(np.float64).max)  # exp overflowed: the bound is still finite
    return _keep_empty(lo, hi, alo, ahi)


def log(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    with np.errstate(divide="ignore", invalid="ignore"):
        lo = np.where(alo <= 0.0, -_INF, widen_down(np.log(np.maximum(alo, 0.0))))
        hi = widen_up(np.log(ahi))
    dead = ahi <= 0.0  # no positive part: empty
    lo = np.where(dead, _INF, lo)
    hi = np.where(dead, -_INF, hi)
    return lo, hi


def half_pi_multiple(m: np.ndarray) -> Pair:
    """An enclosure ``[lo, hi]`` of ``m π/2`` for integer-valued floats ``m`` (``|m| < 2^52``):
    the products with the floats around π/2, rounded outward."""
    with np.errstate(invalid="ignore", over="ignore"):
        a = m * (0.5 * _PI_LO)
        b = m * (0.5 * _PI_UP)
    return down(np.minimum(a, b)), up(np.maximum(a, b))


def _scaled(alo, ahi, mag=None):
    """``(slack, (alo - slack) / (π/2))``: what :func:`_may_hold` computes first, the same for
    every candidate (``sin`` and ``cos`` ask twice of one interval).  ``mag``: ``max(|alo|,
    |ahi|)`` if computed already."""
    if mag is None:
        mag = np.maximum(np.abs(alo), np.abs(ahi))
    slack = 1e-9 * np.maximum(1.0, mag)
    return slack, (alo - slack) / (0.5 * np.pi)


def _may_hold(alo, ahi, first, step: int, scaled=None, skip=None):
    """May ``[alo, ahi]`` (narrower than ``step π/2``) contain ``(first + step k) π/2`` for an
    integer ``k``?  (``scaled``: :func:`_scaled` of the interval, if computed already.)

    ``first`` may be an array of candidates' first indices stacked on a new leading axis
    (shape ``(c, 1, ..., 1)``): the answer then has that axis, one row per candidate, in one
    pass of numpy calls.  ``skip``: entries whose answer the caller overrides (wide
    intervals), never sent to the exact test below.

    The nearest candidate above ``alo`` is computed in floats and compared with a relative
    slack of 1e-9 (far more than its rounding error): that settles every interval except
    those with a bound within the slack of the candidate.  Those are decided with
    outward-rounded enclosures of the candidates next to ``alo`` (:func:`half_pi_multiple`),
    so a point is found however close to a bound it lies, and a bound 1e-10 before a pole is
    not taken for the pole.
    """
    # the callers ignore invalid operations (inf - inf at unbounded bounds: no hit)
    slack, q = _scaled(alo, ahi) if scaled is None else scaled
    k = np.ceil((q - first) / step)
    p = (first + step * k) * (0.5 * np.pi)
    hit = p <= ahi + slack
    near = hit & ((p < alo + slack) | (p > ahi - slack))
    if skip is not None:
        near &= ~skip
    if not near.any():
        return hit
    first, alo, ahi, hit = np.broadcast_arrays(first, alo, ahi, hit)
    idx = np.flatnonzero(near)
    lo, hi, first = alo.ravel()[idx], ahi.ravel()[idx], first.ravel()[idx]
    k = np.floor((lo / (0.5 * _PI_LO) - first) / step)
    k = np.where(np.abs(k) < 2**50, k, 0.0)  # NaN / inf / huge: decided by the caller
    exact = np.zeros(idx.size, dtype=bool)
    for d in (0.0, 1.0, 2.0):
        plo, phi = half_pi_multiple(first + step * (k + d))
        exact |= (plo <= hi) & (phi >= lo)
    hit = hit.copy().ravel()
    hit[idx] = exact
    return hit.reshape(alo.shape)


def _sinusoid(fn, alo: np.ndarray, ahi: np.ndarray, top: int) -> Pair:
    """``sin`` or ``cos`` (``fn``), whose maxima are at ``(top + 4k) π/2`` and minima at
    ``(top + 2 + 4k) π/2``: monotone between them, so the image is the hull of the end points'
    values, widened to ``±1`` where an extremum may lie inside (both candidates tested in one
    :func:`_may_hold` pass)."""
    with np.errstate(invalid="ignore"):
        fa = fn(alo)
        fb = fn(ahi)
        lo = widen_down(np.minimum(fa, fb))
        hi = widen_up(np.maximum(fa, fb))
        mag = np.maximum(np.abs(alo), np.abs(ahi))
        wide = ~(ahi - alo < _TWO_PI) | ~(mag < _HUGE)
        firsts = np.array([top, top + 2], dtype=float).reshape((2,) + (1,) * np.ndim(alo))
        has = wide | _may_hold(alo, ahi, firsts, 4, _scaled(alo, ahi, mag), skip=wide)
    lo = np.where(has[1], -1.0, np.maximum(lo, -1.0))
    hi = np.where(has[0], 1.0, np.minimum(hi, 1.0))
    return _keep_empty(lo, hi, alo, ahi)


def cos(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """Maxima at ``2kπ``, minima at ``π + 2kπ``."""
    return _sinusoid(np.cos, alo, ahi, 0)


def sin(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """Maxima at ``π/2 + 2kπ``, minima at ``-π/2 + 2kπ``."""
    return _sinusoid(np.sin, alo, ahi, 1)


def _keep_empty(lo, hi, alo, ahi):
    emp = ~(alo <= ahi)
    return np.where(emp, _INF, lo), np.where(emp, -_INF, hi)


def _finite_bounds(lo: np.ndarray, hi: np.ndarray) -> Pair:
    """A lower bound never ``+inf`` and an upper bound never ``-inf`` (overflowed values)."""
    return np.minimum(lo, _MAX), np.maximum(hi, -_MAX)


def _increasing(fn, alo, ahi, rlo=-_INF, rhi=_INF):
    """Enclosure of an increasing libm function, clipped to its range ``[rlo, rhi]``."""
    with np.errstate(all="ignore"):
        lo = widen_down(fn(alo))
        hi = widen_up(fn(ahi))
    lo, hi = _finite_bounds(np.maximum(lo, rlo), np.minimum(hi, rhi))
    return _keep_empty(lo, hi, alo, ahi)


def _restrict(alo, ahi, dlo, dhi, open_lo=False, open_hi=False):
    """Intersect with the domain ``[dlo, dhi]``; mask of intervals with no point in it.

    ``open_lo`` / ``open_hi`` exclude the end point itself (``atanh`` on ``(-1, 1)``).
    """
    lo = np.maximum(alo, dlo)
    hi = np.minimum(ahi, dhi)
    dead = ~(alo <= ahi) | (ahi < dlo) | (alo > dhi)
    if open_lo:
        dead |= ahi <= dlo
    if open_hi:
        dead |= alo >= dhi
    return lo, hi, dead


def _empty_where(lo, hi, dead):
    return np.where(dead, _INF, lo), np.where(dead, -_INF, hi)


def tan(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``tan`` between poles; ``(-inf, inf)`` when a pole ``π/2 + kπ`` may be inside."""
    with np.errstate(all="ignore"):
        ta = np.tan(alo)
        tb = np.tan(ahi)
        lo = widen_down(ta)
        hi = widen_up(tb)
        wide = ~(ahi - alo < np.pi) | ~(np.maximum(np.abs(alo), np.abs(ahi)) < _HUGE)
        pole = _may_hold(alo, ahi, 1, 2, skip=wide)  # π/2 + kπ
        full = pole | wide | ~(lo <= hi)
    lo = np.where(full, -_INF, lo)
    hi = np.where(full, _INF, hi)
    return _keep_empty(*_finite_bounds(lo, hi), alo, ahi)


def sinh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    return _increasing(np.sinh, alo, ahi)


def cosh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """Even, decreasing then increasing: the minimum 1 is at 0."""
    mig = np.where(ahi < 0.0, -ahi, np.where(alo > 0.0, alo, 0.0))
    mag = np.maximum(np.abs(alo), np.abs(ahi))
    with np.errstate(all="ignore"):
        lo = np.maximum(widen_down(np.cosh(mig)), 1.0)
        hi = widen_up(np.cosh(mag))
    return _keep_empty(*_finite_bounds(lo, hi), alo, ahi)


def tanh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    return _increasing(np.tanh, alo, ahi, -1.0, 1.0)


def atan(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    return _increasing(np.arctan, alo, ahi, -_HALF_PI_UP, _HALF_PI_UP)


def asinh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    return _increasing(np.arcsinh, alo, ahi)


def asin(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``asin`` on ``[-1, 1]`` (domain restriction)."""
    lo, hi, dead = _restrict(alo, ahi, -1.0, 1.0)
    rlo, rhi = _increasing(np.arcsin, lo, hi, -_HALF_PI_UP, _HALF_PI_UP)
    return _empty_where(rlo, rhi, dead)


def acos(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``acos`` on ``[-1, 1]``, decreasing."""
    lo, hi, dead = _restrict(alo, ahi, -1.0, 1.0)
    with np.errstate(all="ignore"):
        rlo = np.maximum(widen_down(np.arccos(hi)), 0.0)
        rhi = np.minimum(widen_up(np.arccos(lo)), _PI_UP)
    return _empty_where(rlo, rhi, dead)


def acosh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``acosh`` on ``[1, inf)``."""
    lo, hi, dead = _restrict(alo, ahi, 1.0, _INF)
    rlo, rhi = _increasing(np.arccosh, lo, hi, 0.0, _INF)
    return _empty_where(rlo, rhi, dead)


def atanh(alo: np.ndarray, ahi: np.ndarray) -> Pair:
    """``atanh`` on ``(-1, 1)``: an end point at ``±1`` gives an infinite bound."""
    lo, hi, dead = _restrict(alo, ahi, -1.0, 1.0, open_lo=True, open_hi=True)
    rlo, rhi = _increasing(np.arctanh, lo, hi)
    return _empty_where(rlo, rhi, dead)


def atan2(ylo: np.ndarray, yhi: np.ndarray, xlo: np.ndarray, xhi: np.ndarray) -> Pair:
    """The angle of ``(x, y)`` in ``(-π, π]`` over a box (see the module docstring).

    Empty when the box is the origin alone (no point of the domain).
    """
    ylo, yhi, xlo, xhi = np.broadcast_arrays(
        np.asarray(ylo, dtype=np.float64) + 0.0,  # -0.0 -> +0.0: atan2(+0, x < 0) = π
        np.asarray(yhi, dtype=np.float64) + 0.0,
        np.asarray(xlo, dtype=np.float64) + 0.0,
        np.asarray(xhi, dtype=np.float64) + 0.0,
    )
    cut = (xlo < 0.0) & (ylo < 0.0) & (yhi >= 0.0)
    with np.errstate(all="ignore"):
        corners = []
        for y in (ylo, yhi):
            for x in (xlo, xhi):
                origin = (x == 0.0) & (y == 0.0)
                corners.append((np.arctan2(y, x), origin))
    big = np.full(ylo.shape, _INF)
    small = np.full(ylo.shape, -_INF)
    for v, origin in corners:
        big = np.where(origin, big, np.minimum(big, v))
        small = np.where(origin, small, np.maximum(small, v))
    dead = (xlo == 0.0) & (xhi == 0.0) & (ylo == 0.0) & (yhi == 0.0)
    with np.errstate(all="ignore"):
        lo = np.maximum(widen_down(big), -_PI_UP)
        hi = np.minimum(widen_up(small), _PI_UP)
    lo = np.where(cut, -_PI_UP, lo)
    hi = np.where(cut, _PI_UP, hi)
    dead |= ~(ylo <= yhi) | ~(xlo <= xhi)
    return _empty_where(lo, hi, dead)


def rpow(xlo: np.ndarray, xhi: np.ndarray, ylo: np.ndarray, yhi: np.ndarray) -> Pair:
    """``x^y = exp(y log x)`` over ``x > 0`` (``0^y = 0`` for ``y > 0``): min/max of corners.

    Empty where the box has no point of the domain (``x < 0``, or ``x = 0`` with ``y <= 0``).
    """
    xlo, xhi, ylo, yhi = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (xlo, xhi, ylo, yhi))
    )
    a = np.maximum(xlo, 0.0)
    big = np.full(a.shape, _INF)
    small = np.full(a.shape, -_INF)
    with np.errstate(all="ignore"):
        for x in (a, xhi):
            for y in (ylo, yhi):
                v = np.power(x, y)
                big = np.minimum(big, v)
                small = np.maximum(small, v)
        lo = np.maximum(widen_down(big), 0.0)
        hi = widen_up(small)
    lo, hi = _finite_bounds(lo, hi)
    dead = (xhi < 0.0) | ((xhi == 0.0) & (yhi <= 0.0)) | ~(xlo <= xhi) | ~(ylo <= yhi)
    return _empty_where(lo, hi, dead)
