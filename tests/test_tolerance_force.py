"""The certified force workspace of a robot known within tolerances (issue 31, item 4): a
region is ``good`` only if the isotropic force is >= F for every robot of the set."""

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.force.certified import certified_workspace
from certsolve.force.isotropic import isotropic_force
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


WEIGHT = [
    {"path": "platform.mass", "plus_minus": 0.002},
    {"path": "platform.center_of_mass[*]", "plus_minus": 0.5},
]


def _t16(extra):
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    data["tolerances"] += extra
    return Robot.load(data)


def test_the_weight_box_has_its_corners():
    from certsolve.robot.params import RobotBounds

    exact = RobotBounds.of_tolerances(_t16([]))
    masses, coms = exact.weight_corners()
    assert masses.tolist() == [0.02] and coms.tolist() == [[0.0, 0.0, 0.0]]
    both = RobotBounds.of_tolerances(_t16(WEIGHT))
    masses, coms = both.weight_corners()
    assert masses.shape == (16,) and coms.shape == (16, 3)
    assert (
        set(masses) == {both.mass[0], both.mass[1]}
        and both.mass[0] <= 0.018 < 0.022 <= both.mass[1]
    )
    assert len({tuple(c) for c in coms}) == 8 and np.all(np.abs(coms) >= 0.5)


def test_the_force_at_a_pose_holds_for_every_mass_and_centre_of_mass():
    """A toleranced mass and centre of mass (the weight's wrench; planar robots have none):
    the set's certified bound is at most the force of every robot drawn from the set
    (corners and random draws, each an exact robot), and close to the least of them."""
    robot = _t16(WEIGHT)
    rng = np.random.default_rng(7)
    drawn = [robot.draw(rng, corner=i % 2 == 0) for i in range(12)]
    for pose in ([115, 60, 118, 0, 0, 0], [112, 63, 110, 4, -3, 2]):
        res = isotropic_force(robot, pose)
        least = min(isotropic_force(r, pose).isotropic_force for r in drawn)
        assert res.set_force_lo is not None and 0.9 * least < res.set_force_lo <= least


def test_the_map_bound_holds_for_every_mass_and_centre_of_mass():
    from certsolve.force.isotropic import set_force_floor

    robot = _t16(WEIGHT)
    positions = np.array([[115, 60, 118], [105, 55, 110], [125, 65, 112], [110, 70, 120]])
    floor = set_force_floor(robot, positions)
    rng = np.random.default_rng(8)
    drawn = [robot.draw(rng, corner=i % 2 == 0) for i in range(10)]
    least = np.min(
        [
            [isotropic_force(r, list(p) + [0, 0, 0]).isotropic_force for p in positions]
            for r in drawn
        ],
        axis=0,
    )
    assert np.all(np.isfinite(floor)) and np.all(floor <= least) and np.all(floor > 0.8 * least)
    # the weight's box costs force: the floor with an exact mass and centre of mass is higher
    assert np.all(set_force_floor(_t16([]), positions) > floor)


def test_a_workspace_good_for_the_set_is_good_for_its_robots():
    robot = _t16(WEIGHT)
    box = [100, 130, 45, 75, 100, 130]
    ws = certified_workspace(robot, 5.0, box, 5.0)
    nominal = certified_workspace(robot.nominal(), 5.0, box, 5.0)
    assert ws.status == "complete" and len(ws.inside)
    assert ws.inside_share < nominal.inside_share
    rng = np.random.default_rng(9)
    robots = [robot.draw(rng, corner=i % 2 == 0) for i in range(6)]
    boxes = ws.inside[rng.choice(len(ws.inside), size=min(12, len(ws.inside)), replace=False)]
    for b in boxes:
        p = b[:3, 0] + rng.random(3) * (b[:3, 1] - b[:3, 0])
        for r in robots:
            f = isotropic_force(r, list(p) + [0, 0, 0]).isotropic_force
            assert f is not None and f >= 5.0 * (1 - 1e-9)


def test_a_zero_tolerance_on_the_weight_gives_the_exact_bits():
    """``platform.mass`` and ``platform.center_of_mass`` at ``plus_minus: 0`` give the
    enclosures of the robot without them, bit for bit (one corner: the nominal weight)."""
    from certsolve.force.enclosure import slack_enclosures
    from certsolve.robot.params import RobotBounds

    zero = [{**t, "plus_minus": 0.0} for t in WEIGHT]
    a, b = _t16([]), _t16(zero)
    rng = np.random.default_rng(10)
    p = np.array([[115.0], [60.0], [118.0]]) + rng.uniform(-8, 8, (3, 24))
    ang = rng.uniform(-4, 4, (3, 24))
    for prm in (RobotBounds.of_tolerances, RobotBounds.point):
        ga = slack_enclosures(a, p - 1, p + 1, 2.0, None, ang, ang + 1, params=prm(a), norms=True)
        gb = slack_enclosures(b, p - 1, p + 1, 2.0, None, ang, ang + 1, params=prm(b), norms=True)
        for x, y in zip(ga, gb, strict=True):
            assert np.array_equal(x, y)
    box = [105, 125, 50, 70, 105, 125]
    wa, wb = certified_workspace(a, 5.0, box, 5.0), certified_workspace(b, 5.0, box, 5.0)
    assert len(wa.inside) and len(wa.boundary)
    assert np.array_equal(wa.inside, wb.inside) and np.array_equal(wa.boundary, wb.boundary)


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


def test_the_map_picture_of_a_set_draws_the_set_bound():
    """``plot_map`` of a robot with tolerances draws ``set_force_lo`` (what holds for every
    robot of the set), says so on its colour bar, and the nominal values otherwise."""
    pytest.importorskip("matplotlib")
    from certsolve.force.maps import isotropic_map
    from certsolve.force.plots import plot_map

    robot = _krut3([{"path": "wires[*].base[*]", "plus_minus": 1.0}])
    xs, ys = np.linspace(-60, 60, 7), np.linspace(-80, 40, 7)
    for res, label in (
        (isotropic_map(robot, xs, ys), "certified lower bound over the set (N)"),
        (isotropic_map(robot.nominal(), xs, ys), "maximum isotropic force (N)"),
    ):
        fig = plot_map(res)
        ax, bar = fig.axes
        drawn = ax.images[0].get_array()
        shown = res.values if res.set_force_lo is None else res.set_force_lo
        assert np.array_equal(
            drawn.filled(np.nan), np.where(shown >= 0, shown, np.nan), equal_nan=True
        )
        assert bar.get_ylabel() == label
