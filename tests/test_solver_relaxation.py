"""The linear relaxation contractor: batched LP, proven bounds, no solution lost.

* :func:`certsolve.solver.lp.dual_active_set` is checked against scipy's HiGHS on random
  programs: the bounds proven from its multipliers never exceed the true optimum (the
  soundness that matters) and reach it when the method converged; a Farkas certificate is
  only given for programs HiGHS also finds infeasible.
* :class:`certsolve.solver.relaxation.PolytopeHull` is checked like every contractor on the
  reference solutions of the Minibex systems (``test_solver_contractors``).
* The solver finds the same solutions with and without it.
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
from certsolve.solver import solve
from certsolve.solver.lp import dual_active_set
from certsolve.solver.relaxation import PolytopeHull, proven_lower_bounds, xtaylor_rows


def _programs(rng, S, n, m, slack_low):
    """``S`` random boxed programs ``{d ∈ [0, w] : G d <= ρ}`` (some infeasible)."""
    G = rng.normal(size=(S, m, n))
    w = rng.uniform(0.5, 2.0, (S, n))
    d0 = rng.uniform(0.0, 1.0, (S, n)) * w
    rho = np.einsum("smn,sn->sm", G, d0) + rng.uniform(slack_low, 1.0, (S, m))
    return G, rho, w


def _solve_all(G, rho, w, max_iter):
    """Both programs (min and max) of every variable, as PolytopeHull sets them up."""
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
    lp = dual_active_set(GA, betaA, c, W0, np.abs(c), max_iter=max_iter)
    box = np.repeat(np.arange(S), K)
    bound = proven_lower_bounds(
        G[box], rho[box], w[box], lp.y[:, :m], sign, np.where(lp.infeasible, -1, j)
    )
    return lp, bound, j, sign


@pytest.mark.parametrize("seed", range(3))
def test_lp_bounds_never_exceed_the_optimum(seed):
    rng = np.random.default_rng(seed)
    S, n, m = 40, 5, 20
    G, rho, w = _programs(rng, S, n, m, slack_low=-0.4)
    lp, bound, j, sign = _solve_all(G, rho, w, max_iter=60)
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


def test_lp_iteration_cap_only_weakens_bounds():
    rng = np.random.default_rng(7)
    G, rho, w = _programs(rng, 30, 6, 24, slack_low=0.05)  # all feasible
    _, full, _, _ = _solve_all(G, rho, w, max_iter=60)
    _, capped, _, _ = _solve_all(G, rho, w, max_iter=2)
    assert np.all(capped <= full + 1e-9 * (1.0 + np.abs(full)))


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
    """Brown's almost-linear system: the relaxation refutes boxes HC4 and Newton cannot."""
    system = load_minibex(SYSTEMS / "brown-5.mbx")
    with_lp = solve(system, relax=True)
    without = solve(system, relax=False)
    assert len(with_lp.solutions) == len(without.solutions) == 3
    assert 5 * with_lp.stats.boxes < without.stats.boxes


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
