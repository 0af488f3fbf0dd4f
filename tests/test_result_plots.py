"""Pictures of results read back from their JSON: the forward-kinematics poses (Merlet's
Figs. 4-8) and the maps and pavings rebuilt by ``from_dict`` (what the service draws)."""

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "examples/robots"
KRUT3 = json.loads((ROBOTS / "krut-3.json").read_text())
PNG = b"\x89PNG\r\n\x1a\n"


# -- the results read back for drawing -------------------------------------------------------------
def test_isotropic_map_from_dict_round_trip():
    from certsolve.force.maps import IsotropicMap, isotropic_map
    from certsolve.robot.model import Robot

    robot = Robot.load(KRUT3)
    m = isotropic_map(robot, np.linspace(-120, 120, 9), np.linspace(-120, 60, 7))
    assert (m.status != 0).any() and (m.status == 0).any()  # both sides of the boundary
    back = IsotropicMap.from_dict(json.loads(json.dumps(m.to_dict())), robot.A)
    np.testing.assert_array_equal(back.values, m.values)
    np.testing.assert_array_equal(back.status, m.status)
    np.testing.assert_array_equal(back.xs, m.xs)
    assert back.summary()["inside"] == m.summary()["inside"]
    with pytest.raises(ValueError, match="without its values"):
        IsotropicMap.from_dict(m.to_dict(values=False), robot.A)


def test_workspace_from_dict_round_trip():
    from certsolve.force.certified import CertifiedWorkspace, certified_workspace
    from certsolve.robot.model import Robot

    robot = Robot.load(KRUT3)
    ws = certified_workspace(robot, 100.0, [[-90, 90], [-100, 50]], 15.0)
    back = CertifiedWorkspace.from_dict(json.loads(json.dumps(ws.to_dict())))
    for key in ("inside", "outside", "boundary", "pending", "box"):
        np.testing.assert_array_equal(getattr(back, key), getattr(ws, key))
    assert back.to_dict() == {**ws.to_dict(), "time": back.time}
    with pytest.raises(ValueError, match="without its boxes"):
        CertifiedWorkspace.from_dict(ws.to_dict(boxes=False))


# -- drawing a pose --------------------------------------------------------------------------------
def test_platform_outline():
    from certsolve.kinematics.plots import _hull_faces

    cube = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
    faces = _hull_faces(cube)
    assert len(faces) == 12 and all(len(f) == 3 for f in faces)  # 6 squares, 2 triangles each
    square = np.array([[0, 0, 5], [1, 1, 5], [1, 0, 5], [0, 1, 5]], dtype=float)  # in a plane
    (face,) = _hull_faces(square)
    assert sorted(face) == [0, 1, 2, 3] and set(face[[0, 2]]) in ({0, 1}, {2, 3})  # in order
    line = np.array([[0, 0, 0], [2, 2, 2], [1, 1, 1]], dtype=float)
    assert [sorted(f) for f in _hull_faces(line)] == [[0, 1]]
    assert [list(f) for f in _hull_faces(np.ones((3, 2)))] == [[0]]


def test_plot_pose_of_a_spatial_robot(tmp_path):
    """The T-platform: 7 wires on 3 distinct points, drawn in 3-D (the level middle pose)."""
    from certsolve.kinematics.fk import FKPose
    from certsolve.kinematics.plots import _distinct_attachments, plot_pose, plot_poses
    from certsolve.robot.model import Robot

    robot = Robot.load(ROBOTS / "marionet-t.json")
    position = np.array([115.0, 60.0, 118.0])
    points = position + robot.B
    assert len(_distinct_attachments(robot, points)) == 3
    rho = np.linalg.norm(robot.A - points, axis=1)
    pose = FKPose(
        position=position, rotation=np.eye(3), platform_points=points, rho=rho,
        tau=np.linspace(1, 9, 7), box=[], variables=[],
    )  # fmt: skip
    plot_pose(robot, pose, tmp_path / "pose.png", number=(1, 1))
    plot_poses(robot, [pose, pose], tmp_path / "poses.png")
    for name in ("pose.png", "poses.png"):
        assert (tmp_path / name).read_bytes().startswith(PNG)
