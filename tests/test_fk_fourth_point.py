"""The fourth-point constraints of general-19: ``E4 = a E2 + b E3 + c (E2 × E3)``.

They are redundant (contraction only): they must hold at every proper pose, fail at the
mirror image, and leave the certified poses of a search unchanged when switched off.  With
them, the frame formulation never splits ``E4`` (an auxiliary variable, like the wire
lengths): splitting it too must certify the same poses.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_fk import ik_u, load, local_boxes, matching

import certsolve.kinematics.fk_points as fk_points
import certsolve.kinematics.fk_systems as fk_systems
from certsolve.expr.compiled import CompiledSystem
from certsolve.kinematics import FKSolver
from certsolve.robot import Pose
from certsolve.robot.geometry import rotation_zyx

FORMULATIONS = ["auto", "general-19"]


def _fourth_point_rows(form):
    """Indices of the fourth-point constraints among the system's constraints."""
    n_extra = len(fk_points.fourth_point_constraints(form.Q, *([[0.0] * 3] * 3)))
    cons = form.system.constraints
    # they are appended right after the two signed-volume constraints
    first = next(i for i, c in enumerate(cons) if c.redundant and c.lo == c.hi) + 2
    return list(range(first, first + n_extra))


@pytest.mark.parametrize("name", FORMULATIONS)
def test_fourth_point_constraints_hold_at_proper_poses_only(name):
    robot = load("marionet")
    form = fk_systems.build_formulation(robot, name)
    rows = _fourth_point_rows(form)
    csys = CompiledSystem(form.system)
    rng = np.random.default_rng(0)
    for _ in range(20):
        R = rotation_zyx(*rng.uniform(-np.pi, np.pi, 3))
        p = rng.uniform(60, 120, 3)
        P = p + form.Q @ R.T
        x = np.concatenate([form.coordinates_of(P), np.full(robot.m, 150.0)])
        glo, ghi = csys.eval_constraints(x[None], x[None])
        assert np.all(np.abs(glo[0, rows]) < 1e-9) and np.all(np.abs(ghi[0, rows]) < 1e-9)
        # the mirror image of the chosen points (a reflection, then any placement)
        M = p + (form.Q * np.array([1.0, 1.0, -1.0])) @ R.T
        xm = np.concatenate([form.coordinates_of(M), np.full(robot.m, 150.0)])
        glo, ghi = csys.eval_constraints(xm[None], xm[None])
        assert np.max(np.abs(glo[0, rows])) > 1e-3


@pytest.mark.parametrize("name", FORMULATIONS)
def test_search_finds_the_same_poses_without_them(name, monkeypatch):
    robot = load("marionet")
    pose = Pose.from_params(6, (111, 58, 107, 5, -3, 2))
    u = ik_u(robot, pose)
    found = []
    for on in (True, False):
        if not on:
            monkeypatch.setattr(fk_points, "fourth_point_constraints", lambda *a: [])
        fk = FKSolver(robot, name)
        res = fk.solve(u, boxes=local_boxes(fk, robot, pose, 1.0, u), timeout=120)
        assert res.status == "complete"
        assert len(matching(res, robot, pose)) == 1
        found.append(np.array(sorted(s.position.tolist() for s in res.solutions)))
    assert found[0].shape == found[1].shape and np.allclose(found[0], found[1], atol=1e-7)


def test_e4_is_auxiliary_and_splitting_it_finds_the_same_poses(monkeypatch):
    robot = load("marionet")
    fk = FKSolver(robot, "auto")
    names = fk.form.system.variables
    e4 = [names.index(v) for v in ("ex4", "ey4", "ez4")]
    assert list(fk.form.determined) == e4
    mask = fk.form.bisect_mask()
    assert not mask[e4].any() and mask[:9].all()
    pose = Pose.from_params(6, (108, 60, 104, 5, 3, -4))
    u = ik_u(robot, pose)
    found = []
    for split_e4 in (False, True):
        fk = FKSolver(robot, "auto")
        if split_e4:  # the mask only (the bisector still treats E_4 as determined)
            split = fk.form.bisect_mask()
            split[e4] = True
            monkeypatch.setattr(fk.form, "bisect_mask", lambda split=split: split)
        res = fk.solve(u, boxes=local_boxes(fk, robot, pose, 2.0, u), timeout=120)
        assert res.status == "complete" and not res.undecided
        assert len(matching(res, robot, pose)) == 1
        found.append(np.array(sorted(s.platform_points.ravel().tolist() for s in res.solutions)))
    assert found[0].shape == found[1].shape and np.allclose(found[0], found[1], atol=1e-7)
