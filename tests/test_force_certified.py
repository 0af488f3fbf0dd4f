"""Certified isotropic-force workspace: every proven box is checked by sampling poses.

A box labelled inside must not contain a pose whose pointwise index (computed in floats by
:func:`isotropic_values`) is below ``f_req``; a box labelled outside must not contain one at
or above it.  The paving must also be a partition of the initial box.
"""

from pathlib import Path

import numpy as np
import pytest

from certsolve.force import certified_workspace, isotropic_map, isotropic_values
from certsolve.force.enclosure import slack_enclosures
from certsolve.robot import Robot
from certsolve.robot.geometry import rotation_2d, rotation_zyx

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"


def load(name: str) -> Robot:
    return Robot.load(ROBOTS / f"{name}.json")


def sample_boxes(boxes, rng, n):
    """``n`` random points per box plus its corners (position and angle axes)."""
    lo, hi = boxes[..., 0], boxes[..., 1]
    u = rng.random((len(boxes), n, boxes.shape[1]))
    corners = np.array(np.meshgrid(*[[0.0, 1.0]] * boxes.shape[1])).reshape(boxes.shape[1], -1).T
    u = np.concatenate([u, np.broadcast_to(corners, (len(boxes),) + corners.shape)], axis=1)
    return (lo[:, None, :] + u * (hi - lo)[:, None, :]).reshape(-1, boxes.shape[1])


def pointwise(robot, X):
    d = robot.dim
    if robot.dof == 2:
        return isotropic_values(robot, X[:, :d])[0]
    ang = np.radians(X[:, d:])
    R = rotation_2d(ang[:, 0]) if robot.dof == 3 else rotation_zyx(ang[:, 0], ang[:, 1], ang[:, 2])
    return isotropic_values(robot, X[:, :d], R)[0]


def check_paving(robot, ws, rng, n=12):
    f_req = ws.min_force
    if len(ws.inside):
        f = pointwise(robot, sample_boxes(ws.inside, rng, n))
        assert np.all(f >= f_req), f"inside box with f = {np.nanmin(f)} < {f_req}"
    if len(ws.outside):
        f = pointwise(robot, sample_boxes(ws.outside, rng, n))
        assert not np.any(f >= f_req), f"outside box with f = {np.nanmax(f)} >= {f_req}"
    # partition: measures add up and random points fall in exactly one box
    parts = [ws.inside, ws.outside, ws.boundary, ws.pending]
    total = sum(ws._measure(p) for p in parts)
    assert total == pytest.approx(ws.total_measure, rel=1e-9)
    full = np.concatenate([ws.box, ws.angles]) if ws.angles.size else ws.box
    pts = full[:, 0] + rng.random((300, full.shape[0])) * (full[:, 1] - full[:, 0])
    allb = np.concatenate([p for p in parts if len(p)])
    inb = np.all(
        (pts[:, None, :] >= allb[None, :, :, 0]) & (pts[:, None, :] <= allb[None, :, :, 1]), axis=2
    )
    assert np.all(inb.sum(axis=1) >= 1)


@pytest.mark.parametrize("name, f_req", [("krut-3", 100.0), ("krut-5", 300.0), ("krut-6", 50.0)])
def test_planar_point_paving_is_sound(name, f_req):
    robot = load(name)
    ws = certified_workspace(robot, f_req, [-100, 100, -100, 100], 2.0)
    assert ws.complete and len(ws.inside) > 50 and len(ws.outside) > 50
    check_paving(robot, ws, np.random.default_rng(1))
    # the proven area is below, and close to, the area of {f >= f_req} on a fine grid
    xs = np.linspace(-100, 100, 401)
    m = isotropic_map(robot, xs, xs)
    grid_share = float(np.mean(m.values >= f_req))
    assert ws.inside_share <= grid_share + 0.01
    assert ws.inside_share >= 0.8 * grid_share


def test_krut3_share_converges_with_eps():
    robot = load("krut-3")
    coarse = certified_workspace(robot, 100.0, [-100, 100, -100, 100], 4.0)
    fine = certified_workspace(robot, 100.0, [-100, 100, -100, 100], 1.0)
    assert fine.inside_share >= coarse.inside_share
    assert fine._measure(fine.boundary) < coarse._measure(coarse.boundary)


def test_point_enclosures_contain_float_slacks():
    """dof 2: the interval g's enclose the float g's computed here from scratch."""
    robot = load("krut-4")
    rng = np.random.default_rng(4)
    c = rng.uniform(-60, 60, (50, 2))
    h = rng.uniform(0.01, 5.0, (50, 1))
    lo, hi = c - h, c + h
    f_req = 150.0
    glo, ghi, _, _ = slack_enclosures(robot, lo.T, hi.T, f_req)
    A, tmin, tmax = robot.A, robot.tau_min, robot.tau_max
    for k in range(50):
        for p in lo[k] + rng.random((20, 2)) * (hi[k] - lo[k]):
            a = A - p
            rho = np.linalg.norm(a, axis=1)
            cj = np.stack([a[:, 1], -a[:, 0]], axis=1)  # (m, 2): c_j = perp(a_j)
            s = cj @ (a / rho[:, None]).T  # s[j, i] = c_j · h_i
            gp = np.sum(np.maximum(s * tmin, s * tmax), axis=1) - f_req * rho
            gm = np.sum(np.maximum(-s * tmin, -s * tmax), axis=1) - f_req * rho
            g = np.concatenate([gp, gm])
            assert np.all(glo[:, k] <= g + 1e-9 * np.abs(g)) and np.all(
                g <= ghi[:, k] + 1e-9 * np.abs(g)
            )


def test_planar_rigid_paving_is_sound():
    robot = load("planar")
    ws = certified_workspace(robot, 1.0, [30, 150, 20, 100], 2.0)
    assert ws.complete and len(ws.inside) > 20 and len(ws.outside) > 5
    check_paving(robot, ws, np.random.default_rng(2))


def test_planar_rigid_with_orientation_range():
    robot = load("planar")
    ws = certified_workspace(
        robot, 2.0, [60, 120, 40, 80], 3.0, orientation=(-8.0, 8.0), eps_angle=2.0
    )
    assert len(ws.inside) > 5
    assert ws.to_dict()["angles"]["theta"] == [-8.0, 8.0]
    check_paving(robot, ws, np.random.default_rng(3), n=6)


def test_marionet_small_box_is_sound():
    robot = load("marionet")
    ws = certified_workspace(robot, 2.0, [100, 122, 48, 68, 96, 118], 3.0)
    assert len(ws.inside) > 10
    check_paving(robot, ws, np.random.default_rng(4), n=4)


def test_progress_can_stop_and_timeout():
    robot = load("krut-3")
    seen = []

    def progress(p):
        seen.append((p.boxes, p.pending))
        return False

    ws = certified_workspace(robot, 100.0, [-100, 100, -100, 100], 0.5, progress=progress, batch=64)
    assert ws.status == "cancelled" and len(ws.pending) > 0 and len(seen) == 1
    assert seen[0] == (1, len(ws.pending))  # the root box, split in two
    check_paving(robot, ws, np.random.default_rng(5), n=2)
    ws = certified_workspace(robot, 100.0, [-100, 100, -100, 100], 1e-3, timeout=0.2)
    assert ws.status == "timeout" and not ws.complete
    d = ws.to_dict(boxes=False)
    assert d["complete"] is False and "inside_boxes" not in d


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(min_force=0.0), "min_force"),
        (dict(eps=-1.0), "eps"),
        (dict(box=[0, 1, 0]), "box"),
        (dict(box=[1, 0, 0, 1]), "box"),
        (dict(orientation=5.0), "orientation"),
    ],
)
def test_errors(kwargs, match):
    args = dict(min_force=10.0, box=[-10, 10, -10, 10], eps=1.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        certified_workspace(load("krut-3"), **args)


@pytest.mark.slow
def test_marionet_larger_paving_with_angles_is_sound():
    robot = load("marionet")
    ws = certified_workspace(
        robot,
        1.0,
        [95, 125, 45, 75, 95, 125],
        3.0,
        orientation=[(-2, 2), (-2, 2), 0.0],
        eps_angle=2.0,
        timeout=600,
    )
    assert len(ws.inside) > 10
    check_paving(robot, ws, np.random.default_rng(6), n=3)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["krut-4", "planar"])
def test_fine_pavings_are_sound(name):
    robot = load(name)
    box = [-100, 100, -100, 100] if name.startswith("krut") else [0, 180, 0, 120]
    ws = certified_workspace(robot, 200.0 if name.startswith("krut") else 1.0, box, 0.5)
    check_paving(robot, ws, np.random.default_rng(7), n=20)


def test_external_wrench_is_proven_with_its_bias():
    robot = load("krut-3")
    w = np.array([60.0, -25.0])
    ws = certified_workspace(robot, 80.0, [-100, 100, -100, 100], 2.0, external=w)
    assert len(ws.inside) > 20
    rng = np.random.default_rng(8)
    f = isotropic_values(robot, sample_boxes(ws.inside, rng, 10)[:, :2], external=w)[0]
    assert np.all(f >= 80.0)
    f = isotropic_values(robot, sample_boxes(ws.outside, rng, 10)[:, :2], external=w)[0]
    assert not np.any(f >= 80.0)
