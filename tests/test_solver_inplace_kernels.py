"""The fewer-pass kernels of the batched evaluator (``certsolve.interval.inplace``) enclose.

Checked as the general kernels are (``tests/test_interval_enclosure.py``): random intervals,
random points inside, exact results with mpmath at 60 digits.  The sums are also checked on
results that are zero or subnormal, where the kernels skip the ``2^-1074`` widening, and
against the general kernels (never looser).
"""

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import finite, interval_and_point, tiny, wide

from certsolve.interval import arith, inplace, projections

mpmath.mp.dps = 60


def M(x):
    return mpmath.mpf(float(x))


def arr(v):
    return np.array([[float(v)]])


INTO = [
    (inplace.add_into, lambda x, y: M(x) + M(y)),
    (inplace.sub_into, lambda x, y: M(x) - M(y)),
    (inplace.mul_into, lambda x, y: M(x) * M(y)),
]


@pytest.mark.parametrize("op, exact", INTO, ids=["add", "sub", "mul"])
@pytest.mark.parametrize("elements", [wide, tiny], ids=["wide", "tiny"])
@given(data=st.data())
def test_forward_kernels_enclose(op, exact, elements, data):
    alo, ahi, x = data.draw(interval_and_point(elements))
    blo, bhi, y = data.draw(interval_and_point(elements))
    olo, ohi = np.empty((1, 1)), np.empty((1, 1))
    op(arr(alo), arr(ahi), arr(blo), arr(bhi), olo, ohi)
    e = exact(x, y)
    assert M(olo[0, 0]) <= e <= M(ohi[0, 0])


@given(interval_and_point(wide), st.floats(min_value=-1e6, max_value=1e6))
def test_shift_encloses(a, c):
    alo, ahi, x = a
    olo, ohi = np.empty((1, 1)), np.empty((1, 1))
    inplace.shift_into(arr(alo), arr(ahi), np.array([[c]]), olo, ohi)
    assert M(olo[0, 0]) <= M(x) + M(c) <= M(ohi[0, 0])


def test_sums_of_opposite_and_subnormal_values_are_exact():
    """x + y that rounds to 0 or to a subnormal is exact: no widening needed there."""
    vals = np.array([[5e-324, 1e-310, 2.5e-308, 1.0, 3.0]])
    olo, ohi = np.empty_like(vals), np.empty_like(vals)
    inplace.add_into(vals, vals, -vals, -vals, olo, ohi)
    assert np.all(olo == 0.0) and np.all(ohi == 0.0)
    a = np.array([[3e-310]])
    b = np.array([[-1e-310]])
    inplace.add_into(a, a, b, b, olo[:, :1], ohi[:, :1])
    assert M(olo[0, 0]) <= M(a[0, 0]) + M(b[0, 0]) <= M(ohi[0, 0])


BWD = [
    (inplace.bwd_add, lambda x, y: M(x) + M(y)),
    (inplace.bwd_sub, lambda x, y: M(x) - M(y)),
    (inplace.bwd_mul, lambda x, y: M(x) * M(y)),
]


@pytest.mark.parametrize("bwd, exact", BWD, ids=["add", "sub", "mul"])
@given(interval_and_point(), interval_and_point(), finite, finite)
def test_projection_kernels_keep_solutions(bwd, exact, a, b, e1, e2):
    alo, ahi, x = a
    blo, bhi, y = b
    z = exact(x, y)
    zf = float(z)
    zlo = float(np.nextafter(min(zf - abs(e1) * 1e-3, zf), -np.inf))
    zhi = float(np.nextafter(max(zf + abs(e2) * 1e-3, zf), np.inf))
    assume(M(zlo) <= z <= M(zhi))
    nxlo, nxhi, nylo, nyhi = bwd(arr(zlo), arr(zhi), arr(alo), arr(ahi), arr(blo), arr(bhi))
    assert nxlo[0, 0] <= x <= nxhi[0, 0]
    assert nylo[0, 0] <= y <= nyhi[0, 0]


def test_kernels_never_looser_than_the_general_ones():
    rng = np.random.default_rng(0)
    shape = (40, 300)

    def rint():
        a = rng.choice([-3.0, -1.0, 0.0, 1.0, 2.0, 5.0], shape) * rng.random(shape) ** 2
        b = a + rng.choice([0.0, 0.5, 2.0, 10.0], shape) * rng.random(shape)
        a[rng.random(shape) < 0.05] = 0.0
        return a, np.maximum(a, b)

    x, y, z = rint(), rint(), rint()
    with np.errstate(all="ignore"):
        pairs = [
            (projections.bwd_add(*z, *x, *y), inplace.bwd_add(*z, *x, *y)),
            (projections.bwd_sub(*z, *x, *y), inplace.bwd_sub(*z, *x, *y)),
            (projections.bwd_mul(*z, *x, *y), inplace.bwd_mul(*z, *x, *y)),
        ]
        for general, kernel in (
            (arith.add, inplace.add_into),
            (arith.sub, inplace.sub_into),
            (arith.mul, inplace.mul_into),
        ):
            o, q = np.empty(shape), np.empty(shape)
            kernel(*x, *y, o, q)
            pairs.append((general(*x, *y), (o, q)))
    for old, new in pairs:
        for k in range(0, len(old), 2):
            ok = (old[k] <= old[k + 1]) & (new[k] <= new[k + 1])
            assert np.array_equal(~(old[k] <= old[k + 1]), ~(new[k] <= new[k + 1]))
            assert np.all(new[k][ok] >= old[k][ok])
            assert np.all(new[k + 1][ok] <= old[k + 1][ok])


def test_product_of_zero_and_unbounded_is_zero():
    olo, ohi = np.empty((1, 1)), np.empty((1, 1))
    inplace.mul_into(arr(0.0), arr(0.0), arr(-np.inf), arr(np.inf), olo, ohi)
    assert olo[0, 0] <= 0.0 <= ohi[0, 0] and np.isfinite(olo[0, 0]) and np.isfinite(ohi[0, 0])


def test_mul_inverse_kernel_keeps_the_gap():
    lo, hi = inplace.mul_inverse(arr(1.0), arr(2.0), arr(-1.0), arr(1.0), arr(-10.0), arr(0.5))
    assert lo[0, 0] == -10.0 and -1.0 <= hi[0, 0] < -0.999999
