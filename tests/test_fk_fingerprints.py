"""The FK equation systems are built node for node as recorded in ``reference/``.

The fingerprints (graph size, variables, domain, constraints and the values of every
equation and constraint at random points) were recorded before the FK builders were
refactored; a change of the physics or of the expression graphs shows up here.
Regenerate with ``python tests/reference/fk_fingerprints.py`` only for an intended change.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.robot import Robot

REF = Path(__file__).resolve().parent / "reference"
_spec = importlib.util.spec_from_file_location("fk_fingerprints", REF / "fk_fingerprints.py")
fkfp = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fkfp)
RECORDED = json.loads((REF / "fk_fingerprints.json").read_text())


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
    for field in ("system", "kind", "variables", "graph", "constraints"):
        assert now[field] == then[field], field
    np.testing.assert_array_equal(np.array(now["domain"]), np.array(then["domain"]))
    for field in ("f", "g"):
        np.testing.assert_allclose(
            np.array(now[field], dtype=float), np.array(then[field], dtype=float), rtol=1e-13
        )
