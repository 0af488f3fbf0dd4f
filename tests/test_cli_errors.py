"""Every argparse refusal is one ``error:`` line with exit status 2: no usage block, no
traceback, for every command.  An unknown option names the closest of the command's own
options (difflib); a misspelt command the closest command."""

import argparse

import pytest

from certsolve.cli import COMMANDS, build_parser, main

PLANAR = "examples/robots/planar.json"
U = "0.8,1.8,-2.5,-3.6"


def run(capsys, argv: list[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line(code: int, out: str, err: str) -> str:
    assert code == 2 and out == ""
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert "usage:" not in err and "Traceback" not in err
    return err.strip()


def _misspelt(name: str) -> tuple[str, str]:
    """A long option of command ``name`` and that option with one letter dropped."""
    (sub,) = [a for a in build_parser([name])._actions if isinstance(a, argparse._SubParsersAction)]
    options = sorted(
        (s for a in sub.choices[name]._actions for s in a.option_strings if s.startswith("--")),
        key=len,
    )
    option = next((o for o in reversed(options) if o != "--help"), "--help")
    k = len(option) // 2
    return option, option[:k] + option[k + 1 :]


def test_the_issue_example(capsys):
    err = assert_one_line(*run(capsys, ["fk", PLANAR, "--u", U, "--tau-mx", "60"]))
    assert err == "error: --tau-mx: unknown option (did you mean --tau-max?)"
    err = assert_one_line(*run(capsys, ["fk", PLANAR, "--u", U, "--tau-mx=60"]))
    assert err == "error: --tau-mx: unknown option (did you mean --tau-max?)"


@pytest.mark.parametrize("name", [c.name for c in COMMANDS])
def test_unknown_option_of_every_command(capsys, name):
    option, wrong = _misspelt(name)
    err = assert_one_line(*run(capsys, [name, wrong]))
    assert err == f"error: {wrong}: unknown option (did you mean {option}?)"


def test_unknown_option_without_a_close_one(capsys):
    err = assert_one_line(*run(capsys, ["solve", "x.mbx", "--zzzzzz"]))
    assert err == "error: --zzzzzz: unknown option (see certsolve solve --help)"


def test_a_misspelt_required_option_is_unknown_not_missing(capsys):
    err = assert_one_line(*run(capsys, ["ik", PLANAR, "--pse", "1,2"]))
    assert err == "error: --pse: unknown option (did you mean --pose?)"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["fk", PLANAR], "--u: required (see certsolve fk --help)"),
        (["fk"], "robot, --u: required (see certsolve fk --help)"),
        (["isotropic", PLANAR], "one of the arguments --at --grid is required"),
        (["ik", PLANAR], "--pose: required (see certsolve ik --help)"),
        (["solve"], "file: required (see certsolve solve --help)"),
        (["result"], "id: required (see certsolve result --help)"),
        ([], "COMMAND: required (see certsolve --help)"),
    ],
)
def test_missing_arguments(capsys, argv, message):
    assert assert_one_line(*run(capsys, argv)) == f"error: {message}"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["fk", PLANAR, "--u"], "--u: expected one argument"),
        (["fk", PLANAR, "--u", U, "--eps", "abc"], "--eps: invalid float value: 'abc'"),
        (["fk", PLANAR, "--u", U, "--max", "3"], "ambiguous option: --max could match"),
        (["fk", PLANAR, "--u", U, "--formulation", "x"], "--formulation: invalid choice: 'x'"),
        (["status", "--limit", "many"], "--limit: invalid int value: 'many'"),
        (["solve", "a.mbx", "b.mbx"], "'b.mbx': unexpected argument (see certsolve solve --help)"),
        (["fkk"], "fkk: unknown command (did you mean fk?)"),
        (["zzzz"], "zzzz: unknown command (see certsolve --help)"),
    ],
)
def test_bad_values_and_commands(capsys, argv, message):
    assert assert_one_line(*run(capsys, argv)).startswith(f"error: {message}")


def test_help_still_exits_zero(capsys):
    with pytest.raises(SystemExit) as info:
        main(["fk", "--help"])
    assert info.value.code == 0 and "--tau-max" in capsys.readouterr().out
