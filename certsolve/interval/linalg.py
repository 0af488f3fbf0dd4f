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

**Krawczyk.**  The one Krawczyk kernel of the package lives here too (the solver's Newton
contractor, the IK certificates and tracking all call it; :mod:`certsolve.solver.verify`
keeps its own mpmath version on purpose, as a second opinion).  For a box ``X``, a point
``c`` in it, ``f(c)`` enclosed by ``fc ± fr`` and ``J(X)`` by ``Jc ± Jr``, the midpoint
inverse ``Y ≈ Jc^-1`` (any ``Y`` is sound) gives::

    K(X) = c - Y f(c) + (I - Y J(X)) (X - c)

which contains every zero of ``f`` in ``X``; ``K(X) ⊂ int X`` proves that ``X`` holds
*exactly one* zero (Krawczyk 1969; Neumaier 1990, Thm 5.1.8).  With ``M = Y J ∈ Mc ± Mr``
and ``b = Y f(c) ∈ bc ± br`` (:func:`precondition`, built on :func:`mr_matmul`)::

    (I - M)(X - c) ⊆ [-v, v],  v = (|I - Mc| + Mr) r,  r = max(hi - c, c - lo)

and ``K(X) ⊆ (c - bc) ± (br + v)`` (:func:`krawczyk_image`).  These bounds are computed in
round-to-nearest: ``|I - Mc|`` is exact off the diagonal and has one rounding on it (factor
``1 + 4u``), ``r`` one rounding (``1 + 4u``), the sums and the product ``|I - M| r`` at
most ``n + 4`` relative roundings (factor ``1 + 2 γ_{n+4}``), ``c - bc`` one rounding
(``2u |c - bc|``), then one ``nextafter`` outward.  Everything is batched over stacks of
boxes: ``(B, n)`` vectors and ``(B, n, n)`` (or shared ``(n, n)``) matrices; a NaN or an
infinity anywhere makes the test fail, never succeed.

**Gauss–Seidel.**  The Hansen–Sengupta contraction (preconditioned interval Gauss–Seidel)
uses the same ``M`` and ``b``: with ``d = X - c`` (enclosed as ``dc ± dr``), for
``i = 1..n``::

    x_i ∈ X_i ∩ ( c_i - (b_i + Σ_{j≠i} M_ij d_j) / M_ii )

with the already narrowed ``d_j`` for ``j < i`` (:func:`gauss_seidel`).  The sum is a dot
product in midpoint-radius form (``Σ |M_ij| |d_j|`` times ``γ_n`` for its rounding, the
radii added, the total times ``1 + 2 γ_{n+4}``), then every bound is rounded outward.
The work that does not depend on ``i`` -- the off-diagonal parts of ``M`` and their
magnitudes, the pivots ``M_ii`` and whether they are free of 0 -- is done once for all
components, so a sweep costs about 25 numpy calls per component whatever the batch size;
one box (a search's small rounds, a tracking step) takes a scalar path with the same floats
(:func:`_sweep_one`: one numpy call per component, the rest on Python floats).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .arith import div_nonzero
from .reductions import all_last
from .rounding import down, up

__all__ = [
    "U",
    "UNDERFLOW",
    "gamma",
    "mr_from_bounds",
    "mr_to_bounds",
    "mr_matmul",
    "point_matmul_interval",
    "batched_inverse",
    "stack_or_nan",
    "Preconditioned",
    "precondition",
    "krawczyk_magnitude",
    "krawczyk_image",
    "krawczyk_mr",
    "gauss_seidel",
]

U = 2.0**-53  # unit roundoff of binary64, round to nearest
UNDERFLOW = 2.0**-1000  # per-summand underflow allowance (<< any meaningful width)
_U = U
_UNDERFLOW = UNDERFLOW


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


def batched_inverse(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Approximate inverses of a stack of matrices ``(B, n, n)`` and a mask of usable ones.

    Singular or non-finite matrices get a NaN inverse and ``ok = False``: no preconditioner,
    no contraction, no proof (sound).  Only float work; rigour comes from the bounds that use
    the result (any ``Y`` is sound).
    """
    finite = np.all(np.isfinite(A), axis=(-2, -1))
    Y = np.full_like(A, np.nan)
    if not np.any(finite):
        return Y, finite
    with np.errstate(all="ignore"):
        Y[finite] = stack_or_nan(np.linalg.inv, A[finite], like=A[finite])
    ok = np.all(np.isfinite(Y), axis=(-2, -1))
    return Y, ok


def stack_or_nan(fn, *stacks: np.ndarray, like: np.ndarray) -> np.ndarray:
    """``fn(*stacks)`` for stacks of matrices along axis 0 (``np.linalg.inv``, ``solve``), NaN
    rows (shaped as those of ``like``) for the members numpy refuses.

    numpy refuses the whole stack if one matrix is exactly singular; the stack is then
    halved until the singular ones are alone: a few calls per singular matrix instead of
    one per matrix (the results are the ones a single call would give).
    """
    try:
        return fn(*stacks)
    except np.linalg.LinAlgError:
        if like.shape[0] == 1:
            return np.full(like.shape, np.nan)
        h = like.shape[0] // 2
        first = stack_or_nan(fn, *(a[:h] for a in stacks), like=like[:h])
        return np.concatenate([first, stack_or_nan(fn, *(a[h:] for a in stacks), like=like[h:])])


@dataclass(kw_only=True)
class Preconditioned:
    """A midpoint-inverse preconditioning of ``J`` and ``f(c)`` for a stack of boxes.

    ``Y`` approximates ``(mid J)^-1`` (NaN where unusable); ``M = Y J ∈ Mc ± Mr`` and
    ``b = Y f(c) ∈ bc ± br`` rigorously; ``ok`` marks boxes where ``Y`` exists and every
    bound is finite (the others are set to zero preconditioner and must not be trusted).
    """

    Y: np.ndarray  # (B, n, n)
    ok: np.ndarray  # (B,)
    Mc: np.ndarray  # (B, n, n)
    Mr: np.ndarray
    bc: np.ndarray  # (B, n)
    br: np.ndarray


def precondition(Jc, Jr, fc, fr) -> Preconditioned:
    """Midpoint inverse preconditioning of ``J ∈ Jc ± Jr`` ``(B, n, n)`` and ``f ∈ fc ± fr``
    ``(B, n)``: ``Y = Jc^-1``, ``Y J`` and ``Y f`` enclosed with :func:`mr_matmul`."""
    Y, ok = batched_inverse(Jc)
    ok = ok & all_last(np.isfinite(fc) & np.isfinite(fr))
    Ys = np.where(ok[..., None, None], Y, 0.0)
    with np.errstate(all="ignore"):
        Mc, Mr = mr_matmul(Ys, None, Jc, Jr)
        bc, br = mr_matmul(Ys, None, fc[..., None], fr[..., None])
    bc, br = bc[..., 0], br[..., 0]
    ok &= np.all(np.isfinite(Mr), axis=(-2, -1)) & all_last(np.isfinite(br))
    return Preconditioned(Y=Y, ok=ok, Mc=Mc, Mr=Mr, bc=bc, br=br)


def krawczyk_magnitude(Mc, Mr):
    """Upper bound of ``|I - M|`` for ``M ∈ Mc ± Mr`` (``(..., n, n)``; see module docstring)."""
    n = Mc.shape[-1]
    with np.errstate(invalid="ignore", over="ignore"):
        return np.abs(np.eye(n) - Mc) * (1.0 + 4.0 * U) + Mr


def krawczyk_image(c, lo, hi, mag, bc, br):
    """The Krawczyk operator ``K(X)`` and the mask ``K(X) ⊂ int X`` for a stack of boxes.

    ``X = [lo, hi]`` and ``c ∈ X`` are ``(..., n)``; ``mag`` bounds ``|I - Y J(X)|``
    (:func:`krawczyk_magnitude`, ``(..., n, n)`` or one shared ``(n, n)``) and ``bc ± br``
    encloses ``Y f(c)``.  ``c`` need not be the midpoint.  Returns ``(klo, khi, proven)``;
    ``proven[k]`` means box ``k`` holds exactly one zero, inside ``[klo, khi]``.
    """
    n = c.shape[-1]
    with np.errstate(invalid="ignore", over="ignore"):
        r = np.maximum(hi - c, c - lo) * (1.0 + 4.0 * U)
        v = (mag @ r[..., None])[..., 0]
        ce = c - bc
        rr = (1.0 + 2.0 * gamma(n + 4)) * (br + v) + (2.0 * U) * np.abs(ce) + (n + 2) * UNDERFLOW
        klo = np.nextafter(ce - rr, -np.inf)
        khi = np.nextafter(ce + rr, np.inf)
    proven = all_last((klo > lo) & (khi < hi))
    return klo, khi, proven


def krawczyk_mr(c, lo, hi, fc, fr, Jc, Jr):
    """Krawczyk test from midpoint-radius enclosures, batched: ``(klo, khi, proven)``.

    ``c ∈ X = [lo, hi]`` ``(B, n)``; ``fc ± fr`` encloses ``f(c)`` and ``Jc ± Jr`` the
    Jacobian over the hull of ``X`` and ``c``.  Boxes whose preconditioner is unusable are
    never proven.
    """
    c = np.asarray(c, dtype=float)
    pre = precondition(Jc, Jr, fc, fr)
    klo, khi, proven = krawczyk_image(c, lo, hi, krawczyk_magnitude(pre.Mc, pre.Mr), pre.bc, pre.br)
    return klo, khi, proven & pre.ok


def gauss_seidel(c, lo, hi, Mc, Mr, bc, br, ok):
    """One preconditioned interval Gauss–Seidel sweep (module docstring): ``(lo, hi, empty)``.

    ``c ∈ X = [lo, hi]`` ``(B, n)``; ``M ∈ Mc ± Mr`` ``(B, n, n)`` and ``b ∈ bc ± br``
    ``(B, n)`` enclose ``Y J(X)`` and ``Y f(c)``.  Rows where ``ok`` is false, and components
    whose pivot ``M_ii`` contains 0 (no extended division), are left unchanged; ``empty[k]``
    proves that box ``k`` holds no zero.  Every bound is rounded as an array of ``B``
    elements (:func:`.rounding.up`), whatever the number of components done at once.
    """
    lo = lo.copy()
    hi = hi.copy()
    B, n = lo.shape
    g = 1.0 + 2.0 * gamma(n + 4)
    gn = gamma(n)
    tiny = n * _UNDERFLOW
    with np.errstate(all="ignore"):
        # the parts of the sweep that do not depend on the narrowed components
        off_c = Mc.copy()
        off_r = Mr.copy()
        diag = np.arange(n)
        off_c[:, diag, diag] = 0.0
        off_r[:, diag, diag] = 0.0
        off_abs = np.abs(off_c)
        piv_c = Mc[:, diag, diag]
        piv_r = Mr[:, diag, diag]
        plo = down(piv_c - piv_r, size=B)
        phi = up(piv_c + piv_r, size=B)
        usable = ok[:, None] & ((plo > 0.0) | (phi < 0.0))
        # a component no box can narrow (its pivot holds 0 everywhere) changes nothing:
        # its bounds, and so its d_i, stay as they are; skipping it gives the same floats
        narrowed = usable.any(axis=0)
        if not narrowed.any():
            return lo, hi, ~np.all(lo <= hi, axis=1)
        dlo = down(lo - c)
        dhi = up(hi - c)
        dc, dr = mr_from_bounds(dlo, dhi)  # column i is updated after step i
        if B == 1:
            _sweep_one(lo[0], hi[0], c[0], off_c[0], off_abs[0], off_r[0], bc[0], br[0],
                       plo[0], phi[0], np.flatnonzero(narrowed), dc[0], dr[0])  # fmt: skip
            return lo, hi, ~np.all(lo <= hi, axis=1)
        adc = np.abs(dc)
        adr = adc + dr
        for i in np.flatnonzero(narrowed):
            # S = Σ_{j≠i} M_ij d_j, midpoint-radius with a priori rounding bound
            mc, amc, mr = off_c[:, i, :], off_abs[:, i, :], off_r[:, i, :]
            sc = np.einsum("bj,bj->b", mc, dc)
            sr = (
                np.einsum("bj,bj->b", amc, adc) * gn
                + np.einsum("bj,bj->b", amc, dr)
                + np.einsum("bj,bj->b", mr, adr)
            )
            sr = sr * g + tiny
            # numerator t = b_i + S, then c_i - t / M_ii (the pivot is free of 0 where used)
            tc = bc[:, i] + sc
            tr = up(up(br[:, i] + sr) + np.abs(tc) * (2 * _U))
            tlo = down(tc - tr)
            thi = up(tc + tr)
            qlo, qhi = div_nonzero(tlo, thi, plo[:, i], phi[:, i])
            ci = c[:, i]
            use = usable[:, i]
            new_lo = np.where(use, np.fmax(lo[:, i], down(ci - qhi)), lo[:, i])
            new_hi = np.where(use, np.fmin(hi[:, i], up(ci - qlo)), hi[:, i])
            lo[:, i] = new_lo
            hi[:, i] = new_hi
            dci, dri = mr_from_bounds(down(new_lo - ci), up(new_hi - ci), size=dlo.size)
            dc[:, i] = dci
            dr[:, i] = dri
            adc[:, i] = np.abs(dci)
            adr[:, i] = adc[:, i] + dri
    empty = ~np.all(lo <= hi, axis=1)
    return lo, hi, empty


def _fmin(a: float, b: float) -> float:
    """``np.fmin`` of two floats: the smaller, a NaN operand ignored."""
    if b != b:
        return a
    return b if a != a or b < a else a


def _fmax(a: float, b: float) -> float:
    """``np.fmax`` of two floats: the larger, a NaN operand ignored."""
    if b != b:
        return a
    return b if a != a or b > a else a


def _maximum(a: float, b: float) -> float:
    """``np.maximum`` of two floats: NaN if either is NaN."""
    if a != a or b != b:
        return a + b
    return b if b > a else a


def _sweep_one(lo, hi, c, off_c, off_abs, off_r, bc, br, plo, phi, comps, dc, dr) -> None:
    """:func:`gauss_seidel`'s loop for one box, in place on ``lo, hi`` (1-D rows).

    A sweep over ``n`` components costs ~60 numpy calls per component whatever the batch;
    on one box each of them is a single float operation, which Python does ~20x faster.
    The same floats: the four dot products of a component are one ``einsum`` over the
    stacked rows ``(M_i, |M_i|, |M_i|, R_i)`` and ``(d_c, |d_c|, d_r, |d_c| + d_r)`` (numpy
    reduces each row as the batched call does), and every other step is the same IEEE
    operation on Python floats -- ``+ - * /`` correctly rounded, ``math.nextafter`` for
    :func:`.rounding.up`/:func:`.rounding.down`, ``fmin``/``fmax``/``maximum`` with numpy's
    NaN rules.  Only usable components (pivot free of 0) are in ``comps``.
    """
    n = lo.shape[0]
    g = 1.0 + 2.0 * gamma(n + 4)
    gn = gamma(n)
    tiny = n * _UNDERFLOW
    two_u = 2 * _U
    inf = math.inf
    nextafter = math.nextafter
    rows = np.stack([off_c, off_abs, off_abs, off_r], axis=1)  # (n, 4, n)
    vec = np.stack([dc, np.abs(dc), dr, np.abs(dc) + dr])  # (4, n), column i updated
    lo_l, hi_l, c_l = lo.tolist(), hi.tolist(), c.tolist()
    bc_l, br_l, plo_l, phi_l = bc.tolist(), br.tolist(), plo.tolist(), phi.tolist()
    for i in comps.tolist():
        sc, s1, s2, s3 = np.einsum("kj,kj->k", rows[i], vec).tolist()
        sr = (s1 * gn + s2 + s3) * g + tiny
        tc = bc_l[i] + sc
        tr = nextafter(nextafter(br_l[i] + sr, inf) + abs(tc) * two_u, inf)
        tlo = nextafter(tc - tr, -inf)
        thi = nextafter(tc + tr, inf)
        pl, ph = plo_l[i], phi_l[i]  # free of 0
        q1, q2, q3, q4 = tlo / pl, tlo / ph, thi / pl, thi / ph
        qlo = nextafter(_fmin(_fmin(q1, q2), _fmin(q3, q4)), -inf)
        qhi = nextafter(_fmax(_fmax(q1, q2), _fmax(q3, q4)), inf)
        ci = c_l[i]
        new_lo = _fmax(lo_l[i], nextafter(ci - qhi, -inf))
        new_hi = _fmin(hi_l[i], nextafter(ci - qlo, inf))
        lo_l[i], hi_l[i] = new_lo, new_hi
        # mr_from_bounds of the new d_i
        dl = nextafter(new_lo - ci, -inf)
        dh = nextafter(new_hi - ci, inf)
        dci = 0.5 * dl + 0.5 * dh
        dri = _maximum(nextafter(dh - dci, inf), nextafter(dci - dl, inf))
        adc = abs(dci)
        vec[:, i] = (dci, adc, dri, adc + dri)
    lo[:] = lo_l
    hi[:] = hi_l
