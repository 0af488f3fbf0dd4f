"""Slope (mean-value) arithmetic on interval arrays: first-order tight enclosures.

A quantity ``u(x)`` over a box ``X = mid ± r`` is carried as an :class:`MV` triple

* ``m``: an interval containing ``u(mid)``;
* ``x``: an interval containing ``u(X)`` (the natural range);
* ``s[j]``: intervals such that ``u(x) - u(mid) ∈ Σ_j s[j] (x_j - mid_j)`` for every
  ``x ∈ X`` (interval **slopes**; an interval enclosure of ``∂u/∂x_j`` over ``X`` is one).

The rules (Krawczyk & Neumaier's slope arithmetic) keep this invariant:

* ``u ± v``: slopes add;
* ``u v``:  ``uv(x) - uv(mid) = u(x) (v(x) - v(mid)) + v(mid) (u(x) - u(mid))``, slope
  ``u.x · s_v + v.m · s_u``;
* ``u / v``: slope ``s_u / v.x - u.m s_v / (v.x v.m)``;
* ``u²``: slope ``(u.x + u.m) s_u``; ``√u``: slope ``s_u / (√u.x + √u.m)``;
* a Lipschitz ``φ`` with slopes between two points in ``S`` (``φ(s) = τ⁺ max(s,0) +
  τ⁻ min(s,0)``: ``S = {τ⁺}`` on ``s ≥ 0``, ``{τ⁻}`` on ``s ≤ 0``, ``[τ⁻, τ⁺]`` across 0):
  slope ``S · s_u``.

Every interval operation is the outward-rounded one of :mod:`certsolve.interval.arith`, so
:meth:`MV.enclose` ``= x ∩ (m + Σ_j s[j] [-r_j, r_j])`` is a rigorous enclosure of
``u(X)`` whose overestimation is second order in ``r`` (slopes are overestimated by O(r)).
Arrays follow the enclosure module's layout (any shape, batch last).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..interval import arith
from ..interval.core import Pair
from ..interval.linalg import mr_from_bounds, mr_matmul, mr_to_bounds
from ..interval.rounding import down, up
from .wedge import wedge_tables

__all__ = ["MV", "LimitMV", "mv_sum", "wedge_mv", "phi_mv", "pmatmul"]


def _sym(s: Pair, r: np.ndarray) -> np.ndarray:
    """Upper bound of ``|s| · r`` (``s · [-r, r] ⊆ [-bound, bound]``)."""
    mag = np.maximum(np.abs(s[0]), np.abs(s[1]))
    with np.errstate(invalid="ignore"):
        b = up(mag * r)
    return np.where(np.isnan(b), np.inf, b)


def pmatmul(A: np.ndarray, p: Pair) -> Pair:
    """Rigorous bounds of ``A @ [p]`` for a point matrix ``A`` (batched matmul shapes)."""
    c, r = mr_from_bounds(*p)
    c = np.where(np.isfinite(c), c, 0.0)
    r = np.where(np.isfinite(r), r, np.inf)
    cc, rr = mr_matmul(A, None, c, r)
    return mr_to_bounds(cc, rr)


class MV:
    """``(m, x, s)``: midpoint value, range and slopes (see the module docstring)."""

    __slots__ = ("m", "x", "s")

    def __init__(self, m: Pair, x: Pair, s: list[Pair]):
        self.m = m
        self.x = x
        self.s = s

    # -- construction / reshaping ---------------------------------------------------------
    @classmethod
    def const(cls, lo: np.ndarray, hi: np.ndarray, nd: int) -> MV:
        z = np.zeros_like(lo)
        return cls((lo, hi), (lo, hi), [(z, z) for _ in range(nd)])

    def apply(self, fn: Callable[[np.ndarray], np.ndarray]) -> MV:
        """The same array operation (indexing, transposition...) on every part."""
        return MV(
            (fn(self.m[0]), fn(self.m[1])),
            (fn(self.x[0]), fn(self.x[1])),
            [(fn(a), fn(b)) for a, b in self.s],
        )

    def take(self, index: Any) -> MV:
        """``a[index]`` on every part (any numpy index: an integer, arrays, a tuple)."""
        return self.apply(lambda a: a[index])

    def where(self, mask: np.ndarray, value: float) -> MV:
        """Parts replaced by the exact constant ``value`` where ``mask`` holds."""

        def f(a, v):
            return np.where(mask, v, a)

        return MV(
            (f(self.m[0], value), f(self.m[1], value)),
            (f(self.x[0], value), f(self.x[1], value)),
            [(f(a, 0.0), f(b, 0.0)) for a, b in self.s],
        )

    def signed(self, positive: np.ndarray) -> MV:
        """Multiplied by +1 where ``positive`` holds and by -1 elsewhere (exact)."""

        def f(p):
            lo, hi = p
            return np.where(positive, lo, -hi), np.where(positive, hi, -lo)

        return MV(f(self.m), f(self.x), [f(p) for p in self.s])

    # -- arithmetic -----------------------------------------------------------------------
    def __add__(self, o: MV) -> MV:
        return MV(
            arith.add(*self.m, *o.m),
            arith.add(*self.x, *o.x),
            [arith.add(*a, *b) for a, b in zip(self.s, o.s)],
        )

    def __sub__(self, o: MV) -> MV:
        return MV(
            arith.sub(*self.m, *o.m),
            arith.sub(*self.x, *o.x),
            [arith.sub(*a, *b) for a, b in zip(self.s, o.s)],
        )

    def __neg__(self) -> MV:
        return MV(arith.neg(*self.m), arith.neg(*self.x), [arith.neg(*a) for a in self.s])

    def __mul__(self, o: MV) -> MV:
        s = [
            arith.add(*arith.mul(*self.x, *sv), *arith.mul(*o.m, *su))
            for su, sv in zip(self.s, o.s)
        ]
        return MV(arith.mul(*self.m, *o.m), arith.mul(*self.x, *o.x), s)

    def __truediv__(self, o: MV) -> MV:
        den = arith.mul(*o.x, *o.m)
        s = [
            arith.sub(*arith.div(*su, *o.x), *arith.div(*arith.mul(*self.m, *sv), *den))
            for su, sv in zip(self.s, o.s)
        ]
        return MV(arith.div(*self.m, *o.m), arith.div(*self.x, *o.x), s)

    def scale(self, c: np.ndarray | float) -> MV:
        """``c · u`` for point ``c`` (``0 · inf`` counts as 0)."""

        def f(p):
            with np.errstate(invalid="ignore"):
                lo, hi = arith.scale(p[0], p[1], c)
            z = np.broadcast_to(np.asarray(c) == 0, lo.shape)
            return np.where(z, 0.0, lo), np.where(z, 0.0, hi)

        return MV(f(self.m), f(self.x), [f(p) for p in self.s])

    def sqr(self) -> MV:
        t = arith.add(*self.x, *self.m)
        return MV(arith.sqr(*self.m), arith.sqr(*self.x), [arith.mul(*t, *s) for s in self.s])

    def sqrt(self) -> MV:
        rm = arith.sqrt(*self.m)
        rx = arith.sqrt(*self.x)
        den = arith.add(*rx, *rm)
        return MV(rm, rx, [arith.div(*s, *den) for s in self.s])

    # -- result -----------------------------------------------------------------------------
    def enclose(self, radii: np.ndarray) -> Pair:
        """``x ∩ (m + Σ_j s_j [-r_j, r_j])`` (``radii[j]`` broadcasts with the parts)."""
        rad = None
        for j, sj in enumerate(self.s):
            t = _sym(sj, radii[j])
            rad = t if rad is None else up(rad + t)
        if rad is None:
            lo, hi = self.m
        else:
            with np.errstate(invalid="ignore"):
                lo, hi = down(self.m[0] - rad), up(self.m[1] + rad)
        lo = np.maximum(lo, self.x[0])
        hi = np.minimum(hi, self.x[1])
        # both are enclosures, so the intersection cannot be empty; if rounding or a NaN
        # ever made it so, give up on this value rather than prove anything from it
        bad = np.isnan(lo) | np.isnan(hi) | (lo > hi)
        return np.where(bad, -np.inf, lo), np.where(bad, np.inf, hi)

    def tighten(self, radii: np.ndarray) -> MV:
        """Replace the range by :meth:`enclose` (improves later products)."""
        return MV(self.m, self.enclose(radii), self.s)


@dataclass(frozen=True, kw_only=True, slots=True)
class LimitMV:
    """A tension limit that moves with the design parameters, in the slope form of :class:`MV`.

    ``m`` and ``x`` are as in :class:`MV`; ``s[j]`` is ``None`` where the limit does not
    depend on slope variable ``j`` (the pose axes), so that :func:`phi_mv` adds no term
    for it rather than a product with a zero slope.
    """

    m: Pair
    x: Pair
    s: list[Pair | None]


Limit = float | np.ndarray | Pair | LimitMV
"""A tension limit for :func:`phi_mv`: a point (float or array), an interval pair, or a triple."""


def mv_sum(terms: Iterable[MV]) -> MV:
    """``t_0 + t_1 + ...`` from the left, for at least one term."""
    it = iter(terms)
    acc = next(it, None)
    if acc is None:
        raise ValueError("mv_sum needs at least one term")
    for t in it:
        acc = acc + t
    return acc


def _sum_axis0(u: MV) -> MV:
    return mv_sum(u.take(t) for t in range(u.m[0].shape[0]))


def wedge_mv(M: MV) -> MV:
    """Generalised cross products (:func:`~.wedge.wedge_float`) of ``M`` ``(w, w-1, ...)``."""
    w = M.m[0].shape[0]
    if w == 2:
        a = M.apply(lambda t: t[1, 0])
        b = -M.apply(lambda t: t[0, 0])
        return MV(
            (np.stack([a.m[0], b.m[0]]), np.stack([a.m[1], b.m[1]])),
            (np.stack([a.x[0], b.x[0]]), np.stack([a.x[1], b.x[1]])),
            [(np.stack([sa[0], sb[0]]), np.stack([sa[1], sb[1]])) for sa, sb in zip(a.s, b.s)],
        )
    levels, order, csign = wedge_tables(w)
    extra = (1,) * (M.m[0].ndim - 2)
    D = M.apply(lambda a: a[:, 0])
    for r, (row_idx, prev_idx, sign) in enumerate(levels, start=1):
        col = M.take((slice(None), r)).take(row_idx)
        prod = col * D.take(prev_idx)  # (r, C, ...)
        prod = prod.signed((sign > 0).reshape(sign.shape + extra))
        D = _sum_axis0(prod)
    D = D.apply(lambda a: a[order])
    return D.signed((csign > 0).reshape((w,) + extra))


def phi_mv(u: MV, tmin: Limit, tmax: Limit) -> MV:
    """``φ(u) = τmax max(u, 0) + τmin min(u, 0)`` with its slope.

    ``tmin``, ``tmax`` (broadcast with ``u``): floats; interval pairs ``(lo, hi)``; or, when
    the limits depend on the slope variables (design parameters), :class:`LimitMV` triples
    whose slopes may be ``None`` (zero).  Then, from
    ``φ(u, τ) - φ(u_m, τ_m) = [φ(u, τ) - φ(u_m, τ)] + [φ(u_m, τ) - φ(u_m, τ_m)]``, the slope
    is ``S s_u + max(u_m, 0) s_τmax + min(u_m, 0) s_τmin`` with ``S`` the slope set of ``φ``
    in ``u`` over the box (hull over the tension values).
    """
    if isinstance(tmin, LimitMV) and isinstance(tmax, LimitMV):
        return _phi_mv_param(u, tmin, tmax)
    if isinstance(tmin, LimitMV) or isinstance(tmax, LimitMV):
        raise TypeError("phi_mv: tmin and tmax are both LimitMV triples or neither is")
    nlo, nhi = tmin if isinstance(tmin, tuple) else (tmin, tmin)
    xlo_, xhi_ = tmax if isinstance(tmax, tuple) else (tmax, tmax)
    point = (nlo is nhi or np.array_equal(nlo, nhi)) and (
        xlo_ is xhi_ or np.array_equal(xlo_, xhi_)
    )
    xlo, xhi = u.x
    slo, shi = _phi_slopes(xlo, xhi, (nlo, nhi), (xlo_, xhi_), point)
    s = [arith.mul(slo, shi, *sj) for sj in u.s]
    return MV(
        _phi(u.m, (nlo, nhi), (xlo_, xhi_), point), _phi(u.x, (nlo, nhi), (xlo_, xhi_), point), s
    )


def _tscale(lo, hi, t, point: bool):
    """``[t] · [lo, hi]``, ``0 · inf`` counted as 0."""
    if not point:
        return arith.mul(lo, hi, *t)
    with np.errstate(invalid="ignore"):
        rlo, rhi = arith.scale(lo, hi, t[0])
    z = np.broadcast_to(np.asarray(t[0]) == 0, rlo.shape)
    return np.where(z, 0.0, rlo), np.where(z, 0.0, rhi)


def _phi(p, tmin, tmax, point: bool):
    a = _tscale(np.maximum(p[0], 0.0), np.maximum(p[1], 0.0), tmax, point)
    b = _tscale(np.minimum(p[0], 0.0), np.minimum(p[1], 0.0), tmin, point)
    return arith.add(*a, *b)


def _phi_slopes(xlo, xhi, tmin, tmax, point: bool):
    """Slope set of ``φ`` in ``u`` over ``u ∈ [xlo, xhi]``: ``[τmax]`` on ``u ≥ 0``, ``[τmin]``
    on ``u ≤ 0``, their hull across 0."""
    if point:
        tmin_b = np.broadcast_to(tmin[0], xlo.shape)
        tmax_b = np.broadcast_to(tmax[0], xlo.shape)
        slo = np.where(xlo >= 0.0, tmax_b, tmin_b)
        shi = np.where(xhi <= 0.0, tmin_b, tmax_b)
    else:
        n_lo, n_hi = (np.broadcast_to(t, xlo.shape) for t in tmin)
        x_lo, x_hi = (np.broadcast_to(t, xlo.shape) for t in tmax)
        slo = np.where(xlo >= 0.0, x_lo, np.where(xhi <= 0.0, n_lo, np.minimum(n_lo, x_lo)))
        shi = np.where(xlo >= 0.0, x_hi, np.where(xhi <= 0.0, n_hi, np.maximum(n_hi, x_hi)))
    return np.minimum(slo, shi), np.maximum(slo, shi)  # u ≡ 0: any slope, keep it non-empty


def _phi_mv_param(u: MV, tmin: LimitMV, tmax: LimitMV) -> MV:
    """:func:`phi_mv` with tension limits that are slope triples (see its docstring)."""
    slo, shi = _phi_slopes(*u.x, tmin.x, tmax.x, point=False)
    pos = np.maximum(u.m[0], 0.0), np.maximum(u.m[1], 0.0)
    neg = np.minimum(u.m[0], 0.0), np.minimum(u.m[1], 0.0)
    s = []
    for j, sj in enumerate(u.s):
        acc = arith.mul(slo, shi, *sj)
        smax, smin = tmax.s[j], tmin.s[j]
        if smax is not None:
            acc = arith.add(*acc, *arith.mul(*pos, *smax))
        if smin is not None:
            acc = arith.add(*acc, *arith.mul(*neg, *smin))
        s.append(acc)
    m = _phi(u.m, tmin.m, tmax.m, point=False)
    x = _phi(u.x, tmin.x, tmax.x, point=False)
    return MV(m, x, s)
