"""Bisectors: the curvature score, the box coin and the smear/curvature mix.

The scores are checked on hand-computed Jacobian enclosures; the coin for its share and
for not depending on the batch a box is in; the mix for taking smear's choice on one side
of the coin and curvature's on the other; the fallback where no score is positive for
splitting the variable widest relative to the domain; the mix leaving out variables whose
impact is far below the box's largest (not those merely narrow); the sign split at 0, and
the solutions it puts on a bisection face.  That the default solver (the mix) loses no
solution is checked by every solver test on the reference systems, and on a quadratic
eigenvalue problem in ``test_solver_geneig.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from certsolve.expr.minibex import parse_minibex
from certsolve.solver import Solver
from certsolve.solver.bisectors import (
    NARROW_SPLIT,
    SmearCurvatureMix,
    SmearSumRelative,
    _negligible,
    box_coin,
    curvature_scores,
    smear_impact,
    smear_scores,
    split,
)


def bilinear_box():
    """``f = (x y - 1, x + y - 3, z - x)`` on ``x in [1, 2], y in [0.5, 3], z in [0, 4]``:
    ``J = [[y, x, 0], [1, 1, 0], [-1, 0, 1]]`` enclosed over the box."""
    lo = np.array([[1.0, 0.5, 0.0]])
    hi = np.array([[2.0, 3.0, 4.0]])
    jlo = np.array([[[0.5, 1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]]])
    jhi = np.array([[[3.0, 2.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]]])
    return lo, hi, jlo, jhi


def test_curvature_score_by_hand():
    lo, hi, jlo, jhi = bilinear_box()
    # row 1: w(J_xx)·w_x = 2.5·1 and w(J_xy)·w_y = 1·2.5, over the smear |y| w_x + |x| w_y = 3 + 5
    # rows 2 and 3 are linear: no curvature
    assert curvature_scores(lo, hi, jlo, jhi)[0] == pytest.approx([2.5 / 8, 2.5 / 8, 0.0])
    # smear: row 1 (3/8, 5/8, 0), row 2 (1/3.5, 2.5/3.5, 0), row 3 (1/5, 0, 4/5)
    expect = [3 / 8 + 1 / 3.5 + 1 / 5, 5 / 8 + 2.5 / 3.5, 4 / 5]
    assert smear_scores(lo, hi, jlo, jhi)[0] == pytest.approx(expect)
    # the mask and eps exclude variables in both
    for scores in (curvature_scores, smear_scores):
        assert scores(lo, hi, jlo, jhi, mask=np.array([True, False, True]))[0, 1] == -1.0
        assert scores(lo, hi, jlo, jhi, eps=1.5)[0, 0] == -1.0


def test_box_coin_share_and_independence_of_the_batch():
    rng = np.random.default_rng(7)
    lo = rng.normal(size=(20000, 5))
    hi = lo + rng.random((20000, 5))
    for share in (0.25, 1 / 3, 0.5):
        coin = box_coin(lo, hi, share)
        assert abs(coin.mean() - share) < 0.02
        # a box draws the same coin alone, in another batch, or in another order
        alone = np.array([box_coin(lo[k : k + 1], hi[k : k + 1], share)[0] for k in range(50)])
        assert np.array_equal(alone, coin[:50])
        perm = rng.permutation(len(lo))
        assert np.array_equal(box_coin(lo[perm], hi[perm], share), coin[perm])
    assert not box_coin(lo, hi, 0.0).any() and box_coin(lo, hi, 1.0).all()
    # the two halves of a split draw unrelated coins
    mid = (lo[:, 0] + hi[:, 0]) / 2
    left, right = hi.copy(), lo.copy()
    left[:, 0], right[:, 0] = mid, mid
    agree = box_coin(lo, left, 0.5) == box_coin(right, hi, 0.5)
    assert abs(agree.mean() - 0.5) < 0.02


def test_mix_takes_smear_or_curvature_by_the_coin():
    rng = np.random.default_rng(3)
    B, n = 400, 4
    lo = rng.normal(size=(B, n))
    hi = lo + rng.random((B, n))
    jlo = rng.normal(size=(B, n, n))
    jhi = jlo + rng.random((B, n, n)) * (rng.random((B, n, n)) < 0.5)
    jhi[:40] = jlo[:40]  # constant Jacobian: no curvature anywhere, smear decides
    mix = SmearCurvatureMix(share=0.5)
    var = mix.choose(lo, hi, jlo, jhi)
    coin = box_coin(lo, hi, 0.5)
    smear = SmearSumRelative().choose(lo, hi, jlo, jhi)
    curv = np.argmax(curvature_scores(lo, hi, jlo, jhi), axis=1)
    linear = np.arange(B) < 40
    assert np.array_equal(var[~coin | linear], smear[~coin | linear])
    assert np.array_equal(var[coin & ~linear], curv[coin & ~linear])
    assert np.any(var[coin & ~linear] != smear[coin & ~linear])  # the two do differ
    # a mask is obeyed on both sides of the coin
    mask = np.array([True, False, True, False])
    assert set(mix.choose(lo, hi, jlo, jhi, mask=mask)) <= {0, 2}


@pytest.mark.parametrize("bisector", [SmearSumRelative(), SmearCurvatureMix(share=1.0)])
def test_no_information_splits_the_widest_allowed_variable(bisector):
    lo = np.zeros((2, 3))
    hi = np.array([[1.0, 3.0, 2.0], [1.0, 3.0, 2.0]])
    zero = np.zeros((2, 3, 3))  # a Jacobian of zeros: every score is 0
    assert bisector.choose(lo, hi, zero, zero).tolist() == [1, 1]
    assert bisector.choose(lo, hi, zero, zero, mask=np.array([True, False, True])).tolist() == [
        2,
        2,
    ]
    assert bisector.choose(lo, hi, zero, zero, eps=2.5).tolist() == [1, 1]


@pytest.mark.parametrize("bisector", [SmearSumRelative(), SmearCurvatureMix(share=1.0)])
def test_no_information_splits_the_widest_relative_to_the_domain(bisector):
    lo = np.zeros((1, 3))
    hi = np.array([[1.0, 3.0, 2.0]])
    zero = np.zeros((1, 3, 3))
    scale = np.array([0.5, 30.0, 2.0])  # relative widths 2, 0.1, 1
    assert bisector.choose(lo, hi, zero, zero, scale=scale).tolist() == [0]
    assert bisector.choose(lo, hi, zero, zero).tolist() == [1]  # absolute without a scale


def test_the_solver_scale_is_its_domain():
    s = parse_minibex("Variables x in [0, 2]; y; z in [1, 1]; Constraints x = 1; y = 1; z = 1; end")
    solver = Solver.default(s)
    assert solver.scale.tolist() == [2.0, 1.0, 1.0]  # unbounded, degenerate: 1
    assert solver.on_domain(np.array([[0, 4], [0, 1], [1, 1]])).scale.tolist() == [4, 1, 1]


def narrow_box():
    """``f = (x + s - 1, y + s - 1, s + t² - 2)`` on a box where ``x``, ``y`` and ``s`` are
    1e-7 wide and ``t`` is 0.5 wide: the relative smear gives ``s`` half of the first two
    equations (2 x 0.5) and ``t`` most of the third (< 1)."""
    lo = np.array([[0.5, 0.5, 0.5, 1.0]])
    hi = lo + np.array([[1e-7, 1e-7, 1e-7, 0.5]])
    one = np.ones((1, 3, 4))
    jlo = np.array([[[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 2.0]]])
    jhi = np.array([[[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 3.0]]])
    return lo, hi, jlo * one, jhi * one


def test_a_variable_far_narrower_than_the_widest_is_not_split():
    lo, hi, jlo, jhi = narrow_box()
    assert smear_scores(lo, hi, jlo, jhi).argmax() == 2  # the plain score picks s
    assert SmearSumRelative().choose(lo, hi, jlo, jhi).tolist() == [2]
    mix = SmearCurvatureMix(share=0.0)  # smear on every box
    assert mix.narrow == NARROW_SPLIT
    assert mix.choose(lo, hi, jlo, jhi).tolist() == [3]
    assert SmearCurvatureMix(share=0.0, narrow=0.0).choose(lo, hi, jlo, jhi).tolist() == [2]
    # narrow in width but not relative to its domain: s is still split
    scale = np.array([1.0, 1.0, 1e-6, 1.0])
    assert mix.choose(lo, hi, jlo, jhi, scale=scale).tolist() == [2]
    # an unbounded variable sets no scale: beside t = [1, inf] nothing is narrow
    wide = hi.copy()
    wide[0, 3] = np.inf
    score = np.ones((1, 4))
    assert _negligible(score, lo, hi, None, NARROW_SPLIT).tolist() == [[True] * 3 + [False]]
    assert not _negligible(score, lo, wide, None, NARROW_SPLIT).any()


def multiplier_box():
    """``f = (l x - 1, l y - 1, l (x + y) - 2)`` on ``l in [1e-4, 2.5e-4]``, ``x, y in [0,
    1e3]``: the multiplier ``l`` is 1.5e-7 of the others' width, but it multiplies them, so it
    moves the equations as much as they do (``|x + y| w_l = 0.3`` against ``|l| w_x =
    0.25``)."""
    lo = np.array([[1e-4, 0.0, 0.0]])
    hi = np.array([[2.5e-4, 1e3, 1e3]])
    jlo = np.array([[[0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4], [0.0, 1e-4, 1e-4]]])
    jhi = np.array([[[1e3, 2.5e-4, 0.0], [1e3, 0.0, 2.5e-4], [2e3, 2.5e-4, 2.5e-4]]])
    return lo, hi, jlo, jhi


def test_a_narrow_variable_with_a_large_impact_is_still_split():
    """The rule compares impacts (``max_i |J_ij| w_j``), not widths: IBEX's Geneig-icse (an
    eigenvalue ``λ`` multiplying ``x_j`` in ``[-1e8, 1e8]``) left ``λ``, 1-2,500 wide beside
    products 1e9 wide, out of the split by width, and took 110k boxes and 160 s where it took
    4,864 (``docs/solver.md``, *The narrow rule compares impacts*)."""
    lo, hi, jlo, jhi = multiplier_box()
    impact = smear_impact(lo, hi, jlo, jhi)
    assert np.allclose(impact, [[0.3, 0.25, 0.25]])
    score = np.ones((1, 3))
    assert _negligible(score, lo, hi, None, NARROW_SPLIT).tolist() == [[True, False, False]]
    assert not _negligible(score, lo, hi, None, NARROW_SPLIT, impact).any()
    # the mix splits l (the largest smear share: 1.125 against 0.9375), as without the rule
    assert smear_scores(lo, hi, jlo, jhi).argmax() == 0
    mix = SmearCurvatureMix(share=0.0)
    assert mix.choose(lo, hi, jlo, jhi).tolist() == [0]
    # and in narrow_box, s moves its equations by 1e-7 against t's 1.5: still left out
    lo, hi, jlo, jhi = narrow_box()
    impact = smear_impact(lo, hi, jlo, jhi)
    score = np.ones((1, 4))
    assert _negligible(score, lo, hi, None, NARROW_SPLIT, impact).tolist() == [[True] * 3 + [False]]


TRIGO = """Variables x[4] in [1.e-8, 2*pi - 1.e-8]; s in [-10, 10];
Constraints
  5 - cos(x(1)) + s - sin(x(1)) = 0;
  4 + 2*(1 - cos(x(2))) + s - sin(x(2)) = 0;
  4 + 3*(1 - cos(x(3))) + s - sin(x(3)) = 0;
  4 + 4*(1 - cos(x(4))) + s - sin(x(4)) = 0;
  -cos(x(1)) - cos(x(2)) - cos(x(3)) - cos(x(4)) - s = 0;
end"""


def test_leaving_narrow_variables_out_loses_no_solution():
    """IBEX's Trigo1 at n = 4 (its Trigo1-0010sp made the rule): the same certified
    solutions with the rule and without, and nothing undecided."""
    system = parse_minibex(TRIGO)
    answers = []
    for narrow in (NARROW_SPLIT, 0.0):
        bisector = SmearCurvatureMix(narrow=narrow)
        r = Solver.default(system, bisector=bisector).solve(timeout=60)
        assert r.status == "complete" and not r.undecided
        answers.append(np.array(sorted(((s.lo + s.hi) / 2).tolist() for s in r.solutions)))
    # the same solutions (midpoints of certified boxes ~1e-12 wide, from different trees)
    assert len(answers[0]) > 0 and answers[0].shape == answers[1].shape
    assert np.allclose(answers[0], answers[1], rtol=0.0, atol=1e-9)


POLE = """Variables x in [0, 1.5707963]; y in [0, 2]; z in [-1e8, 1e8];
Constraints
  1/(1 - y) + tan(x) = 4;
  tan(x)*(1 - y) + 1/(1 - y) = 10/3;
  z*(1/(1 - y) - 2*tan(x)) = 1;
end"""


def test_a_pole_inside_the_domain_and_a_wide_multiplier():
    """Every equation has the pole y = 1 (an infinite Jacobian on boxes around it), and
    ``z`` only multiplies: the smear scores say nothing, and the fallback splits the variable
    widest relative to its domain (6 boxes; the widest in absolute terms, ``z``, took 67).
    Both solutions, (π/4, 2/3, 1) and (atan(8/3), 1/4, -1/4), and nothing undecided."""
    r = Solver.default(parse_minibex(POLE)).solve(timeout=60)
    assert r.status == "complete" and not r.undecided
    got = sorted(((s.lo + s.hi) / 2).tolist() for s in r.solutions)
    want = sorted([[math.pi / 4, 2 / 3, 1.0], [math.atan(8 / 3), 0.25, -0.25]])
    assert np.allclose(got, want, atol=1e-9)


def test_the_sign_split_cuts_at_zero_well_inside_only():
    """``at_zero``: 0 where it lies at least 5 % of the width inside; elsewhere, unbounded
    intervals and without ``at_zero``, the ratio's point as before."""
    inf = math.inf
    cases = [  # (lo, hi, the point with at_zero)
        (-1.0, 3.0, 0.0),
        (-0.01, 3.0, -0.01 + 0.45 * 3.01),  # 0 within 5 % of the end
        (2.0, 4.0, 2.9),
        (-inf, inf, 0.0),  # the unbounded rule's point
        (-1e8, 20.0, -1e8 + 0.45 * (1e8 + 20)),
    ]
    lo = np.array([[c[0]] for c in cases])
    hi = np.array([[c[1]] for c in cases])
    var = np.zeros(len(cases), dtype=int)
    (alo, ahi), (blo, bhi) = split(lo, hi, var, 0.45, at_zero=True)
    assert ahi[:, 0] == pytest.approx([c[2] for c in cases])
    assert np.array_equal(blo, ahi) and np.array_equal(alo, lo) and np.array_equal(bhi, hi)
    (_, plain), _ = split(lo, hi, var, 0.45)
    assert plain[0, 0] == pytest.approx(0.8)  # without at_zero: the ratio
    assert np.array_equal(plain[1:], ahi[1:])
    mask = np.array([False, True])  # at_zero as a mask: only the variables it names
    two_lo, two_hi = np.array([[-1.0, -1.0], [-1.0, -1.0]]), np.array([[3.0, 3.0], [3.0, 3.0]])
    (_, masked), _ = split(two_lo, two_hi, np.array([0, 1]), 0.45, at_zero=mask)
    assert masked[0, 0] == pytest.approx(0.8) and masked[1, 1] == 0.0
    assert not SmearCurvatureMix().at_zero and not hasattr(SmearSumRelative(), "at_zero")


def test_split_at_zero_names_the_variables_that_multiply_others():
    """``split_at_zero``'s mask is :attr:`CompiledSystem.coupled`: a variable whose
    Jacobian column depends on another variable (``x`` and ``y`` of ``x y``, ``w`` of
    ``w^2 + sin(w + y)``), not one that only enters by itself (``z^3``, ``sin(v)``)."""
    s = parse_minibex(
        "Variables x in [-1, 1]; y in [-1, 1]; z in [-1, 1]; v in [-1, 1]; w in [-1, 1];"
        "Constraints x*y = 0.1; z^3 + x = 0; sin(v) + z = 0; w^2 + sin(w + y) = 0.5;"
        "v + w = 0; end"
    )
    solver = Solver.default(s)  # on by default
    assert solver.csys.coupled.tolist() == [True, True, False, False, True]
    assert solver.bisector.at_zero.tolist() == [True, True, False, False, True]
    assert solver.faces.tolist() == [True, True, False, False, True]  # 0 inside each domain
    assert Solver.default(s, split_at_zero=False).bisector.at_zero is False
    assert Solver.default(s, split_at_zero=False).faces is None
    s.domain[0] = [0.0, 1.0]  # x can no longer be split at 0
    assert Solver.default(s).faces.tolist() == [False, True, False, False, True]


AXES = """Variables x in [-2, 2]; y in [-2, 2];
Constraints x^2 + y^2 = 1; x*y = 0; end"""


@pytest.mark.parametrize("at_zero", [True, False])
def test_solutions_on_the_sign_split_faces(at_zero):
    """The four solutions (±1, 0), (0, ±1) each have a coordinate at 0, the first face a sign
    split makes: each is still certified once (the inflated proof crosses the face, its
    unicity box prunes the other side), nothing undecided, the same with the ratio's split."""
    bisector = SmearCurvatureMix(at_zero=at_zero)
    r = Solver.default(parse_minibex(AXES), bisector=bisector).solve(timeout=60, verify=True)
    assert r.status == "complete" and not r.undecided
    got = sorted(np.round((s.lo + s.hi) / 2, 9).tolist() for s in r.solutions)
    assert got == [[-1.0, 0.0], [0.0, -1.0], [0.0, 1.0], [1.0, 0.0]]
