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

import numpy as np

__all__ = ["down", "up", "widen_down", "widen_up", "LIBM_ULPS", "EPS", "TINY"]

_NEG_INF = -np.inf
_POS_INF = np.inf

#: unit roundoff of binary64 is 2**-53; EPS is the spacing of floats at 1.0
EPS = 2.0**-52
#: smallest positive subnormal
TINY = 2.0**-1074
#: safety margin (in ulps) applied to results of libm functions
LIBM_ULPS = 8


def down(x):
    """The next float below ``x`` (elementwise): a lower bound of anything that rounds to x."""
    return np.nextafter(x, _NEG_INF)


def up(x):
    """The next float above ``x`` (elementwise): an upper bound of anything that rounds to x."""
    return np.nextafter(x, _POS_INF)


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
