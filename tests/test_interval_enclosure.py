"""Enclosure properties of the interval arithmetic, checked against mpmath at 60 digits.

For random intervals and random points inside them, the exact result of the operation at
those points (computed by mpmath from the exact binary values) must lie inside the
computed interval.  This is the property that makes a certificate a proof.
"""

import math

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import finite, interval_and_point, wide

from certsolve.interval import arith, elementary, linalg, projections, rounding

mpmath.mp.dps = 60


def inside(lo, hi, exact) -> bool:
    return mpmath.mpf(float(lo)) <= exact <= mpmath.mpf(float(hi))


def M(x):
    return mpmath.mpf(float(x))


BINARY = [
    (arith.add, lambda x, y: M(x) + M(y)),
    (arith.sub, lambda x, y: M(x) - M(y)),
    (arith.mul, lambda x, y: M(x) * M(y)),
]


@pytest.mark.parametrize("op, exact", BINARY, ids=["add", "sub", "mul"])
@given(interval_and_point(wide), interval_and_point(wide))
def test_binary_encloses(op, exact, a, b):
    alo, ahi, x = a
    blo, bhi, y = b
    lo, hi = op(np.float64(alo), np.float64(ahi), np.float64(blo), np.float64(bhi))
    assert inside(lo, hi, exact(x, y))


@given(interval_and_point(wide), interval_and_point(wide))
def test_div_encloses(a, b):
    alo, ahi, x = a
    blo, bhi, y = b
    assume(y != 0.0)
    lo, hi = arith.div(np.float64(alo), np.float64(ahi), np.float64(blo), np.float64(bhi))
    assert inside(lo, hi, M(x) / M(y))


@given(interval_and_point(wide))
def test_sqr_and_powers_enclose(a):
    alo, ahi, x = a
    assume(abs(x) < 1e30 or True)
    lo, hi = arith.sqr(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, M(x) ** 2)
    for n in (3, 4, 5, -1, -2, -3):
        if n < 0 and x == 0.0:
            continue
        if abs(x) > 1e50 and n > 0:
            continue
        lo, hi = arith.pow_int(np.float64(alo), np.float64(ahi), n)
        assert inside(lo, hi, M(x) ** n), n


@given(interval_and_point(st.floats(min_value=0, max_value=1e300)))
def test_sqrt_encloses(a):
    alo, ahi, x = a
    lo, hi = arith.sqrt(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, mpmath.sqrt(M(x)))


@given(interval_and_point(st.floats(min_value=-700, max_value=700)))
def test_exp_encloses(a):
    alo, ahi, x = a
    lo, hi = elementary.exp(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, mpmath.exp(M(x)))


@given(interval_and_point(st.floats(min_value=1e-300, max_value=1e300)))
def test_log_encloses(a):
    alo, ahi, x = a
    lo, hi = elementary.log(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, mpmath.log(M(x)))


trig_points = st.floats(min_value=-1e5, max_value=1e5)


@pytest.mark.parametrize("fn, exact", [(elementary.sin, mpmath.sin), (elementary.cos, mpmath.cos)])
@given(interval_and_point(trig_points))
def test_trig_encloses(fn, exact, a):
    alo, ahi, x = a
    lo, hi = fn(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, exact(M(x)))


@pytest.mark.parametrize("fn, exact", [(elementary.sin, mpmath.sin), (elementary.cos, mpmath.cos)])
@given(st.integers(-10000, 10000), st.floats(min_value=-1e-9, max_value=1e-9), st.floats(0, 1e-6))
def test_trig_near_critical_points(fn, exact, k, off, w):
    """Intervals around k*pi/2 must include the extreme value when it is inside."""
    c = float(k * math.pi / 2) + off
    lo, hi = fn(np.float64(c - w), np.float64(c + w))
    for x in (c - w, c, c + w):
        assert inside(lo, hi, exact(M(x)))
    # the exact extreme value at the critical point nearest c, if it lies inside
    cp = mpmath.mpf(k) * mpmath.pi / 2
    if M(c - w) <= cp <= M(c + w):
        assert inside(lo, hi, exact(cp))


@given(interval_and_point(wide))
def test_abs_min_max(a):
    alo, ahi, x = a
    lo, hi = arith.iabs(np.float64(alo), np.float64(ahi))
    assert inside(lo, hi, abs(M(x)))


def test_division_by_interval_containing_zero_follows_ibex():
    # [1, 2] / [0, 1] = [1, +inf)
    lo, hi = arith.div(np.float64(1), np.float64(2), np.float64(0), np.float64(1))
    assert lo <= 1.0 and hi == np.inf
    # [1, 2] / [-1, 1]: hull of two half-lines = the whole line
    lo, hi = arith.div(np.float64(1), np.float64(2), np.float64(-1), np.float64(1))
    assert lo == -np.inf and hi == np.inf
    # x / [0, 0] is empty (no point of the domain)
    lo, hi = arith.div(np.float64(1), np.float64(2), np.float64(0), np.float64(0))
    assert lo > hi
    # sqrt of an entirely negative interval is empty, of a straddling one is from 0
    lo, hi = arith.sqrt(np.float64(-2), np.float64(-1))
    assert lo > hi
    lo, hi = arith.sqrt(np.float64(-2), np.float64(4))
    assert lo == 0.0 and 2.0 <= hi < 2.0 + 1e-15


def test_vectorised_and_scalar_paths_both_enclose():
    """Large arrays round arithmetically, small ones with nextafter: both enclose the exact
    endpoint products and agree to a few ulps."""
    rng = np.random.default_rng(0)
    a = np.sort(rng.normal(size=(2, 2000)) * 10, axis=0)
    b = np.sort(rng.normal(size=(2, 2000)) * 10, axis=0)
    lo, hi = arith.mul(a[0], a[1], b[0], b[1])
    for k in range(0, 2000, 149):
        slo, shi = arith.mul(a[0, k], a[1, k], b[0, k], b[1, k])
        ends = [M(p) * M(q) for p in (a[0, k], a[1, k]) for q in (b[0, k], b[1, k])]
        for L, H in ((lo[k], hi[k]), (slo, shi)):
            assert M(L) <= min(ends) and max(ends) <= M(H)
        assert abs(lo[k] - slo) <= 4 * np.spacing(abs(slo)) + 1e-300
        assert abs(hi[k] - shi) <= 4 * np.spacing(abs(shi)) + 1e-300


@pytest.mark.parametrize("size", [5, 511, 512, 3000])
def test_rounding_is_nextafter_at_every_size(size):
    """Small arrays step with ``nextafter``, large ones on the bit patterns (the size
    threshold is a speed choice): the same floats on both sides of it, the special values
    (signed zeros, subnormals, the largest float, infinities, NaN) included."""
    rng = np.random.default_rng(size)
    special = [0.0, -0.0, 5e-324, -5e-324, 2.0**-1022, -(2.0**-1022), 1.7976931348623157e308,
               -1.7976931348623157e308, np.inf, -np.inf, np.nan, 1.0, -1.0]  # fmt: skip
    x = rng.standard_normal(size) * 10.0 ** rng.integers(-300, 300, size)
    x[: min(size, len(special))] = special[:size]
    with np.errstate(over="ignore"):
        up_x, down_x = np.nextafter(x, np.inf), np.nextafter(x, -np.inf)
        pairs = _roundings(x, up_x, down_x)
    for got, want in pairs:
        assert np.array_equal(got.view(np.int64), want.view(np.int64))


def _roundings(x, up_x, down_x):
    """(the package's rounding, nextafter's) pairs for every rounding function."""
    tiny = ~(np.abs(x) >= 2.0**-1022)  # left alone by the in-place roundings of sums
    return (
        (rounding.up(x), up_x),
        (rounding.down(x), down_x),
        (rounding.up_inplace(x.copy()), up_x),
        (rounding.down_inplace(x.copy()), down_x),
        (rounding.up_inplace(x.copy(), exact_tiny=True), np.where(tiny, x, up_x)),
        (rounding.down_inplace(x.copy(), exact_tiny=True), np.where(tiny, x, down_x)),
    )


# --- projections: never remove a point that satisfies the relation -------------------

BWD_BINARY = [
    (projections.bwd_add, lambda x, y: M(x) + M(y)),
    (projections.bwd_sub, lambda x, y: M(x) - M(y)),
    (projections.bwd_mul, lambda x, y: M(x) * M(y)),
    (projections.bwd_div, lambda x, y: M(x) / M(y)),
    (projections.bwd_min, lambda x, y: min(M(x), M(y))),
    (projections.bwd_max, lambda x, y: max(M(x), M(y))),
]


@pytest.mark.parametrize("bwd, exact", BWD_BINARY, ids=["add", "sub", "mul", "div", "min", "max"])
@given(interval_and_point(), interval_and_point(), finite, finite)
def test_projection_keeps_solutions(bwd, exact, a, b, e1, e2):
    """If z = op(x, y) with x ∈ [a], y ∈ [b], z ∈ [z], the projection keeps x and y."""
    alo, ahi, x = a
    blo, bhi, y = b
    if bwd is projections.bwd_div:
        assume(y != 0.0)
    z = exact(x, y)
    zf = float(z)
    # a z-interval around the exact value, of random width
    zlo = min(
        zf - abs(e1) * 1e-3,
        float(mpmath.mpf(zf) if mpmath.mpf(zf) <= z else np.nextafter(zf, -np.inf)),
    )
    zhi = max(
        zf + abs(e2) * 1e-3,
        float(mpmath.mpf(zf) if mpmath.mpf(zf) >= z else np.nextafter(zf, np.inf)),
    )
    zlo = float(np.nextafter(zlo, -np.inf))
    zhi = float(np.nextafter(zhi, np.inf))
    assert M(zlo) <= z <= M(zhi)
    f = np.float64
    nxlo, nxhi, nylo, nyhi = bwd(f(zlo), f(zhi), f(alo), f(ahi), f(blo), f(bhi))
    assert nxlo <= x <= nxhi
    assert nylo <= y <= nyhi


UNARY = [
    (projections.bwd_sqr, lambda x: M(x) ** 2),
    (projections.bwd_abs, lambda x: abs(M(x))),
    (projections.bwd_exp, lambda x: mpmath.exp(M(x))),
    (lambda z0, z1, x0, x1: projections.bwd_pow(z0, z1, x0, x1, 3), lambda x: M(x) ** 3),
    (lambda z0, z1, x0, x1: projections.bwd_pow(z0, z1, x0, x1, 4), lambda x: M(x) ** 4),
    (projections.bwd_neg, lambda x: -M(x)),
]


@pytest.mark.parametrize("bwd, exact", UNARY, ids=["sqr", "abs", "exp", "pow3", "pow4", "neg"])
@given(interval_and_point(st.floats(min_value=-300, max_value=300)))
def test_unary_projection_keeps_solutions(bwd, exact, a):
    alo, ahi, x = a
    z = exact(x)
    zlo = float(np.nextafter(float(z), -np.inf))
    zhi = float(np.nextafter(float(z), np.inf))
    assert M(zlo) <= z <= M(zhi)
    nlo, nhi = bwd(np.float64(zlo), np.float64(zhi), np.float64(alo), np.float64(ahi))
    assert nlo <= x <= nhi


@given(interval_and_point(st.floats(min_value=0, max_value=1e6)))
def test_sqrt_and_log_projections(a):
    alo, ahi, x = a
    z = mpmath.sqrt(M(x))
    zlo = float(np.nextafter(float(z), -np.inf))
    zhi = float(np.nextafter(float(z), np.inf))
    nlo, nhi = projections.bwd_sqrt(
        np.float64(zlo), np.float64(zhi), np.float64(alo), np.float64(ahi)
    )
    assert nlo <= x <= nhi
    if x > 0:
        z = mpmath.log(M(x))
        zlo = float(np.nextafter(float(z), -np.inf))
        zhi = float(np.nextafter(float(z), np.inf))
        nlo, nhi = projections.bwd_log(
            np.float64(zlo), np.float64(zhi), np.float64(alo), np.float64(ahi)
        )
        assert nlo <= x <= nhi


def test_mul_inverse_keeps_the_gap():
    # x*y ∈ [1, 2], y ∈ [-1, 1], x ∈ [-10, 0.5]: x ∈ (-inf, -1] ∪ [1, inf) -> x ∈ [-10, -1]
    lo, hi = projections.mul_inverse(1.0, 2.0, -1.0, 1.0, -10.0, 0.5)
    assert lo == -10.0 and -1.0 <= hi < -0.999999


# --- rigorous matrix products ------------------------------------------------------------


@given(st.integers(1, 12), st.integers(0, 2**31))
def test_point_times_interval_matrix_encloses(n, seed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n)) * 10.0 ** rng.integers(-5, 5)
    c = rng.normal(size=(n, n))
    r = np.abs(rng.normal(size=(n, n))) * 0.1
    lo, hi = linalg.point_matmul_interval(a, c - r, c + r)
    # a random member of [B], and the exact product entry by entry in mpmath
    t = rng.uniform(size=(n, n))
    b = np.clip((c - r) + t * 2 * r, c - r, c + r)
    for i in range(n):
        for j in range(n):
            exact = mpmath.fsum(M(a[i, k]) * M(b[k, j]) for k in range(n))
            assert inside(lo[i, j], hi[i, j], exact)
