"""The generated per-box code (``certsolve.expr.scalar``) encloses the true values.

The real-time path (tracking, IK Algorithm 2) evaluates ``f`` and ``J`` one box at a time
with generated Python code whose fast variant inlines ``+ - *`` and checks finiteness only
where a non-finite bound could be mishandled.  Checked here: at random points of random
boxes, the exact value (mpmath interval arithmetic at 100 bits, at the point) lies inside
the generated code's enclosure over the box; and overflowing intermediate results never
produce a bound that excludes the true value.
"""

from pathlib import Path

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr import System, sqr, var
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.solver.verify import iv_eval

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"
CTX = mpmath.iv
CTX.prec = 100


@pytest.mark.parametrize("name", ["kin2-6r", "katsura-5", "trig-exp", "eco-6"])
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_scalar_fj_encloses_exact_values(name, data):
    csys = CompiledSystem(load_minibex(SYSTEMS / f"{name}.mbx"))
    dom = csys.system.domain
    seed = data.draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    a = rng.uniform(dom[:, 0], dom[:, 1])
    b = rng.uniform(dom[:, 0], dom[:, 1])
    w = data.draw(st.sampled_from([1e-6, 1e-2, 1.0]))
    lo = np.maximum(np.minimum(a, b), a - w)
    hi = np.minimum(np.maximum(a, b), a + w)
    flo, fhi, jlo, jhi = csys.fj_box(lo, hi)
    x = rng.uniform(lo, hi)
    nodes_f = [int(v) for v in csys.f.global_ids[csys.f.outputs]]
    exact = iv_eval(csys, nodes_f, x, x, CTX)
    for i, e in enumerate(exact):
        assert flo[i] <= e.a and e.b <= fhi[i]
    # the point enclosure (used as f(c) by Krawczyk) holds the exact value as well
    plo, phi = csys.f_point(x)
    for i, e in enumerate(exact):
        assert plo[i] <= e.a and e.b <= phi[i]
    # Jacobian entries: the exact derivative at x lies in the enclosure over the box
    rows, cols = np.nonzero(csys.jac_structure)
    nodes_j = [int(v) for v in csys.fj.global_ids[csys.fj.outputs]][csys.n :]
    exact_j = iv_eval(csys, nodes_j, x, x, CTX)
    for (r, c), e in zip(zip(rows, cols), exact_j):
        assert jlo[r, c] <= e.a and e.b <= jhi[r, c]


def test_overflow_inside_a_sum_is_not_lost():
    """``(x·1e300)·1e300 - (y·1e300)·1e300`` overflows to ``inf - inf``; multiplied by z
    the result must still enclose the true value (the fast code must bail out)."""
    x, y, z = var("x"), var("y"), var("z")
    big = (x * 1e300) * 1e300 - (y * 1e300) * 1e300
    system = System(
        ["x", "y", "z"],
        np.array([[1.0, 2.0], [1.0, 2.0], [0.0, 1.0]]),
        [big * z, sqr(x) - 1.0, z],
    )
    csys = CompiledSystem(system)
    lo, hi = np.array([1.0, 1.0, 0.0]), np.array([2.0, 2.0, 1.0])
    flo, fhi, _, _ = csys.fj_box(lo, hi)
    # true range of big * z over the box: (x - y)·1e600·z, i.e. all of [-1e600, 1e600]
    assert flo[0] == -np.inf and fhi[0] == np.inf
    # at a point where x == y the true value is 0
    plo, phi = csys.f_point(np.array([1.5, 1.5, 0.5]))
    assert plo[0] <= 0.0 <= phi[0]


# endpoints of every sign, zeros of both signs, and magnitudes far apart
_ENDPOINT = st.one_of(
    st.sampled_from([0.0, -0.0, 1.0, -1.0, 2.0**-1074, -(2.0**-1074)]),
    st.floats(-1e150, 1e150, allow_nan=False, allow_infinity=False),
    st.floats(-1e-150, 1e-150, allow_nan=False, allow_infinity=False),
)


def _interval(data) -> tuple[float, float]:
    a, b = data.draw(_ENDPOINT), data.draw(_ENDPOINT)
    return (a, b) if a <= b else (b, a)


def _corners(op, x, y):
    """The values of ``op`` at the corners of the boxes, to 2200 bits: products of two
    doubles exactly, quotients within ``2**-2200`` relative, far inside the gap of at
    least half an ulp (``2**-1075``) between a rounded-outward bound and the value."""
    with mpmath.workprec(2200):
        xs = [mpmath.mpf(v) for v in x]
        ys = [mpmath.mpf(v) for v in y]
        if op == "sqr":
            return [v * v for v in xs]
        if op == "mul":
            return [a * b for a in xs for b in ys]
        return [a / b for a in xs for b in ys]


@pytest.mark.parametrize("op", ["mul", "div", "sqr"])
@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_fast_signed_products_are_the_helpers_bounds(op, data):
    """The fast variant picks the bounds of ``x·y``, ``x/y`` and ``x²`` by the operands'
    signs: the same floats as the helper-based variant (min/max of the four rounded
    corner values, one ulp outward), and they enclose the exact range."""
    from certsolve.expr.graph import Graph
    from certsolve.expr.scalar import ScalarProgram, _Bail

    x, y = var("x"), var("y")
    expr = {"mul": x * y, "div": x / y, "sqr": sqr(x)}[op]
    g = Graph(["x", "y"], [])
    prog = ScalarProgram(g, [g.add_expr(expr)])
    xb, yb = _interval(data), _interval(data)
    if op == "div":  # the fast code's inline cases: divisor away from 0
        if yb[0] <= 0.0 <= yb[1]:
            yb = (abs(yb[1]) + 1.0, abs(yb[1]) + 2.0) if data.draw(st.booleans()) else yb
    args = ([xb[0], yb[0]], [xb[1], yb[1]], [], [])
    safe = prog.interval_safe(*args)
    try:
        fast = prog._interval_fast(*args)
    except _Bail:  # an overflowed bound: the fast code hands over to the helpers
        fast = prog.interval(*args)
    assert fast == safe
    lo, hi = fast[0][0], fast[1][0]
    if op == "div" and yb[0] <= 0.0 <= yb[1]:
        return  # extended division: the helper's IBEX cases, tested with the solver
    with mpmath.workprec(2200):
        exact = _corners(op, xb, yb)
        assert mpmath.mpf(lo) <= min(exact) and max(exact) <= mpmath.mpf(hi)
