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
