"""Outward rounding: both code paths (numpy's nextafter for small arrays, integer steps on the
bit patterns for large ones) must bound every real that rounds to the given float, and give
the same floats: one ulp out, whatever the size of the array."""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from certsolve.interval.rounding import down, rational_enclosure, up

MAX = np.finfo(float).max
SPECIALS = [
    0.0,
    -0.0,
    np.inf,
    -np.inf,
    5e-324,
    -5e-324,
    2.0**-1022,
    -(2.0**-1022),
    MAX,
    -MAX,
    1.0,
    -1.0,
    2.0,
    -2.0,
    0.5,
    -0.5,
    3.0,
    2.0**-1070,
    1e-310,
    -1e-310,
]


def _samples(n, seed=0):
    rng = np.random.default_rng(seed)
    mant = rng.uniform(-2, 2, n)
    expo = rng.integers(-330, 308, n).astype(float)
    with np.errstate(over="ignore", under="ignore"):
        x = mant * 10.0**expo
    return np.concatenate([x, np.array(SPECIALS * 4)])


@pytest.mark.parametrize("size", [1, 10, 63, 64, 1000, 100_000])
def test_up_down_bound_the_rounding_interval(size):
    x = _samples(size)[: max(size, len(SPECIALS))]
    with np.errstate(all="ignore"):
        u = up(x)
        d = down(x)
        nu = np.nextafter(x, np.inf)
        nd = np.nextafter(x, -np.inf)
    # at least one float outward (hence beyond half an ulp), never NaN for non-NaN input
    assert np.all(u >= nu)
    assert np.all(d <= nd)
    assert not np.any(np.isnan(u)) and not np.any(np.isnan(d))
    # and not absurdly far: at most 3 floats away for finite normal inputs
    fin = np.isfinite(x) & (np.abs(x) > 1e-300) & (np.abs(x) < 1e300)
    steps_u = np.abs(u[fin] - x[fin]) / np.spacing(np.abs(x[fin]))
    assert np.all(steps_u <= 3.0)


@pytest.mark.parametrize("size", [1, 63, 64, 65, 1000, 100_000])
def test_up_down_are_nextafter_at_every_size(size):
    x = np.concatenate([_samples(size, seed=size)[:size], [np.nan, -np.nan], SPECIALS])
    with np.errstate(all="ignore"):
        for got, want in ((up(x), np.nextafter(x, np.inf)), (down(x), np.nextafter(x, -np.inf))):
            assert np.array_equal(np.isnan(got), np.isnan(want))
            ok = ~np.isnan(want)
            assert np.array_equal(got[ok].view(np.int64), want[ok].view(np.int64))  # -0.0 too
        # a strided view and a 2-D array round element by element as well
        y = x[: 2 * (x.size // 2)].reshape(2, -1)[:, ::3]
        assert np.array_equal(up(y), np.nextafter(y, np.inf), equal_nan=True)
        assert np.array_equal(down(y), np.nextafter(y, -np.inf), equal_nan=True)


def test_overflowed_values_stay_valid_bounds():
    big = np.full(100, -np.inf)
    assert np.all(up(big) == -MAX)  # -inf came from an overflow: -max is an upper bound
    assert np.all(down(np.full(100, np.inf)) == MAX)
    assert np.all(up(np.full(100, np.inf)) == np.inf)


@given(st.fractions(min_value=-1e300, max_value=1e300))
def test_rational_enclosure_is_the_tightest_float_interval(q):
    lo, hi = rational_enclosure(q)
    assert Fraction(lo) <= q <= Fraction(hi)
    assert lo == hi or np.nextafter(lo, np.inf) == hi
    assert (lo == hi) == (Fraction(lo) == q)


def test_rational_enclosure_beyond_the_float_range_raises():
    with pytest.raises(OverflowError):
        rational_enclosure(Fraction(10) ** 400)
