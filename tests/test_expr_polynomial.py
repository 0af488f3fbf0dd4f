"""Exact polynomial expansion and the degree-lowering equivalent system.

The expansion must enclose the expression for every value its interval constants allow,
the replaced equations must enclose the exact combination they stand for, the combination
matrix must be nonsingular, and the solver must find the same solutions on both systems.
"""

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr import System, const, exp, param, sqr, var
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.expr.node import Expr
from certsolve.expr.polynomial import degree_reductions, expand, reduce_degree
from certsolve.solver import Solver

ROOT = Path(__file__).resolve().parent.parent
DIETMAIER = ROOT / "benchmarks" / "systems" / "dietmaier.mbx"


def _exact(e: Expr, x: dict[str, Fraction], pick: int) -> Fraction:
    """``e`` at ``x`` in exact rationals, each interval constant at its end ``pick``."""
    op, a = e.op, e.args
    if op == "var":
        return x[e.param]
    if op == "const":
        return Fraction(e.param[pick])
    v = [_exact(c, x, pick) for c in a]
    if op == "add":
        return v[0] + v[1]
    if op == "sub":
        return v[0] - v[1]
    if op == "mul":
        return v[0] * v[1]
    if op == "div":
        return v[0] / v[1]
    if op == "neg":
        return -v[0]
    if op == "sqr":
        return v[0] * v[0]
    if op == "pow":
        return v[0] ** e.param
    raise AssertionError(op)


def _value(p, names, x) -> tuple[Fraction, Fraction]:
    lo = hi = Fraction(0)
    for m, (clo, chi) in p.items():
        mono = Fraction(1)
        for v, k in zip(names, m, strict=True):
            mono *= x[v] ** k
        lo += min(clo * mono, chi * mono)
        hi += max(clo * mono, chi * mono)
    return lo, hi


_X, _Y, _Z = var("x"), var("y"), var("z")
_LEAVES = [_X, _Y, _Z, const(0.1, 0.1 + 2**-55), const(-3.0), const(2.5, 2.75)]


@st.composite
def _polynomials(draw, depth=3):
    if depth == 0 or draw(st.integers(0, 3)) == 0:
        return draw(st.sampled_from(_LEAVES))
    op = draw(st.sampled_from(["add", "sub", "mul", "neg", "sqr", "pow", "div"]))
    a = draw(_polynomials(depth - 1))
    if op in ("neg", "sqr"):
        return Expr(op, (a,))
    if op == "pow":
        return Expr("pow", (a,), draw(st.integers(0, 3)))
    if op == "div":
        return a / draw(st.sampled_from([const(3.0), const(-0.7, -0.5)]))
    return Expr(op, (a, draw(_polynomials(depth - 1))))


@settings(max_examples=200, deadline=None)
@given(
    e=_polynomials(),
    xs=st.lists(st.fractions(-5, 5, max_denominator=64), min_size=3, max_size=3),
    pick=st.sampled_from([0, 1]),
)
def test_expansion_encloses_the_expression(e, xs, pick):
    names = ["x", "y", "z"]
    p = expand(e, names)
    assert p is not None
    x = dict(zip(names, xs, strict=True))
    lo, hi = _value(p, names, x)
    assert lo <= _exact(e, x, pick) <= hi


def test_expansion_is_exact_for_point_constants():
    p = expand(sqr(_X - 1.5) * (_Y + 2) - _X / 4, ["x", "y"])
    assert p == {
        (2, 1): (1, 1),
        (2, 0): (2, 2),
        (1, 1): (-3, -3),
        (1, 0): (Fraction(-25, 4), Fraction(-25, 4)),
        (0, 1): (Fraction(9, 4), Fraction(9, 4)),
        (0, 0): (Fraction(9, 2), Fraction(9, 2)),
    }


@pytest.mark.parametrize(
    "e",
    [exp(_X), _X / _Y, _X * param("p"), _X + const(0.0, np.inf), Expr("pow", (_X,), -1)],
)
def test_what_is_not_a_polynomial_is_left_alone(e):
    assert expand(e, ["x", "y"]) is None


def _spheres() -> System:
    """Three spheres through two points: every pairwise difference is a plane."""
    c = [(0.0, 0.0, 0.0), (2.0, 0.1, 0.0), (0.3, 1.7, 0.2)]
    p = np.array([0.7, 0.4, 0.9])
    eqs = [
        sqr(_X - a) + sqr(_Y - b) + sqr(_Z - d) - float(np.sum((p - (a, b, d)) ** 2))
        for a, b, d in c
    ]
    return System.build({v: (-5, 5) for v in "xyz"}, eqs)


def _cubics() -> System:
    """Two cubics with the same leading part: their difference is a quadratic."""
    eqs = [_X**3 + 2 * _X * _Y + sqr(_Y) - 1, _X**3 + 2 * _X * _Y - _Y + const(0.1, 0.1 + 2**-55)]
    return System.build({"x": (-3, 3), "y": (-3, 3)}, eqs)


def _check_replaced(system, reduced, samples=20, seed=0):
    """Each replaced equation encloses its exact combination, which is nonsingular."""
    red = degree_reductions(system)
    assert set(red) == {
        k for k, (a, b) in enumerate(zip(system.equations, reduced.equations)) if a is not b
    }
    rows = sorted(red)
    T = [[red[r].get(c, Fraction(0)) for c in rows] for r in rows]
    assert np.linalg.matrix_rank(np.array(T, dtype=float)) == len(rows)
    csys = CompiledSystem(reduced)
    rng = np.random.default_rng(seed)
    for _ in range(samples):
        xf = rng.uniform(system.domain[:, 0], system.domain[:, 1])
        flo, fhi = csys.eval_f(xf[None], xf[None])
        x = {v: Fraction(float(t)) for v, t in zip(system.variables, xf, strict=True)}
        for k in rows:
            for pick in (0, 1):
                exact = sum(t * _exact(system.equations[j], x, pick) for j, t in red[k].items())
                assert Fraction(float(flo[0, k])) <= exact <= Fraction(float(fhi[0, k]))
    return red


def test_sphere_differences_become_planes():
    system = _spheres()
    reduced = reduce_degree(system)
    red = _check_replaced(system, reduced)
    assert len(red) == 2
    for k in red:
        p = expand(reduced.equations[k], system.variables)
        assert max(sum(m) for m in p) == 1


def test_a_lower_degree_level_is_found_too():
    system = _cubics()
    reduced = reduce_degree(system)
    red = _check_replaced(system, reduced)
    assert len(red) == 1
    (k,) = red
    assert max(sum(m) for m in expand(reduced.equations[k], system.variables)) == 2


def test_dietmaier_has_two_linear_combinations():
    system = load_minibex(DIETMAIER)
    reduced = reduce_degree(system)
    red = _check_replaced(system, reduced)
    assert len(red) == 2
    for k in red:  # quadratic terms left only as the constants' uncertainty
        p = expand(reduced.equations[k], system.variables)
        for m, (lo, hi) in p.items():
            assert sum(m) <= 1 or (lo <= 0 <= hi and hi - lo < 1e-12)


def test_nothing_to_lower_returns_the_system():
    system = load_minibex(ROOT / "examples" / "systems" / "katsura-5.mbx")
    assert reduce_degree(system) is system


def test_coefficients_beyond_the_float_range_leave_the_system_as_given():
    """An expansion (1e400 x) or a combination (f2 - 1e600 f1) beyond the float range
    cannot be written as a float expression: the system is searched as given."""
    dom = {"x": (-3, 3), "y": (-3, 3)}
    tiny, huge = const(1e-300) * const(1e-300), const(1e200) * const(1e200)
    circle = sqr(_X) + sqr(_Y) + _Y - 2
    for first in (tiny * (sqr(_X) + sqr(_Y)) - 1, huge * _X + sqr(_X) + sqr(_Y)):
        system = System.build(dom, [first, circle])
        assert reduce_degree(system) is system
        assert Solver.default(system).csys.system is system


@pytest.mark.parametrize("build, count", [(_spheres, 2), (_cubics, None)])
def test_solver_finds_the_same_solutions_on_the_lowered_system(build, count):
    system = build()
    results = {}
    for reduce in (True, False):
        solver = Solver.default(system, reduce_degree=reduce)
        assert (solver.csys.system is not system) == reduce
        res = solver.solve(verify=True)
        assert res.status == "complete" and not res.undecided
        assert all(s.certificate == "unique" and s.verified for s in res.solutions)
        results[reduce] = sorted(tuple(np.round(s.midpoint, 9)) for s in res.solutions)
    assert results[True] == results[False] and results[True]
    if count is not None:
        assert len(results[True]) == count
        assert any(np.allclose(r, [0.7, 0.4, 0.9]) for r in results[True])


def test_expand_walks_a_deep_chain_without_recursion():
    """A sum of thousands of terms is a chain that deep (IBEX's Yamamura1-0400 raised
    RecursionError): the walk is iterative, and the coefficients are exact."""
    x = var("x")
    e = x
    for i in range(5000):
        e = e + x * x if i % 2 else e - x
    p = expand(e, ["x"])
    assert p == {(1,): (Fraction(-2499), Fraction(-2499)), (2,): (Fraction(2500), Fraction(2500))}
