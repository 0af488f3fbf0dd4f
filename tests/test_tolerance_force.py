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


def test_the_isotropic_map_of_a_set_gives_its_certified_lower_bounds():
    """``isotropic_map`` on a robot with tolerances: the nominal values, and at each grid
    point a lower bound that no robot drawn from the set goes below (``null`` where the
    force is not proven >= 0), with a note; the job's stored form keeps them."""
    from certsolve.force.maps import IsotropicMap, isotropic_map

    robot = _krut3([{"path": "wires[*].base[*]", "plus_minus": 1.0}])
    xs, ys = np.linspace(-60, 60, 13), np.linspace(-80, 40, 13)
    fmap = isotropic_map(robot, xs, ys)
    assert np.array_equal(
        fmap.values, isotropic_map(robot.nominal(), xs, ys).values, equal_nan=True
    )
    lo = fmap.set_force_lo
    rng = np.random.default_rng(3)
    least = np.min(
        [isotropic_map(robot.draw(rng, corner=i % 2 == 0), xs, ys).values for i in range(8)], axis=0
    )
    proven = np.isfinite(lo)
    assert proven.sum() > 0.5 * (fmap.values > 0).sum()
    assert np.all(lo[proven] <= least[proven] * (1 + 1e-9))
    assert np.all(least[proven] >= 0)  # proven >= 0 for the set: no drawn robot is outside
    d = fmap.to_dict()
    assert "set_force_lo" in d and d["summary"]["set_inside"] == int(np.sum(lo > 0))
    assert d["notes"] and d["notes"][0].startswith("robot with tolerances")
    back = IsotropicMap.from_dict(d, robot.A)
    assert np.array_equal(back.set_force_lo, lo, equal_nan=True)
    exact = isotropic_map(robot.nominal(), xs, ys)
    assert exact.set_force_lo is None and "set_force_lo" not in exact.to_dict()
