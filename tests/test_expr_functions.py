"""Every elementary function through the expression layer: batched and per-box enclosures of
``f`` and of its symbolic Jacobian, HC4 soundness, and where Krawczyk may be applied.

Exact values come from :func:`certsolve.solver.verify.iv_eval` (``mpmath.iv`` at 100 bits, node
by node, no code shared with the numpy evaluator).
"""

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr import System, const, var
from certsolve.expr import node as N
from certsolve.expr.compiled import CompiledSystem
from certsolve.solver.verify import iv_eval

CTX = mpmath.iv
CTX.prec = 100

x, y = var("x"), var("y")

# every function, on x, y in [0.1, 0.9] (inside every domain)
EQUATIONS = [
    N.tan(x) + N.sinh(y) - N.cosh(x * y) + N.tanh(x - y) + N.atan(2 * x),
    N.asin(y) - N.acos(x) + N.asinh(x * y) + N.acosh(1.5 + x) + N.atanh(y - 0.5),
    N.atan2(y, x - 0.5) * N.rpow(x, y) + N.rpow(x, const(0.5)) - N.sign(x) + N.abs_(y - 0.5),
    N.min_(x, y) * N.max_(x, 1 - y) + N.exp(x) * N.log(y) + N.sin(x) * N.cos(y) + N.sqrt(x) / y,
]


def system(eqs, dom=((0.1, 0.9), (0.1, 0.9))):
    return System(["x", "y"], np.array(dom), eqs[:2] if len(eqs) > 2 else eqs)


def compiled(eq_pair):
    return CompiledSystem(system(list(eq_pair)))


PAIRS = [(EQUATIONS[0], EQUATIONS[1]), (EQUATIONS[2], EQUATIONS[3])]


@pytest.mark.parametrize("k", [0, 1])
@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.1, 0.9),
    st.floats(0.1, 0.9),
    st.sampled_from([0.0, 1e-9, 1e-3, 0.2]),
    st.floats(0, 1),
    st.floats(0, 1),
)
def test_f_and_jacobian_enclose_exact_values(k, a, b, w, s, t):
    csys = compiled(PAIRS[k])
    lo = np.array([max(0.1, a - w), max(0.1, b - w)])
    hi = np.array([min(0.9, a + w), min(0.9, b + w)])
    pt = lo + np.array([s, t]) * (hi - lo)
    pt = np.clip(pt, lo, hi)
    nodes_f = [int(v) for v in csys.f.global_ids[csys.f.outputs]]
    nodes_j = [int(v) for v in csys.fj.global_ids[csys.fj.outputs]][csys.n :]
    ef = iv_eval(csys, nodes_f, pt, pt, CTX)
    ej = iv_eval(csys, nodes_j, pt, pt, CTX)
    rows, cols = np.nonzero(csys.jac_structure)
    # batched and per-box code, over the box; and the point enclosures
    flo, fhi, jlo, jhi = csys.eval_fj(lo[None], hi[None])
    slo, shi, sjlo, sjhi = csys.fj_box(lo, hi)
    plo, phi = csys.f_point(pt)
    for i, e in enumerate(ef):
        for lo_, hi_ in ((flo[0, i], fhi[0, i]), (slo[i], shi[i]), (plo[i], phi[i])):
            assert lo_ <= e.a and e.b <= hi_
    for (r, c), e in zip(zip(rows, cols), ej):
        assert jlo[0, r, c] <= e.a and e.b <= jhi[0, r, c]
        assert sjlo[r, c] <= e.a and e.b <= sjhi[r, c]
    # float evaluation (Newton points) agrees with the exact values
    fv = csys.eval_f_float(pt[None])[0]
    for i, e in enumerate(ef):
        assert abs(fv[i] - float(e.mid)) <= 1e-9 * (1 + abs(float(e.mid)))


@pytest.mark.parametrize("k", [0, 1])
@settings(max_examples=40, deadline=None)
@given(st.floats(0.1, 0.9), st.floats(0.1, 0.9), st.floats(0, 0.3), st.floats(0, 0.3))
def test_hc4_keeps_the_zero(k, a, b, wa, wb):
    """Shift the equations so that (a, b) is a zero: HC4 never removes it."""
    pt = np.array([a, b])
    base = compiled(PAIRS[k])
    v = base.eval_f_float(pt[None])[0]
    vlo, vhi = base.f_point(pt)
    eqs = [e - const(float(lo_), float(hi_)) for e, lo_, hi_ in zip(PAIRS[k], vlo, vhi)]
    assert np.all(np.isfinite(v))
    csys = CompiledSystem(system(eqs))
    lo = np.array([[max(0.1, a - wa), max(0.1, b - wb)]])
    hi = np.array([[min(0.9, a + wa), min(0.9, b + wb)]])
    nlo, nhi, empty = csys.hc4_revise(lo, hi)
    assert not empty[0]
    assert np.all(nlo[0] <= pt) and np.all(pt <= nhi[0])


TRIG = [N.sin(x) + N.cos(2 * y), N.cos(x) * N.sin(y) - N.sin(x - y)]


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-20, 20),
    st.floats(-20, 20),
    st.floats(0, 4),
    st.floats(0, 4),
    st.floats(0, 1),
    st.floats(0, 1),
)
def test_hc4_through_sin_and_cos_keeps_the_zero(a, b, wa, wb, s, t):
    """sin and cos are inverted over up to two monotone branches: a zero anywhere in a box
    of width up to 4 (about 1.3 periods) is never removed."""
    dom = ((a - wa, a + wa), (b - wb, b + wb))
    pt = np.array([dom[0][0] + s * 2 * wa, dom[1][0] + t * 2 * wb])
    pt = np.clip(pt, [dom[0][0], dom[1][0]], [dom[0][1], dom[1][1]])  # rounding
    base = CompiledSystem(system(TRIG, dom))
    vlo, vhi = base.f_point(pt)
    eqs = [e - const(float(lo_), float(hi_)) for e, lo_, hi_ in zip(TRIG, vlo, vhi)]
    csys = CompiledSystem(system(eqs, dom))
    lo, hi = np.array(dom).T[None, 0], np.array(dom).T[None, 1]
    for _ in range(3):
        lo, hi, empty = csys.hc4_revise(lo, hi)
        assert not empty[0]
        assert np.all(lo[0] <= pt) and np.all(pt <= hi[0])


def test_hc4_inverts_sin_near_a_pole():
    """IBEX's AOL-legentil: y within 8e-9 of the pole asin(0.7) of 1/(3.5 - 5 sin y); the
    equation pins ``sin y`` and so ``y``, on one side of the pole (it once stayed put)."""
    sys_ = System(
        ["y"],
        np.array([[0.7753974918039738, 0.7753974997037314]]),
        [1 / (3.5 - 5 * N.sin(var("y"))) - 1e9],
    )
    lo, hi, empty = CompiledSystem(sys_).hc4_revise(
        sys_.domain[None, :, 0], sys_.domain[None, :, 1]
    )
    assert not empty[0]
    assert hi[0, 0] - lo[0, 0] < 1e-12
    assert hi[0, 0] < np.arcsin(0.7)  # 3.5 - 5 sin y = 1e-9 > 0


NOT_SMOOTH = {
    # expression of x, box where it is not smooth somewhere, box where it is
    "tan": (N.tan(x), (1.5, 1.6), (1.4, 1.5)),
    "asin": (N.asin(x), (0.5, 1.0), (0.5, 0.99)),
    "acos": (N.acos(x), (-1.0, 0.0), (-0.9, 0.0)),
    "atanh": (N.atanh(x), (0.5, 1.0), (0.5, 0.9)),
    "acosh": (N.acosh(x), (1.0, 2.0), (1.01, 2.0)),
    "log": (N.log(x), (0.0, 1.0), (0.1, 1.0)),
    "rpow": (N.rpow(x, const(0.5)), (0.0, 1.0), (0.1, 1.0)),
    "atan2": (N.atan2(x - 1.0, var("y")), (0.5, 1.5), (1.1, 1.5)),
    "sign": (N.sign(x), (-1.0, 1.0), (0.5, 1.0)),
    "abs": (N.abs_(x), (-1.0, 1.0), (0.5, 1.0)),
    "min": (N.min_(x, 1 - x), (0.0, 1.0), (0.0, 0.4)),
    "max": (N.max_(x, 1 - x), (0.0, 1.0), (0.6, 1.0)),
    "div": (1 / x, (-1.0, 1.0), (0.5, 1.0)),
}


@pytest.mark.parametrize("name", list(NOT_SMOOTH))
def test_krawczyk_only_where_smooth(name):
    e, bad, good = NOT_SMOOTH[name]
    sys_ = System(["x", "y"], np.array([[-3.0, 3.0], [-3.0, 3.0]]), [e, var("y") - 0.25])
    csys = CompiledSystem(sys_)
    lo = np.array([[bad[0], -1.0], [good[0], -1.0]])
    hi = np.array([[bad[1], -0.5], [good[1], -0.5]])
    *_, defined = csys.eval_fj(lo, hi, check_domain=True)
    assert not defined[0] and defined[1]


def test_tan_box_with_a_pole_is_unbounded_and_not_certified():
    csys = CompiledSystem(System(["x"], np.array([[1.0, 2.0]]), [N.tan(x) - 1.0]))
    flo, fhi, _, _, defined = csys.eval_fj(np.array([[1.0]]), np.array([[2.0]]), check_domain=True)
    assert flo[0, 0] == -np.inf and fhi[0, 0] == np.inf and not defined[0]
