"""Elementary functions on intervals: ``exp``, ``log``, ``sin``, ``cos``.

libm results are not correctly rounded, so bounds are widened by
:data:`~certsolve.interval.rounding.LIBM_ULPS` ulps (:func:`widen_down` / :func:`widen_up`)
instead of one.  ``log`` restricts its argument to ``(0, inf)`` (IBEX's domain convention:
``log([-1, 1]) = [-inf, 0]``, ``log([-2, -1])`` is empty).

``sin`` and ``cos`` are monotone between critical points.  A bound is the extreme value
(``±1``) whenever a critical point ``kπ/2`` may lie in the interval; the test is made on the
interval enlarged by a relative ``1e-9`` so that the inexact value of π in floating point can
never hide a critical point (a false positive only loses tightness).  Intervals wider than
``2π``, or with huge bounds, map to ``[-1, 1]``.
"""

from __future__ import annotations

import numpy as np

from .rounding import widen_down, widen_up

__all__ = ["exp", "log", "sin", "cos"]

_INF = np.inf
_TWO_PI = 2.0 * np.pi
_HUGE = 1e8  # beyond this, return [-1, 1] for sin/cos


def exp(alo, ahi):
    with np.errstate(over="ignore"):
        lo = np.maximum(widen_down(np.exp(alo)), 0.0)
        hi = widen_up(np.exp(ahi))
    lo = np.minimum(lo, np.finfo(np.float64).max)  # exp overflowed: the bound is still finite
    return _keep_empty(lo, hi, alo, ahi)


def log(alo, ahi):
    with np.errstate(divide="ignore", invalid="ignore"):
        lo = np.where(alo <= 0.0, -_INF, widen_down(np.log(np.maximum(alo, 0.0))))
        hi = widen_up(np.log(ahi))
    dead = ahi <= 0.0  # no positive part: empty
    lo = np.where(dead, _INF, lo)
    hi = np.where(dead, -_INF, hi)
    return lo, hi


def _has_point(alo, ahi, offset):
    """Does ``[alo, ahi]`` (slightly enlarged) contain ``offset + 2kπ`` for an integer k?"""
    slack = 1e-9 * np.maximum(1.0, np.maximum(np.abs(alo), np.abs(ahi)))
    k = np.ceil((alo - slack - offset) / _TWO_PI)
    return offset + k * _TWO_PI <= ahi + slack


def cos(alo, ahi):
    with np.errstate(invalid="ignore"):
        ca = np.cos(alo)
        cb = np.cos(ahi)
        lo = widen_down(np.minimum(ca, cb))
        hi = widen_up(np.maximum(ca, cb))
        wide = ~(ahi - alo < _TWO_PI) | ~(np.maximum(np.abs(alo), np.abs(ahi)) < _HUGE)
        has_max = wide | _has_point(alo, ahi, 0.0)
        has_min = wide | _has_point(alo, ahi, np.pi)
    lo = np.where(has_min, -1.0, np.maximum(lo, -1.0))
    hi = np.where(has_max, 1.0, np.minimum(hi, 1.0))
    return _keep_empty(lo, hi, alo, ahi)


def sin(alo, ahi):
    with np.errstate(invalid="ignore"):
        sa = np.sin(alo)
        sb = np.sin(ahi)
        lo = widen_down(np.minimum(sa, sb))
        hi = widen_up(np.maximum(sa, sb))
        wide = ~(ahi - alo < _TWO_PI) | ~(np.maximum(np.abs(alo), np.abs(ahi)) < _HUGE)
        has_max = wide | _has_point(alo, ahi, 0.5 * np.pi)
        has_min = wide | _has_point(alo, ahi, -0.5 * np.pi)
    lo = np.where(has_min, -1.0, np.maximum(lo, -1.0))
    hi = np.where(has_max, 1.0, np.minimum(hi, 1.0))
    return _keep_empty(lo, hi, alo, ahi)


def _keep_empty(lo, hi, alo, ahi):
    emp = ~(alo <= ahi)
    return np.where(emp, _INF, lo), np.where(emp, -_INF, hi)
