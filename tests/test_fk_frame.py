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
        info = f.info["translation"]
        # lengths + forces in the reference point and the wire lengths: square
        assert len(info["equations"]) == len(info["variables"])
        names = [f.system.variables[i] for i in info["variables"]]
        assert all(v.startswith(("rho", "x", "y", "z")) for v in names)


def test_wires_sharing_a_point_have_identical_coefficients():
    r = robot("marionet-t")
    _, gidx = r.attachment_groups()
    for form in ("T-16", "frame"):
        L = build_formulation(r, form).L
        for g in np.unique(gidx):
            rows = L[gidx == g]
            assert np.all(rows == rows[0])  # bitwise: redundant equations rely on it
