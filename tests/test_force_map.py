"""Isotropic-force maps: vectorised values equal the single-pose computation; pictures."""

from pathlib import Path

import numpy as np
import pytest

from certsolve.force import isotropic_force, isotropic_map
from certsolve.force.plots import plot_map, plot_maps
from certsolve.robot import Pose, Robot
from certsolve.robot.geometry import rotation_2d

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"


def load(name: str) -> Robot:
    return Robot.load(ROBOTS / f"{name}.json")


@pytest.mark.parametrize("name", ["krut-3", "krut-6"])
def test_map_matches_single_poses(name):
    robot = load(name)
    xs = np.linspace(-100, 100, 41)
    ys = np.linspace(-90, 90, 31)
    m = isotropic_map(robot, xs, ys)
    assert m.values.shape == (31, 41)
    rng = np.random.default_rng(0)
    for _ in range(25):
        i, j = rng.integers(41), rng.integers(31)
        ref = isotropic_force(robot, Pose.from_params(2, [xs[i], ys[j]]))
        assert m.values[j, i] == pytest.approx(ref.isotropic_force, rel=1e-9, abs=1e-9)
        assert (m.status[j, i] == 0) == (ref.status == "inside")
    # the centre is the best pose of the symmetric robots; far corners are outside
    k = int(np.argmin(np.abs(xs)))
    assert np.nanargmax(m.values[15]) == k
    assert m.values[0, 0] < 0


def test_map_rigid_platforms_with_orientation():
    planar = load("planar")
    xs = np.linspace(20, 160, 8)
    ys = np.linspace(20, 100, 6)
    m = isotropic_map(planar, xs, ys, rotation=5.0)
    R = rotation_2d(np.radians(5.0))
    for i, j in [(3, 2), (5, 4), (0, 0)]:
        ref = isotropic_force(planar, Pose(np.array([xs[i], ys[j]]), R))
        assert m.values[j, i] == pytest.approx(ref.isotropic_force, rel=1e-9, abs=1e-12)
    mar = load("marionet")
    m6 = isotropic_map(
        mar, np.linspace(60, 160, 6), np.linspace(40, 100, 5), z=107.0, rotation=[5.0, 0.0, -3.0]
    )
    ref = isotropic_force(mar, [m6.xs[2], m6.ys[3], 107.0, 5.0, 0.0, -3.0])
    assert m6.values[3, 2] == pytest.approx(ref.isotropic_force, rel=1e-9)
    assert m6.to_dict()["summary"]["poses"] == 30


def test_map_errors():
    robot = load("krut-3")
    with pytest.raises(ValueError, match="z"):
        isotropic_map(robot, [0.0], [0.0], z=3.0)
    with pytest.raises(ValueError, match="rotation"):
        isotropic_map(robot, [0.0], [0.0], rotation=10.0)
    with pytest.raises(ValueError, match="empty"):
        isotropic_map(robot, [], [0.0])


def test_plots_write_png(tmp_path):
    maps = [
        isotropic_map(load(n), np.linspace(-100, 100, 41), np.linspace(-100, 100, 41))
        for n in ("krut-4", "krut-5")
    ]
    p1 = tmp_path / "one.png"
    p2 = tmp_path / "two.png"
    plot_map(maps[0], p1)
    plot_maps(maps, p2, titles=["4", "5"])
    for p in (p1, p2):
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
