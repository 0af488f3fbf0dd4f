"""The contraction fixpoint counts only the variables the bisector may split.

A box goes round again (instead of being bisected) when contraction shrank it at least as
much as a bisection would.  Auxiliary variables (``bisect_mask`` False: forward kinematics'
wire lengths) narrow whenever the others move; their shrinking alone must not send a box
round again.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from certsolve.expr import System, var
from certsolve.expr.minibex import load_minibex
from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.kinematics.fk_points import ALPHA_MAX, ALPHA_MAX_GENERAL
from certsolve.robot import Robot
from certsolve.solver import Solver
from certsolve.solver.batch import NARROW_SHARE, progress_gain

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"


def _cubic():
    """Roots x = -1, 0, 1 with y = x; HC4 narrows y (auxiliary) a lot, x not at all."""
    x, y = var("x"), var("y")
    return System(["x", "y"], np.array([[-2.0, 2.0], [-100.0, 100.0]]), [x * x * x - x, y - x])


@pytest.mark.parametrize(("mask", "bisected"), [([True, False], 1), (None, 0)])
def test_auxiliary_shrinking_alone_does_not_send_a_box_round_again(mask, bisected):
    solver = Solver.default(_cubic(), bisect_mask=mask, cid_slices=0, relax=False)
    state = solver.start()
    dom = solver.domain
    solver.process(dom[:, 0][None].copy(), dom[:, 1][None].copy(), state)
    lo, hi = state.stack.snapshot()
    assert state.stats.bisections == bisected
    assert len(lo) == 1 + bisected
    assert np.all(hi[:, 1] - lo[:, 1] < 4.001)  # y contracted to x's range either way


@pytest.mark.parametrize("mask", [[True, False], None])
def test_same_roots_with_and_without_the_mask(mask):
    res = Solver.default(_cubic(), bisect_mask=mask).solve()
    assert res.status == "complete" and not res.undecided
    mids = sorted(float(s.midpoint[0]) for s in res.solutions)
    assert np.allclose(mids, [-1.0, 0.0, 1.0], atol=1e-9)


@pytest.mark.parametrize(
    ("name", "tau", "alpha"),
    [
        ("marionet", 60.0, ALPHA_MAX_GENERAL),
        ("marionet", 10.0, 0.25),
        ("marionet-t", 60.0, ALPHA_MAX),
        ("marionet-t", 10.0, 0.25),
    ],
)
def test_frame_bisector_splits_the_position_only_when_much_wider(name, tau, alpha):
    robot = with_tau_max(Robot.load(f"examples/robots/{name}.json"), tau)
    fk = FKSolver(robot)
    assert fk.search(np.zeros(robot.m)).solver.bisector.alpha == pytest.approx(alpha)


def test_variables_narrower_than_eps_do_not_count_as_progress():
    """A component converging to an exact zero (``[-1e-200, 1e-200]`` -> ``[-1e-250,
    1e-250]``) is no progress towards a bisection: the box must not go round again for it."""
    solver = Solver.default(_cubic(), eps=1e-8)
    lo0, hi0 = np.array([[0.5, -1e-200]]), np.array([[0.6, 1e-200]])
    lo1, hi1 = np.array([[0.5, -1e-250]]), np.array([[0.6, 1e-250]])

    def gain():  # as the solver's rounds measure it (its Batch.progress)
        s = solver
        return progress_gain(
            lo0, hi0, lo1, hi1, s.eps, s.bisect_mask, faces=s.faces, scale=s.scale
        )[0]

    assert gain() == 0.0
    lo1[0, 0] = 0.55  # the wide variable halved: that counts
    assert gain() == pytest.approx(np.log(0.5))


def test_variables_far_narrower_than_the_widest_do_not_count_as_progress():
    """A variable the bisector splits at 0 and narrower than ``NARROW_SHARE`` of the box's
    widest (in units of the domain's widths): its shrinking leaves the box as undecided, so
    it is no progress (boxes converging linearly onto solutions on the split's faces went
    round again, katsura-6 with the sign split)."""
    thin = 0.5 * NARROW_SHARE  # y's width, x's being 1
    lo0, hi0 = np.array([[0.0, 0.0]]), np.array([[1.0, thin]])
    lo1, hi1 = np.array([[0.0, 0.0]]), np.array([[1.0, thin / 8]])

    def gain(scale=None, faces=(True, True)):
        return progress_gain(lo0, hi0, lo1, hi1, 1e-8, None, faces=np.array(faces), scale=scale)[0]

    assert gain() == 0.0  # y shrank 8x: no progress
    assert gain(faces=(True, False)) == pytest.approx(np.log(1 / 8))  # y is not split at 0
    assert gain(np.array([1.0, 0.1])) == pytest.approx(np.log(1 / 8))  # y's domain is narrow
    hi1[0, 0] = 0.5  # x halved: only that counts
    assert gain() == pytest.approx(np.log(0.5))
    hi0[0, 1] = 2 * NARROW_SHARE  # y no longer far narrower: it counts
    hi1[0, 0], hi1[0, 1] = 1.0, NARROW_SHARE
    assert gain() == pytest.approx(np.log(0.5))


def test_no_long_tail_of_rounds_at_solutions_on_the_sign_split_faces():
    """katsura-6 has solutions with zero coordinates ((1/3, 0, 0, 0, 0, 0, 1/3) among them):
    the sign split puts them on the faces of its halves, where HC4 narrows the zero
    components linearly, by about half a round, while the others stay wide.  Counted as
    progress, the boxes there went round again instead of being split: 83 rounds, where the
    midpoint split takes 42 (~50 now)."""
    system = load_minibex(SYSTEMS / "katsura-6.mbx")
    res = Solver.default(system, split_at_zero=True).solve(timeout=300)
    assert res.status == "complete" and len(res.solutions) == 32 and not res.undecided
    assert res.stats.rounds < 65


def test_no_long_tail_of_single_box_rounds_at_a_solution_with_zeros():
    """katsura-5 has the solution (1, 0, 0, 0, 0, 0): near it, HC4 shrinks the zero components
    by orders of magnitude at every round.  Counted as progress, one box went round again
    ~180 times (210 batches in all with batches of 1024; 28 without the tail)."""
    system = load_minibex(SYSTEMS / "katsura-5.mbx")
    res = Solver.default(system, batch_size=1024).solve(timeout=300)
    assert res.status == "complete" and len(res.solutions) == 16 and not res.undecided
    assert res.stats.rounds < 60
