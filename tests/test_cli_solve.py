"""``certsolve solve``: bounded JSON answers, infinite bounds as null, whole-run time limits."""

import contextlib
import io
import json

from certsolve.cli import main as cli_main


def run_cli(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli_main(list(argv))
    return code, out.getvalue(), err.getvalue()


def test_infinite_bounds_are_null_in_json(tmp_path):
    f = tmp_path / "asymptote.mbx"
    f.write_text("Variables\n  x;\nConstraints\n  x*exp(-x) = 0.1;\nend\n")
    code, out, _ = run_cli("solve", str(f), "--json")
    assert code == 0
    d = json.loads(out)
    assert d["status"] == "complete" and len(d["solutions"]) == 2
    assert d["undecided"] and all(u["box"][0][1] is None for u in d["undecided"])
    for key in ("undecided_total", "undecided_dropped", "pending_total", "pending_boxes"):
        assert key in d


def test_time_limit_and_bounded_output(tmp_path):
    """The issue-13 system: a line of solutions, searched at eps 1e-12 until the limit."""
    f = tmp_path / "line.mbx"
    f.write_text(
        "Variables\n  x in [-1e6, 1e6];\n  y in [-1e6, 1e6];\n"
        "Constraints\n  x - y = 0;\n  2*x - 2*y = 0;\nend\n"
    )
    code, out, _ = run_cli(
        "solve", str(f), "--eps", "1e-12", "--timeout", "2", "--json", "--max-pending", "50",
        "--max-undecided", "20",
    )  # fmt: skip
    assert code == 0
    d = json.loads(out)
    assert d["status"] == "timeout" and d["stats"]["stopped_by"] == "timeout"
    assert len(d["pending"]) <= 50 and len(d["pending_boxes"]) == len(d["pending"])
    assert sum(d["pending_boxes"]) == d["pending_total"]
    assert len(d["undecided"]) <= 20
    assert sum(u["boxes"] for u in d["undecided"]) + d["undecided_dropped"] == d["undecided_total"]
    code, out, _ = run_cli("solve", str(f), "--eps", "1e-12", "--timeout", "1")
    assert code == 0 and "stopped by timeout" in out


def test_bad_limits_are_refused(tmp_path):
    f = tmp_path / "c.mbx"
    f.write_text("Variables\n  x in [0, 1];\nConstraints\n  x = 0.5;\nend\n")
    for opt, val in (("--timeout", "-1"), ("--timeout", "nan"), ("--max-pending", "0")):
        code, _, err = run_cli("solve", str(f), opt, val)
        assert code == 2 and err.startswith("error: ") and opt in err


def test_cid_vars_shaves_more_and_keeps_the_solutions():
    """``--cid-vars all`` (CID on every variable before a bisection) needs fewer boxes on
    eco-6 and certifies the same solutions; a bad value is one ``error:`` line, and the
    job kind refuses it with the same message."""
    import pytest
    from pydantic import ValidationError

    from certsolve.jobs.kinds.solve import SolveParams

    eco6 = "examples/systems/eco-6.mbx"
    runs = {}
    for k in ("1", "3", "all", "auto"):
        code, out, _ = run_cli("solve", eco6, "--json", "--workers", "1", "--cid-vars", k)
        assert code == 0
        runs[k] = json.loads(out)
    assert {d["status"] for d in runs.values()} == {"complete"}
    ref = [s["box"] for s in runs["1"]["solutions"]]
    assert len(ref) == 4
    for k in ("3", "all", "auto"):  # the same 4 solutions: each box meets exactly one reference box
        found = [s["box"] for s in runs[k]["solutions"]]
        assert len(found) == 4
        for box in found:
            meets = [all(a <= d and c <= b for (a, b), (c, d) in zip(box, r)) for r in ref]
            assert sum(meets) == 1
    assert runs["all"]["stats"]["boxes"] < runs["1"]["stats"]["boxes"]
    for bad in ("0", "x", "1.5", "101"):
        code, _, err = run_cli("solve", eco6, "--cid-vars", bad)
        assert code == 2 and err.startswith("error: --cid-vars") and "'all'" in err
    assert SolveParams(cid_vars="all").solver_cid_vars() is None
    assert SolveParams(cid_vars="auto").solver_cid_vars() == "auto"
    assert SolveParams(cid_vars=4).solver_cid_vars() == 4
    assert SolveParams(cid_vars=4.0).cid_vars == 4  # a JSON Schema integer
    with pytest.raises(ValidationError, match="cid_vars"):
        SolveParams(cid_vars=True)
