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


_SMALL = 512  # below this many elements numpy's nextafter is cheaper (one call, ~5 ns an element)
_MIN_NORMAL = 2.0**-1022


def _step_up(x: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """``x`` moved to the next float up, in place, except where ``keep`` (float64 ``x``).

    Small arrays use numpy's ``nextafter``.  Large ones step the bit patterns: a float's
    bits read as an ``int64`` grow with the float for ``x >= +0`` and shrink for ``x <= -0``,
    so the next float up is one integer step away (``+1`` or ``-1``), once ``-0`` is made
    ``+0``; the same floats, about four times faster than ``nextafter`` there and as fast
    as a margin.  ``keep`` must hold ``+inf`` and NaN (a step would change them).
    """
    kept = x[keep] if keep.any() else None
    if x.size < _SMALL:
        np.nextafter(x, _POS_INF, out=x)
    else:
        np.add(x, 0.0, out=x)  # -0.0 becomes +0.0
        i = x.view(np.int64)
        step = i >> 63  # 0 for x >= +0, -1 for x < 0
        step |= 1
        i += step
    if kept is not None:
        x[keep] = kept
    return x


def up(x, size: int | None = None):
    """The next float above ``x``: an upper bound of any real that rounds to ``x``.

    Exactly ``nextafter(x, +inf)`` at every size (NaN stays NaN, ``-inf`` becomes
    ``-max_float``): the bound of one element does not depend on the array it is in, so a
    batched evaluation gives the same floats however its operations are grouped.  Small
    arrays use numpy's ``nextafter`` (one call), large ones integer steps on the bit
    patterns (:func:`_step_up`).  ``size`` chooses the path as for an array of that many
    elements; the floats are the same either way.
    """
    if (np.size(x) if size is None else size) < _SMALL or np.ndim(x) == 0:
        return np.nextafter(x, _POS_INF)
    y = np.add(x, 0.0, dtype=np.float64)  # a new array
    return _step_up(y, ~(y < _POS_INF))


def down(x, size: int | None = None):
    """The next float below ``x`` (mirror of :func:`up`)."""
    if (np.size(x) if size is None else size) < _SMALL or np.ndim(x) == 0:
        return np.nextafter(x, _NEG_INF)
    y = np.negative(x, dtype=np.float64)
    _step_up(y, ~(y < _POS_INF))
    return np.negative(y, out=y)


def _kept(x: np.ndarray, exact_tiny: bool) -> np.ndarray:
    """Where :func:`up_inplace` leaves ``x``: ``+inf``, NaN, and with ``exact_tiny`` zeros
    and subnormals."""
    if exact_tiny:
        return ~((np.abs(x) >= _MIN_NORMAL) & (x < _POS_INF))
    return ~(x < _POS_INF)


def up_inplace(x: np.ndarray, exact_tiny: bool = False) -> np.ndarray:
    """:func:`up` written into the float array ``x``: the same floats.

    ``exact_tiny=True`` is for results of ``+`` and ``-`` only: a sum or difference of
    floats that rounds to zero or to a subnormal is exact (gradual underflow), so it is
    left as it is.

    A small array is ``nextafter`` (which leaves ``+inf`` and NaN as they are), written
    only where :func:`_kept` would not keep: everywhere, or with ``exact_tiny`` where
    ``|x|`` is normal (NaN is not): two or four numpy calls where the mask took nine.
    """
    if x.size < _SMALL:
        if not exact_tiny:
            return np.nextafter(x, _POS_INF, out=x)
        np.copyto(x, np.nextafter(x, _POS_INF), where=np.abs(x) >= _MIN_NORMAL)
        return x
    return _step_up(x, _kept(x, exact_tiny))


def down_inplace(x: np.ndarray, exact_tiny: bool = False) -> np.ndarray:
    """:func:`down` written into ``x`` (see :func:`up_inplace`)."""
    if x.size < _SMALL:
        if not exact_tiny:
            return np.nextafter(x, _NEG_INF, out=x)
        np.copyto(x, np.nextafter(x, _NEG_INF), where=np.abs(x) >= _MIN_NORMAL)
        return x
    np.negative(x, out=x)
    _step_up(x, _kept(x, exact_tiny))
    return np.negative(x, out=x)


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
