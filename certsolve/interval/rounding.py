"""Outward rounding: the one place where floating-point results become enclosures.

numpy computes in IEEE-754 binary64 with round-to-nearest.  For the basic operations
(``+ - * /`` and ``sqrt``) the computed result is the exact result rounded to the nearest
float, so moving it one float outward (``nextafter``) gives a bound that encloses the
exact result.  Elementary functions (``exp``, ``log``, ``sin``, ``cos``) come from libm
or numpy's SIMD kernels, which are *not* correctly rounded; their documented error is a
few ulps, so :func:`widen_down` / :func:`widen_up` move them outward by ``LIBM_ULPS`` ulps
(relative) plus a tiny absolute amount, well beyond any documented error.

Every interval operation in :mod:`certsolve.interval` funnels its bounds through these
functions; this is what makes an interval result a proof.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = [
    "down",
    "up",
    "down_inplace",
    "up_inplace",
    "widen_down",
    "widen_up",
    "rational_enclosure",
    "LIBM_ULPS",
    "EPS",
    "TINY",
]

_NEG_INF = -np.inf
_POS_INF = np.inf

#: unit roundoff of binary64 is 2**-53; EPS is the spacing of floats at 1.0
EPS = 2.0**-52
#: smallest positive subnormal
TINY = 2.0**-1074
#: safety margin (in ulps) applied to results of libm functions
LIBM_ULPS = 8


_MAX = float(np.finfo(np.float64).max)
_BIG = 2.0**1000
_SMALL = 64  # below this many elements numpy's nextafter is cheaper (one call)


def _margin(x, tiny: bool = True) -> np.ndarray:
    """``min(|x|·2^-52, 2^1000) (+ 2^-1074)``: at least one ulp of ``x`` (a new array)."""
    a = np.abs(x)
    a *= EPS
    np.fmin(a, _BIG, out=a)
    if tiny:
        a += TINY
    return a


def up(x, size: int | None = None):
    """An upper bound, as a float, of any real that rounds to ``x`` (elementwise).

    Small arrays use ``nextafter``.  Large ones use ``x + (|x|·2^-52 + 2^-1074)``, ~9x
    faster in numpy: ``|x|·2^-52`` is at least the spacing of floats above ``x`` (exactly
    ``ulp(x)`` for positive ``x``, twice the spacing above a negative power of two), so the
    rounded sum is at least the next float after ``x``; the ``2^-1074`` term covers 0 and
    subnormals.  The ``|x|`` term is capped so that ``-inf`` (an overflowed negative value)
    becomes ``-max_float`` as with ``nextafter``; NaN stays NaN.

    ``size`` chooses the rule as for an array of that many elements: a column updated on
    its own then rounds exactly as it would inside its whole array.
    """
    if (np.size(x) if size is None else size) < _SMALL:
        return np.nextafter(x, _POS_INF)
    a = _margin(x)
    a += x
    return np.maximum(a, -_MAX, out=a)


def down(x, size: int | None = None):
    """A lower bound, as a float, of any real that rounds to ``x`` (mirror of :func:`up`)."""
    if (np.size(x) if size is None else size) < _SMALL:
        return np.nextafter(x, _NEG_INF)
    a = _margin(x)
    np.subtract(x, a, out=a)
    return np.minimum(a, _MAX, out=a)


def up_inplace(x: np.ndarray, exact_tiny: bool = False) -> np.ndarray:
    """:func:`up` written into the float array ``x`` (the large-array rule at any size).

    ``exact_tiny=True`` is for results of ``+`` and ``-`` only: a sum or difference of
    floats that rounds to zero or to a subnormal is exact (gradual underflow), so the
    ``2^-1074`` term is not needed there.
    """
    x += _margin(x, not exact_tiny)
    return np.maximum(x, -_MAX, out=x)


def down_inplace(x: np.ndarray, exact_tiny: bool = False) -> np.ndarray:
    """:func:`down` written into ``x`` (see :func:`up_inplace`)."""
    x -= _margin(x, not exact_tiny)
    return np.minimum(x, _MAX, out=x)


def widen_down(x):
    """Lower bound for a libm result ``x`` whose error is at most a few ulps."""
    with np.errstate(over="ignore", invalid="ignore"):
        r = x - (np.abs(x) * (LIBM_ULPS * EPS) + 2.0**-1020)
    return np.where(np.isnan(r), x, down(r))


def widen_up(x):
    """Upper bound for a libm result ``x`` whose error is at most a few ulps."""
    with np.errstate(over="ignore", invalid="ignore"):
        r = x + (np.abs(x) * (LIBM_ULPS * EPS) + 2.0**-1020)
    return np.where(np.isnan(r), x, up(r))


def rational_enclosure(q: Fraction) -> tuple[float, float]:
    """The tightest float interval containing the exact rational ``q``.

    ``float(q)`` is ``q`` rounded to nearest; compared exactly with ``q``, it is one bound
    and its neighbour the other.  Raises ``OverflowError`` when ``q`` is beyond the float
    range (as ``float(q)`` does).
    """
    x = float(q)
    fx = Fraction(x)
    if fx == q:
        return x, x
    if fx < q:
        return x, float(np.nextafter(x, _POS_INF))
    return float(np.nextafter(x, _NEG_INF)), x
