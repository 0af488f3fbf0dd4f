"""One validation for Python, the command line and HTTP: the library's entry points refuse
what the job kinds and the quick calls refuse, with the same message, as an ``InputError``
(a ``ValueError``) whose ``field`` names the value; and they take what the docs write --
a system as a path or Minibex text, a pose as a plain list, tuple or array."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

import certsolve
from certsolve.inputs import InputError
from certsolve.jobs.errors import validation_details
from certsolve.jobs.kinds import IsotropicCall, TrackCall, request_adapter

ROOT = Path(__file__).resolve().parents[1]
CIRCLE_FILE = str(ROOT / "examples/systems/circle-line.mbx")
CIRCLE = Path(CIRCLE_FILE).read_text()
PLANAR_FILE = str(ROOT / "examples/robots/planar.json")
PLANAR = json.loads(Path(PLANAR_FILE).read_text())
U = [0.8, 1.8, -2.5, -3.6]  # two poses at tau_max 60 (README)
POSE = [90.0, 60.0, 0.0]


@pytest.fixture(scope="module")
def robot():
    return certsolve.load_robot(PLANAR_FILE)


def service_error(model, request: dict) -> tuple[str, str]:
    """``(field, message)`` of the single problem the service finds in ``request``."""
    with pytest.raises(ValidationError) as info:
        model.validate_python(request) if hasattr(model, "validate_python") else (
            model.model_validate(request)
        )
    (d,) = validation_details(info.value.errors(), ("body",))
    return d["field"], d["msg"]


def job(kind: str, **params) -> dict:
    body = {"system": CIRCLE} if kind == "solve" else {"robot": PLANAR}
    return {"kind": kind, **body, "params": params}


NAN, INF = float("nan"), float("inf")
CASES = [
    # (library call, the model and request the service validates)
    (
        lambda r: certsolve.solve(CIRCLE_FILE, timeout=-1),
        request_adapter(), job("solve", timeout=-1),
    ),
    (lambda r: certsolve.solve(CIRCLE, eps=0), request_adapter(), job("solve", eps=0)),
    (lambda r: certsolve.solve(CIRCLE, max_boxes=0), request_adapter(), job("solve", max_boxes=0)),
    (lambda r: certsolve.solve(CIRCLE, eps=NAN), request_adapter(), job("solve", eps=NAN)),
    (
        lambda r: certsolve.forward_kinematics(r, U, tau_max=-5),
        request_adapter(), job("fk", u=U, tau_max=-5),
    ),
    (
        lambda r: certsolve.forward_kinematics(r, U, tau_max=NAN),
        request_adapter(), job("fk", u=U, tau_max=NAN),
    ),
    (
        lambda r: certsolve.forward_kinematics(r, [1e300, 0, 0, 0]),
        request_adapter(), job("fk", u=[1e300, 0, 0, 0]),
    ),
    (lambda r: certsolve.forward_kinematics(r, U[:2]), request_adapter(), job("fk", u=U[:2])),
    (
        lambda r: certsolve.forward_kinematics(r, U, eps=INF),
        request_adapter(), job("fk", u=U, eps=INF),
    ),
    (
        lambda r: certsolve.forward_kinematics(r, U, formulation="T-17"),
        request_adapter(), job("fk", u=U, formulation="T-17"),
    ),
    (
        lambda r: certsolve.forward_kinematics(r, U, max_solutions=0),
        request_adapter(), job("fk", u=U, max_solutions=0),
    ),
    (
        lambda r: certsolve.inverse_kinematics(r, [1, 2, 3, 4]),
        request_adapter(), job("ik", pose=[1, 2, 3, 4]),
    ),
    (
        lambda r: certsolve.inverse_kinematics(r, POSE, method="alg3"),
        request_adapter(), job("ik", pose=POSE, method="alg3"),
    ),
    (
        lambda r: certsolve.inverse_kinematics(r, [90, 2e6, 0]),
        request_adapter(), job("ik", pose=[90, 2e6, 0]),
    ),
    (
        lambda r: certsolve.track(r, U, [1]),
        TrackCall, {"robot": PLANAR, "params": {"u": U, "near_pose": [1]}},
    ),
    (
        lambda r: certsolve.track(r, U, POSE, half_width=0),
        TrackCall, {"robot": PLANAR, "params": {"u": U, "near_pose": POSE, "half_width": 0}},
    ),
    (
        lambda r: certsolve.track(r, U[:3], POSE),
        TrackCall, {"robot": PLANAR, "params": {"u": U[:3], "near_pose": POSE}},
    ),
    (
        lambda r: certsolve.isotropic_force(r, POSE, external=[1, 2]),
        IsotropicCall, {"robot": PLANAR, "params": {"pose": POSE, "external": [1, 2]}},
    ),
    (
        lambda r: certsolve.isotropic_force(r, POSE, algorithm="simplex"),
        IsotropicCall, {"robot": PLANAR, "params": {"pose": POSE, "algorithm": "simplex"}},
    ),
]  # fmt: skip


@pytest.mark.parametrize("call, model, request_", CASES)
def test_python_refuses_what_the_service_refuses(robot, call, model, request_):
    field, msg = service_error(model, request_)
    with pytest.raises(InputError) as info:
        call(robot)
    assert isinstance(info.value, ValueError)
    assert "params." + info.value.field == field
    assert info.value.message == msg
    assert str(info.value) == f"{info.value.field}: {msg}"


def test_the_issue_example_and_the_cli(robot, capsys):
    """tau_max=-5: no longer a certified empty answer; the CLI says the same."""
    with pytest.raises(InputError) as info:
        certsolve.forward_kinematics(robot, U, tau_max=-5)
    assert info.value.field == "tau_max"
    assert info.value.message == "must be greater than or equal to 0"
    from certsolve.cli import main

    assert main(["fk", PLANAR_FILE, "--u", ",".join(map(str, U)), "--tau-max", "-5"]) == 2
    assert capsys.readouterr().err == f"error: --tau-max: {info.value.message}\n"


def test_solve_takes_a_system_a_path_or_text():
    from certsolve.expr.minibex import MinibexError

    system = certsolve.load_system(CIRCLE_FILE)
    answers = [certsolve.solve(x) for x in (system, CIRCLE_FILE, Path(CIRCLE_FILE), CIRCLE)]
    boxes = [sorted(s.box for s in a.solutions) for a in answers]
    assert all(a.status == "complete" and len(a.solutions) == 2 for a in answers)
    assert boxes[1:] == boxes[:-1]
    with pytest.raises(MinibexError):
        certsolve.solve("Variables x in [0, 1];\nConstraints x^ = 1;\nend")
    with pytest.raises(OSError):
        certsolve.solve(str(ROOT / "no-such-file.mbx"))


def test_poses_as_lists_tuples_arrays_and_text(robot):
    fk = certsolve.forward_kinematics(robot, np.array(U), tau_max=60)
    assert fk.status == "complete" and len(fk.solutions) == 2
    assert len(certsolve.forward_kinematics(robot, U, tau_max=60).solutions) == 2
    s = fk.solutions[0]
    params = [*s.position, *s.euler_deg]
    pose = certsolve.Pose.from_params(3, params)
    steps = [
        certsolve.track(robot, U, near, formulation="auto")
        for near in (pose, params, tuple(params), np.array(params), s)
    ]
    assert all(t.certified for t in steps)
    for t in steps[1:]:  # the same certified pose (each proof is about its own Newton point)
        np.testing.assert_allclose(t.pose.position, steps[0].pose.position, rtol=1e-12)
    ik = [certsolve.inverse_kinematics(robot, p) for p in (POSE, tuple(POSE), np.array(POSE))]
    ik.append(certsolve.inverse_kinematics(robot, "90,60,0"))
    for r in ik[1:]:
        np.testing.assert_allclose(r.tau, ik[0].tau, rtol=1e-12)
    iso = [certsolve.isotropic_force(robot, p) for p in (POSE, tuple(POSE), np.array(POSE))]
    force = iso[0].isotropic_force
    assert force is not None and math.isfinite(force)
    assert iso[1].isotropic_force == pytest.approx(force, rel=1e-12)
    assert iso[2].isotropic_force == pytest.approx(force, rel=1e-12)


@pytest.mark.parametrize(
    "pose, field, message",
    [
        ([[90, 60, 0]], "near_pose.0", "must be a valid number"),
        (np.zeros((1, 3)), "near_pose", "expected a list of numbers, got shape (1, 3)"),
        ([90, NAN, 0], "near_pose.1", "must be a finite number"),
        ("90,sixty,0", "near_pose", "expected comma-separated numbers"),
    ],
)
def test_a_bad_pose_names_its_field(robot, pose, field, message):
    with pytest.raises(InputError) as info:
        certsolve.track(robot, U, pose)
    assert info.value.field == field and message in info.value.message


def test_http_places_a_library_error_at_the_field_it_names():
    """``POST /v1/fk/track`` & co. read the field from the error, not from its text."""
    from certsolve.api.routers.sync import _input_error

    req = TrackCall.model_validate({"robot": PLANAR, "params": {"u": U, "near_pose": POSE}})
    err = _input_error(InputError("near_pose.1", "must be a finite number"), req)
    assert err.status == 422
    assert [(d["field"], d["msg"]) for d in err.detail] == [
        ("params.near_pose.1", "must be a finite number")
    ]
    err = _input_error(InputError("robot.wires.2.k", "required for FK"), req)  # the robot's
    assert [(d["field"], d["msg"]) for d in err.detail] == [("robot.wires.2.k", "required for FK")]
    err = _input_error(InputError("", "wires[2].k: must be positive"), req)  # no field: no guess
    assert [d["field"] for d in err.detail] == ["body"] and err.status == 422


def test_quick_calls_answer_input_errors(tmp_path):
    """A refusal crosses the quick-call process's pipe as an InputError (with the field the
    library named; the test kind names none)."""
    from certsolve.jobs.kinds.sleep import SleepCall
    from certsolve.jobs.quick import QuickCalls
    from certsolve.jobs.settings import ServiceSettings

    quick = QuickCalls(ServiceSettings(data_dir=tmp_path, workers=0, quick_workers=1))
    try:
        with pytest.raises(InputError) as info:
            quick.run("sleep", SleepCall(params={"seconds": 0, "fail": "bad input"}))
        assert info.value.field == "" and str(info.value) == "bad input"
    finally:
        quick.close()
