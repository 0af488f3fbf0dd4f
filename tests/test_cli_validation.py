"""One validation for the command line and the service: the CLI builds the job kinds' own
parameter models, so an option is refused exactly when the same value in a job request is,
with the same message, naming the option instead of the field."""

import json
from pathlib import Path

import pytest
from pydantic import ValidationError

from certsolve.cli import main
from certsolve.jobs.errors import validation_details
from certsolve.jobs.kinds import request_adapter

ROOT = Path(__file__).resolve().parents[1]
CIRCLE_FILE = str(ROOT / "examples/systems/circle-line.mbx")
PLANAR_FILE = str(ROOT / "examples/robots/planar.json")
KRUT3_FILE = str(ROOT / "examples/robots/krut-3.json")
CIRCLE = Path(CIRCLE_FILE).read_text()
PLANAR = json.loads(Path(PLANAR_FILE).read_text())
KRUT3 = json.loads(Path(KRUT3_FILE).read_text())
U = "0.5,0.5,0.5,0.5"

CASES = [
    # (argv, job request, option, field)
    (
        ["solve", CIRCLE_FILE, "--timeout", "-1"],
        {"kind": "solve", "system": CIRCLE, "params": {"timeout": -1}},
        "--timeout",
        "params.timeout",
    ),
    (
        ["solve", CIRCLE_FILE, "--eps", "0"],
        {"kind": "solve", "system": CIRCLE, "params": {"eps": 0}},
        "--eps",
        "params.eps",
    ),
    (
        ["solve", CIRCLE_FILE, "--max-boxes", "0"],
        {"kind": "solve", "system": CIRCLE, "params": {"max_boxes": 0}},
        "--max-boxes",
        "params.max_boxes",
    ),
    (
        ["fk", PLANAR_FILE, "--u", U, "--tau-max", "-5"],
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.5] * 4, "tau_max": -5}},
        "--tau-max",
        "params.tau_max",
    ),
    (
        ["fk", PLANAR_FILE, "--u", U, "--tau-max", "nan"],
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.5] * 4, "tau_max": float("nan")}},
        "--tau-max",
        "params.tau_max",
    ),
    (
        ["fk", PLANAR_FILE, "--u", "1e300,0.5,0.5,0.5"],
        {"kind": "fk", "robot": PLANAR, "params": {"u": [1e300, 0.5, 0.5, 0.5]}},
        "--u, number 1",
        "params.u.0",
    ),
    (
        ["fk", PLANAR_FILE, "--u", "0.5,0.5"],
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.5, 0.5]}},
        "--u",
        "params.u",
    ),
    (
        ["fk", PLANAR_FILE, "--u", U, "--eps", "inf"],
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.5] * 4, "eps": float("inf")}},
        "--eps",
        "params.eps",
    ),
    (
        ["ik", PLANAR_FILE, "--pose", "1,2,3,4"],
        {"kind": "ik", "robot": PLANAR, "params": {"pose": [1, 2, 3, 4]}},
        "--pose",
        "params.pose",
    ),
    (
        ["workspace", KRUT3_FILE, "--min-force", "-1", "--box", "0,1,0,1", "--eps", "1"],
        {
            "kind": "workspace",
            "robot": KRUT3,
            "params": {"min_force": -1, "box": [[0, 1], [0, 1]], "eps": 1},
        },
        "--min-force",
        "params.min_force",
    ),
    (
        ["workspace", KRUT3_FILE, "--min-force", "1", "--box", "0,1,0,1,0,1", "--eps", "1"],
        {
            "kind": "workspace",
            "robot": KRUT3,
            "params": {"min_force": 1, "box": [[0, 1], [0, 1], [0, 1]], "eps": 1},
        },
        "--box",
        "params.box",
    ),
    (
        ["workspace", KRUT3_FILE, "--min-force", "1", "--box", "0,1,0,1", "--eps", "1",
         "--eps-angle", "400"],
        {
            "kind": "workspace",
            "robot": KRUT3,
            "params": {"min_force": 1, "box": [[0, 1], [0, 1]], "eps": 1, "eps_angle": 400},
        },
        "--eps-angle",
        "params.eps_angle",
    ),
]  # fmt: skip


def job_error(request: dict) -> tuple[str, str]:
    """``(field, message)`` of the (single) problem the service finds in ``request``."""
    with pytest.raises(ValidationError) as info:
        request_adapter().validate_python(request)
    (d,) = validation_details(info.value.errors(), ("body",))
    return d["field"], d["msg"]


@pytest.mark.parametrize("argv, request_, option, field", CASES)
def test_cli_refuses_what_the_service_refuses(capsys, argv, request_, option, field):
    got_field, msg = job_error(request_)
    assert got_field == field
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err == f"error: {option}: {msg}\n", err


def test_messages_read_must_be():
    assert job_error({"kind": "solve", "system": CIRCLE, "params": {"timeout": -1}}) == (
        "params.timeout",
        "must be greater than 0",
    )
    field, msg = job_error(
        {"kind": "fk", "robot": PLANAR, "params": {"u": [0.5] * 4, "tau_max": float("nan")}}
    )
    assert msg == "must be a finite number"


def test_robot_checks_are_shared_by_every_request_with_a_robot():
    """The one check against the robot runs for jobs and for the quick calls' bodies."""
    from certsolve.jobs.kinds import IsotropicCall, TrackCall

    with pytest.raises(ValidationError, match="params.near_pose"):
        TrackCall.model_validate({"robot": PLANAR, "params": {"u": [0] * 4, "near_pose": [1]}})
    with pytest.raises(ValidationError, match="expected 3 wrench components, got 2"):
        IsotropicCall.model_validate(
            {"robot": PLANAR, "params": {"pose": [90, 60, 0], "external": [1, 2]}}
        )
    assert job_error(
        {"kind": "isotropic-map", "robot": PLANAR, "params": {"grid": [0, 1, 0, 1], "z": 3}}
    ) == ("params.z", "a dof-3 robot is planar (no z)")


def test_valid_options_still_run(capsys):
    assert main(["solve", CIRCLE_FILE, "--timeout", "30", "--eps", "1e-9"]) == 0
    out = capsys.readouterr().out
    assert "complete, 2 solution(s)" in out
