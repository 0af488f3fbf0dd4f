"""``certsolve ik``: tables, JSON, and one-line errors without tracebacks."""

from __future__ import annotations

import json

import pytest

from certsolve.cli import main

MARIONET = "examples/robots/marionet.json"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("method", ["tension", "alg1", "alg2"])
def test_table(capsys, method):
    code, out, err = run(capsys, "ik", MARIONET, "--pose", "111,58,107,0,0,0", "--method", method)
    assert code == 0 and err == ""
    assert f"method {method}" in out and "status: ok (feasible)" in out
    rows = [line for line in out.splitlines() if line[:4].strip().isdigit()]
    assert len(rows) == 7
    if method != "tension":
        assert "certificate: unique-in-box" in out


def test_json(capsys):
    code, out, _ = run(
        capsys, "ik", MARIONET, "--pose", "111,58,107,10,5,-3", "--method", "alg2", "--json"
    )
    assert code == 0
    d = json.loads(out)
    assert d["method"] == "alg2" and d["status"] == "limits-violated"
    assert len(d["u"]) == 7 and d["certificate"]["kind"] == "unique-in-box"
    assert d["violations"] and {"wire", "quantity", "value", "limit"} <= set(d["violations"][0])
    assert d["pose"] == pytest.approx([111, 58, 107, 10, 5, -3])


def test_planar_and_window(capsys):
    code, out, _ = run(capsys, "ik", "examples/robots/planar.json", "--pose", "90,60,0")
    assert code == 0 and "theta=0" in out
    code, out, _ = run(
        capsys, "ik", MARIONET, "--pose", "111,58,107", "--method", "alg1",
        "--u-last", "0,0,0,0,0,0,0", "--window", "0.1", "--json",
    )  # fmt: skip
    assert code == 0
    d = json.loads(out)
    assert d["status"] == "ok" and all(abs(u) <= 0.05 for u in d["u"])


def test_stroke_violation_in_table(capsys):
    code, out, _ = run(capsys, "ik", MARIONET, "--pose", "153.36,66.8,128.81,-0.103,1.172,11.431")
    assert code == 0
    assert "limits-violated" in out and "stroke!" in out and "above the stroke" in out


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["ik", MARIONET, "--pose", "1,2"], "--pose: a spatial pose is x,y,z"),
        (["ik", MARIONET, "--pose", "a,b,c"], "expected comma-separated numbers"),
        (["ik", "examples/robots/krut-3.json", "--pose", "0,0", "--method", "alg2"],
         "no elastic wire model"),
        (["ik", "examples/robots/nope.json", "--pose", "0,0"], "cannot read robot file"),
        (["ik", MARIONET, "--pose", "111,58,107", "--method", "alg1", "--u-last", "1,2"],
         "--u-last: expected 7 values"),
        (["ik", MARIONET, "--pose", "111,58,107", "--u-last", "0,0,0,0,0,0,0"],
         "--u-last: applies to method alg1 or alg2"),
        (["ik", MARIONET, "--pose", "111,58,107", "--method", "alg2", "--fixed-wire", "9"],
         "--fixed-wire: the robot has wires 1..7"),
        (["ik", MARIONET, "--pose", "111,58,107", "--method", "alg1", "--u-last",
          "0,0,0,0,0,0,0", "--window", "-1"], "--window: must be greater than 0"),
    ],
)  # fmt: skip
def test_errors_are_one_line(capsys, argv, needle):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and needle in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_another_methods_option_is_refused_not_ignored():
    from certsolve.inputs import InputError, checked
    from certsolve.robot.inputs import IkOptions

    pose = [111, 58, 107, 0, 0, 0]
    for method, name, value in [
        ("tension", "fixed_wire", 3),
        ("tension", "solve", "newton"),
        ("alg2", "distribution", "lp"),
        ("alg1", "tau_fixed", 5.0),
    ]:
        with pytest.raises(InputError) as e:
            checked(IkOptions, {"pose": pose, "method": method, name: value})
        assert e.value.field == name and method in str(e.value)
    # defaults given explicitly (the CLI's) are fine
    checked(IkOptions, {"pose": pose, "method": "tension", "fixed_wire": 1, "solve": "tau"})
