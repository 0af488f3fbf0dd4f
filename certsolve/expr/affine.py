"""Batched affine forms of a DAG's outputs over boxes: ``f(x) ∈ c₀ + c·(x - m) ± e``.

For a box ``X = [lo, hi]`` with (floating-point) midpoint ``m`` and radius ``r`` (rounded up,
so that ``X ⊆ [m - r, m + r]``), every node ``v`` of a :class:`~.program.Program` gets an
*affine form* ``(c₀, c, e)``: for every ``x ∈ X``,

    v(x) = c₀ + Σ_j c_j (x_j - m_j) + δ,    |δ| <= e,

with ``c₀``, ``c`` floats and ``e >= 0`` a rigorous bound (Comba & Stolfi 1993; de Figueiredo
& Stolfi 2004).  Unlike an interval, the form keeps the first-order dependence on each
variable, so ``x² - x·y`` over a wide box is not the difference of two unrelated ranges.
The rules, with ``R(v) = Σ_j |c_j| r_j + e`` the radius of a form:

* variable ``x_j``: ``(m_j, e_j, 0)``; a constant or parameter ``[a, b]``: its midpoint,
  no coefficients, its radius;
* ``u ± v``, ``-u``, ``u + p``, ``p·u``: exact on the forms;
* ``u·v``: ``(u₀v₀, u₀c_v + v₀c_u, |u₀|e_v + |v₀|e_u + R(u)R(v))``;
* ``u²``: ``(u₀² + R²/2, 2u₀c_u, 2|u₀|e_u + R²/2)`` (the quadratic term lies in ``[0, R²]``);
* ``f(u)`` for division (``u · (1/v)``), the other integer powers and every elementary
  function with a derivative: the mean value at the centre, ``f(u₀) + f'(ξ)(u - u₀)``: its
  slope is the midpoint ``α`` of the interval derivative ``f'(U)`` over the range
  ``U = u₀ ± R`` of ``u``, and ``max|f'(U) - α|·R`` goes into ``e``.  ``f'(U)`` is infinite
  wherever ``U`` reaches outside ``f``'s domain (0 for log and sqrt, ±1 for asin ...), so
  no form is made there;
* ``abs``, ``sign``, ``min``, ``max``, ``atan2``, real powers: the interval the operation
  gives on its arguments' ranges ``c₀ ± R``, as a form without coefficients (sound, but it
  forgets the dependence; the X-Taylor rows of :mod:`certsolve.solver.relaxation` still
  see it).

**Rounding.**  Every coefficient is one floating-point expression of at most three
operations on the operands' coefficients, so it differs from its exact value by at most
``γ₃`` times the sum of the magnitudes of its terms (Higham, Thm 3.1, plus the underflow
unit).  That error, weighted by ``r_j`` (and ``1`` for ``c₀``), is added to ``e``; ``e``
itself is a sum of non-negative products computed in floating point, multiplied by
``1 + γ_K`` (``K`` grows with ``n``) and increased by an absolute underflow term, which
bounds its exact value.  A form whose numbers overflow is not finite: the caller drops it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..interval import arith as A
from ..interval import elementary as EL
from ..interval.linalg import gamma as _gamma
from ..interval.linalg import mr_from_bounds
from ..interval.rounding import up
from .ops import FORWARD
from .program import Program

__all__ = ["AffineForms", "affine_forms"]


@dataclass(kw_only=True)
class AffineForms:
    """Affine forms of ``k`` outputs over ``B`` boxes of ``n`` variables.

    ``c0`` ``(B, k)``, ``c`` ``(B, k, n)``, ``e`` ``(B, k)``: for every ``x`` in box ``b``,
    output ``i`` lies in ``c0[b, i] + c[b, i]·(x - mid[b]) ± e[b, i]``.  ``mid`` ``(B, n)``.
    """

    c0: np.ndarray
    c: np.ndarray
    e: np.ndarray
    mid: np.ndarray


def affine_forms(prog: Program, lo: np.ndarray, hi: np.ndarray, plo=None, phi=None) -> AffineForms:
    """Affine forms of ``prog``'s outputs over the boxes ``lo, hi`` ``(B, n)`` (module doc).

    ``plo, phi`` are the parameter bounds (``(p,)``, the same for every box).
    """
    B, n = lo.shape
    N = prog.n_nodes
    with np.errstate(all="ignore"):
        mid = 0.5 * lo + 0.5 * hi
        mid = np.where(np.isfinite(mid), mid, 0.0)
        ctx = _Rounding(up(np.maximum(hi - mid, mid - lo)))  # X ⊆ [mid - r, mid + r]
        c0 = np.zeros((N, B))
        C = np.zeros((N, B, n))
        E = np.zeros((N, B))
        c0[:n] = mid.T
        C[np.arange(n), :, np.arange(n)] = 1.0
        if prog.n_params:
            _const_rows(c0, E, prog.param_slice, np.asarray(plo, float), np.asarray(phi, float))
        _const_rows(c0, E, prog.const_slice, prog.const_lo[:, 0], prog.const_hi[:, 0])
        for g in prog.fwd_groups:
            s, op = slice(g.start, g.stop), g.op
            a = (c0[g.a], C[g.a], E[g.a])
            b = None if g.b is None else (c0[g.b], C[g.b], E[g.b])
            if op in ("add", "sub"):
                c0[s], C[s], E[s] = ctx.add(a, b, 1.0 if op == "add" else -1.0)
            elif op == "neg":
                c0[s], C[s], E[s] = -a[0], -a[1], a[2]
            elif op == "cadd":
                p = np.asarray(g.param)  # (k, 1): exact floats
                c0[s] = a[0] + p
                C[s] = a[1]
                E[s] = ctx.close(a[2], np.abs(a[0]) + np.abs(p), None, 1)
            elif op == "cmul":
                p = np.asarray(g.param)
                c0[s] = a[0] * p
                C[s] = a[1] * p[:, :, None]
                E[s] = ctx.close(a[2] * np.abs(p), np.abs(c0[s]), np.abs(C[s]), 1)
            elif op == "mul":
                c0[s], C[s], E[s] = ctx.mul(a, b)
            elif op == "sqr" or (op == "pow" and g.param == 2):
                c0[s], C[s], E[s] = ctx.sqr(a)
            elif op == "div":
                c0[s], C[s], E[s] = ctx.mul(a, ctx.smooth(b, _recip_forward, _DERIV["recip"], None))
            elif op in _DERIV:
                c0[s], C[s], E[s] = ctx.smooth(a, FORWARD[op], _DERIV[op], g.param)
            else:
                c0[s], C[s], E[s] = ctx.interval(a, b, FORWARD[op], g.param)
        out = prog.outputs
        return AffineForms(
            c0=c0[out].T.copy(),
            c=np.ascontiguousarray(np.swapaxes(C[out], 0, 1)),
            e=E[out].T.copy(),
            mid=mid,
        )


def _const_rows(c0, E, rows: slice, lo: np.ndarray, hi: np.ndarray) -> None:
    """Constants and parameters ``[lo, hi]``: the midpoint and the radius, rounded up."""
    m, rad = mr_from_bounds(lo, hi)
    c0[rows] = m[:, None]
    E[rows] = rad[:, None]


def _shifted_sqr(lo, hi, sign: float, c: float):
    """``c + sign·[u]²``."""
    slo, shi = A.sqr(lo, hi)
    if sign < 0:
        slo, shi = A.neg(slo, shi)
    return A.shift(slo, shi, c)


def _inv_sqrt(lo, hi):
    """``1 / √[u]``."""
    rlo, rhi = A.sqrt(lo, hi)
    return A.recip(rlo, rhi)


def _d_sqrt(lo, hi, p):
    return A.scale(*_inv_sqrt(lo, hi), 0.5)


def _d_tan(lo, hi, p):
    return _shifted_sqr(*EL.tan(lo, hi), 1.0, 1.0)


def _d_tanh(lo, hi, p):
    return _shifted_sqr(*EL.tanh(lo, hi), -1.0, 1.0)


def _d_acos(lo, hi, p):
    return A.neg(*_inv_sqrt(*_shifted_sqr(lo, hi, -1.0, 1.0)))


def _d_pow(lo, hi, p):
    return A.scale(*A.pow_int(lo, hi, p - 1), float(p))


def _d_recip(lo, hi, p):
    return A.neg(*A.recip(*A.sqr(lo, hi)))


#: interval derivatives ``f'([u])`` of the operations with the mean-value rule; each is
#: infinite where ``[u]`` reaches outside ``f``'s domain (0 for log, sqrt; ±1 for asin...)
_DERIV = {
    "exp": lambda lo, hi, p: EL.exp(lo, hi),
    "log": lambda lo, hi, p: A.recip(lo, hi),
    "sqrt": _d_sqrt,
    "sin": lambda lo, hi, p: EL.cos(lo, hi),
    "cos": lambda lo, hi, p: A.neg(*EL.sin(lo, hi)),
    "tan": _d_tan,
    "sinh": lambda lo, hi, p: EL.cosh(lo, hi),
    "cosh": lambda lo, hi, p: EL.sinh(lo, hi),
    "tanh": _d_tanh,
    "atan": lambda lo, hi, p: A.recip(*_shifted_sqr(lo, hi, 1.0, 1.0)),
    "asinh": lambda lo, hi, p: _inv_sqrt(*_shifted_sqr(lo, hi, 1.0, 1.0)),
    "asin": lambda lo, hi, p: _inv_sqrt(*_shifted_sqr(lo, hi, -1.0, 1.0)),
    "acos": _d_acos,
    "atanh": lambda lo, hi, p: A.recip(*_shifted_sqr(lo, hi, -1.0, 1.0)),
    "acosh": lambda lo, hi, p: _inv_sqrt(*_shifted_sqr(lo, hi, 1.0, -1.0)),
    "pow": _d_pow,
    "recip": _d_recip,
}


def _recip_forward(lo, hi, b, c, p):
    """``1 / [u]`` with the signature of :data:`.ops.FORWARD` (division is ``u · (1/v)``)."""
    return A.recip(lo, hi)


class _Rounding:
    """The rules on forms ``(c₀, c, e)`` (arrays ``(k, B)``, ``(k, B, n)``, ``(k, B)``) for
    boxes of radii ``r`` ``(B, n)``, with the rounding bounds of the module doc."""

    def __init__(self, r: np.ndarray):
        n = r.shape[1]
        self.r = r
        self.big = 1.0 + _gamma(4 * n + 32)  # the relative slack of every computed e
        # an absolute bound of the underflow of every product of a rule (< 2^60 of them)
        self.under = (1.0 + np.sum(r, axis=1)) * 2.0**-960

    def radius(self, a):
        """An upper bound of ``R = Σ|c_j| r_j + e`` (``inf`` where it is NaN: ``0·inf``
        in an unbounded box)."""
        R = (np.einsum("kbn,bn->kb", np.abs(a[1]), self.r) + a[2]) * self.big + self.under
        return np.where(np.isnan(R), np.inf, R)

    def range(self, a):
        """An interval ``c₀ ± R`` holding ``u`` (the whole line where it is not a number:
        no interval function may then turn a NaN bound into a finite one)."""
        rad = self.radius(a)
        lo, hi = -up(rad - a[0]), up(a[0] + rad)
        return np.where(np.isnan(lo), -np.inf, lo), np.where(np.isnan(hi), np.inf, hi)

    def close(self, e_terms, mag0, mag, k: int):
        """``e`` from its exact terms and the rounding of a rule of ``k`` operations per
        coefficient (``mag0``, ``mag``: the magnitudes of the terms of ``c₀`` and ``c``)."""
        rounding = mag0 if mag is None else mag0 + np.einsum("kbn,bn->kb", mag, self.r)
        return (e_terms + _gamma(k) * rounding) * self.big + self.under

    def add(self, a, b, sign: float):
        c0 = a[0] + sign * b[0]
        C = a[1] + sign * b[1]
        mag0, mag = np.abs(a[0]) + np.abs(b[0]), np.abs(a[1]) + np.abs(b[1])
        return c0, C, self.close(a[2] + b[2], mag0, mag, 1)

    def mul(self, a, b):
        """``u·v = u₀v₀ + u₀c_v·t + v₀c_u·t + (u₀δ_v + v₀δ_u) + (u - u₀)(v - v₀)``."""
        a0, b0 = a[0], b[0]
        t1, t2 = a0[:, :, None] * b[1], b0[:, :, None] * a[1]
        c0 = a0 * b0
        e_terms = np.abs(a0) * b[2] + np.abs(b0) * a[2] + self.radius(a) * self.radius(b)
        return c0, t1 + t2, self.close(e_terms, np.abs(c0), np.abs(t1) + np.abs(t2), 3)

    def sqr(self, a):
        """``u² = u₀² + 2u₀c_u·t + 2u₀δ_u + (u - u₀)²``, the last in ``[0, R²] = R²/2 ± R²/2``."""
        a0 = a[0]
        ra = self.radius(a)
        h = 0.5 * (ra * ra)
        C = (2.0 * a0)[:, :, None] * a[1]
        e_terms = 2.0 * np.abs(a0) * a[2] + h
        return a0 * a0 + h, C, self.close(e_terms, a0 * a0 + h, np.abs(C), 3)

    def smooth(self, a, f, df, param):
        """Mean value at the centre: ``f(u) = f(u₀) + f'(ξ)(u - u₀)``, ``ξ`` in the range
        ``U = u₀ ± R`` of ``u``; with ``α`` the midpoint of ``f'(U)``:
        ``c₀ ± e ∋ f(u₀)``, ``c = α c_u``, ``e += |α| e_u + max|f'(U) - α| R``."""
        a0 = a[0]
        ra = self.radius(a)
        flo, fhi = f(a0, a0, None, None, param)
        dlo, dhi = df(*self.range(a), param)
        c0, frad = mr_from_bounds(flo, fhi)
        alpha = 0.5 * dlo + 0.5 * dhi
        dev = up(np.maximum(dhi - alpha, alpha - dlo))
        C = alpha[:, :, None] * a[1]
        e_terms = frad + np.abs(alpha) * a[2] + dev * ra
        e = self.close(e_terms, np.zeros_like(c0), np.abs(C), 1)
        return c0, C, np.where(np.isfinite(a0), e, np.nan)  # f(NaN) may look finite

    def interval(self, a, b, f, param):
        """No rule: the interval of ``f`` on the arguments' ranges ``c₀ ± R``, without
        coefficients (sound; it forgets the dependence on the variables)."""
        if b is None:
            zlo, zhi = f(*self.range(a), None, None, param)
        else:
            zlo, zhi = f(*self.range(a), *self.range(b), param)
        c0, rad = mr_from_bounds(zlo, zhi)
        return c0, np.zeros_like(a[1]), rad
