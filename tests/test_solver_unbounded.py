"""Unbounded domains: finite split points and centres, no NaN box ever, complete answers where
contraction bounds the search.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr.minibex import MinibexError, parse_minibex
from certsolve.interval.core import cut_points, midpoint, split_point, splittable_width
from certsolve.solver import solve
from certsolve.solver.bisectors import split

INF = math.inf
MAX = float(np.finfo(float).max)

bound = st.one_of(
    st.just(-INF),
    st.just(INF),
    st.floats(allow_nan=False, allow_infinity=False),
)


@given(bound, bound, st.floats(0.05, 0.95))
def test_points_are_finite_and_inside(a, b, ratio):
    lo, hi = min(a, b), max(a, b)
    if lo == hi and math.isinf(lo):
        return  # not an interval of reals
    lo, hi = np.float64(lo), np.float64(hi)
    for m in (midpoint(lo, hi), split_point(lo, hi, ratio)):
        assert np.isfinite(m) and lo <= m <= hi
    cuts = cut_points(lo, hi, 4)
    assert cuts[0] == lo and cuts[-1] == hi
    assert np.all(np.diff(cuts) >= 0) and np.all(np.isfinite(cuts[1:-1]))
    w = splittable_width(lo, hi)
    m = split_point(lo, hi, 0.5)
    assert (w > 0) == (lo < m < hi)


def test_half_line_bisection_reaches_the_end_of_the_floats():
    lo, hi = np.float64(0.0), np.float64(INF)
    steps = 0
    while splittable_width(lo, hi) > 0:
        m = split_point(lo, hi, 0.45)
        assert lo < m < hi and np.isfinite(m)
        lo = m
        steps += 1
    assert lo == MAX and hi == INF and steps < 700


def test_split_of_unbounded_boxes():
    lo = np.array([[-INF, 0.0], [1.0, -INF]])
    hi = np.array([[INF, 1.0], [INF, -3.0]])
    (alo, ahi), (blo, bhi) = split(lo, hi, np.array([0, 1]), 0.45)
    assert ahi[0, 0] == 0.0 and blo[0, 0] == 0.0
    assert np.isfinite(ahi[1, 1]) and ahi[1, 1] < -3.0
    for arr in (alo, ahi, blo, bhi):
        assert not np.isnan(arr).any()


CASES = [
    # text, number of solutions, points
    ("Variables x; Constraints x^2 = 4; end", [[-2.0], [2.0]]),
    ("Variables x; y; Constraints x + y = 3; x - y = 1; end", [[2.0, 1.0]]),
    ("Variables x in [0, +oo]; y; Constraints x*y = 1; x - y = 0; end", [[1.0, 1.0]]),
    ("Variables x; y; Constraints x^2 + y^2 = 1; x = y; end", [[-(0.5**0.5)] * 2, [0.5**0.5] * 2]),
    ("Variables x; Constraints atan(x) = 1.5; end", [[math.tan(1.5)]]),
    ("Variables x in [-oo, 0]; Constraints exp(x) = 0.5; end", [[math.log(0.5)]]),
]


@pytest.mark.parametrize("text, points", CASES)
def test_complete_answers_on_unbounded_domains(text, points):
    r = solve(parse_minibex(text), eps=1e-8, timeout=60)
    assert r.status == "complete"
    assert not r.undecided
    assert len(r.solutions) == len(points)
    for p in points:  # each expected point (rounded) is in exactly one solution box
        near = [s for s in r.solutions if np.all(s.lo - 1e-12 <= p) and np.all(p <= s.hi + 1e-12)]
        assert len(near) == 1


def test_an_asymptote_leaves_only_the_last_float_interval_undecided():
    """x exp(-x) = 0.1 has two roots; towards +oo the function tends to 0 and the search ends
    at [max_float, +oo), which has no float inside: reported undecided, never dropped."""
    r = solve(parse_minibex("Variables x; Constraints x*exp(-x) = 0.1; end"), eps=1e-8, timeout=60)
    assert r.status == "complete" and len(r.solutions) == 2
    assert all(u.lo[0] >= MAX and u.hi[0] == INF for u in r.undecided)


def no_nan(result) -> bool:
    boxes = [np.array(s.box) for s in result.solutions] + [
        np.array(u.box) for u in result.undecided
    ]
    if result.pending_lo is not None and result.pending_lo.size:
        boxes += [result.pending_lo, result.pending_hi]
    return not any(np.isnan(b).any() for b in boxes)


FUNCS = ["x", "y", "x*y", "x^2", "y^3", "exp(x)", "sin(y)", "atan(x)", "x/y", "sqrt(x)", "log(y)"]


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.sampled_from(FUNCS), min_size=2, max_size=2),
    st.lists(st.sampled_from(FUNCS), min_size=2, max_size=2),
    st.sampled_from(["x; y;", "x in [0, +oo]; y;", "x in [-oo, 1]; y in [2, +oo];"]),
    st.integers(-3, 3),
)
def test_no_nan_box_ever(f, g, decl, c):
    text = f"Variables {decl} Constraints {f[0]} - {f[1]} = {c}; {g[0]} + {g[1]} = 1; end"
    try:
        system = parse_minibex(text)
    except MinibexError:  # a constraint without variables (x - x): not this test's business
        return
    r = solve(system, eps=1e-6, max_boxes=3000)
    assert no_nan(r)
    for s in r.solutions:
        assert np.all(np.isfinite(s.lo)) and np.all(np.isfinite(s.hi))
