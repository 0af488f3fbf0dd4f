"""Exclusion regions: unicity boxes grown by epsilon-inflation never swallow a second root.

A certified solution's unicity box ``U`` is grown as far as the Krawczyk test still proves
that ``U`` holds one solution only (:meth:`Certifier.expand`), and the search then discards
every box inside ``U``.  Two roots very close to each other must both be found, each in its
own box, and the grown ``U`` must reach out towards the other root without containing it.
"""

from __future__ import annotations

import numpy as np
import pytest

from certsolve.expr import System, var
from certsolve.solver import solve
from certsolve.solver.certify import SolutionSet, box_difference


@pytest.mark.parametrize("gap", [1e-6, 1e-7])
def test_two_roots_close_together_are_both_found(gap):
    x, y = var("x"), var("y")
    a = 0.3
    # roots (a, a) and (a + gap, a + gap); y = x couples the second variable
    system = System(
        ["x", "y"], np.array([[-1.0, 1.0], [-1.0, 1.0]]), [(x - a) * (x - (a + gap)), y - x]
    )
    res = solve(system)
    assert res.status == "complete" and not res.undecided
    assert len(res.solutions) == 2
    roots = np.array([[a, a], [a + gap, a + gap]])
    for sol, root, other in zip(res.solutions, roots, roots[::-1], strict=True):
        assert np.all((sol.lo <= root) & (root <= sol.hi))
        assert not np.all((sol.ulo <= other) & (other <= sol.uhi))  # the other root is outside U
        # epsilon-inflation: U reaches a good part of the way to the other root
        assert np.max(sol.uhi - sol.ulo) > 0.3 * gap


def test_unicity_boxes_grow_far_from_other_roots():
    """A single root in a wide domain gets a unicity box of a sizeable share of the domain."""
    x, y = var("x"), var("y")
    system = System(["x", "y"], np.array([[-10.0, 10.0], [-10.0, 10.0]]), [x + y - 1, x - y])
    res = solve(system)
    (sol,) = res.solutions
    assert np.min(sol.uhi - sol.ulo) > 1.0


def _prune_all_pairs(sols, lo, hi):
    """The pruning rule written out on every (box, unicity box) pair (the reference)."""
    n = lo.shape[1]
    entries = [sols.entry(i) for i in range(len(sols))]
    ulo, uhi = np.array([e[2] for e in entries]), np.array([e[3] for e in entries])
    cover = (lo[:, None, :] >= ulo[None]) & (hi[:, None, :] <= uhi[None])
    keep = ~np.any(cover.all(axis=2), axis=1)
    meet = ((lo[:, None, :] < uhi[None]) & (hi[:, None, :] > ulo[None])).all(axis=2)
    clip = keep[:, None] & meet & (n - cover.sum(axis=2) == 1)
    plo, phi, done = [], [], set()
    for r, k in zip(*np.nonzero(clip), strict=True):
        if r not in done:
            done.add(r)
            for a, b in box_difference(lo[r], hi[r], ulo[k], uhi[k]):
                plo.append(a)
                phi.append(b)
            keep[r] = False
    return keep, np.array(plo).reshape(-1, n), np.array(phi).reshape(-1, n)


def test_pruning_by_unicity_boxes_equals_the_rule_on_every_pair():
    """SolutionSet.prune tests only the pairs whose closed boxes meet; the answer must be
    the rule's on every pair, boxes on a face of a unicity box (or flat) included."""
    rng = np.random.default_rng(11)
    n = 3
    grid = np.linspace(-1.0, 1.0, 9)  # shared coordinates: many faces touch exactly
    sols = SolutionSet(n)
    for _ in range(12):
        a, b = np.sort(rng.choice(grid, size=(2, n), replace=True), axis=0)
        sols.add(a, b, a, b, "alias")
    a, b = np.sort(rng.choice(grid, size=(2, 4000, n)), axis=0)
    b[::7, 0] = a[::7, 0]  # some flat boxes
    keep, plo, phi = sols.prune(a, b)
    rkeep, rlo, rhi = _prune_all_pairs(sols, a, b)
    assert np.array_equal(keep, rkeep) and not keep.all() and len(rlo) > 0
    assert np.array_equal(plo, rlo) and np.array_equal(phi, rhi)
