"""The certified force workspace of a robot known within tolerances (issue 31, item 4): a
region is ``good`` only if the isotropic force is >= F for every robot of the set."""

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.force.certified import certified_workspace
from certsolve.force.isotropic import isotropic_force
from certsolve.inputs import InputError
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
BOX = [-40, 40, -40, 40]


def _krut3(tolerances):
    data = json.loads((ROBOTS / "krut-3.json").read_text())
    data["tolerances"] = tolerances
    return Robot.load(data)


def test_inside_boxes_hold_for_drawn_robots():
    robot = _krut3([{"path": "wires[*].base[*]", "plus_minus": 1.0}])
    nominal = certified_workspace(robot.nominal(), 100.0, BOX, 2.5)
    ws = certified_workspace(robot, 100.0, BOX, 2.5)
    assert ws.status == "complete" and len(ws.inside)
    assert ws.inside_share < nominal.inside_share  # a set is harder to certify than one robot
    rng = np.random.default_rng(5)
    robots = [robot.draw(rng, corner=i % 2 == 0) for i in range(6)]
    boxes = ws.inside[rng.choice(len(ws.inside), size=min(20, len(ws.inside)), replace=False)]
    for b in boxes:
        p = b[:, 0] + rng.random(2) * (b[:, 1] - b[:, 0])
        for r in robots:
            f = isotropic_force(r, list(p)).isotropic_force
            assert f is not None and f >= 100.0 * (1 - 1e-9)
    # the set's inside boxes are inside for the nominal robot too: its paving, finer,
    # proves at least the set's share
    assert nominal.inside_share >= ws.inside_share


def test_zero_tolerance_is_the_nominal_paving():
    exact = _krut3([])
    zero = _krut3([{"path": "wires[*].base[*]", "plus_minus": 0.0}])
    a = certified_workspace(exact, 100.0, BOX, 2.5)
    b = certified_workspace(zero, 100.0, BOX, 2.5)
    assert np.array_equal(a.inside, b.inside) and np.array_equal(a.boundary, b.boundary)


def test_a_toleranced_mass_is_refused_by_name():
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    data["tolerances"].append({"path": "platform.mass", "plus_minus": 0.001})
    with pytest.raises(InputError) as err:
        certified_workspace(Robot.load(data), 1.0, [100, 110, 50, 60, 100, 110], 5.0)
    assert err.value.field == "robot.tolerances"


def test_isotropic_force_at_a_pose_holds_for_the_set():
    robot = _krut3([{"path": "wires[*].base[*]", "plus_minus": 1.0}])
    res = isotropic_force(robot, [5, -3])
    nominal = isotropic_force(robot.nominal(), [5, -3]).isotropic_force
    assert res.isotropic_force == nominal and res.set_force_lo is not None
    rng = np.random.default_rng(2)
    drawn = [isotropic_force(robot.draw(rng, corner=i % 2 == 0), [5, -3]) for i in range(12)]
    least = min(r.isotropic_force for r in drawn)
    assert 0.8 * least < res.set_force_lo <= least
    assert res.to_dict()["set_force_lo"] == res.set_force_lo
    assert isotropic_force(robot.nominal(), [5, -3]).set_force_lo is None


def test_ik_on_a_set_says_it_answers_for_the_nominal_robot():
    from certsolve.kinematics import inverse_kinematics

    robot = Robot.load(ROBOTS / "marionet-t-tol.json")
    pose = [115, 60, 118, 0, 0, 0]
    res = inverse_kinematics(robot, pose)
    nominal = inverse_kinematics(robot.nominal(), pose)
    assert np.array_equal(res.u, nominal.u)
    assert any("nominal robot's controls" in m for m in res.messages)
