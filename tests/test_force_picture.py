"""The force picture at one pose (Krut 2004, Fig. 4): the geometry that is drawn is checked
against independent computations (box vertices mapped by H, distances to the polygon's
edges), and the CLI writes a PNG."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from certsolve.cli import main
from certsolve.force import isotropic_force
from certsolve.force.krut import box_vertices
from certsolve.force.picture import force_picture, halfplane_polygon
from certsolve.robot import Pose, Robot, wrench_matrix

CASES = [
    ("examples/robots/krut-3.json", [30.0, 20.0]),
    ("examples/robots/krut-5.json", [-40.0, 10.0]),
    ("examples/robots/planar.json", [95.0, 55.0, 3.0]),
    ("examples/robots/marionet.json", [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]),
    ("examples/robots/marionet.json", [100.0, 50.0, 100.0, 5.0, -2.0, 3.0]),
]


def edge_distances(poly: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Signed distances from ``x`` to the edge lines of a counter-clockwise polygon."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    e = b - a
    normal = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    return np.einsum("ij,ij->i", a - x, normal)


@pytest.mark.parametrize("path, pose", CASES)
def test_drawn_circle_is_the_isotropic_force(path, pose):
    robot = Robot.load(path)
    res = isotropic_force(robot, pose, ellipse=True)
    pic = force_picture(res)
    r = res.isotropic_force
    assert r is not None and r > 0
    assert len(pic.panels) == (3 if robot.dof == 6 else 1)
    weight = robot.mass * robot.gravity
    assert np.allclose(pic.centre, -weight[: len(pic.centre)], atol=1e-12)
    for panel in pic.panels:
        assert panel.radius == r
        poly = panel.polygon
        assert poly is not None and len(poly) >= 3
        dist = edge_distances(poly, panel.centre)
        assert np.all(dist > 0)  # counter-clockwise, centre inside
        if robot.dof == 6:  # a section through the centre: the great circle fits inside
            assert dist.min() >= r * (1 - 1e-9)
        else:  # the polygon is the polytope itself: its inscribed radius about x0 is r
            assert dist.min() == pytest.approx(r, rel=1e-9)
        # the ellipse lies inside the polygon (and touches it in the plane of a 2-D polytope)
        ell = panel.ellipse
        assert ell is not None
        inside = min(edge_distances(poly, p).min() for p in ell)
        assert inside >= -1e-6 * r
        if robot.dof != 6:
            assert inside <= 1e-3 * r


@pytest.mark.parametrize("path, pose", CASES[:3])
def test_polygon_is_the_polytope(path, pose):
    """dof 2: the hull of H τ over the box vertices; dof 3: the section's hull vertices."""
    robot = Robot.load(path)
    res = isotropic_force(robot, pose)
    poly = force_picture(res).panels[0].polygon
    if robot.dof == 2:
        P = Pose.from_params(2, pose)
        H = wrench_matrix(robot, P.position[None], P.rotation[None])[0]
        pts = box_vertices(robot.tau_min, robot.tau_max) @ H.T
        ref = pts[ConvexHull(pts).vertices]
    else:
        ref = res.polytope.vertices
    assert len(ref) == len(poly)
    for v in ref:
        assert np.min(np.linalg.norm(poly - v, axis=1)) <= 1e-7 * (1 + np.abs(v).max())


def test_halfplane_polygon_square_and_empty():
    N = np.array([[1.0, 0], [-1, 0], [0, 1], [0, -1]])
    sq = halfplane_polygon(N, [1.0, 1, 2, 0])
    assert sq.shape == (4, 2)
    assert {tuple(np.round(p, 12)) for p in sq} == {(1, 0), (1, 2), (-1, 2), (-1, 0)}
    assert halfplane_polygon(N, [1.0, -2, 1, 1]) is None  # x <= 1 and x >= 2
    assert halfplane_polygon(N[:2], [1.0, 1]) is None


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("robot, at", [("krut-3", "30,20"), ("marionet", "111,58,107")])
def test_cli_writes_png(capsys, tmp_path, robot, at):
    png = tmp_path / "pose.png"
    code, out, err = run(
        capsys, "isotropic", f"examples/robots/{robot}.json", "--at", at, "--plot", str(png),
        "--ellipse", "--json",
    )  # fmt: skip
    assert code == 0 and err == ""
    d = json.loads(out)
    assert d["plot"] == str(png) and d["ellipse"] is not None
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, _ = run(capsys, "isotropic", f"examples/robots/{robot}.json", "--at", at)
    assert code == 0 and "wrote" not in out


def test_cli_grid_options_rejected_with_at(capsys):
    code, _, err = run(
        capsys, "isotropic", "examples/robots/krut-3.json", "--at", "0,0", "--vmax", "100"
    )
    assert code == 2 and "--vmax goes with --grid" in err and err.count("\n") == 1
