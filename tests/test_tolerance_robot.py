"""Tolerances in robot files: the path grammar shared with the design spec, the validation
that names the field, and the intervals of every number (issue 31, item 1)."""

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.robot import Robot
from certsolve.robot.params import AffineRobot, ParameterDef
from certsolve.robot.paths import PathError, parse_path
from certsolve.robot.schema import RobotFileError
from certsolve.robot.tolerance import widen

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"


def _t16(tolerances):
    data = json.loads((ROBOTS / "marionet-t.json").read_text())
    data["tolerances"] = tolerances
    return data


TOL = [
    {"path": "wires[*].base[*]", "plus_minus": 0.05},
    {"path": "wires[*].k", "relative": 0.01},
    {"path": "platform.mass", "plus_minus": 0.002},
]


def test_paths_one_grammar_for_design_and_tolerances():
    assert parse_path("wires[0,2].base[1]", m=7, dof=6) == ("base", [(0, 1), (2, 1)])
    assert parse_path("wires[*].k", m=3, dof=6) == ("k", [(0,), (1,), (2,)])
    assert parse_path("platform.mass", m=3, dof=6) == ("mass", [()])
    assert parse_path("platform.center_of_mass[*]", m=3, dof=3) == (
        "center_of_mass",
        [(0,), (1,)],
    )
    for bad in ("wires[7].k", "wires[*].k[0]", "wires[*].base", "wires[*].foo[0]", "mass"):
        with pytest.raises(PathError):
            parse_path(bad, m=7, dof=6)
    # the design spec keeps its own fields: a path to k parses, but is not a design parameter
    with pytest.raises(ValueError, match=r"parameters\[0\]\.path: .*design parameter"):
        AffineRobot(
            ROBOTS / "krut-3.json", [ParameterDef(name="k", path="wires[*].k", range=(1, 2))]
        )


def test_bounds_beside_the_nominal_arrays():
    robot = Robot.load(_t16(TOL))
    nominal = Robot.load(_t16([]))
    b = robot.bounds()
    assert np.array_equal(robot.A, nominal.A) and np.array_equal(robot.k, nominal.k)
    assert np.all(b.A[0] < robot.A) and np.all(b.A[1] > robot.A)
    assert np.all(b.A[0] >= robot.A - 0.05 - 1e-12) and np.all(b.A[1] <= robot.A + 0.05 + 1e-12)
    assert np.all(b.k[0] <= 0.99 * robot.k) and np.all(b.k[1] >= 1.01 * robot.k)
    assert np.array_equal(b.L0[0], b.L0[1])  # not toleranced: a point
    assert b.mass[0] <= 0.018 and b.mass[1] >= 0.022
    wlo, whi = robot.weight_bounds()
    assert wlo[2] <= -0.022 * 9.81 and whi[2] >= -0.018 * 9.81 and wlo[0] == whi[0] == 0.0
    assert robot.toleranced and not nominal.toleranced and not robot.nominal().toleranced
    # a zero tolerance is the nominal robot
    zero = Robot.load(_t16([{"path": "wires[*].base[*]", "plus_minus": 0.0}]))
    assert not zero.toleranced and np.array_equal(zero.bounds().A[0], zero.A)


def test_draws_stay_in_the_set():
    robot = Robot.load(_t16(TOL))
    b = robot.bounds()
    rng = np.random.default_rng(0)
    for corner in (False, True):
        r = robot.draw(rng, corner=corner)
        assert not r.toleranced
        assert np.all((r.A >= b.A[0]) & (r.A <= b.A[1]))
        assert np.all((r.k >= b.k[0]) & (r.k <= b.k[1]))
        assert b.mass[0] <= r.mass <= b.mass[1]
        assert np.array_equal(r.L0, robot.L0)
    r = robot.draw(rng, corner=True)
    assert np.all(np.isin(r.k, [b.k[0][0], b.k[1][0]]))


def test_widen_rounds_outward():
    lo, hi = widen(0.1, 0.2, None)
    assert lo < -0.1 < 0.3 < hi
    assert widen(5.0, None, 0.0) == (5.0, 5.0)


@pytest.mark.parametrize(
    ("tolerances", "message"),
    [
        ([{"path": "wires[*].k", "relative": 0.01}, {"path": "wires[9].k", "plus_minus": 1}],
         r"tolerances\[1\]\.path: wire index 9"),
        ([{"path": "wires[*].k", "plus_minus": -1}], r"tolerances\[0\]\.plus_minus"),
        ([{"path": "wires[*].k", "relative": 1.5}], r"tolerances\[0\]\.relative"),
        ([{"path": "wires[*].k", "plus_minus": 380}], r"tolerances\[0\]: wires\[0\]\.k .*tau_max"),
        ([{"path": "wires[1].L0", "plus_minus": 300}], r"tolerances\[0\]: wires\[1\]\.L0 .*> 0"),
        ([{"path": "platform.mass", "plus_minus": 1}], r"tolerances\[0\]: platform\.mass .*>= 0"),
        ([{"path": "wires[*].tau[1]", "plus_minus": 1}], r"tolerances\[0\]\.path: tau is a req"),
        ([{"path": "wires[*].k", "relative": 0.1}, {"path": "wires[3].k", "plus_minus": 1}],
         r"tolerances\[1\]\.path: wires\[3\]\.k already has a tolerance"),
        ([{"path": "wires[*].k"}], r"tolerances\[0\]: give exactly one"),
        ([{"path": "wires[*].k", "plus_minus": 1, "relative": 0.1}], "exactly one"),
    ],
)  # fmt: skip
def test_bad_tolerances_name_the_field(tolerances, message):
    with pytest.raises(RobotFileError, match=message):
        Robot.load(_t16(tolerances))


def test_a_missing_number_cannot_be_toleranced():
    with pytest.raises(RobotFileError, match=r"tolerances\[0\]\.path: wires\[0\]\.k is not given"):
        Robot.load(
            {
                "dof": 2,
                "wires": [{"base": [0, 0], "tau": [0, 1]}, {"base": [1, 0], "tau": [0, 1]}],
                "tolerances": [{"path": "wires[*].k", "relative": 0.01}],
            }
        )
