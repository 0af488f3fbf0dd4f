"""Dietmaier's Stewart-Gough platform: all 40 real postures of the literature, certified.

``benchmarks/systems/dietmaier.mbx`` (12 variables) describes the platform by four of its
points; six distances fix those up to a reflection, so the system's real solutions are the
postures of the platform and of its mirror image.  Dietmaier (1998) built the geometry to
have 40 real postures: exactly 40 certified solutions must have the platform's handedness.
The solver searches with two linear combinations of the equations in place of the last two
(:func:`~certsolve.expr.polynomial.reduce_degree`).  About 50 s with two worker processes:
``slow``.
"""

from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.minibex import load_minibex
from certsolve.solver import solve

FILE = Path(__file__).resolve().parent.parent / "benchmarks" / "systems" / "dietmaier.mbx"


@pytest.mark.slow
def test_forty_real_postures_and_their_mirror_images():
    system = load_minibex(FILE)
    res = solve(system, workers=2, verify=True)
    assert res.status == "complete" and not res.undecided
    assert all(s.certificate == "unique" and s.verified for s in res.solutions)
    b = np.array([s.midpoint for s in res.solutions]).reshape(-1, 4, 3)
    handed = np.linalg.det(np.stack([b[:, 1] - b[:, 0], b[:, 2] - b[:, 0], b[:, 3] - b[:, 0]], 1))
    assert np.all(np.abs(handed) > 1e-3)  # no degenerate (flat) tetrahedron
    counts = sorted([int(np.sum(handed > 0)), int(np.sum(handed < 0))])
    assert counts == [14, 40]
    # distinct postures: the certified boxes are disjoint and far apart
    mids = b.reshape(len(b), -1)
    gaps = np.abs(mids[:, None, :] - mids[None, :, :]).max(axis=2) + np.eye(len(mids))
    assert gaps.min() > 1e-3
