"""The linear relaxation contractor: batched LP, proven bounds, no solution lost.

* :func:`certsolve.solver.lp.dual_active_set` is checked against scipy's HiGHS on random
  programs: the bounds proven from its multipliers never exceed the true optimum (the
  soundness that matters) and reach it when the method converged; a Farkas certificate is
  only given for programs HiGHS also finds infeasible.
* :class:`certsolve.solver.relaxation.PolytopeHull` is checked like every contractor on the
  reference solutions of the Minibex systems (``test_solver_contractors``).
* The solver finds the same solutions with and without it, and with it on every box or
  on the boxes :class:`~certsolve.solver.relaxation.HullShare` plans.
* Warm starts (:func:`certsolve.solver.lp.warm_start`): a program started from a nearby
  program's active set reaches the same proven bounds in fewer iterations; the hull
  started from a parent box's hints keeps every solution, and the solver finds the same
  solutions with and without them.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from test_solver_contractors import (
    NAMES,
    REFERENCE,
    SYSTEMS,
    check_contractor,
    holds,
)

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.solver import Solver, solve
from certsolve.solver.batch import Batch
from certsolve.solver.lp import StallRule, dual_active_set, warm_start
from certsolve.solver.pipeline import HULL_SHARE, find
from certsolve.solver.relaxation import (
    HullShare,
    PolytopeHull,
    proven_lower_bounds,
    xtaylor_rows,
)


def _programs(rng, S, n, m, slack_low):
    """``S`` random boxed programs ``{d ∈ [0, w] : G d <= ρ}`` (some infeasible)."""
    G = rng.normal(size=(S, m, n))
    w = rng.uniform(0.5, 2.0, (S, n))
    d0 = rng.uniform(0.0, 1.0, (S, n)) * w
    rho = np.einsum("smn,sn->sm", G, d0) + rng.uniform(slack_low, 1.0, (S, m))
    return G, rho, w


def _solve_all(G, rho, w, max_iter, long_step=False, cutoff=False, stall=None, slabs=(), warm=None):
    """Both programs (min and max) of every variable, as PolytopeHull sets them up
    (``long_step``: with the bound-flipping ratio test, across the bounds and the row pairs
    ``slabs`` (:meth:`PolytopeHull._pair`); ``cutoff``: a set stops once one of its programs
    passes the far side of the box; ``stall``: a :class:`StallRule`, the variable's width as
    each program's scale; ``warm``: active sets to start from, :func:`warm_start`)."""
    S, m, n = G.shape
    eye = np.eye(n)
    GA = np.concatenate([G, np.broadcast_to(eye, (S, n, n)), np.broadcast_to(-eye, (S, n, n))], 1)
    betaA = np.concatenate([rho, w, np.zeros((S, n))], axis=1)
    K = 2 * n
    j = np.tile(np.arange(K) % n, S)
    sign = np.tile(np.where(np.arange(K) < n, 1.0, -1.0), S)
    c = np.zeros((S * K, n))
    c[np.arange(S * K), j] = sign
    W0 = np.tile(m + n + np.arange(n), (S * K, 1))
    up = np.flatnonzero(sign < 0)
    W0[up, j[up]] = m + j[up]
    box = np.repeat(np.arange(S), K)
    wj = w[box, j]
    pair = PolytopeHull._pair(m, n, slabs)
    lam0, inv0 = np.abs(c), None
    if warm is not None:
        inv0 = np.linalg.inv(GA[box[:, None], W0])
        started, W_w, lam_w, inv_w = warm_start(GA, c, warm, pair)
        W0[started], lam0[started], inv0[started] = W_w, lam_w, inv_w
    lp = dual_active_set(
        GA,
        betaA,
        c,
        W0,
        lam0,
        inv0,
        pair=pair if long_step else None,
        cutoff=np.where(sign > 0, wj, 0.0) + 1e-9 * wj if cutoff else None,
        stall=stall,
        scale=wj,
        max_iter=max_iter,
    )
    bound = proven_lower_bounds(G, rho, w, lp.y[:, :m], sign, np.where(lp.infeasible, -1, j))
    return lp, bound, j, sign


@pytest.mark.parametrize("kind", ["plain", "long_step", "slabs"])
@pytest.mark.parametrize("seed", range(3))
def test_lp_bounds_never_exceed_the_optimum(seed, kind):
    """``slabs``: the rows are opposite pairs, as the relaxation's are, flipped like the
    bounds and priced by one matmul column."""
    if kind == "slabs":
        S, n, q = 30, 6, 10
        G, rho, w = _slab_programs(np.random.default_rng(200 + seed), S, n, q, slack_low=-0.08)
        slabs: tuple = ((0, q, q),)
    else:
        S, n, m = 40, 5, 20
        G, rho, w = _programs(np.random.default_rng(seed), S, n, m, slack_low=-0.4)
        slabs = ()
    lp, bound, j, sign = _solve_all(G, rho, w, max_iter=60, long_step=kind != "plain", slabs=slabs)
    K = 2 * n
    checked = infeasible = 0
    for s in range(S):
        feas = linprog(
            np.zeros(n), A_ub=G[s], b_ub=rho[s], bounds=list(zip(np.zeros(n), w[s])), method="highs"
        )
        for k in range(K):
            row = s * K + k
            if lp.infeasible[row]:
                assert feas.status == 2, "Farkas certificate for a feasible program"
                infeasible += bound[row] > 0.0
                continue
            if feas.status != 0:
                continue
            c = np.zeros(n)
            c[j[row]] = sign[row]
            opt = linprog(
                c, A_ub=G[s], b_ub=rho[s], bounds=list(zip(np.zeros(n), w[s])), method="highs"
            ).fun
            scale = 1.0 + abs(opt)
            assert bound[row] <= opt + 1e-9 * scale  # sound: a lower bound of the minimum
            assert bound[row] >= opt - 1e-6 * scale  # and tight: 60 iterations converge here
            checked += 1
    assert checked > 30 and infeasible > 0


@pytest.mark.parametrize("long_step", [False, True])
def test_lp_iteration_cap_only_weakens_bounds(long_step):
    rng = np.random.default_rng(7)
    G, rho, w = _programs(rng, 30, 6, 24, slack_low=0.05)  # all feasible
    _, full, _, _ = _solve_all(G, rho, w, max_iter=60, long_step=long_step)
    _, capped, _, _ = _solve_all(G, rho, w, max_iter=2, long_step=long_step)
    assert np.all(capped <= full + 1e-9 * (1.0 + np.abs(full)))


def test_lp_stall_rule_only_weakens_bounds():
    """Programs stopped because their objective crept stay sound (below the optimum); a lax
    rule stops some of them early; before its first check the rule changes nothing."""
    rng = np.random.default_rng(5)
    G, rho, w = _programs(rng, 30, 8, 32, slack_low=0.05)  # all feasible
    full, opt, _, _ = _solve_all(G, rho, w, max_iter=80, long_step=True)
    lax = StallRule(start=2, window=1, fraction=0.2, few=0)
    _, capped, _, _ = _solve_all(G, rho, w, max_iter=80, long_step=True, stall=lax)
    assert np.all(capped <= opt + 1e-9 * (1.0 + np.abs(opt)))
    assert np.any(capped < opt - 1e-6 * (1.0 + np.abs(opt)))  # the rule did stop some
    late = StallRule(start=full.iterations + 1, window=1, fraction=0.2, few=0)
    _, same, _, _ = _solve_all(G, rho, w, max_iter=80, long_step=True, stall=late)
    np.testing.assert_array_equal(same, opt)


def test_lp_stops_a_tail_of_few_programs():
    """Past ``few_after`` iterations the batch stops once fewer than ``few`` programs run;
    the bounds stay sound."""
    rng = np.random.default_rng(5)
    G, rho, w = _programs(rng, 30, 8, 32, slack_low=0.05)
    full, opt, _, _ = _solve_all(G, rho, w, max_iter=80, long_step=True)
    assert full.iterations > 6
    rule = StallRule(start=100, few=10**6, few_after=3)  # a tail from the 4th iteration on
    cut, capped, _, _ = _solve_all(G, rho, w, max_iter=80, long_step=True, stall=rule)
    assert cut.iterations == 4
    assert np.all(capped <= opt + 1e-9 * (1.0 + np.abs(opt)))


def test_long_step_converges_in_fewer_iterations():
    """Bound flipping passes the box's bounds in one step: the same optima, fewer pivots."""
    rng = np.random.default_rng(11)
    S, n, m = 30, 7, 28
    G, rho, w = _programs(rng, S, n, m, slack_low=0.05)  # all feasible
    plain, _, _, _ = _solve_all(G, rho, w, max_iter=60)
    flips, bound, j, sign = _solve_all(G, rho, w, max_iter=60, long_step=True)
    assert flips.iterations < plain.iterations
    for row in range(S * 2 * n):
        s = row // (2 * n)
        c = np.zeros(n)
        c[j[row]] = sign[row]
        opt = linprog(c, A_ub=G[s], b_ub=rho[s], bounds=list(zip(np.zeros(n), w[s]))).fun
        assert opt - 1e-7 * (1.0 + abs(opt)) <= bound[row] <= opt + 1e-9 * (1.0 + abs(opt))


@pytest.mark.parametrize("seed", range(3))
def test_lp_cutoff_keeps_bounds_sound(seed):
    """Sets stopped early (a program proved them empty) still give only valid bounds; the
    empty sets are still proven empty and feasible sets never stop."""
    rng = np.random.default_rng(100 + seed)
    S, n, m = 40, 5, 20
    G, rho, w = _programs(rng, S, n, m, slack_low=-0.6)
    _, ref, _, _ = _solve_all(G, rho, w, max_iter=60, long_step=True)
    lp, bound, j, sign = _solve_all(G, rho, w, max_iter=60, long_step=True, cutoff=True)
    K = 2 * n
    for s in range(S):
        feas = linprog(
            np.zeros(n), A_ub=G[s], b_ub=rho[s], bounds=list(zip(np.zeros(n), w[s])), method="highs"
        )
        rows = slice(s * K, (s + 1) * K)
        if feas.status == 0:  # feasible: no program may prove it empty, none stops early
            assert not np.any(lp.infeasible[rows])
            np.testing.assert_allclose(bound[rows], ref[rows], rtol=1e-9, atol=1e-12)
        else:  # still proven empty: a Farkas certificate or a bound past the box
            far = np.where(sign[rows] > 0, w[s, j[rows]], 0.0)
            proves = (lp.infeasible[rows] & (bound[rows] > 0.0)) | (
                ~lp.infeasible[rows] & (bound[rows] > far)
            )
            assert np.any(proves) or not np.any(ref[rows] > far)


def test_objective_rows_enclose_the_exact_values():
    """The batched matmul's error bound covers the exact ``c + Gᵀy`` (rationals), with
    cancellation, huge and tiny (subnormal) terms, and the objective's ±1 added."""
    from fractions import Fraction

    from certsolve.solver.relaxation import _objective_rows

    rng = np.random.default_rng(3)
    S, K, m, n = 15, 2, 12, 4
    L = S * K
    y = np.abs(rng.normal(size=(L, m))) * 10.0 ** rng.integers(-8, 8, (L, m))
    G = rng.normal(size=(S, m, n)) * 10.0 ** rng.integers(-8, 8, (S, m, n))
    G[0] = 1e-310  # subnormal products
    y[2:4] = 1.0 / 3.0
    G[1, :, 0] = np.tile([1.0, -1.0], m // 2) * (1.0 + 2.0**-40)  # cancellation
    G[2, :, 1] = 2.0**-60  # the ±1 of c dominates
    j = rng.integers(-1, n, L)
    sign = rng.choice([-1.0, 1.0], L)
    g, err = _objective_rows(G, y, sign, j)
    for li in range(L):
        s = li // K
        for k in range(n):
            exact = sum(Fraction(float(y[li, i])) * Fraction(float(G[s, i, k])) for i in range(m))
            exact += Fraction(int(sign[li])) if j[li] == k else 0
            assert abs(Fraction(float(g[li, k])) - exact) <= Fraction(float(err[li, k]))


def test_proven_lower_bounds_per_set_and_per_program_agree():
    """Sets shared by ``K`` programs give the bounds of the same sets repeated per program."""
    rng = np.random.default_rng(4)
    S, K, m, n = 10, 3, 8, 3
    G, rho, w = _programs(rng, S, n, m, slack_low=0.05)
    y = np.abs(rng.normal(size=(S * K, m)))
    j = rng.integers(-1, n, S * K)
    sign = rng.choice([-1.0, 1.0], S * K)
    box = np.repeat(np.arange(S), K)
    shared = proven_lower_bounds(G, rho, w, y, sign, j)
    single = proven_lower_bounds(G[box], rho[box], w[box], y, sign, j)
    np.testing.assert_allclose(shared, single, rtol=1e-12, atol=1e-12)


def test_xtaylor_rows_hold_at_every_solution():
    """Every reference solution in a box satisfies the box's relaxation rows (rigorously)."""
    for name in NAMES:
        system = load_minibex(SYSTEMS / f"{name}.mbx")
        csys = CompiledSystem(system)
        pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
        rng = np.random.default_rng(5)
        for p in pts:
            w = 10.0 ** rng.uniform(-3, -0.5, (20, system.n))
            lo = p - w * rng.random((20, system.n))
            hi = lo + w
            G, rho, wb, ok = xtaylor_rows(csys, lo, hi)
            d = p - lo
            viol = np.einsum("bmn,bn->bm", G, d) - rho
            # relative to the row's magnitude: the float product here rounds, the rows do not
            mag = np.einsum("bmn,bn->bm", np.abs(G), np.abs(d)) + np.abs(rho)
            assert np.all(viol[ok] <= 1e-12 * mag[ok])
            assert np.all(wb >= hi - lo)


@pytest.mark.parametrize("name", NAMES)
def test_polytope_hull_keeps_solutions(name):
    for directions in (1, 3, 10):

        def contract(csys, lo, hi, directions=directions):
            return PolytopeHull(csys, directions=directions).contract(lo, hi)

        check_contractor(name, contract, seed=directions)


def test_relaxation_prunes_what_hc4_and_newton_keep():
    """Brown's almost-linear system: the relaxation refutes boxes HC4 and Newton cannot
    (with the midpoint split, 114 boxes against 3,948; the sign split, which makes every
    product over a half tight, narrows the gap to 75 against 364)."""
    system = load_minibex(SYSTEMS / "brown-5.mbx")
    for split_at_zero, factor in ((False, 10), (True, 3)):
        with_lp = solve(system, relax=True, split_at_zero=split_at_zero)
        without = solve(system, relax=False, split_at_zero=split_at_zero)
        assert len(with_lp.solutions) == len(without.solutions) == 3
        assert factor * with_lp.stats.boxes < without.stats.boxes


@pytest.mark.parametrize("name", ["circle-line", "brown-5", "trig-exp", "eco-6", "kin2-6r"])
def test_solver_with_and_without_relaxation(name):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
    for relax in (True, False):
        res = solve(system, timeout=300, relax=relax)
        assert res.status == "complete" and not res.undecided
        assert len(res.solutions) == len(pts)
        for p in pts:
            assert sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1


def test_hull_share_samples_while_the_hull_is_useless_and_comes_back():
    """:class:`HullShare`: every box while the share is high; below the threshold one box
    in ``sample``, by position in the count of boxes offered; useful samples switch the
    hull back on.  The plan is a function of the state."""
    share = HullShare(window=8, threshold=0.5, sample=4)
    assert share.plan(6).all()
    share.done(np.zeros(6, dtype=bool), 6)  # six useless contractions: share (7/8)^6
    assert share.share < 0.5
    plan = share.plan(10)
    assert np.flatnonzero(plan).tolist() == [2, 6]  # boxes 8 and 12 of the search
    assert HullShare(**vars(share)).plan(10).tolist() == plan.tolist()
    share.done(np.zeros(2, dtype=bool), 10)
    low = share.share
    for _ in range(20):
        if share.share >= 0.5:
            break
        plan = share.plan(4)
        assert plan.sum() == 1
        share.done(np.ones(1, dtype=bool), 4)
    assert share.share >= 0.5 > low and share.plan(3).all()


def test_adaptive_hull_keeps_every_solution_and_skips_boxes():
    """katsura-5: the hull rarely halves a box in the first rounds, so the search contracts
    a sample of them; deeper it pays again and contracts every box.  The solutions are those
    of the hull on every box, and two runs take the same boxes.  (eco-6 was the example
    until Newton iterated inside a round and ACID learnt on the first boxes: Newton's steps
    now leave the hull less to halve there, and its share ends below the threshold.)"""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    solver = Solver.default(system)
    state = solver.start()
    dom = solver.domain
    state.stack.push(dom[:, 0][None], dom[:, 1][None])
    shares = []
    while len(state.stack):
        solver.process(*state.stack.pop(solver.batch_size), state)
        shares.append(state.hull.share)
    low = [s < state.hull.threshold for s in shares]
    assert any(low) and not low[-1]
    adaptive = solve(system)
    hull = find(solver.contractor, PolytopeHull)
    solver.contractor = solver.contractor.replace(hull, PolytopeHull(solver.csys, adaptive=False))
    always = solver.solve()
    pts = np.array([[float(v) for v in s] for s in REFERENCE["katsura-5"]["solutions"]])
    for res in (adaptive, always):
        assert res.status == "complete" and not res.undecided
        assert len(res.solutions) == len(pts)
        assert all(sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1 for p in pts)
    assert solve(system).stats.boxes == adaptive.stats.boxes


def test_adaptive_hull_contracts_only_the_stalled_rows(monkeypatch):
    """A row the round has already shrunk as much as a bisection (from the box it began
    with) is not given to the hull: it goes back to the buffer anyway.  The other rows are,
    as the share plans them; the learnt state counts every row offered."""
    csys = CompiledSystem(load_minibex(SYSTEMS / "katsura-5.mbx"))
    dom = csys.system.domain
    lo = np.repeat(dom[:, 0][None], 3, axis=0)
    hi = np.repeat(dom[:, 1][None], 3, axis=0)
    hull = PolytopeHull(csys)
    batch = Batch(lo, hi, csys=csys, eps=1e-8, hull=hull.hull_learner())
    # row 1 has been halved along one variable in this round, row 2 shrank by a third
    batch.lo, batch.hi = lo.copy(), hi.copy()
    batch.hi[1, 0] = 0.5 * (lo[1, 0] + hi[1, 0])
    batch.hi[2, 0] = lo[2, 0] + (2.0 / 3.0) * (hi[2, 0] - lo[2, 0])
    seen = []
    contract = hull.contract_hinted

    def spy(a, b, hints=None):
        seen.append(a.copy())
        return contract(a, b, hints)

    monkeypatch.setattr(hull, "contract_hinted", spy)
    halved = batch.lo[1].copy(), batch.hi[1].copy()
    hull.apply(batch)
    assert len(seen) == 1 and seen[0].shape[0] == 2
    assert np.array_equal(seen[0], batch.start_lo[[0, 2]])
    assert batch.hull.boxes == 3
    assert np.array_equal(batch.lo[1], halved[0]) and np.array_equal(batch.hi[1], halved[1])
    # without a learnt state the hull is the plain contractor: every row
    seen.clear()
    hull.apply(Batch(lo.copy(), hi.copy(), csys=csys, eps=1e-8))
    assert seen[0].shape[0] == 3


def test_hull_share_settings_are_a_template():
    """Each search starts from a fresh copy of the hull's ``share`` settings
    (``HULL_SHARE`` in the solver's pipeline; a hull built without settings, as forward
    kinematics builds it, keeps ``HullShare()``); a search's learning never reaches the
    template, and the settings are in the fingerprint."""
    csys = CompiledSystem(load_minibex(SYSTEMS / "katsura-5.mbx"))
    solver = Solver.default(csys)
    hull = find(solver.contractor, PolytopeHull)
    first, second = hull.hull_learner(), hull.hull_learner()
    assert first == HULL_SHARE and first is not second and first is not HULL_SHARE
    first.done(np.zeros(5, dtype=bool), 5)
    assert first.share < 1.0 and second.share == 1.0
    assert HULL_SHARE.share == 1.0 and HULL_SHARE.boxes == 0
    assert PolytopeHull(csys).hull_learner() == HullShare()
    assert f"ratio={HULL_SHARE.ratio}" in solver.fingerprint()
    assert f"window={HULL_SHARE.window}" in solver.fingerprint()
    other = PolytopeHull(csys, share=HullShare(ratio=0.25, window=16)).describe()
    assert "ratio=0.25" in other and "window=16" in other


@pytest.mark.parametrize("name", ["katsura-5", "trig-exp", "kin2-6r", "troesch-10"])
def test_corners_in_one_call_give_the_same_rows(name, monkeypatch):
    """Small batches evaluate ``f`` at the corners in the ``f + J`` call with the boxes;
    the rows are the floats of the separate calls (``f``'s own program at the corners)."""
    import certsolve.solver.relaxation as relaxation

    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(5)
    dom = np.clip(system.domain, -10.0, 10.0)
    for B, scale in [(1, 1 / 4), (3, 1e-3)]:
        w = (dom[:, 1] - dom[:, 0]) * scale
        lo = dom[:, 0] + rng.random((B, csys.n)) * (dom[:, 1] - dom[:, 0] - w)
        hi = lo + w
        assert B * csys.fj.n_nodes <= relaxation._CORNERS_WITH_J  # the one-call path
        one = xtaylor_rows(csys, lo, hi)
        with monkeypatch.context() as m:
            m.setattr(relaxation, "_CORNERS_WITH_J", 0)
            apart = xtaylor_rows(csys, lo, hi)
        for a, b in zip(one, apart):
            assert np.array_equal(a, b, equal_nan=True)
        assert one[3].any()  # some rows are valid


def _slab_programs(rng, S, n, q, slack_low):
    """``S`` random programs whose ``2q`` rows are ``q`` slabs ``-ρ' <= g·d <= ρ``: rows
    ``i`` and ``q + i`` opposite (``g_{q+i} = -g_i``), as the relaxation's rows are."""
    G1 = rng.normal(size=(S, q, n))
    w = rng.uniform(0.5, 2.0, (S, n))
    d0 = rng.uniform(0.0, 1.0, (S, n)) * w
    gd = np.einsum("smn,sn->sm", G1, d0)
    G = np.concatenate([G1, -G1], axis=1)
    rho = np.concatenate(
        [gd + rng.uniform(slack_low, 1.0, (S, q)), -gd + rng.uniform(slack_low, 1.0, (S, q))], 1
    )
    return G, rho, w


def test_lp_pair_must_be_an_involution():
    pair = PolytopeHull._pair(6, 3, ((0, 4, 2),))  # rows 0, 1 <-> 4, 5; bounds 6-8 <-> 9-11
    assert pair.tolist() == [4, 5, -1, -1, 0, 1, 9, 10, 11, 6, 7, 8]
    G = np.zeros((1, 4, 2))
    with pytest.raises(ValueError, match="pair"):
        dual_active_set(
            G, np.ones((1, 4)), np.ones((1, 2)), np.array([[0, 1]]), np.ones((1, 2)),
            pair=np.array([1, 2, 0, -1]),
        )  # fmt: skip


@pytest.mark.parametrize("name", ["katsura-5", "trig-exp", "kin2-6r"])
def test_hull_rows_paired_as_slabs_are_opposite(name, monkeypatch):
    """The rows :class:`PolytopeHull` pairs (X-Taylor's corner rows, the affine forms' two
    sides, the bounds) are exact opposites, as the LP's ``pair`` requires."""
    import certsolve.solver.relaxation as relaxation

    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    dom = np.clip(system.domain, -10.0, 10.0)
    rng = np.random.default_rng(1)
    w = (dom[:, 1] - dom[:, 0]) / 8
    lo = dom[:, 0] + rng.random((5, csys.n)) * (dom[:, 1] - dom[:, 0] - w)
    seen = []

    def spy(GA, *args, **kw):
        seen.append((GA, kw["pair"]))
        return dual_active_set(GA, *args, **kw)

    monkeypatch.setattr(relaxation, "dual_active_set", spy)
    PolytopeHull(csys).contract(lo, lo + w)
    ((G, pair),) = seen
    paired = np.flatnonzero(pair >= 0)
    assert paired.size == G.shape[1]  # every row has its opposite
    assert np.array_equal(G[:, pair[paired]], -G[:, paired])


def _nearby(rng, G, rho, q, size):
    """The slab programs moved a little: each slab's normal and both sides (its rows stay
    opposite)."""
    G1 = G[:, :q] + size * rng.normal(size=G[:, :q].shape)
    return np.concatenate([G1, -G1], axis=1), rho + size * rng.uniform(-1.0, 1.0, rho.shape)


@pytest.mark.parametrize("seed", range(3))
def test_warm_start_from_a_nearby_program_is_sound_and_shorter(seed):
    """The programs of a box whose data moved a little (as a bisected box's children),
    started from the first programs' last active sets, reach the optimum HiGHS finds (sound
    and tight) in fewer iterations than from the box's corner."""
    rng = np.random.default_rng(300 + seed)
    S, n, q = 30, 6, 10
    G, rho, w = _slab_programs(rng, S, n, q, slack_low=0.05)
    slabs: tuple = ((0, q, q),)
    first, _, _, _ = _solve_all(G, rho, w, max_iter=60, long_step=True, slabs=slabs)
    G2, rho2 = _nearby(rng, G, rho, q, 0.03)
    cold, cold_bound, j, sign = _solve_all(G2, rho2, w, max_iter=60, long_step=True, slabs=slabs)
    warm, bound, _, _ = _solve_all(
        G2, rho2, w, max_iter=60, long_step=True, slabs=slabs, warm=first.active
    )
    assert warm.iterations < cold.iterations
    K = 2 * n
    checked = 0
    for s in range(S):
        for k in range(K):
            row = s * K + k
            c = np.zeros(n)
            c[j[row]] = sign[row]
            opt = linprog(
                c, A_ub=G2[s], b_ub=rho2[s], bounds=list(zip(np.zeros(n), w[s])), method="highs"
            )
            if opt.status != 0:
                continue
            scale = 1.0 + abs(opt.fun)
            assert bound[row] <= opt.fun + 1e-9 * scale
            assert bound[row] >= opt.fun - 1e-6 * scale
            checked += 1
    assert checked > 100


def test_warm_start_makes_any_basis_dual_feasible_by_flipping():
    """From a random basis of opposite pairs, every multiplier is made >= 0 by taking the
    opposite constraint where it was negative: ``c + Σ λ_k g_{W_k} = 0`` and ``N_W^{-1}``
    is the inverse of the flipped active matrix.  Without pairs those bases are refused;
    indices out of range, repeated ones and ``-1`` (no hint) are refused."""
    rng = np.random.default_rng(11)
    S, n, q = 20, 5, 8
    G, rho, w = _slab_programs(rng, S, n, q, slack_low=0.05)
    m = 2 * q
    eye = np.eye(n)
    GA = np.concatenate([G, np.broadcast_to(eye, (S, n, n)), np.broadcast_to(-eye, (S, n, n))], 1)
    pair = PolytopeHull._pair(m, n, ((0, q, q),))
    c = rng.normal(size=(S, n))
    lower = np.concatenate([np.arange(q), m + np.arange(n)])  # one side of every pair
    W = np.array([rng.choice(lower, n, replace=False) for _ in range(S)])
    W = np.where(rng.random(W.shape) < 0.5, pair[W], W)
    started, W2, lam, inv = warm_start(GA, c, W, pair)
    assert started.tolist() == list(range(S)) and np.all(lam >= 0.0)
    assert np.all((W2 == W) | (W2 == pair[W]))
    N = GA[started[:, None], W2]
    assert np.allclose(np.einsum("sij,sjk->sik", inv, N), np.eye(n), atol=1e-8)
    assert np.allclose(c + np.einsum("sk,skn->sn", lam, N), 0.0, atol=1e-8)
    plain, *_ = warm_start(GA, c, W)
    assert plain.size < S  # some random bases are not dual feasible as they are
    bad = W.copy()
    bad[0, 0], bad[1, 1], bad[2, 1], bad[3] = -1, m + 2 * n, bad[2, 0], -1
    assert warm_start(GA, c, bad, pair)[0].min() == 4


@pytest.mark.parametrize("name", NAMES)
def test_polytope_hull_started_from_a_parent_keeps_solutions(name):
    """The hull on a box, started from the hints its parent (the box widened) left."""
    for directions in (1, 3):

        def contract(csys, lo, hi, directions=directions):
            hull = PolytopeHull(csys, directions=directions)
            wide = 0.5 * (hi - lo)
            hints = hull.contract_hinted(lo - wide, hi + wide)[3]
            assert (hints >= 0).any()
            return hull.contract_hinted(lo, hi, hints)[:3]

        check_contractor(name, contract, seed=directions)


@pytest.mark.parametrize("name", ["brown-5", "eco-6", "kin2-6r"])
def test_solver_with_and_without_warm_starts(name):
    """The same solutions, each certified once, with the hull's warm starts and without."""
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    pts = np.array([[float(v) for v in s] for s in REFERENCE[name]["solutions"]])
    solver = Solver.default(system)
    hull = find(solver.contractor, PolytopeHull)
    cold = PolytopeHull(solver.csys, share=HULL_SHARE, warm=False)
    assert "warm=False" in cold.describe() and "warm" not in hull.describe()
    for contractor in (solver.contractor, solver.contractor.replace(hull, cold)):
        solver.contractor = contractor
        res = solver.solve(timeout=300)
        assert res.status == "complete" and not res.undecided
        assert len(res.solutions) == len(pts)
        for p in pts:
            assert sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1
