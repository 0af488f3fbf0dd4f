"""Enclosures and projections of the elementary functions beyond exp/log/sin/cos.

As in ``test_interval_enclosure.py``: for random intervals and random points of the function's
domain inside them, the exact value (mpmath at 60 digits, from the exact binary inputs) must
lie in the computed interval; and a backward projection must never remove a point ``x`` whose
image lies in ``[z]``.
"""

import math

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import interval_and_point

from certsolve.interval import elementary as E
from certsolve.interval import projections as P

mpmath.mp.dps = 60
f64 = np.float64


def M(x):
    return mpmath.mpf(float(x))


def inside(lo, hi, exact) -> bool:
    return M(lo) <= exact <= M(hi)


def floats(a, b):
    return st.floats(min_value=a, max_value=b, allow_nan=False, allow_infinity=False)


@st.composite
def interval_with_point_in(draw, lo, hi, dlo, dhi):
    """An interval drawn from [lo, hi] and a point of it inside the domain [dlo, dhi]."""
    a, b = sorted((draw(floats(lo, hi)), draw(floats(lo, hi))))
    # + 0.0 turns -0.0 into 0.0: hypothesis refuses the range [0.0, -0.0]
    c, d = max(a, dlo) + 0.0, min(b, dhi) + 0.0
    assume(c <= d)
    return a, b, draw(floats(c, d))


@st.composite
def near_branch_ends(draw, max_width=7.0):
    """An interval of width up to ``max_width`` (at any scale down to 1e-12), often starting
    or ending within a few ulps of a multiple of π/2 (where sin and cos change branch), and a
    point of it."""
    k = draw(st.integers(-2000, 2000))
    jitter = draw(st.one_of(st.just(0.0), floats(-1e-12, 1e-12), floats(-3.0, 3.0)))
    start = k * math.pi / 2 + jitter
    width = draw(st.one_of(floats(0.0, max_width), st.sampled_from([1e-12, 1e-9, 1e-6, 1e-3])))
    lo, hi = sorted((start, start + draw(st.sampled_from([1.0, -1.0])) * width))
    return lo, hi, draw(floats(lo, hi))


UNARY = {
    "tan": (E.tan, mpmath.tan, interval_and_point(floats(-1e5, 1e5))),
    "sinh": (E.sinh, mpmath.sinh, interval_and_point(floats(-800, 800))),
    "cosh": (E.cosh, mpmath.cosh, interval_and_point(floats(-800, 800))),
    "tanh": (E.tanh, mpmath.tanh, interval_and_point(floats(-1e300, 1e300))),
    "atan": (E.atan, mpmath.atan, interval_and_point(floats(-1e300, 1e300))),
    "asinh": (E.asinh, mpmath.asinh, interval_and_point(floats(-1e300, 1e300))),
    "asin": (E.asin, mpmath.asin, interval_with_point_in(-3, 3, -1, 1)),
    "acos": (E.acos, mpmath.acos, interval_with_point_in(-3, 3, -1, 1)),
    "acosh": (E.acosh, mpmath.acosh, interval_with_point_in(-10, 1e300, 1, 1e300)),
    "atanh": (
        E.atanh,
        mpmath.atanh,
        interval_with_point_in(-3, 3, math.nextafter(-1, 0), math.nextafter(1, 0)),
    ),
}


@pytest.mark.parametrize("name", list(UNARY))
@given(data=st.data())
def test_unary_encloses(name, data):
    fn, exact, strategy = UNARY[name]
    lo, hi, x = data.draw(strategy)
    rlo, rhi = fn(f64(lo), f64(hi))
    assert rlo <= rhi and not np.isnan(rlo) and not np.isnan(rhi)
    assert rlo < np.inf and rhi > -np.inf
    assert inside(rlo, rhi, exact(M(x)))


@given(st.integers(-10000, 10000), floats(-1e-9, 1e-9), floats(0, 1e-6))
def test_tan_near_poles(k, off, w):
    """An interval around a pole (k + 1/2)π maps to the whole line; nearby ones enclose."""
    c = float((k + 0.5) * math.pi) + off
    lo, hi = E.tan(f64(c - w), f64(c + w))
    pole = (mpmath.mpf(k) + mpmath.mpf(1) / 2) * mpmath.pi
    if M(c - w) <= pole <= M(c + w):
        assert lo == -np.inf and hi == np.inf
    for x in (c - w, c, c + w):
        if M(x) != pole:
            assert inside(lo, hi, mpmath.tan(M(x)))


@given(st.integers(-10000, 10000), st.sampled_from([1e-10, 1e-12, 1e-14]), floats(0, 1e-8))
def test_tan_is_finite_next_to_a_pole(k, gap, w):
    """An interval ending ``gap`` before a pole (IBEX's AOL-legentil: x <= π/2 - 1e-10) is
    bounded; the poles are located with an outward-rounded enclosure of (k + 1/2)π, not with
    a relative slack (1e-9 once made ``tan`` unbounded there)."""
    pole = (mpmath.mpf(k) + mpmath.mpf(1) / 2) * mpmath.pi
    hi = float(pole - gap * max(1, abs(k)))
    lo = hi - w
    assume(M(hi) < pole)
    tlo, thi = E.tan(f64(lo), f64(hi))
    assert np.isfinite(tlo) and np.isfinite(thi)
    assert inside(tlo, thi, mpmath.tan(M(lo))) and inside(tlo, thi, mpmath.tan(M(hi)))


ULPS = st.sampled_from([-3, -1, 0, 1, 3, 1000, 10**5, 10**7])


@given(st.integers(-10000, 10000), st.sampled_from(["tan", "sin", "cos"]), ULPS, ULPS)
def test_critical_points_near_a_bound(k, name, below, above):
    """Intervals from ``below`` ulps under a pole of tan (or an extremum of sin or cos) to
    ``above`` ulps over it: bounds within the 1e-9 relative slack of the point are decided by
    the enclosures of ``(k + 1/2)π``.  A pole inside gives the whole line, an extremum
    inside its value ±1, and the values at both bounds are enclosed."""
    fn, exact = {"tan": (E.tan, mpmath.tan), "sin": (E.sin, mpmath.sin)}.get(
        name, (E.cos, mpmath.cos)
    )
    point = (mpmath.mpf(k) + (0 if name == "cos" else mpmath.mpf(1) / 2)) * mpmath.pi
    c = float(point)
    lo, hi = c - below * math.ulp(c), c + above * math.ulp(c)
    assume(lo <= hi)
    rlo, rhi = fn(f64(lo), f64(hi))
    if M(lo) <= point <= M(hi):
        if name == "tan":
            assert rlo == -np.inf and rhi == np.inf
        else:
            assert inside(rlo, rhi, exact(point))
    for x in (lo, hi):
        if M(x) != point:
            assert inside(rlo, rhi, exact(M(x)))


@given(interval_and_point(floats(-1e6, 1e6)), interval_and_point(floats(-1e6, 1e6)))
def test_atan2_encloses(ya, xa):
    ylo, yhi, y = ya
    xlo, xhi, x = xa
    assume(not (x == 0.0 and y == 0.0))
    lo, hi = E.atan2(f64(ylo), f64(yhi), f64(xlo), f64(xhi))
    assert inside(lo, hi, mpmath.atan2(M(y), M(x)))


@pytest.mark.parametrize("y", [-0.0, 0.0])
def test_atan2_on_the_cut(y):
    """(-1, 0) has angle π; a box reaching below the negative x axis spans [-π, π]."""
    lo, hi = E.atan2(f64(y), f64(0.0), f64(-1.0), f64(-1.0))
    assert inside(lo, hi, mpmath.pi)
    lo, hi = E.atan2(f64(-1e-300), f64(0.0), f64(-1.0), f64(-0.5))
    assert inside(lo, hi, mpmath.pi) and inside(lo, hi, -mpmath.pi + mpmath.mpf(1e-200))


@given(
    interval_and_point(floats(0, 1e3)),
    interval_and_point(floats(-8, 8)),
)
def test_rpow_encloses(xa, ya):
    xlo, xhi, x = xa
    ylo, yhi, y = ya
    assume(x > 0 or y > 0)
    lo, hi = E.rpow(f64(xlo), f64(xhi), f64(ylo), f64(yhi))
    exact = mpmath.mpf(0) if x == 0 else mpmath.power(M(x), M(y))
    assert inside(lo, hi, exact)


def test_domain_restriction():
    def empty(lo, hi):
        return bool(lo > hi)

    assert empty(*E.asin(f64(1.5), f64(2.0)))
    assert empty(*E.acos(f64(-3.0), f64(-1.5)))
    assert empty(*E.acosh(f64(-1.0), f64(0.5)))
    assert empty(*E.atanh(f64(1.0), f64(2.0)))
    assert empty(*E.rpow(f64(-2.0), f64(-1.0), f64(0.5), f64(0.5)))
    assert empty(*E.rpow(f64(0.0), f64(0.0), f64(-1.0), f64(0.0)))
    assert empty(*E.atan2(f64(0.0), f64(0.0), f64(0.0), f64(0.0)))
    lo, hi = E.asin(f64(0.0), f64(5.0))  # the part in [-1, 1]
    assert lo <= 0 and math.pi / 2 <= hi < 1.5708
    lo, hi = E.rpow(f64(-4.0), f64(4.0), f64(0.5), f64(0.5))  # sqrt of the non-negative part
    assert lo == 0.0 and 2.0 <= hi < 2.0 + 1e-12
    lo, hi = E.sinh(f64(800.0), f64(900.0))  # overflow: still a (finite) lower bound
    assert lo == np.finfo(float).max and hi == np.inf


# -- projections --------------------------------------------------------------------------------


def tight(z):
    """The two floats around the exact real ``z`` (an interval holding it)."""
    zf = float(z)
    lo = zf if M(zf) <= z else math.nextafter(zf, -math.inf)
    hi = zf if M(zf) >= z else math.nextafter(zf, math.inf)
    return math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)


BWD = {
    "sin": (P.bwd_sin, mpmath.sin, near_branch_ends()),
    "cos": (P.bwd_cos, mpmath.cos, near_branch_ends()),
    "tan": (P.bwd_tan, mpmath.tan, interval_and_point(floats(-50, 50))),
    "sinh": (P.bwd_sinh, mpmath.sinh, interval_and_point(floats(-700, 700))),
    "cosh": (P.bwd_cosh, mpmath.cosh, interval_and_point(floats(-700, 700))),
    "tanh": (P.bwd_tanh, mpmath.tanh, interval_and_point(floats(-15, 15))),
    "atan": (P.bwd_atan, mpmath.atan, interval_and_point(floats(-1e15, 1e15))),
    "asinh": (P.bwd_asinh, mpmath.asinh, interval_and_point(floats(-1e300, 1e300))),
    "asin": (P.bwd_asin, mpmath.asin, interval_with_point_in(-3, 3, -1, 1)),
    "acos": (P.bwd_acos, mpmath.acos, interval_with_point_in(-3, 3, -1, 1)),
    "acosh": (P.bwd_acosh, mpmath.acosh, interval_with_point_in(-10, 1e300, 1, 1e300)),
    "atanh": (
        P.bwd_atanh,
        mpmath.atanh,
        interval_with_point_in(-3, 3, math.nextafter(-1, 0), math.nextafter(1, 0)),
    ),
    "sign": (P.bwd_sign, mpmath.sign, interval_and_point(floats(-10, 10))),
}


@pytest.mark.parametrize("name", list(BWD))
@given(data=st.data())
def test_projection_keeps_the_preimage(name, data):
    bwd, exact, strategy = BWD[name]
    lo, hi, x = data.draw(strategy)
    zlo, zhi = tight(exact(M(x)))
    nlo, nhi = bwd(f64(zlo), f64(zhi), f64(lo), f64(hi))
    assert nlo <= x <= nhi


@given(
    interval_and_point(floats(0, 1e3)),
    interval_and_point(floats(-8, 8)),
)
def test_rpow_projection_keeps_the_preimage(xa, ya):
    xlo, xhi, x = xa
    ylo, yhi, y = ya
    assume(x > 0)
    zlo, zhi = tight(mpmath.power(M(x), M(y)))
    nxlo, nxhi, nylo, nyhi = P.bwd_rpow(f64(zlo), f64(zhi), f64(xlo), f64(xhi), f64(ylo), f64(yhi))
    assert nxlo <= x <= nxhi
    assert nylo <= y <= nyhi


@pytest.mark.parametrize("name", ["sin", "cos"])
@given(data=st.data())
def test_sine_projection_keeps_the_preimage_of_an_interval(name, data):
    """[z] an interval around f(x) (or reaching past [-1, 1]): x stays in the projection."""
    bwd, exact, _ = BWD[name]
    lo, hi, x = data.draw(near_branch_ends())
    fx = exact(M(x))
    below = data.draw(st.one_of(floats(0.0, 2.5), st.sampled_from([0.0, 1e-15, 1e-9])))
    above = data.draw(st.one_of(floats(0.0, 2.5), st.sampled_from([0.0, 1e-15, 1e-9])))
    zlo, _ = tight(fx - below)
    _, zhi = tight(fx + above)
    nlo, nhi = bwd(f64(zlo), f64(zhi), f64(lo), f64(hi))
    assert nlo <= x <= nhi


def test_projections_contract():
    """Not only sound: the inverse images are used (x in [-10, 10] narrowed)."""
    lo, hi = P.bwd_sinh(f64(1.0), f64(1.0), f64(-10.0), f64(10.0))
    assert abs(lo - math.asinh(1.0)) < 1e-12 and abs(hi - math.asinh(1.0)) < 1e-12
    lo, hi = P.bwd_tan(f64(1.0), f64(1.0), f64(3.0), f64(4.0))  # x = π/4 + π
    assert abs(lo - (math.pi / 4 + math.pi)) < 1e-12 and abs(hi - lo) < 1e-12
    lo, hi = P.bwd_cosh(f64(2.0), f64(2.0), f64(0.0), f64(10.0))
    assert abs(lo - math.acosh(2.0)) < 1e-12
    lo, hi = P.bwd_sin(f64(0.9), f64(1.0), f64(0.5), f64(2.5))  # two branches, split at π/2
    assert abs(lo - math.asin(0.9)) < 1e-12 and abs(hi - (math.pi - math.asin(0.9))) < 1e-12
    lo, hi = P.bwd_cos(f64(0.5), f64(0.5), f64(-1.5), f64(1.5))  # x = ±π/3
    assert abs(lo + math.pi / 3) < 1e-12 and abs(hi - math.pi / 3) < 1e-12
    lo, hi = P.bwd_cos(f64(-0.2), f64(0.3), f64(3.5), f64(6.0))  # cos increasing on [π, 2π]
    assert abs(lo - (2 * math.pi - math.acos(-0.2))) < 1e-12
    assert abs(hi - (2 * math.pi - math.acos(0.3))) < 1e-12
    lo, hi = P.bwd_sin(f64(2.0), f64(3.0), f64(0.0), f64(1.0))  # outside [-1, 1]: empty
    assert lo > hi
    lo, hi = P.bwd_sin(f64(0.5), f64(0.5), f64(-10.0), f64(10.0))  # several periods: unchanged
    assert lo == -10.0 and hi == 10.0
    lo, hi, _, _ = P.bwd_rpow(f64(2.0), f64(2.0), f64(-5.0), f64(10.0), f64(0.5), f64(0.5))
    assert abs(lo - 4.0) < 1e-12 and abs(hi - 4.0) < 1e-12
    lo, hi = P.bwd_sign(f64(1.0), f64(1.0), f64(-3.0), f64(3.0))
    assert lo == 0.0 and hi == 3.0
