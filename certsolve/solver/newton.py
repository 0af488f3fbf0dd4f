"""Batched interval Newton machinery: linearisation, Krawczyk operator, Hansen–Sengupta.

For a box ``X`` with midpoint ``c``, an interval Jacobian ``J(X)`` and a rigorous enclosure of
``f(c)``, the mean value theorem gives, for every zero ``x*`` of ``f`` in ``X``::

    0 = f(c) + J (x* - c)   for some J ∈ J(X).

With a point preconditioner ``Y ≈ (mid J(X))^-1`` (any ``Y`` is sound) two operators follow:

* **Krawczyk**: ``K(X) = c - Y f(c) + (I - Y J(X)) (X - c)`` contains every zero in ``X``,
  and ``K(X) ⊂ int X`` proves that ``X`` contains *exactly one* zero (Krawczyk 1969,
  Moore 1977; Neumaier 1990, Thm 5.1.8).  This is the certificate of the solver.
* **Hansen–Sengupta** (preconditioned interval Gauss–Seidel): with ``M = Y J(X)`` and
  ``b = Y f(c)``, sweep ``i = 1..n``::

      x_i ∈ X_i ∩ ( c_i - (b_i + Σ_{j≠i} M_ij (X_j - c_j)) / M_ii )

  using the already narrowed ``X_j`` for ``j < i``; an empty result discards the box.  This
  is the Newton contractor (IBEX ``CtcNewton``).

``M`` and ``b`` are formed in midpoint-radius arithmetic with rigorous error bounds
(:mod:`certsolve.interval.linalg`), one batched ``matmul`` for all boxes.  Every function
here takes ``(B, n)`` / ``(B, n, n)`` arrays and loops only over the ``n`` Gauss–Seidel
components, never over boxes.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval.core import midpoint
from ..interval.linalg import (
    batched_inverse,
    gauss_seidel,
    krawczyk_image,
    krawczyk_magnitude,
    mr_from_bounds,
    mr_matmul,
    precondition,
    stack_or_nan,
)
from ..interval.reductions import all_last

__all__ = [
    "Linearization",
    "linearize",
    "linearization_from_bounds",
    "krawczyk",
    "KrawczykPoint",
    "hansen_sengupta",
    "batched_inverse",
    "batched_solve",
]


def batched_solve(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Approximate solutions of ``A x = b`` for a stack, and a mask of usable ones.

    Float linear algebra for Newton *points* (no rigour needed there); about twice as fast
    as forming the inverses.  Singular or non-finite systems give NaN and ``ok = False``.
    """
    finite = np.all(np.isfinite(A), axis=(1, 2)) & np.all(np.isfinite(b), axis=1)
    x = np.full(b.shape, np.nan)
    if not np.any(finite):
        return x, finite
    with np.errstate(all="ignore"):
        x[finite] = stack_or_nan(_solve, A[finite], b[finite], like=b[finite])
    return x, all_last(np.isfinite(x))


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.solve(A, b[:, :, None])[:, :, 0]


@dataclass
class Linearization:
    """Everything interval Newton and Krawczyk need about a batch of boxes ``X``."""

    lo: np.ndarray  # (B, n) the boxes X
    hi: np.ndarray
    c: np.ndarray  # (B, n) midpoints
    jlo: np.ndarray  # (B, n, n) J(X)
    jhi: np.ndarray
    Y: np.ndarray  # (B, n, n) preconditioners (NaN where unusable)
    ok: np.ndarray  # (B,) preconditioner usable and f defined on all of X
    Mc: np.ndarray  # (B, n, n) Y J(X), midpoint-radius
    Mr: np.ndarray
    bc: np.ndarray  # (B, n) Y f(c), midpoint-radius
    br: np.ndarray

    def with_rows(self, rows: np.ndarray, other: Linearization) -> Linearization:
        """This linearisation with rows ``rows`` (indices) replaced by ``other``'s (one row
        of ``other`` per index, in order); every array is copied, none is changed."""
        out = {}
        for f in fields(self):
            a = getattr(self, f.name).copy()
            a[rows] = getattr(other, f.name)
            out[f.name] = a
        return Linearization(**out)


def linearize(csys: CompiledSystem, lo: np.ndarray, hi: np.ndarray) -> Linearization:
    """Evaluate ``J(X)`` and ``f(c)`` and precondition, for a batch of boxes."""
    c = midpoint(lo, hi)
    _, _, jlo, jhi, defined = csys.eval_fj(lo, hi, check_domain=True)
    flo, fhi = csys.eval_f_at(c)
    return linearization_from_bounds(lo, hi, c, flo, fhi, jlo, jhi, defined)


def linearization_from_bounds(lo, hi, c, flo, fhi, jlo, jhi, defined=None) -> Linearization:
    """Build a :class:`Linearization` from raw enclosures (any source of ``f`` and ``J``).

    ``flo, fhi`` must enclose ``f(c)`` rigorously and ``jlo, jhi`` the Jacobian over the box
    (shapes ``(B, n)`` and ``(B, n, n)``); ``defined`` (default all true) marks boxes on which
    ``f`` is defined and continuous everywhere.
    """
    if defined is None:
        defined = np.ones(lo.shape[0], dtype=bool)
    Jc, Jr = mr_from_bounds(jlo, jhi)
    fc, fr = mr_from_bounds(flo, fhi)
    pre = precondition(Jc, Jr, fc, fr)
    ok = pre.ok & defined
    return Linearization(lo, hi, c, jlo, jhi, pre.Y, ok, pre.Mc, pre.Mr, pre.bc, pre.br)


def krawczyk(lin: Linearization) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Krawczyk operator ``K(X)`` for every box, and the mask ``K(X) ⊂ int X``.

    The kernel is :func:`certsolve.interval.linalg.krawczyk_image` (``(I - M)(X - c) ⊆
    [-v, v]`` with ``v = (|I - Mc| + Mr) rad(X)``).  Returns ``(klo, khi, proven)``; boxes
    whose linearisation is unusable are never proven.
    """
    mag = krawczyk_magnitude(lin.Mc, lin.Mr)
    klo, khi, proven = krawczyk_image(lin.c, lin.lo, lin.hi, mag, lin.bc, lin.br)
    return klo, khi, proven & lin.ok


class KrawczykPoint:
    """Krawczyk tests for one centre ``c``, one ``f(c)`` and one Jacobian enclosure ``J``.

    ``K(X) = c - Y f(c) + (I - Y J)(X - c)``, with ``Y = mid(J)^-1``: ``Y``, ``Y f(c)`` and
    ``|I - Y J|`` are computed once (:func:`certsolve.interval.linalg.precondition`), then
    :meth:`image` costs one matrix-vector product per box ``X``
    (:func:`certsolve.interval.linalg.krawczyk_image`).  Valid for every box ``X`` such
    that ``J`` encloses the Jacobian over the hull of ``X`` and ``c``; ``c`` need not be the
    midpoint.  For real-time callers (tracking): 1-D / 2-D arrays.
    """

    def __init__(self, c, flo, fhi, jlo, jhi):
        # :func:`precondition` for one box, without the stack's masks, and with ``J`` and
        # ``f(c)`` side by side as one ``n x (n + 1)`` matrix ``[J | f]``: one midpoint-
        # radius conversion and one product ``Y [J | f]`` (a step of tracking pays numpy's
        # per-call cost, not the arithmetic).  The bounds of each column are those of its
        # own product (:func:`mr_matmul`'s error bound is per entry, over the inner size n)
        self.c = c
        n = c.shape[-1]
        both_c, both_r = mr_from_bounds(
            np.concatenate((jlo, flo[:, None]), axis=1),
            np.concatenate((jhi, fhi[:, None]), axis=1),
            size=1,  # numpy's nextafter, one call (the same floats as the integer steps)
        )
        self.ok = False
        if not np.isfinite(both_r).all():  # a NaN or inf midpoint makes its radius NaN
            return
        try:
            Y = np.linalg.inv(both_c[:, :n])
        except np.linalg.LinAlgError:
            return
        with np.errstate(all="ignore"):
            pc, pr = mr_matmul(Y, None, both_c, both_r)
        self.ok = bool(np.isfinite(pr).all())
        #: the preconditioner ``Y ≈ mid(J)^-1`` (any ``Y`` is sound: tests at other centres)
        self.Y = Y
        if self.ok:
            self.mag = krawczyk_magnitude(pc[:, :n], pr[:, :n])
            self.bc = pc[:, n]
            self.br = pr[:, n]

    def image(self, lo, hi):
        """``(klo, khi, proven)``: ``K(X)`` and whether ``K(X) ⊂ int X``."""
        if not self.ok:
            return lo, hi, False
        klo, khi, proven = krawczyk_image(self.c, lo, hi, self.mag, self.bc, self.br)
        return klo, khi, bool(proven)


def hansen_sengupta(lin: Linearization) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One preconditioned interval Gauss–Seidel sweep; returns ``(lo, hi, empty)``.

    Boxes whose linearisation is unusable (``lin.ok`` false) are returned unchanged; a
    component whose pivot ``M_ii`` contains 0 is left unchanged (no extended division).
    The kernel is :func:`certsolve.interval.linalg.gauss_seidel`.
    """
    return gauss_seidel(lin.c, lin.lo, lin.hi, lin.Mc, lin.Mr, lin.bc, lin.br, lin.ok)
