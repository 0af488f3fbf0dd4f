"""New contractors never lose a solution: partial Newton, mixed-Jacobian Newton and CID
(on one variable, and the solver's CID on several variables before a bisection).

Soundness is checked against the independent reference solutions of the Minibex systems
(``tests/reference/reference.json``): for random boxes around each reference point (and
random boxes anywhere), a contracted box must still hold every reference point it held,
and a box proven empty must have held none.  Reference points are compared with the float
bounds widened by a few ulps (they are given to 40 digits).
"""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex, parse_minibex
from certsolve.solver import Solver, solve
from certsolve.solver.bisectors import smear_scores
from certsolve.solver.contractors import HC4, IntervalNewton, PartialNewton, log_volume_ratio
from certsolve.solver.pipeline import find
from certsolve.solver.search import run_search
from certsolve.solver.shaving import CID, AdaptiveCount, Shave

ROOT = Path(__file__).resolve().parent.parent
SYSTEMS = ROOT / "examples" / "systems"
REFERENCE = json.loads((Path(__file__).parent / "reference" / "reference.json").read_text())
NAMES = ["circle-line", "brown-5", "trig-exp", "eco-6", "kin2-6r"]
ULPS = 4


@cache
def compiled(name: str):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
    return CompiledSystem(system), pts


def holds(lo, hi, p) -> bool:
    """``p`` in ``[lo, hi]`` widened by a few ulps per side."""
    a = np.array([v - ULPS * math.ulp(v) for v in lo])
    b = np.array([v + ULPS * math.ulp(v) for v in hi])
    return bool(np.all((a <= p) & (p <= b)))


def random_boxes(pts, dom, rng, count=300):
    """Boxes around reference points (various widths and offsets) and anywhere."""
    n = pts.shape[1]
    span = np.minimum(dom[:, 1] - dom[:, 0], 20.0)
    out_lo, out_hi = [], []
    for _ in range(count):
        w = span * 10.0 ** rng.uniform(-4, -0.5, n)
        if rng.random() < 0.8 and len(pts):
            c = pts[rng.integers(len(pts))]
            lo = c - w * rng.random(n)
        else:
            lo = dom[:, 0] + (dom[:, 1] - dom[:, 0] - w) * rng.random(n)
        lo = np.maximum(lo, dom[:, 0])
        hi = np.minimum(lo + w, dom[:, 1])
        out_lo.append(lo)
        out_hi.append(hi)
    return np.array(out_lo), np.array(out_hi)


def check_contractor(name, contract, seed=0):
    csys, pts = compiled(name)
    rng = np.random.default_rng(seed)
    lo, hi = random_boxes(pts, csys.system.domain, rng)
    nlo, nhi, empty = contract(csys, lo, hi)
    kept = 0
    for k in range(lo.shape[0]):
        for p in pts:
            if holds(lo[k], hi[k], p) and np.all((lo[k] < p) & (p < hi[k])):
                assert not empty[k], f"box {k} holds a solution but was declared empty"
                assert holds(nlo[k], nhi[k], p), f"box {k} lost solution {p}"
                kept += 1
    assert kept > 50  # the test exercised boxes with solutions
    assert np.all(nlo >= lo) and np.all(nhi <= hi)  # contraction only


def _partition(n, rng):
    perm = rng.permutation(n)
    cuts = sorted(rng.choice(np.arange(1, n), size=min(2, n - 1), replace=False)) if n > 1 else []
    groups = []
    for part in np.split(perm, cuts):
        g = np.zeros(n, dtype=bool)
        g[part] = True
        groups.append(g)
    return groups


@pytest.mark.parametrize("name", NAMES)
def test_mixed_jacobian_newton_keeps_solutions(name):
    csys, _ = compiled(name)
    rng = np.random.default_rng(1)
    for groups in ([np.eye(csys.n, dtype=bool)[j] for j in range(csys.n)], _partition(csys.n, rng)):
        newton = IntervalNewton(csys, groups)

        def contract(csys, lo, hi, newton=newton):
            step = newton.contract(lo, hi)
            # a proven box holds exactly one solution: the Krawczyk image must hold it
            return step.lo, step.hi, step.empty

        check_contractor(name, contract)


@pytest.mark.parametrize("name", NAMES)
def test_mixed_newton_proofs_are_unique_solutions(name):
    """Boxes proven by the mixed-then-full Krawczyk test hold exactly one reference point."""
    csys, pts = compiled(name)
    newton = IntervalNewton(csys, [np.eye(csys.n, dtype=bool)[j] for j in range(csys.n)])
    rng = np.random.default_rng(2)
    lo, hi = random_boxes(pts, csys.system.domain, rng, count=400)
    step = newton.contract(lo, hi)
    for k in np.flatnonzero(step.proven):
        inside = [p for p in pts if holds(lo[k], hi[k], p)]
        assert len(inside) == 1


@pytest.mark.parametrize("name", NAMES)
def test_partial_newton_keeps_solutions(name):
    csys, _ = compiled(name)
    rng = np.random.default_rng(3)
    n = csys.n
    for size in sorted({1, max(1, n // 2), n}):
        S = rng.choice(n, size=size, replace=False)
        V = rng.choice(n, size=size, replace=False)
        pn = PartialNewton(csys, S, V)
        check_contractor(name, lambda csys, lo, hi, pn=pn: pn.contract(lo, hi))


@pytest.mark.parametrize("name", NAMES)
def test_cid_keeps_solutions(name):
    csys, _ = compiled(name)
    hc4 = HC4(csys, max_passes=2)
    rng = np.random.default_rng(4)
    for slices in (2, 3, 5):
        cid = CID(hc4.contract, slices)

        def contract(csys, lo, hi, cid=cid):
            var = rng.integers(csys.n, size=lo.shape[0])
            return cid.contract(lo, hi, var)

        check_contractor(name, contract)


def test_cid_on_a_circle_contracts_and_excludes():
    """x² + y² = 1, y = x: CID on x removes the middle slices HC4 alone keeps."""
    from certsolve.expr import System, sqr, var

    x, y = var("x"), var("y")
    system = System(["x", "y"], np.array([[-2.0, 2.0], [-2.0, 2.0]]), [sqr(x) + sqr(y) - 1, y - x])
    csys = CompiledSystem(system)
    hc4 = HC4(csys)
    lo, hi = np.array([[-1.0, -1.0]]), np.array([[1.0, 1.0]])
    a, b, e = hc4.contract(lo, hi)
    cid = CID(hc4.contract, 8)
    c, d, e2 = cid.contract(a, b, np.array([0]))
    assert not e2[0]
    r = math.sqrt(0.5)
    assert c[0, 0] <= -r <= d[0, 0] and c[0, 0] <= r <= d[0, 0]
    # two solutions at ±(r, r): the hull cannot shrink below them, but x stays inside
    assert np.all(c >= a) and np.all(d <= b)


@pytest.mark.parametrize("name", ["circle-line", "brown-5", "trig-exp", "kin2-6r"])
def test_solver_with_mixed_newton_matches_reference(name):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    n = system.n
    groups = [np.eye(n, dtype=bool)[j] for j in range(n)]
    res = solve(system, timeout=300, newton_groups=groups)
    pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
    assert res.status == "complete"
    assert not res.undecided
    assert len(res.solutions) == len(pts)
    for p in pts:
        assert sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1


@pytest.mark.parametrize(
    "stacked, swept",
    [(0, 0), (10**9, 0), (10**9, 10**9)],
    ids=["sequence", "side-by-side", "swept"],
)
@pytest.mark.parametrize("name", NAMES)
def test_cid_on_several_variables_keeps_solutions(name, stacked, swept):
    """The solver's CID before bisection (chosen variable, then the others by smear score,
    one after the other, side by side, or side by side swept again on every batch) never
    loses a reference point, and contracts at least as much as CID on one variable."""
    csys, _ = compiled(name)
    rng = np.random.default_rng(5)
    every = find(Solver.default(csys, cid_vars=None).contractor, Shave)  # all the variables
    every.stacked_pairs = stacked
    every.sweep_rows = swept
    one = find(Solver.default(csys, cid_vars=1).contractor, Shave)  # the chosen variable only
    assert every.count == csys.n and one.count == 1
    gains = []

    def contract(csys, lo, hi):
        _, _, jlo, jhi = csys.eval_fj(lo, hi)
        var = rng.integers(csys.n, size=lo.shape[0])
        a = every.contract(lo, hi, jlo, jhi, var, eps=1e-8)
        b = one.contract(lo, hi, jlo, jhi, var, eps=1e-8)
        # the extra rounds only contract what CID on ``var`` alone left
        live = ~b[2] & ~a[2]
        assert np.all(a[0][live] >= b[0][live]) and np.all(a[1][live] <= b[1][live])
        assert np.all(a[2] >= b[2])
        gains.append(np.sum(log_volume_ratio(b[0][live], b[1][live], a[0][live], a[1][live])))
        return a

    check_contractor(name, contract)
    if csys.n > 2:
        assert gains[0] < 0.0  # the other variables contracted some boxes further


BROYDEN_TRI = (
    "Variables x[8] in [-100, 100]; Constraints\n"
    + "\n".join(
        f"1 {'' if i == 1 else f'- x({i - 1}) '}+ (3 - 2*x({i}))*x({i})"
        + ("" if i == 8 else f" - 2*x({i + 1})")
        + " = 0;"
        for i in range(1, 9)
    )
    + "\nend"
)


def test_a_small_batch_is_swept_again_and_keeps_its_solutions():
    """IBEX's BroydenTri at n = 8 (a tridiagonal chain): on a box of one batch row, the
    side-by-side sweep repeated while it pays contracts more than one sweep, inside it, and
    keeps both solutions; a batch wider than ``sweep_rows`` is swept once."""
    system = parse_minibex(BROYDEN_TRI)
    sols = solve(system, timeout=120)
    assert sols.status == "complete" and len(sols.solutions) == 2
    csys = CompiledSystem(system)
    shave = find(Solver.default(csys, cid_vars=None).contractor, Shave)
    assert shave.sweep_rows >= 1 and shave.sweeps > 1
    points = np.array([(s.lo + s.hi) / 2 for s in sols.solutions])
    lo, hi = points.min(axis=0)[None, :] - 0.3, points.max(axis=0)[None, :] + 0.3  # both
    _, _, jlo, jhi = csys.eval_fj(lo, hi)
    var = np.array([0])
    out = {}
    for sweeps in (1, shave.sweeps):
        shave.sweeps = sweeps
        out[sweeps] = shave.contract(lo, hi, jlo, jhi, var, eps=1e-8)
    (alo, ahi, aemp), (blo, bhi, bemp) = out[1], out[shave.sweeps]
    assert not aemp[0] and not bemp[0]
    assert np.all(blo >= alo) and np.all(bhi <= ahi)
    assert log_volume_ratio(alo, ahi, blo, bhi)[0] < 0.0  # the sweeps after the first paid
    for s in sols.solutions:
        assert np.all(blo[0] <= s.lo) and np.all(s.hi <= bhi[0])
    # the same box beside more rows than sweep_rows: swept once, as the first contract above
    # (to rounding: a batch and a single box may round differently), not as the second
    many = shave.sweep_rows + 1
    rep = [np.repeat(a, many, axis=0) for a in (lo, hi, jlo, jhi)]
    clo, chi, _ = shave.contract(*rep, np.zeros(many, dtype=np.int64), eps=1e-8)
    assert np.allclose(clo[0], alo[0], rtol=1e-9, atol=1e-12)
    assert np.allclose(chi[0], ahi[0], rtol=1e-9, atol=1e-12)
    assert log_volume_ratio(clo[:1], chi[:1], blo, bhi)[0] < -1.0


def test_cid_vars_needs_fewer_boxes_and_keeps_the_solutions():
    system = load_minibex(SYSTEMS / "eco-6.mbx")
    one = solve(system, cid_vars=1, timeout=300)
    every = solve(system, cid_vars=None, timeout=300)
    assert one.status == every.status == "complete"
    assert len(one.solutions) == len(every.solutions) == len(REFERENCE["eco-6"]["solutions"])
    assert every.stats.boxes < one.stats.boxes
    with pytest.raises(ValueError):
        Solver.default(system, cid_vars=0)


@pytest.mark.parametrize("side_by_side", [False, True], ids=["sequence", "side-by-side"])
@pytest.mark.parametrize("name", ["eco-6", "kin2-6r"])
def test_cid_on_several_variables_box_by_box(name, side_by_side):
    """The batched rounds equal CID applied to one box at a time (to rounding: a batch and
    a single box may round differently): the chosen variable, then every other one with a
    positive smear score -- one after the other, best first (a large batch), or each on the
    box the chosen one left, the results intersected (a small batch)."""
    csys, pts = compiled(name)
    shave = find(Solver.default(csys, cid_vars=None).contractor, Shave)
    rng = np.random.default_rng(6)
    lo, hi = random_boxes(pts, csys.system.domain, rng, count=60)
    if not side_by_side:
        shave.stacked_pairs = 0
    assert (lo.shape[0] * (csys.n - 1) <= shave.stacked_pairs) == side_by_side
    _, _, jlo, jhi = csys.eval_fj(lo, hi)
    var = rng.integers(csys.n, size=lo.shape[0])
    blo, bhi, bemp = shave.contract(lo, hi, jlo, jhi, var, eps=1e-8)
    for k in range(lo.shape[0]):
        a, b, e = shave.cid.contract(lo[k : k + 1], hi[k : k + 1], var[k : k + 1])
        score = smear_scores(lo[k : k + 1], hi[k : k + 1], jlo[k : k + 1], jhi[k : k + 1])[0]
        score[var[k]] = -1.0
        ilo, ihi, empty = a[0].copy(), b[0].copy(), bool(e[0])
        for v in np.argsort(-score, kind="stable"):
            if e[0] or empty or score[v] <= 0.0:
                break
            c, d, f = shave.cid.contract(a, b, np.array([v]))
            if side_by_side:  # each from the box CID on the chosen variable left
                empty |= bool(f[0])
                ilo, ihi = np.maximum(ilo, c[0]), np.minimum(ihi, d[0])
            else:
                a, b, e = c, d, f
                ilo, ihi, empty = c[0], d[0], bool(f[0])
        empty |= bool(np.any(ilo > ihi))
        assert bemp[k] == empty
        if not empty:
            assert np.allclose(blo[k], ilo, rtol=1e-9, atol=1e-12), (k, blo[k] - ilo)
            assert np.allclose(bhi[k], ihi, rtol=1e-9, atol=1e-12), (k, bhi[k] - ihi)


def test_adaptive_count_learns_the_mean_need():
    """ACID's rule, counted in boxes: the last ``learn`` boxes of every ``cycle`` shave more
    (all the variables in the first phase, then twice the learnt count) and record what they
    needed; at the end of a phase the mean (rounded up, at least 1) is the count in use.
    Until the first phase ends the count is ``start``: the chosen variable only."""
    acid = AdaptiveCount(7, cycle=10, learn=4)
    limit, learns = acid.plan(5)  # boxes 0-4: no learning yet, the chosen variable only
    assert limit.tolist() == [1] * 5 and not learns.any()
    acid.done(np.zeros(0, dtype=int), 5)
    limit, learns = acid.plan(3)  # boxes 5-7: 6 and 7 learn, with every variable
    assert learns.tolist() == [False, True, True] and limit.tolist() == [1, 7, 7]
    acid.done(np.array([1, 2]), 3)
    assert acid.count == 1 and acid.phases == 0  # the phase is not over
    limit, learns = acid.plan(3)  # boxes 8-10: 8 and 9 end the phase
    assert learns.tolist() == [True, True, False] and limit.tolist() == [7, 7, 1]
    acid.done(np.array([4, 3]), 3)  # mean 2.5 -> 3
    assert acid.count == 3 and acid.phases == 1
    limit, learns = acid.plan(9)  # boxes 11-19: 16-19 learn with twice the count
    assert learns.tolist() == [False] * 5 + [True] * 4 and limit.tolist() == [3] * 5 + [6] * 4
    acid.done(np.array([1, 1, 1, 2]), 9)
    assert acid.count == 2 and acid.phases == 2  # mean 1.25 -> 2
    with pytest.raises(ValueError):
        AdaptiveCount(3, cycle=2, learn=3)
    plain = AdaptiveCount(3, cycle=10, learn=4, count=1, phases=1, boxes=16, double=False)
    assert plain.plan(1)[0].tolist() == [3]  # without doubling, learning shaves every variable


@pytest.mark.parametrize("name", ["eco-6", "kin2-6r"])
def test_auto_cid_count_keeps_every_solution(name):
    """cid_vars="auto" changes how much is shaved, never what is found."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    one = solve(system, cid_vars=1, timeout=300)
    auto = Solver.default(system, cid_vars="auto")
    res = auto.solve(timeout=300)
    assert res.status == one.status == "complete"
    assert len(res.solutions) == len(one.solutions) == len(REFERENCE[name]["solutions"])
    dom = auto.domain
    acid = run_search(auto, dom[:, 0][None], dom[:, 1][None]).state.acid  # the search's state
    assert acid is not None and acid.boxes > 0 and 1 <= acid.count <= system.n
    for s in res.solutions:
        assert sum(np.all((s.lo <= o.hi) & (o.lo <= s.hi)) for o in one.solutions) == 1
