"""The FK equation systems are built node for node as recorded in ``reference/``.

The fingerprints (graph size, variables, domain, constraints and the values of every
equation and constraint at random points) pin what the builders decide; a change of the
physics or of the expression graphs shows up here.  Regenerate with
``python tests/reference/fk_fingerprints.py`` only for an intended change.

What the build decides is compared exactly: it must be the same on every CPU, whichever
BLAS kernel numpy loads (the builders do their small linear algebra in exact rationals).
The values at the random points are compared to a tolerance relative to the largest value
of the fingerprint, far above rounding and far below any change of a coefficient or term.
"""

from __future__ import annotations

import importlib.util
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from certsolve.kinematics import fk_geometry, fk_systems
from certsolve.robot import Robot

REF = Path(__file__).resolve().parent / "reference"
_spec = importlib.util.spec_from_file_location("fk_fingerprints", REF / "fk_fingerprints.py")
fkfp = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fkfp)
RECORDED = json.loads((REF / "fk_fingerprints.json").read_text())
VALUE_RTOL = 1e-9  # of the largest |value| in the fingerprint's f (or g)


def test_every_bundled_robot_has_fingerprints():
    names = {key.split("/")[0] for key in RECORDED}
    assert {"marionet", "marionet-t", "planar", "almost-planar"} <= names


@pytest.mark.parametrize("key", sorted(RECORDED))
def test_fk_system_built_as_recorded(key):
    robot_name, formulation = key.split("/")
    robot = Robot.load(fkfp.ROBOTS / f"{robot_name}.json")
    now = fkfp.fingerprint(robot, formulation)
    then = RECORDED[key]
    assert now is not None
    for field in ("system", "kind", "variables", "graph", "constraints", "domain"):
        assert now[field] == then[field], field
    for field in ("f", "g"):
        recorded = np.array(then[field], dtype=float)
        scale = float(np.max(np.abs(recorded), initial=0.0))
        np.testing.assert_allclose(
            np.array(now[field], dtype=float), recorded, rtol=0.0, atol=VALUE_RTOL * scale
        )


def test_affine_coefficients_are_exact():
    """The almost-planar platform is a 20 x 10 rectangle with its centre of mass in the
    middle: the fourth corner is ``P1 - P2 + P3`` and ``G = (P1 + P3) / 2``, exactly (a
    LAPACK solve gave ``1 ± 4e-16``, which changed the graph from one CPU to another)."""
    form = fk_systems.build_formulation(Robot.load(fkfp.ROBOTS / "almost-planar.json"))
    assert form.L is not None and form.lG is not None
    assert form.L.tolist() == [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, -1, 1]]
    assert form.lG.tolist() == [0.5, 0.0, 0.5]


def test_inexact_affine_coefficients_are_rounded_to_nearest():
    """A coefficient that is not a float is the exact one rounded to nearest (so the same
    everywhere), and the fit still reproduces the point."""
    Q = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    X = np.array([[1.0, 1.0], [0.1, 2.0]])
    coef = fk_geometry.affine_coordinates(Q, X)
    assert coef[0].tolist() == [float(Fraction(1, 3)), float(Fraction(1, 3)), float(Fraction(1, 3))]
    exact = [Fraction(1) - Fraction(0.1) / 3 - Fraction(2.0) / 3, Fraction(0.1) / 3, Fraction(2, 3)]
    assert coef[1].tolist() == [float(q) for q in exact]
    np.testing.assert_allclose(coef @ Q, X, rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="affine combination"):
        fk_geometry.affine_coordinates(Q[:2], X)


def test_equal_simplices_choose_the_first():
    """Every three corners of a rectangle span the same triangle: the first is chosen
    (the volumes are compared exactly, not as rounded determinants)."""
    corners = np.array([[-10.0, -5.0, 0.0], [10.0, -5.0, 0.0], [10.0, 5.0, 0.0], [-10.0, 5.0, 0.0]])
    assert fk_geometry.choose_points(corners, 3) == [0, 1, 2]
    assert fk_geometry.choose_points(corners[::-1], 3) == [0, 1, 2]
    assert fk_geometry.choose_points(np.vstack([corners, [[0.0, 0.0, 30.0]]]), 4) == [0, 1, 2, 4]
