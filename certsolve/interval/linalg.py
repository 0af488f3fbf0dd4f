"""Rigorous interval linear algebra in midpoint-radius form, batched with ``matmul``.

Interval Newton and Krawczyk multiply a *point* preconditioner ``Y`` (an approximate
inverse of ``mid J``) by interval matrices and vectors.  Doing that elementwise with
rounded interval products costs ``n**3`` operations per box; instead we use
``numpy.matmul`` on midpoints and radii and add an *a priori* bound of the floating-point
error (Higham, *Accuracy and Stability of Numerical Algorithms*, Thm 3.1/3.5):

    |fl(A @ B) - A @ B| <= gamma_n |A| @ |B|,   gamma_n = n u / (1 - n u),  u = 2**-53,

valid for any order of summation and with or without fused multiply-add.  All radius
terms are sums of non-negative products computed in round-to-nearest; each is at most a
factor ``1 + gamma_{n+2}`` below its exact value, so we multiply the total radius by
``1 + 2 gamma_{n+4}`` and add a small absolute term for underflow.  The resulting
``[c - r, c + r]`` is a proven enclosure of every product of members.
"""

from __future__ import annotations

import functools

import numpy as np

from .rounding import up

__all__ = ["gamma", "mr_from_bounds", "mr_to_bounds", "mr_matmul", "point_matmul_interval"]

_U = 2.0**-53
_UNDERFLOW = 2.0**-1000  # per-summand underflow allowance (<< any meaningful width)


@functools.lru_cache(maxsize=256)
def gamma(n: int) -> float:
    """Upper bound of ``n u / (1 - n u)`` (rounded up generously)."""
    nu = n * _U
    return float(up(np.float64(nu / (1.0 - nu) * (1.0 + 4 * _U))))


def mr_from_bounds(lo, hi, size: int | None = None):
    """Midpoint-radius form ``(c, r)`` enclosing ``[lo, hi]``: ``[c - r, c + r] ⊇ [lo, hi]``.

    ``size``: round as inside an array of that many elements (:func:`.rounding.up`).
    """
    with np.errstate(invalid="ignore", over="ignore"):
        c = 0.5 * lo + 0.5 * hi
        r = np.maximum(up(hi - c, size), up(c - lo, size))
    return c, r


def mr_to_bounds(c, r):
    """Bounds ``[c - r, c + r]`` rounded outward."""
    return np.nextafter(c - r, -np.inf), np.nextafter(c + r, np.inf)


def mr_matmul(ac, ar, bc, br):
    """Enclosure ``(c, r)`` of ``{A @ B : A ∈ ⟨ac, ar⟩, B ∈ ⟨bc, br⟩}`` (batched matmul shapes).

    ``ar`` or ``br`` may be ``None`` for point operands.  Uses
    ``|A B - ac bc| <= |ac| br + ar (|bc| + br)`` plus the rounding error of ``ac @ bc``.
    """
    n = ac.shape[-1]
    c = ac @ bc
    abs_ac = np.abs(ac)
    abs_bc = np.abs(bc)
    # |ac| (gamma |bc| + br): the rounding error of ac @ bc and the radius of B in one product
    rb = gamma(n) * abs_bc if br is None else gamma(n) * abs_bc + br
    r = abs_ac @ rb
    if ar is not None:
        r = r + ar @ (abs_bc if br is None else abs_bc + br)
    r = r * (1.0 + 2.0 * gamma(n + 4)) + (n + 2) * _UNDERFLOW
    # infinities: inf * 0 gives NaN; an infinite radius is the honest answer there
    r = np.where(np.isnan(r), np.inf, r)
    c = np.where(np.isnan(c), 0.0, c)
    return c, r


def point_matmul_interval(a, blo, bhi):
    """Bounds of ``a @ [B]`` for a point matrix ``a`` and interval matrix/vector ``[B]``."""
    bc, br = mr_from_bounds(blo, bhi)
    c, r = mr_matmul(a, None, bc, br)
    return mr_to_bounds(c, r)
