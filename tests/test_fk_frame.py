"""Forward kinematics in the platform-frame formulation against the paper's formulations.

The frame formulation is a linear change of variables of the paper's point systems (plus
redundant equations), so both must certify the same poses.  Also checks the pieces it adds:
exact attachment coefficients for wires sharing a point and the sub-system indices handed
to the solver.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.kinematics.fk_systems import build_formulation
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"


def robot(name, tau=None):
    return with_tau_max(Robot.load(ROBOTS / f"{name}.json"), tau)


def poses(res):
    return sorted(
        (tuple(np.round(s.platform_points.ravel(), 5)) for s in res.solutions),
    )


@pytest.mark.parametrize(
    ("name", "tau", "u", "paper"),
    [
        ("planar", None, [0.0] * 4, "planar-10"),
        ("planar", 60.0, [0.8, 1.8, -2.5, -3.6], "planar-10"),
        ("marionet-t", None, [0.0] * 7, "T-16"),
    ],
)
def test_frame_formulation_finds_the_papers_solutions(name, tau, u, paper):
    r = robot(name, tau)
    a = FKSolver(r, paper).solve(u, timeout=120)
    b = FKSolver(r, "frame").solve(u, timeout=120)
    assert a.status == b.status == "complete"
    assert not a.undecided and not b.undecided
    assert len(a.solutions) == len(b.solutions) >= 1
    for pa, pb in zip(poses(a), poses(b)):
        assert np.allclose(pa, pb, atol=1e-4)
    for s in b.solutions:  # decoded poses are consistent rigid placements
        P = r.B @ s.rotation.T + s.position
        assert np.allclose(P, s.platform_points, atol=1e-6)
        assert np.allclose(np.linalg.norm(r.A - s.platform_points, axis=1), s.rho, atol=1e-6)


def test_frame_formulation_names_and_sizes():
    for name, paper, n in [
        ("planar", "planar-10", 10),
        ("almost-planar", "almost-planar-13", 13),
        ("marionet-t", "T-16", 16),
        ("marionet", "general-19", 19),
    ]:
        f = build_formulation(robot(name), "frame")
        assert f.name == f"frame-{paper}"
        assert f.kind == "frame"
        assert f.system.n == len(f.system.equations) == n
        ((equations, variables),) = f.subsystems()
        # lengths + forces in the reference point and the wire lengths: square
        assert len(equations) == len(variables)
        names = [f.system.variables[i] for i in variables]
        assert all(v.startswith(("rho", "x", "y", "z")) for v in names)


def test_wires_sharing_a_point_have_identical_coefficients():
    r = robot("marionet-t")
    _, gidx = r.attachment_groups()
    for form in ("T-16", "frame"):
        L = build_formulation(r, form).L
        for g in np.unique(gidx):
            rows = L[gidx == g]
            assert np.all(rows == rows[0])  # bitwise: redundant equations rely on it


@pytest.mark.parametrize("order", ["edges first (default)", "lengths first"])
def test_mixed_jacobian_group_order_keeps_the_poses(order, monkeypatch):
    """Hansen's mixed Jacobian in either group order (a sound linearisation both ways)
    certifies the same single pose near an IK pose of general-19."""
    from test_fk import ik_u, local_boxes, matching

    from certsolve.robot import Pose
    from certsolve.solver.contractors import IntervalNewton
    from certsolve.solver.pipeline import find

    r = robot("marionet")
    pose = Pose.from_params(6, (108, 60, 104, 5, 3, -4))
    u = ik_u(r, pose)
    fk = FKSolver(r)
    names = fk.form.system.variables
    newton = find(fk.search(u).solver.contractor, IntervalNewton)
    assert [names[j][0] for j in np.flatnonzero(newton.groups[0])] == ["e"] * 9
    if order == "lengths first":  # the formulation's part, as every search asks for it
        reversed_groups = fk.form.newton_groups()[::-1]
        monkeypatch.setattr(fk.form, "newton_groups", lambda: reversed_groups)
        newton = find(fk.search(u).solver.contractor, IntervalNewton)
        assert [names[j][:3] for j in np.flatnonzero(newton.groups[0])] == ["rho"] * 7
    res = fk.solve(u, boxes=local_boxes(fk, r, pose, 2.0, u), timeout=120)
    assert res.status == "complete" and not res.undecided
    (s,) = matching(res, r, pose)
    assert len(res.solutions) == 1
    assert np.allclose(s.platform_points, r.B @ pose.rotation.T + pose.position, atol=1e-6)
