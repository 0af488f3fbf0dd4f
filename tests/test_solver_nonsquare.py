"""Over- and under-determined systems (``certsolve.solver.nonsquare``)."""

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.cli import main as cli_main
from certsolve.expr.minibex import load_minibex, parse_minibex
from certsolve.inputs import InputError
from certsolve.solver import Solver, solve
from certsolve.solver.nonsquare import ManifoldPaver, pivots
from certsolve.solver.result import Certificate

NONSQUARE = Path(__file__).resolve().parent.parent / "examples" / "systems" / "nonsquare"


def test_pivots_choose_independent_columns():
    # column 1 is zero, column 2 is twice column 0: the pivots are 0 (or 2) and 3
    A = np.array([[[1.0, 0.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]]])
    (chosen,) = pivots(A, 2)
    assert set(chosen.tolist()) in ({2, 3}, {0, 3})
    assert 1 not in chosen


def test_ibex_overdetermined_file_has_one_subsystem_solution():
    """IBEX's others/ex14-2-3: 9 equations, 6 unknowns."""
    system = load_minibex(NONSQUARE / "ex14-2-3.mbx")
    assert (len(system.equations), system.n) == (9, 6)
    result = Solver.default(system).solve()
    assert result.status == "complete"
    (sol,) = result.solutions
    assert sol.certificate == Certificate.SQUARE_SUBSYSTEM
    assert sol.to_dict()["certificate"] == "square-subsystem-certified"


def _text(domain: str, equations: list[str]) -> str:
    return (
        "Variables\n" + domain + "\nConstraints\n" + "".join(e + ";\n" for e in equations) + "end\n"
    )


def test_overdetermined_keeps_consistent_solutions_and_refutes_the_others():
    dom = "  x in [-2, 2];\n  y in [-2, 2];"
    consistent = parse_minibex(_text(dom, ["x^2 + y^2 = 2", "x - y = 0", "x*y = 1"]))
    result = solve(consistent)
    assert result.status == "complete" and len(result.solutions) == 2
    for s in result.solutions:
        assert s.certificate == Certificate.SQUARE_SUBSYSTEM
        assert abs(abs(s.midpoint[0]) - 1.0) < 1e-9
    # the square subsystem's solution (0, 0) violates x + 1 = 0: refuted
    inconsistent = parse_minibex(_text(dom, ["x + y = 0", "x - y = 0", "x + 1 = 0"]))
    result = solve(inconsistent)
    assert result.status == "complete" and not result.solutions and not result.undecided


def test_circle_is_paved_by_parametric_boxes():
    system = load_minibex(NONSQUARE / "circle.mbx")
    result = solve(system)
    assert result.status == "complete" and result.solutions and not result.undecided_total
    boxes = result.solutions
    for s in boxes:
        assert s.certificate == Certificate.PARAMETRIC and len(s.parameters) == 1
        # every value of the parameter in the box: exactly one solution in the box
        j = system.variables.index(s.parameters[0])
        k = 1 - j
        for t in np.linspace(s.lo[j], s.hi[j], 7):
            other = np.sqrt(max(1.0 - t * t, 0.0))
            assert sum(s.lo[k] <= v <= s.hi[k] for v in (other, -other)) == 1
    # the boxes cover the circle
    for a in np.linspace(0.0, 2.0 * np.pi, 200):
        p = np.array([np.cos(a), np.sin(a)])
        assert any(np.all((s.lo <= p) & (p <= s.hi)) for s in boxes), a


def test_a_paving_is_bounded_by_max_boxes():
    result = solve(load_minibex(NONSQUARE / "circle.mbx"), max_boxes=5)
    assert result.status == "max_boxes" and result.pending_total > 0


def test_underdetermined_refuses_verify_and_the_square_solver():
    system = load_minibex(NONSQUARE / "circle.mbx")
    with pytest.raises(InputError) as err:
        solve(system, verify=True)
    assert err.value.field == "verify"
    with pytest.raises(ValueError, match="under-determined"):
        Solver.default(system)
    with pytest.raises(ValueError, match="not under-determined"):
        ManifoldPaver(load_minibex(NONSQUARE / "ex14-2-3.mbx"))


@pytest.mark.parametrize(
    ("name", "certificate"), [("circle", "parametric"), ("ex14-2-3", "square-subsystem-certified")]
)
def test_cli_solves_nonsquare_files(name, certificate):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = cli_main(["solve", str(NONSQUARE / f"{name}.mbx"), "--json"])
    assert code == 0
    data = json.loads(out.getvalue())
    assert data["status"] == "complete" and data["solutions"]
    assert {s["certificate"] for s in data["solutions"]} == {certificate}


def test_a_system_without_equations_is_refused_naming_the_field():
    text = "Variables\n  x in [0, 1];\n  y in [0, 1];\nConstraints\n  x + y <= 1;\nend\n"
    with pytest.raises(InputError) as err:
        solve(parse_minibex(text))
    assert err.value.field == "system" and "no equations" in str(err.value)
