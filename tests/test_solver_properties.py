"""Soundness of the solver's parts on systems whose solutions are known by construction.

* HC4 and interval Newton never remove a solution.
* Krawczyk never certifies a box that holds zero or two solutions.
* The whole solver finds every solution of systems with an exactly known solution set, each
  in exactly one certified box.
"""

import itertools

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr import CompiledSystem, System, const, esum, sqr, var
from certsolve.solver import solve
from certsolve.solver.contractors import HC4, IntervalNewton
from certsolve.solver.newton import KrawczykPoint, krawczyk, linearize

mpmath.mp.dps = 50


def _poly_terms(rng, xs, n_terms):
    """A random polynomial in the variables xs (sum of monomials with small coefficients)."""
    terms = []
    for _ in range(n_terms):
        c = float(rng.integers(-4, 5)) / 2 or 0.5
        e = rng.integers(0, 3, len(xs))
        mono = c
        for x, k in zip(xs, e, strict=True):
            if k == 1:
                mono = mono * x
            elif k == 2:
                mono = mono * sqr(x)
        terms.append(mono)
    return terms


def _value_enclosure(terms_fn, point):
    """[lo, hi] floats enclosing the exact value (mpmath, 50 digits) of the polynomial."""
    v = terms_fn(point)
    return float(mpmath.mpf(v) - mpmath.mpf("1e-30")), float(mpmath.mpf(v) + mpmath.mpf("1e-30"))


def random_system_through(seed, n=3):
    """A square system f_i(x) = p_i(x) - [c_i] with [c_i] ∋ p_i(x*): x* is a solution."""
    rng = np.random.default_rng(seed)
    names = [f"x{i}" for i in range(n)]
    xs = [var(v) for v in names]
    xstar = rng.uniform(-1.5, 1.5, n)
    eqs = []
    for _ in range(n):
        coef = rng.integers(-3, 4, size=(4, n))
        consts = rng.integers(-3, 4, size=4) / 2
        terms = []
        for t in range(4):
            mono = float(consts[t]) or 0.5
            for x, k in zip(xs, coef[t], strict=True):
                k = abs(int(k)) % 3
                if k == 1:
                    mono = mono * x
                elif k == 2:
                    mono = mono * sqr(x)
            terms.append(mono)

        def exact(p, coef=coef, consts=consts):
            tot = mpmath.mpf(0)
            for t in range(4):
                m = mpmath.mpf(float(consts[t]) or 0.5)
                for xi, k in zip(p, coef[t], strict=True):
                    m *= mpmath.mpf(float(xi)) ** (abs(int(k)) % 3)
                tot += m
            return tot

        val = exact(xstar)
        lo = float(mpmath.mpf(val) - mpmath.mpf("1e-25"))
        hi = float(mpmath.mpf(val) + mpmath.mpf("1e-25"))
        lo = float(np.nextafter(lo, -np.inf))
        hi = float(np.nextafter(hi, np.inf))
        eqs.append(esum(terms) - const(lo, hi))
    system = System(names, np.array([[-2.0, 2.0]] * n), eqs)
    return system, xstar


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.lists(st.floats(0.01, 1.5), min_size=3, max_size=3))
def test_hc4_and_newton_never_remove_a_solution(seed, radii):
    system, xstar = random_system_through(seed)
    csys = CompiledSystem(system)
    rng = np.random.default_rng(seed + 1)
    r = np.array(radii)
    off = rng.uniform(-1, 1, 3) * r  # the solution anywhere inside the box
    lo = (xstar - r + off)[None]
    hi = (xstar + r + off)[None]
    lo, hi = np.minimum(lo, xstar), np.maximum(hi, xstar)
    nlo, nhi, empty = HC4(csys).contract(lo, hi)
    assert not empty[0]
    assert np.all(nlo[0] <= xstar) and np.all(xstar <= nhi[0])
    step = IntervalNewton(csys).contract(nlo, nhi)
    assert not step.empty[0]
    assert np.all(step.lo[0] <= xstar) and np.all(xstar <= step.hi[0])


# -- systems with exactly known, finite solution sets -------------------------------------------

# roots that are exact binary floats, so the solution set is known exactly
ROOTS = [[-1.5, 0.25, 1.0], [-0.75, 0.5], [-1.25, 0.125, 0.875]]


def product_system(mix: bool):
    """f_i(y) = Π_k (y_i - r_ik) with y = A x, A an integer matrix with det ±1 (so the
    solutions x = A^-1 y are exact too); ``mix=False`` keeps A = I."""
    n = 3
    A = np.array([[1, 1, 0], [0, 1, 1], [0, 0, 1]]) if mix else np.eye(3, dtype=int)
    names = ["x0", "x1", "x2"]
    xs = [var(v) for v in names]
    ys = [esum(float(A[i, j]) * xs[j] for j in range(n) if A[i, j]) for i in range(n)]
    eqs = []
    for i in range(n):
        e = ys[i] - ROOTS[i][0]
        for r in ROOTS[i][1:]:
            e = e * (ys[i] - r)
        eqs.append(e)
    Ainv = np.round(np.linalg.inv(A)).astype(int)
    sols = [Ainv @ np.array(c) for c in itertools.product(*ROOTS)]
    return System(names, np.array([[-4.0, 4.0]] * n), eqs), np.array(sols, dtype=float)


@pytest.mark.parametrize("mix", [False, True])
def test_solver_finds_exactly_the_known_solutions(mix):
    system, sols = product_system(mix)
    res = solve(system, eps=1e-10)
    assert res.status == "complete"
    assert len(res.undecided) == 0
    assert len(res.solutions) == len(sols) == 18
    for s in res.solutions:
        inside = [np.all((s.lo <= x) & (x <= s.hi)) for x in sols]
        assert sum(inside) == 1  # each box holds exactly one known solution
    for x in sols:
        assert sum(np.all((s.lo <= x) & (x <= s.hi)) for s in res.solutions) == 1


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    st.lists(st.floats(0.001, 2.0), min_size=3, max_size=3),
    st.booleans(),
)
def test_krawczyk_never_certifies_zero_or_two_solutions(centre, radii, mix):
    system, sols = product_system(mix)
    csys = CompiledSystem(system)
    c, r = np.array(centre), np.array(radii)
    lo, hi = (c - r)[None], (c + r)[None]
    _, _, proven = krawczyk(linearize(csys, lo, hi))
    inside = int(np.sum(np.all((sols >= lo) & (sols <= hi), axis=1)))
    if proven[0]:
        assert inside == 1


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    st.lists(st.floats(0.001, 2.0), min_size=3, max_size=3),
    st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3),
    st.booleans(),
)
def test_krawczyk_about_any_centre_never_certifies_zero_or_two(centre, radii, where, mix):
    """:class:`KrawczykPoint` (tracking): centre anywhere in X, J over X, then reused on
    ``K(X) ∩ X`` -- a proof always means exactly one solution, and it lies in ``K``."""
    system, sols = product_system(mix)
    csys = CompiledSystem(system)
    lo, hi = np.array(centre) - np.array(radii), np.array(centre) + np.array(radii)
    c = lo + np.array(where) * (hi - lo)
    flo, fhi = csys.f_point(c)
    _, _, jlo, jhi = csys.fj_box(lo, hi)
    kp = KrawczykPoint(c, flo, fhi, jlo, jhi)
    for _ in range(3):
        klo, khi, proven = kp.image(lo, hi)
        inside = np.all((sols >= lo) & (sols <= hi), axis=1)
        if proven:
            assert int(np.sum(inside)) == 1
            assert np.all((klo <= sols[inside][0]) & (sols[inside][0] <= khi))
            break
        # every solution of X is in K(X) ∩ X: the next test is on that box
        in_k = np.all((sols >= klo) & (sols <= khi), axis=1)
        assert np.all(in_k[inside])
        lo, hi = np.fmax(lo, klo), np.fmin(hi, khi)
        if np.any(lo > hi):
            assert not np.any(inside)
            break


def test_krawczyk_certifies_small_boxes_around_simple_roots():
    """The test is not vacuous: it does prove small boxes around each root."""
    system, sols = product_system(True)
    csys = CompiledSystem(system)
    lin = linearize(csys, sols - 1e-3, sols + 1e-3)
    assert np.all(krawczyk(lin)[2])


def test_double_root_is_never_certified():
    x, y = var("x"), var("y")
    system = System(
        ["x", "y"], np.array([[-2.0, 2.0], [-2.0, 2.0]]), [sqr(x) + sqr(y) - 1.0, y - 1.0]
    )  # tangent: (0, 1) is a double root
    res = solve(system, eps=1e-9)
    assert res.status == "complete"
    assert res.solutions == []
    assert res.undecided and all(u.reason == "eps" for u in res.undecided)
    hull_lo = np.min([u.lo for u in res.undecided], axis=0)
    hull_hi = np.max([u.hi for u in res.undecided], axis=0)
    assert np.all(hull_lo <= [0.0, 1.0]) and np.all([0.0, 1.0] <= hull_hi)


def test_limits_report_pending_boxes_and_the_limit_as_status():
    system, sols = product_system(True)
    res = solve(system, max_boxes=5)
    assert res.status == "max_boxes" and res.stats.stopped_by == "max_boxes"
    assert len(res.pending) > 0
    # nothing is lost: every known solution is in a certified, undecided or pending box
    boxes = [(s.lo, s.hi) for s in res.solutions] + [(u.lo, u.hi) for u in res.undecided]
    boxes += list(zip(res.pending_lo, res.pending_hi, strict=True))
    for x in sols:
        assert any(np.all((a <= x) & (x <= b)) for a, b in boxes)


def test_progress_callback_can_cancel():
    system, _ = product_system(True)
    seen = []

    def progress(p):
        seen.append(p.boxes)
        return len(seen) < 3

    res = solve(system, progress=progress)
    assert res.stats.stopped_by == "cancelled" and res.status == "cancelled"
    assert len(seen) == 3


@pytest.mark.parametrize("warmup", [0.0, 30.0])
def test_parallel_workers_find_the_same_solutions(warmup):
    """With no serial warm-up every box goes through the workers; with the default one
    this small system is done before they are needed (and says so)."""
    from certsolve.solver import ProcessExecutor

    system, sols = product_system(True)
    serial = solve(system)
    par = solve(system, executor=ProcessExecutor(2, warmup=warmup, grow=0))
    assert par.stats.workers == (2 if warmup == 0.0 else 1)
    assert (par.stats.tasks > 0) == (warmup == 0.0)
    assert par.status == serial.status == "complete"
    assert len(par.solutions) == len(serial.solutions) == len(sols)
    for s in serial.solutions:
        assert (
            sum(np.all((p.ulo <= s.midpoint) & (s.midpoint <= p.uhi)) for p in par.solutions) == 1
        )


def test_verify_reproves_with_mpmath():
    system, _ = product_system(True)
    res = solve(system, verify=True)
    assert res.solutions and all(s.verified is True for s in res.solutions)


def test_result_serialises_to_json():
    import json

    system, _ = product_system(False)
    d = solve(system).to_dict()
    text = json.dumps(d, allow_nan=False)
    back = json.loads(text)
    assert back["status"] == "complete" and len(back["solutions"]) == 18
    assert {"box", "certificate", "midpoint"} <= set(back["solutions"][0])
