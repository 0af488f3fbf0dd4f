"""Fast paths of the kernels: the same values as the plain numpy forms, and sound.

* :mod:`certsolve.interval.reductions` must return exactly what ``np.all``/``np.any``/
  ``np.max``/``np.min``/``np.sum`` along the last axis return (NaN included), on both sides of
  its size threshold;
* the zero-divisor branch of the multiplication projection (``0 ∈ [y]``, one quotient per
  half-line) keeps every solution, never returns NaN from non-NaN inputs, and handles
  unbounded, degenerate-zero and empty operands, on batches small and large enough for
  either rounding path; corners ``∞/∞`` (unbounded operands) do not make a bound NaN;
* sums along an inner axis through :func:`~certsolve.interval.reductions.to_front`, and a
  column rounded on its own with ``size=`` (Hansen–Sengupta), give the same bits;
* the merged forward groups of :class:`~certsolve.expr.program.Program` give the same bits as
  the level-by-level groups.
"""

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import finite, interval_and_point

from certsolve.interval import inplace, projections, rounding
from certsolve.interval.reductions import (
    all_last,
    any_last,
    count_last,
    max_last,
    min_last,
    to_front,
)

mpmath.mp.dps = 60

SPECIAL = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, 1.0, -2.5, 1e308])


@pytest.mark.parametrize("shape", [(3, 4), (50, 7), (220, 32, 7), (100, 16), (100, 17), (9, 0)])
def test_reductions_equal_numpy(shape):
    rng = np.random.default_rng(len(shape) * 1000 + shape[-1])
    x = rng.standard_normal(shape)
    m = rng.random(shape) < 0.2
    x[m] = rng.choice(SPECIAL, int(m.sum()))
    b = x > 0.3
    assert np.array_equal(all_last(b), np.all(b, axis=-1))
    assert np.array_equal(any_last(b), np.any(b, axis=-1))
    assert np.array_equal(count_last(b), np.sum(b, axis=-1))
    if shape[-1]:
        assert np.array_equal(max_last(x), np.max(x, axis=-1), equal_nan=True)
        assert np.array_equal(min_last(x), np.min(x, axis=-1), equal_nan=True)


def M(x):
    return mpmath.mpf(float(x))


def _both_sizes(*bounds):
    """The same case as a (1, 1) array and tiled to (2, 40): both rounding paths."""
    one = [np.array([[v]]) for v in bounds]
    many = [np.full((2, 40), v) for v in bounds]
    return one, many


@given(
    interval_and_point(),
    st.floats(min_value=-1e6, max_value=0.0),
    st.floats(min_value=0.0, max_value=1e6),
    st.floats(min_value=-1e6, max_value=1e6),
    finite,
)
def test_mul_inverse_with_zero_in_y_keeps_solutions(x, ylo, yhi, y, e):
    """x·y ∈ [z] with 0 ∈ [y]: x stays in the projection; no NaN."""
    xlo, xhi, xp = x
    assume(ylo <= y <= yhi)
    z = M(xp) * M(y)
    zf = float(z)
    zlo = float(np.nextafter(min(zf - abs(e) * 1e-3, zf), -np.inf))
    zhi = float(np.nextafter(max(zf + abs(e) * 1e-3, zf), np.inf))
    assume(M(zlo) <= z <= M(zhi))
    for args in _both_sizes(zlo, zhi, ylo, yhi, xlo, xhi):
        for fn in (inplace.mul_inverse, projections.mul_inverse):
            lo, hi = fn(*args)
            assert not np.any(np.isnan(lo)) and not np.any(np.isnan(hi))
            assert np.all(lo <= xp) and np.all(xp <= hi)


CASES = [
    # z, y, x, expected hull (None: empty)
    ((1.0, 2.0), (-1.0, 2.0), (-np.inf, np.inf), (-np.inf, np.inf)),
    ((1.0, 2.0), (-1.0, 2.0), (-0.5, 0.25), None),  # the gap (-1, 0.5) holds all of x
    ((1.0, 2.0), (0.0, 2.0), (-np.inf, np.inf), (0.5, np.inf)),
    ((-2.0, -1.0), (0.0, 2.0), (-np.inf, 3.0), (-np.inf, -0.5)),
    ((1.0, 2.0), (-np.inf, 0.0), (-np.inf, np.inf), (-np.inf, 0.0)),
    ((1.0, 2.0), (0.0, 0.0), (-5.0, 5.0), None),  # t·0 is never in [1, 2]
    ((1.0, 2.0), (-0.0, 0.0), (-5.0, 5.0), None),
    ((-1.0, 2.0), (-1.0, 1.0), (-5.0, 5.0), (-5.0, 5.0)),  # 0 ∈ [z]: no contraction
    ((1.0, np.inf), (-1.0, 1.0), (-5.0, 5.0), (-5.0, 5.0)),
]


@pytest.mark.parametrize("z, y, x, expected", CASES)
def test_mul_inverse_zero_divisor_cases(z, y, x, expected):
    for args in _both_sizes(*z, *y, *x):
        for fn in (inplace.mul_inverse, projections.mul_inverse):
            lo, hi = fn(*args)
            assert not np.any(np.isnan(lo)) and not np.any(np.isnan(hi))
            if expected is None:
                assert np.all(lo > hi)
            else:
                assert np.all(lo <= expected[0]) and np.all(hi >= expected[1])
                assert np.all(lo >= x[0]) and np.all(hi <= x[1])
                assert np.all(np.isfinite(lo) == np.isfinite(expected[0]))
                assert np.all(np.isfinite(hi) == np.isfinite(expected[1]))


def test_mul_inverse_zero_divisor_contracts_to_the_quotients():
    """Tight enough to be useful: [1, 2] / [-1, 2] met with [-10, 10] is [-10, -1] ∪ [0.5, 10]."""
    for args in _both_sizes(1.0, 2.0, -1.0, 2.0, -10.0, 0.25):
        lo, hi = inplace.mul_inverse(*args)
        assert np.all(lo == -10.0) and np.all((-1.0 <= hi) & (hi < -0.999999))


def test_mul_inverse_empty_operand_gives_empty():
    """An empty [x] (lo > hi) stays empty: the projection never invents points."""
    for args in _both_sizes(1.0, 2.0, -1.0, 2.0, 3.0, -3.0):
        lo, hi = inplace.mul_inverse(*args)
        assert np.all(~(lo <= hi))


@pytest.mark.parametrize(
    "shape, axis", [((300, 28, 7), 1), ((40, 64, 16), 1), ((5, 3, 1), 1), ((9, 6, 4), 0)]
)
def test_sums_along_an_inner_axis_are_bit_identical(shape, axis):
    """Cancellation-heavy data: any other order of additions would differ somewhere."""
    rng = np.random.default_rng(shape[0])
    a = rng.standard_normal(shape) * 10.0 ** rng.integers(-8, 9, shape)
    assert np.array_equal(np.sum(to_front(a, axis), axis=0), np.sum(a, axis=axis))
    with pytest.raises(ValueError):
        to_front(a, -1)


UNBOUNDED = [
    # z, y (0 ∉ y), x, a point (x, y) with x·y ∈ z
    ((1.0, np.inf), (1.0, np.inf), (1.0, 2.0), (1.5, 10.0)),
    ((-np.inf, np.inf), (1.0, np.inf), (-3.0, 2.0), (-2.0, 1e300)),
    ((5.0, np.inf), (-np.inf, -1.0), (-np.inf, np.inf), (-7.0, -3.0)),
    ((-np.inf, -1.0), (2.0, np.inf), (-np.inf, 0.0), (-1.0, 5.0)),
    ((1.0, np.inf), (1.0, np.inf), (-np.inf, np.inf), (1e-200, 1e250)),
]


@pytest.mark.parametrize("z, y, x, point", UNBOUNDED)
def test_mul_projection_with_unbounded_corners_is_not_nan(z, y, x, point):
    """Corner quotients ∞/∞ are indeterminate: they must not turn the bound into NaN
    (an empty box to the evaluator) while solutions such as ``point`` exist."""
    xp, yp = point
    for args in _both_sizes(*z, *y, *x):
        for fn in (inplace.mul_inverse, projections.mul_inverse):
            lo, hi = fn(*args)
            assert not np.any(np.isnan(lo)) and not np.any(np.isnan(hi))
            assert np.all(lo <= xp) and np.all(xp <= hi)
        zlo, zhi, ylo, yhi, xlo, xhi = args
        nxlo, nxhi, nylo, nyhi = inplace.bwd_mul(zlo, zhi, xlo, xhi, ylo, yhi)
        assert np.all((nxlo <= xp) & (xp <= nxhi) & (nylo <= yp) & (yp <= nyhi))


def test_mul_projection_of_an_empty_operand_stays_empty():
    for args in _both_sizes(np.nan, np.nan, 1.0, np.inf, 1.0, 2.0):
        lo, hi = inplace.mul_inverse(*args)
        assert np.all(~(lo <= hi))


@pytest.mark.parametrize("shape", [(3, 7), (9, 7), (10, 7), (40, 16)])
def test_a_column_rounds_as_inside_its_array(shape):
    """``up/down(x, size=A.size)`` on a column of ``A`` equals that column of ``up/down(A)``
    (Hansen–Sengupta updates one column of its midpoint-radius form at a time)."""
    rng = np.random.default_rng(shape[0])
    a = rng.standard_normal(shape) * 10.0 ** rng.integers(-300, 300, shape)
    a[0, :] = [0.0, -0.0, np.inf, -np.inf, 5e-324, 1e-310, -1.0] + [2.0] * (shape[1] - 7)
    for j in range(shape[1]):
        for fn in (rounding.up, rounding.down):
            assert np.array_equal(fn(a[:, j], size=a.size), fn(a)[:, j])


@pytest.mark.parametrize("name", ["eco-7", "katsura-6", "kin2-6r", "trig-exp"])
def test_merged_forward_groups_give_the_level_by_level_bits(name):
    """The forward schedule merges groups (fewer numpy calls) without changing a bit."""
    import copy
    from pathlib import Path

    from certsolve.expr.compiled import CompiledSystem
    from certsolve.expr.minibex import load_minibex

    system = load_minibex(Path(__file__).parent.parent / "examples" / "systems" / f"{name}.mbx")
    csys = CompiledSystem(system)
    dom = np.clip(np.asarray(system.domain, dtype=float), -1e3, 1e3)
    rng = np.random.default_rng(1)
    for prog in (csys.hc4, csys.fj):
        for g in prog.fwd_groups:  # a merged group never feeds itself
            kids = set(g.a.tolist()) | set(() if g.b is None else g.b.tolist())
            assert not kids & set(range(g.start, g.stop))
        levelwise = copy.copy(prog)
        levelwise.fwd_groups = prog.groups
        for B in (1, 7, 200):
            lo = dom[:, 0] + rng.random((B, len(dom))) * (dom[:, 1] - dom[:, 0]) * 0.9
            hi = lo + (dom[:, 1] - dom[:, 0]) * rng.choice([0.1, 1e-6], (B, len(dom)))
            a = prog.eval_interval(lo, hi, csys.param_lo, csys.param_hi)
            b = levelwise.eval_interval(lo, hi, csys.param_lo, csys.param_hi)
            for u, v in zip(a, b):
                assert np.array_equal(u.view(np.int64), v.view(np.int64))
            x = 0.5 * (lo + hi)
            u, v = prog.eval_float(x, csys.param_mid), levelwise.eval_float(x, csys.param_mid)
            assert np.array_equal(u.view(np.int64), v.view(np.int64))
    assert len(csys.hc4.fwd_groups) < len(csys.hc4.groups) or name != "eco-7"


def test_batched_inverse_with_singular_members_equals_the_one_call_inverses():
    """Singular matrices in a stack get NaN and ``ok = False``; the others get exactly the
    inverse one ``np.linalg.inv`` call on them gives (the stack is halved, not looped)."""
    from certsolve.interval.linalg import batched_inverse

    rng = np.random.default_rng(3)
    A = rng.normal(size=(257, 4, 4))
    A[[0, 100, 256]] = 0.0
    A[9, :, 2] = 0.0
    A[17, 0] = np.inf
    Y, ok = batched_inverse(A)
    assert np.flatnonzero(~ok).tolist() == [0, 9, 17, 100, 256]
    assert np.all(np.isnan(Y[~ok]))
    assert np.array_equal(Y[ok], np.linalg.inv(A[ok]))


def test_hc4_intersects_the_ranges_of_an_expression_given_twice():
    """An expression bounded by two constraints (one graph node, two ranges) is bounded by
    their intersection, in either order; an empty intersection proves the box empty."""
    from certsolve.expr import Constraint, System, var
    from certsolve.expr.compiled import CompiledSystem

    x, y = var("x"), var("y")
    s = x + y

    def revise(r1, r2):
        system = System(
            variables=["x", "y"],
            domain=[[0.0, 5.0], [0.0, 5.0]],
            equations=[x - y, x * y - 0.01],
            constraints=[Constraint(s, *r1), Constraint(s, *r2)],
        )
        csys = CompiledSystem(system)
        assert csys.hc4_out.size < len(csys.hc4.outputs)  # the node is shared
        return csys.hc4_revise(np.array([[0.0, 0.0]]), np.array([[5.0, 5.0]]))

    for r1, r2 in [((-1.0, 0.5), (0.25, 2.0)), ((0.25, 2.0), (-1.0, 0.5))]:
        lo, hi, empty = revise(r1, r2)
        assert not empty[0]
        assert np.all(hi[0] <= 0.5) and np.all(lo[0] >= 0.0)  # x + y <= 0.5, x, y >= 0
    _, _, empty = revise((-1.0, 0.2), (0.25, 2.0))
    assert empty[0]


@pytest.mark.parametrize("name", ["sin", "cos", "tan"])
@given(seed=st.integers(0, 2**32 - 1))
def test_batched_sine_and_tangent_equal_their_one_interval_calls(name, seed):
    """``sin``, ``cos`` (both extrema tested in one stacked pass) and ``tan`` on a batch that
    mixes intervals ending within ulps of a multiple of π/2 (the exact test), wide and
    overflowed ones (``[max_float, inf]``, skipped by it) and empty ones: every row gives the
    bits of the same interval evaluated alone."""
    from certsolve.interval import elementary

    fn = getattr(elementary, name)
    rng = np.random.default_rng(seed)
    k = rng.integers(-50, 50, 40).astype(float)
    start = k * (np.pi / 2) + rng.choice([0.0, 1e-15, -1e-15, 1e-9, 0.3], 40)
    width = rng.choice([0.0, 1e-12, 0.5, 2.0, 7.0], 40)
    lo, hi = start, start + width
    special = rng.random(40) < 0.2
    lo[special], hi[special] = np.finfo(float).max, np.inf
    empty = rng.random(40) < 0.1
    lo[empty], hi[empty] = np.inf, -np.inf
    blo, bhi = fn(lo.reshape(8, 5), hi.reshape(8, 5))
    for i in range(40):
        olo, ohi = fn(lo[i], hi[i])
        assert (blo.ravel()[i], bhi.ravel()[i]) == (olo, ohi)
