"""``certsolve isotropic`` and ``certsolve workspace``: JSON output and clean user errors."""

import json
from math import sqrt
from pathlib import Path

import pytest

from certsolve.cli import main

ROBOTS = Path(__file__).resolve().parents[1] / "examples" / "robots"
KRUT3 = str(ROBOTS / "krut-3.json")
MARIONET = str(ROBOTS / "marionet.json")


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_isotropic_at_json(capsys):
    code, out, _ = run(capsys, "isotropic", KRUT3, "--at", "0,0", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["isotropic_force"] == pytest.approx(225 * sqrt(3), rel=1e-12)
    assert d["status"] == "inside" and len(d["polytope"]["facets"]) == 6


def test_isotropic_grid_has_the_command_lines_ceiling_not_the_services(capsys):
    """The CLI runs the isotropic-map operation with its own grid limit (5000 a side); the
    job keeps the service's (MAX_GRID_SIDE)."""
    from pydantic import ValidationError

    from certsolve.jobs.kinds.isotropic_map import MAX_GRID_SIDE, IsotropicMapParams

    side = MAX_GRID_SIDE + 1
    with pytest.raises(ValidationError, match="nx"):
        IsotropicMapParams.model_validate({"grid": [0, 1, 0, 1], "nx": side, "ny": 1})
    code, out, _ = run(capsys, "isotropic", KRUT3, "--grid", f"0,1,0,1,{side},1", "--json")
    d = json.loads(out)
    assert code == 0 and len(d["xs"]) == side and d["summary"]["poses"] == side


def test_isotropic_at_text_krut_algorithm(capsys):
    code, out, _ = run(capsys, "isotropic", KRUT3, "--at", "0,0", "--algorithm", "krut")
    assert code == 0 and "389.711" in out and "krut2004" in out


def test_isotropic_marionet_pose_with_angles(capsys):
    code, out, _ = run(capsys, "isotropic", MARIONET, "--at", "111,58,107,0,0,5", "--json")
    d = json.loads(out)
    assert code == 0 and d["dof"] == 6 and d["isotropic_force"] > 0
    assert d["centre"][2] == pytest.approx(0.02 * 9.81)


def test_isotropic_grid_with_plot(capsys, tmp_path):
    png = tmp_path / "map.png"
    code, out, _ = run(
        capsys,
        "isotropic",
        KRUT3,
        "--grid",
        "-100,100,-100,100,21,11",
        "--plot",
        str(png),
        "--json",
    )
    d = json.loads(out)
    assert code == 0 and len(d["isotropic_force"]) == 11 and len(d["isotropic_force"][0]) == 21
    assert png.read_bytes()[:4] == b"\x89PNG"
    # negative bounds also work with a space (not only --grid=-100,...)
    assert d["xs"][0] == -100.0


def test_workspace_json_and_plot(capsys, tmp_path):
    png = tmp_path / "paving.png"
    code, out, _ = run(
        capsys,
        "workspace",
        KRUT3,
        "--min-force",
        "100",
        "--box",
        "-100,100,-100,100",
        "--eps",
        "4",
        "--json",
        "--no-boxes",
        "--plot",
        str(png),
    )
    d = json.loads(out)
    assert code == 0 and d["complete"] and 0.1 < d["inside_share"] < 0.25
    assert "inside_boxes" not in d and png.exists()


def test_workspace_marionet_orientation_ranges(capsys):
    code, out, _ = run(
        capsys,
        "workspace",
        MARIONET,
        "--min-force",
        "1",
        "--box",
        "105,115,53,63,102,112",
        "--eps",
        "5",
        "--orientation",
        "-1:1,0,-1:1",
        "--eps-angle",
        "2",
        "--max-boxes",
        "20",
        "--json",
        "--no-boxes",
    )
    d = json.loads(out)
    assert code == 0 and d["angles"] == {
        "yaw": [-1.0, 1.0],
        "pitch": [0.0, 0.0],
        "roll": [-1.0, 1.0],
    }
    assert d["boxes"] <= 20 + 1024


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["isotropic", KRUT3, "--at", "1"], "--at"),
        (["isotropic", KRUT3, "--at", "a,b"], "--at"),
        (["isotropic", KRUT3, "--grid", "0,1,0"], "--grid"),
        (["isotropic", KRUT3, "--grid", "1,0,0,1"], "--grid"),
        (["isotropic", KRUT3, "--grid", "0,1,0,1,0,5"], "--grid"),
        (
            ["isotropic", KRUT3, "--grid", "0,1,0,1,5001,1"],
            "--grid: must be less than or equal to 5000",
        ),
        (["isotropic", KRUT3, "--grid", "0,1,0,1,2.5,3"], "--grid: nx and ny must be integers"),
        (["isotropic", KRUT3, "--grid", "0,1,0,1", "--z", "3"], "--z"),
        (["isotropic", KRUT3, "--grid", "0,1,0,1", "--orientation", "3"], "--orientation"),
        (["isotropic", KRUT3, "--at", "0,0", "--external", "1"], "--external"),
        (["isotropic", MARIONET, "--at", "100,50,100", "--algorithm", "krut"], "--algorithm"),
        (["isotropic", "/nonexistent/robot.json", "--at", "0,0"], "robot.json"),
        (["workspace", KRUT3, "--min-force", "0", "--box", "0,1,0,1", "--eps", "1"], "--min-force"),
        (["workspace", KRUT3, "--min-force", "1", "--box", "0,1,0,1", "--eps", "0"], "--eps"),
        (["workspace", KRUT3, "--min-force", "1", "--box", "0,1,0", "--eps", "1"], "--box"),
        (
            [
                "workspace",
                str(ROBOTS / "planar.json"),
                "--min-force",
                "1",
                "--box",
                "0,1,0,1",
                "--eps",
                "1",
                "--orientation",
                "2:1",
            ],
            "--orientation",
        ),
        (
            [
                "workspace",
                str(ROBOTS / "almost-planar.json"),
                "--min-force",
                "1",
                "--box",
                "0,1,0,1,0,1",
                "--eps",
                "1",
            ],
            "4 wires",
        ),
    ],
)
def test_user_errors_are_one_line(capsys, argv, needle):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and needle in err and "Traceback" not in err
