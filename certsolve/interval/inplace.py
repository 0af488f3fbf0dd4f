"""Fewer-pass interval kernels for the batched evaluator (:mod:`certsolve.expr.program`).

Same enclosures as :mod:`.arith` / :mod:`.projections`, computed with fewer temporary
arrays and memory passes (``out=`` arguments, results written straight into the
evaluator's node arrays).  Differences from the general functions, all sound:

* results of ``+`` and ``-`` that are zero or subnormal are not moved: such a sum or
  difference of floats is exact (gradual underflow); the others move one ulp out, as
  everywhere (:func:`.rounding.up_inplace`);
* empty operands are not propagated as empty results (the evaluator detects an empty
  node wherever it occurs; mapping an empty operand to a non-empty result only loses
  information);
* a product bound that is NaN (``0 · ∞`` in every corner) is replaced by 0, as in
  :func:`.arith.mul`, but only after a cheap check.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from .core import Pair, Quad
from .projections import _mul_inverse_zero
from .rounding import down_inplace, up_inplace

__all__ = [
    "down_",
    "up_",
    "down_sum_",
    "up_sum_",
    "add_into",
    "sub_into",
    "mul_into",
    "shift_into",
    "bwd_add",
    "bwd_sub",
    "mul_inverse",
    "bwd_mul",
]

_INF = np.inf


#: round ``x`` down / up in place (any operation)
down_ = down_inplace
up_ = up_inplace
#: round down / up in place a result of ``+`` or ``-`` (exact when zero or subnormal)
down_sum_ = partial(down_inplace, exact_tiny=True)
up_sum_ = partial(up_inplace, exact_tiny=True)


# -- forward, into preallocated rows -------------------------------------------------------------


def add_into(
    alo: np.ndarray,
    ahi: np.ndarray,
    blo: np.ndarray,
    bhi: np.ndarray,
    olo: np.ndarray,
    ohi: np.ndarray,
) -> None:
    np.add(alo, blo, out=olo)
    down_sum_(olo)
    np.add(ahi, bhi, out=ohi)
    up_sum_(ohi)


def sub_into(
    alo: np.ndarray,
    ahi: np.ndarray,
    blo: np.ndarray,
    bhi: np.ndarray,
    olo: np.ndarray,
    ohi: np.ndarray,
) -> None:
    np.subtract(alo, bhi, out=olo)
    down_sum_(olo)
    np.subtract(ahi, blo, out=ohi)
    up_sum_(ohi)


def shift_into(
    alo: np.ndarray, ahi: np.ndarray, c: np.ndarray | float, olo: np.ndarray, ohi: np.ndarray
) -> None:
    np.add(alo, c, out=olo)
    down_sum_(olo)
    np.add(ahi, c, out=ohi)
    up_sum_(ohi)


def mul_into(
    alo: np.ndarray,
    ahi: np.ndarray,
    blo: np.ndarray,
    bhi: np.ndarray,
    olo: np.ndarray,
    ohi: np.ndarray,
) -> None:
    with np.errstate(invalid="ignore", over="ignore"):
        p1 = alo * blo
        p2 = alo * bhi
        p3 = ahi * blo
        p4 = ahi * bhi
    np.fmax(p1, p2, out=ohi)
    np.fmax(ohi, p3, out=ohi)
    np.fmax(ohi, p4, out=ohi)
    np.fmin(p1, p2, out=olo)
    np.fmin(olo, p3, out=olo)
    np.fmin(olo, p4, out=olo)
    # NaN only where every corner is 0·∞: the product set is {0}
    for o in (olo, ohi):
        bad = np.isnan(o)
        if bad.any():
            o[bad] = 0.0
    down_(olo)
    up_(ohi)


# -- backward projections -------------------------------------------------------------------------


def bwd_add(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x + y: ``x ∩ (z - y)``, then ``y ∩ (z - x')``."""
    nxlo = down_sum_(zlo - yhi)
    np.maximum(nxlo, xlo, out=nxlo)
    nxhi = up_sum_(zhi - ylo)
    np.minimum(nxhi, xhi, out=nxhi)
    nylo = down_sum_(zlo - nxhi)
    np.maximum(nylo, ylo, out=nylo)
    nyhi = up_sum_(zhi - nxlo)
    np.minimum(nyhi, yhi, out=nyhi)
    return nxlo, nxhi, nylo, nyhi


def bwd_sub(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x - y: ``x ∩ (z + y)``, then ``y ∩ (x' - z)``."""
    nxlo = down_sum_(zlo + ylo)
    np.maximum(nxlo, xlo, out=nxlo)
    nxhi = up_sum_(zhi + yhi)
    np.minimum(nxhi, xhi, out=nxhi)
    nylo = down_sum_(nxlo - zhi)
    np.maximum(nylo, ylo, out=nylo)
    nyhi = up_sum_(nxhi - zlo)
    np.minimum(nyhi, yhi, out=nyhi)
    return nxlo, nxhi, nylo, nyhi


def mul_inverse(
    zlo: np.ndarray,
    zhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
) -> Pair:
    """``[x] ∩ {t : ∃ y ∈ [y], t·y ∈ [z]}`` (hull), as :func:`.projections.mul_inverse`.

    2-D arrays of one shape.  Corner quotients for the whole batch; the entries with
    ``0 ∈ [y]`` are recomputed on the compressed subset.  The hull of the corners skips
    NaN (``fmin``/``fmax``, the same bits as ``minimum``/``maximum`` otherwise): a corner
    ``±∞/±∞`` has no single limit but its two neighbours bound every quotient near it, so
    it can be left out, where a NaN bound would read as an empty box (a lost solution).
    A NaN from an empty operand may be lost here; that operand's row still marks the box
    empty (see the module doc).
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q1 = zlo / ylo
        q2 = zlo / yhi
        q3 = zhi / ylo
        q4 = zhi / yhi
        hi = np.fmax(q1, q2)
        np.fmax(hi, q3, out=hi)
        np.fmax(hi, q4, out=hi)
        lo = np.fmin(q1, q2, out=q1)
        np.fmin(lo, q3, out=lo)
        np.fmin(lo, q4, out=lo)
    down_(lo)
    np.maximum(lo, xlo, out=lo)
    up_(hi)
    np.minimum(hi, xhi, out=hi)
    y0 = ylo <= 0.0
    y0 &= yhi >= 0.0
    if y0.any():
        k = np.flatnonzero(y0)
        glo, ghi = _mul_inverse_zero(*(np.take(a, k) for a in (zlo, zhi, ylo, yhi, xlo, xhi)))
        np.put(lo, k, glo)
        np.put(hi, k, ghi)
    return lo, hi


def bwd_mul(
    zlo: np.ndarray,
    zhi: np.ndarray,
    xlo: np.ndarray,
    xhi: np.ndarray,
    ylo: np.ndarray,
    yhi: np.ndarray,
) -> Quad:
    """z = x * y."""
    nxlo, nxhi = mul_inverse(zlo, zhi, ylo, yhi, xlo, xhi)
    nylo, nyhi = mul_inverse(zlo, zhi, nxlo, nxhi, ylo, yhi)
    return nxlo, nxhi, nylo, nyhi
