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
* any other operation (division, powers other than 2, elementary functions): the interval
  the operation gives on its arguments' ranges ``c₀ ± R``, as a form without coefficients
  (sound, but it forgets the dependence: the X-Taylor rows of :mod:`certsolve.solver.
  relaxation` cover those systems).

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

from ..interval.rounding import EPS, up
from .ops import FORWARD
from .program import Program

__all__ = ["AffineForms", "affine_forms"]

_U = EPS / 2


def _gamma(k: int) -> float:
    """``k u / (1 - k u)`` rounded up generously (Higham's ``γ_k``)."""
    return 1.01 * k * _U / (1.0 - k * _U)


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
        r = up(np.maximum(hi - mid, mid - lo))  # X ⊆ [mid - r, mid + r]
        big = 1.0 + _gamma(4 * n + 32)  # the relative slack of every computed e
        # an absolute bound of the underflow of every product of a rule (< 2^60 of them)
        under = (1.0 + np.sum(r, axis=1)) * 2.0**-960
        c0 = np.zeros((N, B))
        C = np.zeros((N, B, n))
        E = np.zeros((N, B))
        c0[:n] = mid.T
        C[np.arange(n), :, np.arange(n)] = 1.0
        if prog.n_params:
            _const_rows(c0, E, prog.param_slice, np.asarray(plo, float), np.asarray(phi, float))
        _const_rows(c0, E, prog.const_slice, prog.const_lo[:, 0], prog.const_hi[:, 0])

        def radius(idx):
            """An upper bound of ``R`` (the float sum times ``big``, plus ``under``)."""
            return (np.einsum("kbn,bn->kb", np.abs(C[idx]), r) + E[idx]) * big + under

        def close(s, e_terms, mag0, mag, k):
            """``e`` of the nodes ``s`` from its exact terms and the rounding of the rule."""
            rounding = _gamma(k) * (mag0 + np.einsum("kbn,bn->kb", mag, r))
            E[s] = (e_terms + rounding) * big + under

        for g in prog.fwd_groups:
            s, a, b, op = slice(g.start, g.stop), g.a, g.b, g.op
            if op in ("add", "sub"):
                sg = 1.0 if op == "add" else -1.0
                c0[s] = c0[a] + sg * c0[b]
                C[s] = C[a] + sg * C[b]
                close(s, E[a] + E[b], np.abs(c0[a]) + np.abs(c0[b]), np.abs(C[a]) + np.abs(C[b]), 1)
            elif op == "neg":
                c0[s], C[s], E[s] = -c0[a], -C[a], E[a]
            elif op == "cadd":
                p = np.asarray(g.param)  # (k, 1): exact floats
                c0[s] = c0[a] + p
                C[s] = C[a]
                close(s, E[a], np.abs(c0[a]) + np.abs(p), np.zeros_like(C[a]), 1)
            elif op == "cmul":
                p = np.asarray(g.param)
                c0[s] = c0[a] * p
                C[s] = C[a] * p[:, :, None]
                close(s, E[a] * np.abs(p), np.abs(c0[s]), np.abs(C[s]), 1)
            elif op == "mul":
                ra, rb = radius(a), radius(b)
                a0, b0 = c0[a], c0[b]
                c0[s] = a0 * b0
                t1, t2 = a0[:, :, None] * C[b], b0[:, :, None] * C[a]
                C[s] = t1 + t2
                e_terms = np.abs(a0) * E[b] + np.abs(b0) * E[a] + ra * rb
                close(s, e_terms, np.abs(c0[s]), np.abs(t1) + np.abs(t2), 3)
            elif op == "sqr" or (op == "pow" and g.param == 2):
                ra = radius(a)
                a0 = c0[a]
                h = 0.5 * (ra * ra)
                c0[s] = a0 * a0 + h
                C[s] = (2.0 * a0)[:, :, None] * C[a]
                close(s, 2.0 * np.abs(a0) * E[a] + h, a0 * a0 + h, np.abs(C[s]), 3)
            else:
                _interval_rows(g, s, a, b, c0, C, E, radius)
        out = prog.outputs
        return AffineForms(
            c0=c0[out].T.copy(),
            c=np.ascontiguousarray(np.swapaxes(C[out], 0, 1)),
            e=E[out].T.copy(),
            mid=mid,
        )


def _const_rows(c0, E, rows: slice, lo: np.ndarray, hi: np.ndarray) -> None:
    """Constants and parameters ``[lo, hi]``: the midpoint and the radius, rounded up."""
    m = 0.5 * lo + 0.5 * hi
    c0[rows] = m[:, None]
    E[rows] = up(np.maximum(hi - m, m - lo))[:, None]


def _interval_rows(g, s, a, b, c0, C, E, radius) -> None:
    """A node without an affine rule: the interval of its operation on the arguments'
    ranges ``c₀ ± R`` (rounded outward), as a form without coefficients."""

    def rng(idx):
        rad = radius(idx)
        return -up(rad - c0[idx]), up(c0[idx] + rad)

    alo, ahi = rng(a)
    if b is None:
        zlo, zhi = FORWARD[g.op](alo, ahi, None, None, g.param)
    else:
        blo, bhi = rng(b)
        zlo, zhi = FORWARD[g.op](alo, ahi, blo, bhi, g.param)
    m = 0.5 * zlo + 0.5 * zhi
    c0[s] = m
    C[s] = 0.0
    E[s] = up(np.maximum(zhi - m, m - zlo))
