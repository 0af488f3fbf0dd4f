"""Affine forms (``certsolve.expr.affine``) and their relaxation rows enclose the true values.

At random points of random boxes (narrow, wide, huge; points drawn inside and at corners),
the exact value of every equation (mpmath interval arithmetic at 100 bits, at the point)
lies in ``c₀ + c·(x - m) ± e``, that expression itself evaluated in mpmath.  The rows built
from the forms hold at every reference solution, and on quadratic systems they prune boxes
the X-Taylor rows keep.
"""

from pathlib import Path

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_solver_contractors import NAMES, REFERENCE

from certsolve.expr import (
    System,
    abs_,
    acos,
    acosh,
    asin,
    asinh,
    atan,
    atan2,
    atanh,
    cos,
    cosh,
    exp,
    log,
    max_,
    min_,
    rpow,
    sin,
    sinh,
    sqr,
    sqrt,
    tan,
    tanh,
    var,
)
from certsolve.expr.affine import affine_forms
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.solver import Solver
from certsolve.solver.pipeline import find
from certsolve.solver.relaxation import PolytopeHull, affine_rows
from certsolve.solver.verify import iv_eval

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"
CTX = mpmath.iv
CTX.prec = 100


def _mixed_system() -> System:
    """Every rule of the forms: sums, scalings, shifts, products, squares, interval
    constants, and operations without a rule (division, cube, exp, cos)."""
    x, y, z = var("x"), var("y"), var("z")
    return System(
        ["x", "y", "z"],
        np.array([[-1e3, 1e3]] * 3),
        [
            x * y - sqr(x) + 3.0 * y - 0.1 * z,
            sqr(x - 1.1) + sqr(y + 0.3) * z - 2.0,
            x / (sqr(y) + 1.0) + z**3 + exp(0.001 * x) * cos(y) - x * (y * z),
        ],
    )


def _elementary_system() -> System:
    """Every elementary function with the mean-value rule, on a domain where the boxes
    also reach outside some of their domains (log, sqrt, asin, acos, atanh, acosh)."""
    x, y, z = var("x"), var("y"), var("z")
    return System(
        ["x", "y", "z"],
        np.array([[-0.2, 1.2], [-1.1, 1.1], [-0.5, 3.0]]),
        [
            sqrt(z) * log(z) + tan(y) - atan(x * z) + sin(x + y) * abs_(y),
            asin(y) + acos(x) * sinh(y) - cosh(x) + tanh(z * y) + atanh(0.5 * x * y),
            z**-2 + x**5 - 1.0 / (x + y + 2.5) + asinh(y) * acosh(z + 1.2) + exp(-x * z),
        ],
    )


def _check(csys, lo, hi, x):
    F = affine_forms(csys.f, lo[None], hi[None], csys.param_lo, csys.param_hi)
    nodes = [int(v) for v in csys.f.global_ids[csys.f.outputs]]
    for i, node in enumerate(nodes):
        if not (np.isfinite(F.c0[0, i]) and np.isfinite(F.e[0, i])):
            continue  # a form that is not finite is never used
        try:
            (ex,) = iv_eval(csys, [node], x, x, CTX)
        except (ValueError, ZeroDivisionError):
            continue  # f_i is not defined at x: no zero there to keep
        if not (mpmath.isfinite(ex.a) and mpmath.isfinite(ex.b)):
            continue
        lin = CTX.mpf(F.c0[0, i])
        for j in range(csys.n):
            lin += CTX.mpf(F.c[0, i, j]) * (CTX.mpf(x[j]) - CTX.mpf(F.mid[0, j]))
        e = CTX.mpf(F.e[0, i])
        assert (lin - e).a <= ex.a and ex.b <= (lin + e).b, (i, x, lo, hi)


@pytest.mark.parametrize(
    "name", ["kin2-6r", "katsura-5", "trig-exp", "eco-6", "mixed", "elementary"]
)
@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_affine_forms_enclose_exact_values(name, data):
    if name in ("mixed", "elementary"):
        system = _mixed_system() if name == "mixed" else _elementary_system()
    else:
        system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    dom = system.domain
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    a = rng.uniform(dom[:, 0], dom[:, 1])
    w = data.draw(st.sampled_from([1e-9, 1e-3, 0.1, 0.5, 10.0, 1e3]))
    lo = np.maximum(a - w * rng.random(csys.n), dom[:, 0])
    hi = np.minimum(lo + w, dom[:, 1])
    corner = data.draw(st.booleans())
    x = np.where(rng.random(csys.n) < 0.5, lo, hi) if corner else rng.uniform(lo, hi)
    _check(csys, lo, hi, x)


def test_affine_rows_hold_at_every_solution():
    """Every reference solution in a box satisfies the box's affine rows (rigorously)."""
    for name in NAMES:
        csys = CompiledSystem(load_minibex(SYSTEMS / f"{name}.mbx"))
        rng = np.random.default_rng(7)
        for s in REFERENCE[name]["solutions"]:
            p = np.array([float(v) for v in s])
            w = 10.0 ** rng.uniform(-6, 0.5, (20, csys.n))
            lo = p - w * rng.random((20, csys.n))
            hi = lo + w
            G, rho = affine_rows(csys, lo, hi)
            ok = np.any(G != 0.0, axis=(1, 2))
            assert ok.any()
            d = p - lo
            viol = np.einsum("bmn,bn->bm", G, d) - rho
            mag = np.einsum("bmn,bn->bm", np.abs(G), np.abs(d)) + np.abs(rho)
            assert np.all(viol[ok] <= 1e-12 * mag[ok])


def test_forms_that_are_not_finite_give_empty_rows():
    """An unbounded box (every form infinite) and a box where a logarithm's argument
    reaches 0 (that equation's form only): rows ``0 <= 0``, the others kept."""
    csys = CompiledSystem(load_minibex(SYSTEMS / "katsura-5.mbx"))
    lo = np.full((2, csys.n), -1.0)
    hi = np.full((2, csys.n), 1.0)
    hi[0, 2] = np.inf
    G, rho = affine_rows(csys, lo, hi)
    assert not G[0].any() and not rho[0].any()
    assert np.all(np.isfinite(rho[1])) and G[1].any()
    x, y = var("x"), var("y")
    system = System(["x", "y"], np.array([[-1.0, 2.0]] * 2), [log(x) + y, x * y - 1.0])
    G, rho = affine_rows(CompiledSystem(system), np.array([[-1.0, -1.0]]), np.array([[2.0, 2.0]]))
    assert not G[0, [0, 2]].any() and G[0, [1, 3]].any()


@pytest.mark.parametrize("name", ["katsura-5", "kin2-6r"])
def test_affine_rows_prune_quadratic_systems(name):
    """Katsura and the 6R inverse kinematics are all products and squares: with the affine
    rows beside X-Taylor's the search needs far fewer boxes, and finds the same solutions."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    runs = {}
    for affine in (False, True):
        solver = Solver.default(system)
        find(solver.contractor, PolytopeHull).affine = affine
        runs[affine] = solver.solve(workers=1)
    assert runs[True].status == runs[False].status == "complete"
    expected = len(REFERENCE[name]["solutions"])
    assert len(runs[True].solutions) == len(runs[False].solutions) == expected
    assert runs[True].stats.boxes < 0.7 * runs[False].stats.boxes


@pytest.mark.parametrize("op", ["max", "min", "abs", "atan2", "rpow", "div", "exp"])
def test_unbounded_boxes_never_give_finite_wrong_forms(op):
    """In a box with infinite sides, ``0·inf`` makes radii NaN; no rule and no interval
    function may turn that into a finite form: every form is either not finite or holds
    at sample points of the box."""
    x, y = var("x"), var("y")
    expr = {
        "max": max_(x, 1.0) - y,
        "min": min_(x, y) + 2.0,
        "abs": abs_(x) - y,
        "atan2": atan2(y, x) - 1.0,
        "rpow": rpow(x, y) - 2.0,
        "div": x / (y + 3.0) - 1.0,
        "exp": exp(x) * y - 1.0,
    }[op]
    system = System(["x", "y"], np.array([[-np.inf, np.inf]] * 2), [expr, x - 2.0 * y])
    csys = CompiledSystem(system)
    inf = np.inf
    boxes = [([-inf, -inf], [inf, inf]), ([0.5, -inf], [inf, 3.0]), ([0.5, 1.0], [2.0, inf])]
    rng = np.random.default_rng(3)
    for lo, hi in boxes:
        lo, hi = np.array(lo), np.array(hi)
        F = affine_forms(csys.f, lo[None], hi[None])
        assert not (np.isfinite(F.c0[0, 0]) and np.isfinite(F.e[0, 0]))
        for _ in range(5):
            x0 = np.clip(rng.normal(scale=5.0, size=2), lo, hi)
            _check(csys, lo, hi, x0)
