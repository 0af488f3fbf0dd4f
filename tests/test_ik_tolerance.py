"""Inverse kinematics of a robot known within tolerances (issue 31, item 3): control
intervals that hold every robot of the set, checked against robots drawn from the set
(corners and random draws) and solved one by one by the nominal IK."""

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.inputs import InputError
from certsolve.kinematics.ik import ik_algorithm2, ik_tension_first, inverse_kinematics
from certsolve.kinematics.ik_tolerance import tolerant_inverse_kinematics
from certsolve.robot import Pose, Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
POSES = [(115, 60, 118, 0, 0, 0), (112, 63, 110, 4, -3, 2)]
SLACK = 1e-9  # the nominal IK's float controls against the proven bounds


@pytest.fixture(scope="module")
def t16_tol():
    return Robot.load(ROBOTS / "marionet-t-tol.json")


def _samples(robot: Robot, count: int = 8):
    """Robots of the set: half at random corners of the tolerances, half drawn uniformly."""
    rng = np.random.default_rng(31)
    return [robot.draw(rng, corner=i % 2 == 0) for i in range(count)]


def _inside(x, lo, hi) -> bool:
    return bool(np.all((x >= lo - SLACK) & (x <= hi + SLACK)))


def _same_distribution(sample: Robot, pose, res):
    """The sample robot solved by the nominal IK with the distribution the set's answer
    fixed: Algorithm 2 with the same fixed wire at the same tension or control."""
    s = res.details["set"]
    (wire,), (value,) = s["fixed_wires"], s["fixed_values"]
    key = "tau_fixed" if s["fixed"] == "tension" else "u_fixed"
    return ik_algorithm2(sample, Pose.from_params(6, pose), fixed_wire=wire, **{key: value})


@pytest.mark.parametrize("method", ["tension", "alg2"])
@pytest.mark.parametrize("pose", POSES)
def test_sampled_robots_lie_in_the_intervals(t16_tol, method, pose):
    res = inverse_kinematics(t16_tol, pose, method=method)
    s = res.details["set"]
    assert res.certificate.kind == "every-robot"
    assert res.status == "ok" and res.feasible and res.margin > 0
    for sample in _samples(t16_tol):
        own = _same_distribution(sample, pose, res)
        assert own.certificate.kind == "unique-in-box"
        assert _inside(own.u, s["u_lo"], s["u_hi"])
        assert _inside(own.tau, s["tau_lo"], s["tau_hi"])
        # ok: every robot's tensions are within its limits
        assert np.all(own.tau >= sample.tau_min - SLACK) and np.all(
            own.tau <= sample.tau_max + SLACK
        )
    # the control vector given is the middle of the intervals
    assert np.allclose(res.u, 0.5 * (np.array(s["u_lo"]) + np.array(s["u_hi"])))


@pytest.mark.parametrize("method", ["tension", "alg2"])
def test_toleranced_attachments_and_mass(method):
    """The IK of a set also takes the attachments and the mass (the FK of a set does not):
    sampled robots still lie inside."""
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    data["tolerances"] += [
        {"path": "wires[*].platform[*]", "plus_minus": 0.05},
        {"path": "platform.mass", "relative": 0.01},
    ]
    robot = Robot.load(data)
    pose = POSES[1]
    res = inverse_kinematics(robot, pose, method=method)
    s = res.details["set"]
    assert res.status == "ok"
    for sample in _samples(robot):
        own = _same_distribution(sample, pose, res)
        assert _inside(own.u, s["u_lo"], s["u_hi"]) and _inside(own.tau, s["tau_lo"], s["tau_hi"])


def test_the_bounds_are_within_a_few_times_the_spread_of_the_set(t16_tol):
    """The mean-value form keeps a wire column's entries together: the tension bounds are
    at most 2.5 times the spread of 40 robots drawn from the set (3.6-9 times entry by
    entry), the control intervals at most 2.5 times."""
    pose = POSES[0]
    res = inverse_kinematics(t16_tol, pose)
    s = res.details["set"]
    rng = np.random.default_rng(0)
    own = [_same_distribution(t16_tol.draw(rng, corner=i % 2 == 0), pose, res) for i in range(40)]
    for key, values in (("tau", [o.tau for o in own]), ("u", [o.u for o in own])):
        spread = np.ptp(np.array(values), axis=0)
        width = np.array(s[f"{key}_hi"]) - s[f"{key}_lo"]
        moving = spread > 1e-9  # the fixed wire's tension is the same for every robot
        assert np.all(width[moving] <= 2.5 * spread[moving])


@pytest.mark.parametrize(
    ("extra", "factor"),
    [
        ([{"path": "platform.center_of_mass[*]", "plus_minus": 0.5}], 1.06),
        (
            [
                {"path": "platform.mass", "plus_minus": 0.002},
                {"path": "platform.center_of_mass[*]", "plus_minus": 0.5},
            ],
            1.15,
        ),
    ],
    ids=["com", "mass-and-com"],
)
def test_the_weight_is_in_the_mean_value_form(extra, factor):
    """A toleranced mass and centre of mass (the only tolerances) enter the mean-value form
    (``w_g = m u(c)``, slopes ``u(C)`` and ``m0 u_j``): at a tilted pose the tension and
    control bounds hold 40 drawn robots and are within ``factor`` times their spread (as
    plain intervals: 1.13 and 1.19 times)."""
    data = json.loads((ROBOTS / "marionet-t.json").read_text())
    data["tolerances"] = extra
    robot = Robot.load(data)
    pose = POSES[1]
    for method in ("tension", "alg2"):
        rng = np.random.default_rng(0)
        res = inverse_kinematics(robot, pose, method=method)
        s = res.details["set"]
        assert res.status == "ok"
        own = [_same_distribution(robot.draw(rng, corner=i % 2 == 0), pose, res) for i in range(40)]
        for key, values in (("tau", [o.tau for o in own]), ("u", [o.u for o in own])):
            lo, hi = np.array(s[f"{key}_lo"]), np.array(s[f"{key}_hi"])
            assert all(_inside(v, lo, hi) for v in values)
            spread = np.ptp(np.array(values), axis=0)
            moving = spread > 1e-9
            assert np.all((hi - lo)[moving] <= factor * spread[moving])


def test_a_failing_bound_names_its_wire(t16_tol):
    """Wire 1's control fixed from a tension 0.01 N under its limit: with ±1 % on k, some
    robots pull harder than 10 N; the worst case is reported for that wire, and no sampled
    robot exceeds it."""
    pose = POSES[0]
    res = inverse_kinematics(t16_tol, pose, method="alg2", tau_fixed=9.99)
    assert res.status == "limits-violated" and not res.feasible
    s = res.details["set"]
    over = {v.wire: v for v in res.violations if v.quantity == "tau" and v.bound == "max"}
    assert 1 in over
    v = over[1]
    assert v.value == pytest.approx(s["tau_hi"][0]) and v.excess == pytest.approx(v.value - 10.0)
    assert res.margin == pytest.approx(-max(o.excess for o in over.values()), abs=1e-9)
    worst = max(float(_same_distribution(r, pose, res).tau[0]) for r in _samples(t16_tol, 12))
    assert 10.0 < worst <= v.value + SLACK  # a robot of the set does violate, within the bound
    assert any("wire 1: the set's worst case" in m for m in res.messages)


def test_a_wider_set_needs_another_fixed_tension():
    """±1.5 cm anchors near the tension limit: the nominal max-margin tension of the fixed
    wire does not prove the limits for the whole set, another value across its range does,
    or the failing bound is reported; either way, sampled robots lie inside."""
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    data["tolerances"][0]["plus_minus"] = 1.5
    robot = Robot.load(data)
    pose = POSES[1]
    res = inverse_kinematics(robot, pose)
    s = res.details["set"]
    assert s["candidates"] == 97  # the nominal value, then three batches of 32
    for sample in _samples(robot, 6):
        own = _same_distribution(sample, pose, res)
        assert _inside(own.u, s["u_lo"], s["u_hi"]) and _inside(own.tau, s["tau_lo"], s["tau_hi"])
    if res.status == "ok":
        assert res.margin >= 0
    else:
        assert res.status == "limits-violated" and res.violations


def test_zero_tolerance_is_the_nominal_answer():
    data = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    for t in data["tolerances"]:
        t.pop("relative", None)
        t["plus_minus"] = 0.0
    robot = Robot.load(data)
    nominal = Robot.load(ROBOTS / "marionet-t.json")
    for pose in POSES:
        got, want = inverse_kinematics(robot, pose), inverse_kinematics(nominal, pose)
        assert np.array_equal(got.u, want.u) and got.status == want.status
        # the set's own computation on a set of one robot: intervals a few ulps around it
        res = tolerant_inverse_kinematics(nominal, Pose.from_params(6, pose))
        s = res.details["set"]
        assert res.status == want.status
        assert _inside(want.u, s["u_lo"], s["u_hi"]) and _inside(want.tau, s["tau_lo"], s["tau_hi"])
        assert np.max(np.array(s["u_hi"]) - s["u_lo"]) < 1e-9
        assert np.max(np.array(s["tau_hi"]) - s["tau_lo"]) < 1e-9
        assert res.margin == pytest.approx(want.margin, abs=1e-9)


def test_planar_set(tmp_path):
    """A planar robot with ±0.2 cm anchors and a toleranced mass: the same checks."""
    data = json.loads((ROBOTS / "planar.json").read_text())
    data["tolerances"] = [
        {"path": "wires[*].base[*]", "plus_minus": 0.2},
        {"path": "platform.mass", "relative": 0.02},
    ]
    robot = Robot.load(data)
    pose = (90, 60, 0)
    res = inverse_kinematics(robot, pose)
    s = res.details["set"]
    assert res.certificate.kind == "every-robot"
    for sample in _samples(robot, 6):
        want = ik_tension_first(sample, Pose.from_params(3, pose))
        own = ik_algorithm2(
            sample, Pose.from_params(3, pose),
            fixed_wire=s["fixed_wires"][0], tau_fixed=s["fixed_values"][0],
        )  # fmt: skip
        assert want.status == "ok"
        assert _inside(own.tau, s["tau_lo"], s["tau_hi"]) and _inside(own.u, s["u_lo"], s["u_hi"])


def test_refusals(t16_tol):
    with pytest.raises(InputError) as err:
        inverse_kinematics(t16_tol, POSES[0], method="alg1")
    assert err.value.field == "method"
    with pytest.raises(InputError) as err:
        inverse_kinematics(t16_tol, POSES[0], method="alg2", solve="newton")
    assert err.value.field == "solve"
    data = json.loads((ROBOTS / "almost-planar.json").read_text())
    data["tolerances"] = [{"path": "wires[*].base[*]", "plus_minus": 0.05}]
    with pytest.raises(InputError) as err:
        inverse_kinematics(Robot.load(data), (0, 0, -10, 0, 0, 0))
    assert err.value.field == "robot.tolerances"


def test_cli_and_job(capsys, t16_tol):
    from certsolve.cli import main
    from certsolve.jobs.kinds.ik import IkParams

    path = str(ROBOTS / "marionet-t-tol.json")
    assert main(["ik", path, "--pose", "115,60,118,0,0,0", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["status"] == "ok" and d["certificate"]["kind"] == "every-robot"
    assert len(d["details"]["set"]["u_lo"]) == 7 and len(d["certificate"]["enclosure"]) == 7
    assert main(["ik", path, "--pose", "115,60,118,0,0,0"]) == 0
    out = capsys.readouterr().out
    assert "every robot of the set: tension of wire(s)" in out and "u bounds (cm)" in out
    assert main(["ik", path, "--pose", "115,60,118,0,0,0", "--method", "alg1"]) != 0
    assert capsys.readouterr().err.startswith("error: --method: alg1 is not available")
    with pytest.raises(ValueError, match="method: alg1 is not available"):
        IkParams.model_validate({"pose": [115, 60, 118, 0, 0, 0], "method": "alg1"}).check_robot(
            t16_tol.spec
        )


def test_the_quick_call_over_http(tmp_path):
    """``POST /v1/ik`` with the robot and its tolerances inline: the set's answer; Algorithm
    1 refused with a 422 naming the field."""
    from fastapi.testclient import TestClient

    from certsolve.api.app import create_app
    from certsolve.jobs import ServiceSettings

    robot = json.loads((ROBOTS / "marionet-t-tol.json").read_text())
    app = create_app(ServiceSettings(data_dir=tmp_path / "data", workers=0))
    with TestClient(app, base_url="http://localhost") as client:
        r = client.post("/v1/ik", json={"robot": robot, "params": {"pose": list(POSES[0])}})
        assert r.status_code == 200, r.text
        d = r.json()
        assert d["status"] == "ok" and d["certificate"]["kind"] == "every-robot"
        assert len(d["details"]["set"]["u_hi"]) == 7
        body = {"robot": robot, "params": {"pose": list(POSES[0]), "method": "alg1"}}
        r = client.post("/v1/ik", json=body)
        assert r.status_code == 422
        (e,) = r.json()["detail"]  # one problem, named
        assert e["field"] == "params.method" and "alg1 is not available" in e["msg"]
