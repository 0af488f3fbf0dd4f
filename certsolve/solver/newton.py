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

from dataclasses import dataclass

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval import arith
from ..interval.core import midpoint
from ..interval.linalg import gamma, mr_from_bounds, mr_matmul
from ..interval.reductions import all_last
from ..interval.rounding import down, up

__all__ = [
    "Linearization",
    "linearize",
    "linearization_from_bounds",
    "krawczyk",
    "krawczyk_box",
    "KrawczykPoint",
    "hansen_sengupta",
    "batched_inverse",
    "batched_solve",
]

_U = 2.0**-53


def batched_inverse(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Approximate inverses of a stack of matrices and a mask of usable ones.

    Singular or non-finite matrices get a NaN inverse and ``ok = False``; the caller skips
    Newton for those boxes (no preconditioner, no contraction: sound).
    """
    finite = np.all(np.isfinite(A), axis=(1, 2))
    Y = np.full_like(A, np.nan)
    if not np.any(finite):
        return Y, finite
    Af = A[finite]
    try:
        with np.errstate(all="ignore"):
            Yf = np.linalg.inv(Af)
    except np.linalg.LinAlgError:
        Yf = np.full_like(Af, np.nan)
        for k in range(Af.shape[0]):  # rare: some exactly singular matrix in the batch
            try:
                Yf[k] = np.linalg.inv(Af[k])
            except np.linalg.LinAlgError:
                pass
    Y[finite] = Yf
    ok = np.all(np.isfinite(Y), axis=(1, 2))
    return Y, ok


def batched_solve(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Approximate solutions of ``A x = b`` for a stack, and a mask of usable ones.

    Float linear algebra for Newton *points* (no rigour needed there); about twice as fast
    as forming the inverses.  Singular or non-finite systems give NaN and ``ok = False``.
    """
    finite = np.all(np.isfinite(A), axis=(1, 2)) & np.all(np.isfinite(b), axis=1)
    x = np.full(b.shape, np.nan)
    if not np.any(finite):
        return x, finite
    Af, bf = A[finite], b[finite]
    try:
        with np.errstate(all="ignore"):
            xf = np.linalg.solve(Af, bf[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        xf = np.full(bf.shape, np.nan)
        for k in range(Af.shape[0]):  # rare: some exactly singular matrix in the batch
            try:
                xf[k] = np.linalg.solve(Af[k], bf[k])
            except np.linalg.LinAlgError:
                pass
    x[finite] = xf
    return x, all_last(np.isfinite(x))


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
    Y, ok = batched_inverse(Jc)
    ok &= defined & all_last(np.isfinite(flo) & np.isfinite(fhi))
    Ys = np.where(ok[:, None, None], Y, 0.0)
    with np.errstate(all="ignore"):
        Mc, Mr = mr_matmul(Ys, None, Jc, Jr)
        fc, fr = mr_from_bounds(flo, fhi)
        bc, br = mr_matmul(Ys, None, fc[:, :, None], fr[:, :, None])
    ok &= np.all(np.isfinite(Mr), axis=(1, 2)) & all_last(np.isfinite(br[:, :, 0]))
    return Linearization(lo, hi, c, jlo, jhi, Y, ok, Mc, Mr, bc[:, :, 0], br[:, :, 0])


def krawczyk(lin: Linearization) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Krawczyk operator ``K(X)`` for every box, and the mask ``K(X) ⊂ int X``.

    ``(I - M)(X - c) ⊆ [-v, v]`` with ``v = |I - M| rad(X)``, where ``|I - M|`` is bounded
    entrywise by ``|I - Mc| + Mr`` (the diagonal ``1 - Mc_ii`` is rounded, hence the
    ``(1 + 4u)`` factor).  Returns ``(klo, khi, proven)``.
    """
    n = lin.c.shape[1]
    with np.errstate(all="ignore"):
        eye = np.eye(n)
        mag = up(up(np.abs(eye - lin.Mc) * (1.0 + 4 * _U)) + lin.Mr)
        rad = np.maximum(up(lin.hi - lin.c), up(lin.c - lin.lo))
        v = np.einsum("bij,bj->bi", mag, rad)
        v = up(v * (1.0 + 2.0 * gamma(n + 2)) + (n + 2) * 2.0**-1000)
        centre = lin.c - lin.bc
        rr = up(lin.br + v)
        klo = down(down(centre) - rr)
        khi = up(up(centre) + rr)
    proven = lin.ok & all_last((klo > lin.lo) & (khi < lin.hi))
    return klo, khi, proven


def krawczyk_box(lo, hi, flo, fhi, jlo, jhi, c=None):
    """Krawczyk test from raw enclosures: ``(klo, khi, proven)`` for a batch of boxes.

    ``proven[k]`` means box ``k`` contains exactly one zero of ``f``, inside ``K(X)``.  Used by
    callers that evaluate ``f`` and ``J`` with their own interval code (IK, tracking).
    """
    if c is None:
        c = midpoint(lo, hi)
    return krawczyk(linearization_from_bounds(lo, hi, c, flo, fhi, jlo, jhi))


class KrawczykPoint:
    """Krawczyk tests for one centre ``c``, one ``f(c)`` and one Jacobian enclosure ``J``.

    ``K(X) = c - Y f(c) + (I - Y J)(X - c)``, with ``Y = mid(J)^-1``: ``Y``, ``Y f(c)`` and
    ``|I - Y J|`` are computed once (with the same a priori rounding bounds as
    :func:`krawczyk`), then :meth:`image` costs one matrix-vector product per box ``X``.
    Valid for every box ``X`` such that ``J`` encloses the Jacobian over the hull of ``X``
    and ``c``; ``X - c`` is enclosed by ``[-r, r]``, ``r`` the distance from ``c`` to the
    farthest face, so ``c`` need not be the midpoint.  For real-time callers (tracking):
    1-D / 2-D arrays, few numpy calls.
    """

    def __init__(self, c, flo, fhi, jlo, jhi):
        n = c.shape[0]
        self.c = c
        self.ok = False
        Jc = 0.5 * jlo + 0.5 * jhi
        Jr = np.maximum(up(jhi - Jc), up(Jc - jlo))
        try:
            Y = np.linalg.inv(Jc)
        except np.linalg.LinAlgError:
            return
        if not (
            np.all(np.isfinite(Y))
            and np.all(np.isfinite(Jr))
            and np.all(np.isfinite(flo))
            and np.all(np.isfinite(fhi))
        ):
            return
        g = gamma(n + 4)
        aY = np.abs(Y)
        # M = Y J: midpoint Mc and radius Mr (a priori rounding bound of Y @ Jc included)
        Mc = Y @ Jc
        Mr = (aY @ (gamma(n) * np.abs(Jc) + Jr)) * (1.0 + 2.0 * g) + (n + 2) * 2.0**-1000
        # b = Y f(c)
        fc = 0.5 * flo + 0.5 * fhi
        fr = np.maximum(up(fhi - fc), up(fc - flo))
        bc = Y @ fc
        br = (aY @ (gamma(n) * np.abs(fc) + fr)) * (1.0 + 2.0 * g) + (n + 2) * 2.0**-1000
        self.mag = np.abs(np.eye(n) - Mc) * (1.0 + 4 * _U) + Mr
        self.centre = c - bc
        self.br = br
        self.g2 = 1.0 + 2.0 * gamma(n + 2)
        self.tiny = (n + 2) * 2.0**-1000
        self.ok = True

    def image(self, lo, hi):
        """``(klo, khi, proven)``: ``K(X)`` and whether ``K(X) ⊂ int X``."""
        if not self.ok:
            return lo, hi, False
        c = self.c
        rad = np.maximum(up(hi - c), up(c - lo))
        v = (self.mag @ rad) * self.g2 + self.tiny
        rr = (self.br + v) * (1.0 + 4 * _U)
        klo = down(down(self.centre) - rr)
        khi = up(up(self.centre) + rr)
        return klo, khi, bool(np.all((klo > lo) & (khi < hi)))


def hansen_sengupta(lin: Linearization) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One preconditioned interval Gauss–Seidel sweep; returns ``(lo, hi, empty)``.

    Boxes whose linearisation is unusable (``lin.ok`` false) are returned unchanged; a
    component whose pivot ``M_ii`` contains 0 is left unchanged (no extended division).
    """
    lo = lin.lo.copy()
    hi = lin.hi.copy()
    c = lin.c
    B, n = lo.shape
    ok = lin.ok
    empty = np.zeros(B, dtype=bool)
    with np.errstate(all="ignore"):
        dlo = down(lo - c)
        dhi = up(hi - c)
        g = 1.0 + 2.0 * gamma(n + 4)
        dc, dr = mr_from_bounds(dlo, dhi)  # (B, n); column i is updated after step i
        for i in range(n):
            mc = lin.Mc[:, i, :].copy()
            mr = lin.Mr[:, i, :].copy()
            piv_c, piv_r = mc[:, i].copy(), mr[:, i].copy()
            mc[:, i] = 0.0
            mr[:, i] = 0.0
            # S = Σ_{j≠i} M_ij d_j, midpoint-radius with a priori rounding bound
            sc = np.einsum("bj,bj->b", mc, dc)
            amc = np.abs(mc)
            adc = np.abs(dc)
            sr = (
                np.einsum("bj,bj->b", amc, adc) * gamma(n)
                + np.einsum("bj,bj->b", amc, dr)
                + np.einsum("bj,bj->b", mr, adc + dr)
            )
            sr = sr * g + n * 2.0**-1000
            # numerator b_i + S
            tc = lin.bc[:, i] + sc
            tr = up(up(lin.br[:, i] + sr) + np.abs(tc) * (2 * _U))
            tlo = down(tc - tr)
            thi = up(tc + tr)
            plo = down(piv_c - piv_r)
            phi = up(piv_c + piv_r)
            usable = ok & ((plo > 0.0) | (phi < 0.0))
            qlo, qhi = arith.div(tlo, thi, plo, phi)
            nlo, nhi = arith.sub(c[:, i], c[:, i], qlo, qhi)
            new_lo = np.where(usable, np.fmax(lo[:, i], nlo), lo[:, i])
            new_hi = np.where(usable, np.fmin(hi[:, i], nhi), hi[:, i])
            empty |= ~(new_lo <= new_hi)
            lo[:, i] = new_lo
            hi[:, i] = new_hi
            dlo[:, i] = down(new_lo - c[:, i])
            dhi[:, i] = up(new_hi - c[:, i])
            dc[:, i], dr[:, i] = mr_from_bounds(dlo[:, i], dhi[:, i], size=dlo.size)
    return lo, hi, empty
