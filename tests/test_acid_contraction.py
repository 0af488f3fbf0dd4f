"""IBEX's contraction strength in the solver's pipeline: interval Newton iterated inside a
round (IBEX's ``CtcNewton``), and ACID learning its count on the first boxes of a search
(IBEX's ``CtcAcid``).

Soundness is checked as in ``test_solver_contractors.py``: every reference point an input
box holds is either in its row's contracted box or in a unicity box the round proved.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from test_solver_contractors import NAMES, REFERENCE, SYSTEMS, compiled, holds, random_boxes

from certsolve.expr.minibex import load_minibex
from certsolve.solver import Solver, solve
from certsolve.solver.batch import Batch
from certsolve.solver.contractors import HC4, IntervalNewton
from certsolve.solver.pipeline import NEWTON_STEPS, find
from certsolve.solver.shaving import AdaptiveCount, Shave


def _newton_round(csys, lo, hi, iterations):
    """One :meth:`IntervalNewton.apply` on a batch; returns the batch and the proofs."""
    proofs: list[tuple[np.ndarray, ...]] = []
    batch = Batch(lo, hi, csys=csys, eps=1e-8, prove=lambda *a: proofs.append(a))
    groups = list(np.eye(csys.n, dtype=bool))
    IntervalNewton(csys, groups, iterations=iterations).apply(batch)
    return batch, proofs


@pytest.mark.parametrize("name", NAMES)
def test_newton_steps_keep_every_solution(name):
    """Every reference point of an input box is in its row's box after the round, or in a
    unicity box proven on the way; rows only shrink, and at least as much as one step."""
    csys, pts = compiled(name)
    rng = np.random.default_rng(30)
    lo, hi = random_boxes(pts, csys.system.domain, rng, count=200)
    batch, proofs = _newton_round(csys, lo, hi, iterations=8)
    one, _ = _newton_round(csys, lo, hi, iterations=1)
    unicity = [(u0[k], u1[k]) for _, _, u0, u1 in proofs for k in range(u0.shape[0])]
    kept = 0
    row = {int(i): r for r, i in enumerate(batch.ids)}
    for k in range(lo.shape[0]):
        for p in pts:
            if not np.all((lo[k] < p) & (p < hi[k])):
                continue
            kept += 1
            in_row = k in row and not batch.empty[row[k]]
            in_row = in_row and holds(batch.lo[row[k]], batch.hi[row[k]], p)
            assert in_row or any(holds(a, b, p) for a, b in unicity), (k, p)
    assert kept > 30
    assert np.all(batch.lo >= lo[batch.ids]) and np.all(batch.hi <= hi[batch.ids])
    both = np.intersect1d(batch.ids, one.ids)
    at, at1 = np.searchsorted(batch.ids, both), np.searchsorted(one.ids, both)
    assert np.all(batch.lo[at] >= one.lo[at1]) and np.all(batch.hi[at] <= one.hi[at1])
    # the shared Jacobian and the informative rows follow the rows left in the round
    jlo, jhi = batch.jacobian()
    assert jlo.shape == (batch.size, csys.n, csys.n) and batch.regular.shape == (batch.size,)


def test_newton_steps_prove_a_converging_box_in_one_round():
    """A box around a solution where Newton converges: one step contracts it, more steps
    reach the Krawczyk proof in the same round (IBEX's ``newton()`` loop)."""
    csys, pts = compiled("eco-6")
    p = pts[1]  # one step does not prove boxes of 0.02 to 0.1 around it, eight do
    dom = csys.system.domain
    lo = np.maximum(p - 0.045, dom[:, 0])[None]
    hi = np.minimum(p + 0.055, dom[:, 1])[None]
    once, proofs1 = _newton_round(csys, lo, hi, iterations=1)
    looped, proofs = _newton_round(csys, lo, hi, iterations=NEWTON_STEPS)
    assert not proofs1 and once.size == 1  # one step: contracted, not proven
    assert len(proofs) == 1 and looped.size == 0  # proven, out of the round
    e0, e1, u0, u1 = proofs[0]
    assert holds(e0[0], e1[0], p) and np.all(u0[0] >= lo[0]) and np.all(u1[0] <= hi[0])


def test_newton_steps_are_checked():
    csys, _ = compiled("circle-line")
    with pytest.raises(ValueError):
        IntervalNewton(csys, iterations=0)


def test_acid_learns_first_as_ibex():
    """``first=True``: the ``learn`` boxes that open each cycle learn (every variable in the
    first phase, then twice the learnt count), and a phase ends with its last learning box:
    the count is learnt from box ``learn`` on, not from ``cycle``."""
    acid = AdaptiveCount(7, cycle=10, learn=4, first=True)
    limit, learns = acid.plan(5)  # boxes 0-3 learn with every variable, box 4 uses start
    assert learns.tolist() == [True] * 4 + [False] and limit.tolist() == [7] * 4 + [1]
    acid.done(np.array([1, 2, 4, 3]), 5)
    assert acid.phases == 1 and acid.count == 3  # mean 2.5 -> 3
    limit, learns = acid.plan(7)  # boxes 5-11: 10 and 11 open the next cycle
    assert learns.tolist() == [False] * 5 + [True] * 2 and limit.tolist() == [3] * 5 + [6] * 2
    acid.done(np.array([1, 1]), 7)
    assert acid.phases == 1 and acid.count == 3  # boxes 12 and 13 still learn
    limit, learns = acid.plan(3)
    assert learns.tolist() == [True, True, False]
    acid.done(np.array([2, 1]), 3)
    assert acid.phases == 2 and acid.count == 2  # mean 1.25 -> 2


def test_the_solver_learns_first():
    """The solver's ACID learns on the first boxes (IBEX's rule), its Newton iterates."""
    csys, _ = compiled("eco-6")
    solver = Solver.default(csys)
    learner = find(solver.contractor, Shave).learner()
    assert learner.first and learner.plan(1)[0].tolist() == [csys.n]
    assert find(solver.contractor, IntervalNewton).iterations == NEWTON_STEPS


@pytest.mark.parametrize("name", ["trig-exp", "eco-6", "kin2-6r"])
def test_the_default_pipeline_finds_every_reference_solution(name):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    res = solve(system, timeout=300)
    pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
    assert res.status == "complete" and not res.undecided
    assert len(res.solutions) == len(pts)
    for p in pts:
        assert sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1


def test_acid_stops_shaving_past_the_deadline():
    """Past the batch's deadline (the search's time limit) no further variable is shaved:
    one CID call (the chosen variable) instead of one per variable, and every box only
    shrinks less -- each contains what the whole loop leaves, so no solution is lost."""
    csys, pts = compiled("eco-6")
    rng = np.random.default_rng(38)
    lo, hi = random_boxes(pts, csys.system.domain, rng, count=64)
    var = np.argmax(hi - lo, axis=1)
    _, _, jlo, jhi = csys.eval_fj(lo, hi)
    shave = Shave(HC4(csys), count=None, n=csys.n)
    shave.stacked_pairs = 0  # one variable after the other: the loop the deadline cuts
    calls = []
    inner = shave.cid.contract
    shave.cid.contract = lambda *a: calls.append(1) or inner(*a)
    full = shave.contract(lo, hi, jlo, jhi, var)
    n_full, calls[:] = len(calls), []
    cut = shave.contract(lo, hi, jlo, jhi, var, deadline=time.monotonic() - 1.0)
    assert n_full > 1 and len(calls) == 1
    assert np.all(cut[2] <= full[2])  # a box proven empty when cut is empty in full too
    live = ~cut[2]
    assert np.all(cut[0][live] <= full[0][live]) and np.all(cut[1][live] >= full[1][live])
