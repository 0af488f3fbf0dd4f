"""Options of a solve checked without pydantic when they are surely valid (start-up).

``certsolve solve`` and :func:`certsolve.solve` read their options against the JSON Schema
of their model, kept as data (:func:`certsolve.lazy.surely_valid`), and call the model only
when a value is not surely accepted.  The tests: the copies equal the models' schemas; a
value the copy accepts, the model accepts (hypothesis); a run with valid options imports
neither pydantic nor the job kinds; the command line calls the solver as the job's
operation does.  The same refusals with the same messages: ``test_cli_validation.py``,
``test_library_inputs.py``.
"""

import argparse
import contextlib
import io
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from certsolve.cli import build_parser, main
from certsolve.cli.solve import PARAMS_SCHEMA, params_of
from certsolve.jobs.kinds.base import RunContext
from certsolve.jobs.kinds.solve import SolveParams, run_solve
from certsolve.lazy import surely_valid
from certsolve.solver.options import SolveOptions
from certsolve.solver.options_schema import SOLVE_OPTIONS_SCHEMA

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = str(ROOT / "examples" / "systems" / "circle-line.mbx")
COPIES = [(SOLVE_OPTIONS_SCHEMA, SolveOptions), (PARAMS_SCHEMA, SolveParams)]


def validating(schema: Any) -> Any:
    """A JSON Schema without the keywords that do not validate."""
    if isinstance(schema, dict):
        skip = ("title", "description", "default")
        return {k: validating(v) for k, v in schema.items() if k not in skip}
    if isinstance(schema, list):
        return [validating(v) for v in schema]
    return schema


@pytest.mark.parametrize(("copy", "model"), COPIES, ids=["SolveOptions", "SolveParams"])
def test_copies_are_the_models_schemas(copy, model):
    assert copy == validating(model.model_json_schema())


values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**12), max_value=10**12),
    st.sampled_from([0, 1, 100, 101, 10**9, 10**9 + 1, 10**400, -(10**400)]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 5e-324, 1e9, 1e9 + 1e-7, 1.0, 3.0, 100.0, 100.5]),
    st.sampled_from(["auto", "all", "3", " 3", "abc", "", "1e-8", "true"]),
)


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(COPIES), st.data())
def test_what_the_copy_accepts_the_model_accepts(pair, data):
    copy, model = pair
    field = data.draw(st.sampled_from(sorted(copy["properties"])))
    value = data.draw(values)
    if surely_valid(copy, {field: value}):
        try:
            model.model_validate({field: value})
        except ValidationError as exc:  # pragma: no cover - the failure this test looks for
            pytest.fail(f"{field}={value!r}: surely valid, refused by the model: {exc}")


def test_surely_valid_refuses_what_it_cannot_judge():
    props = PARAMS_SCHEMA
    assert surely_valid(props, {"eps": 1e-8, "max_boxes": 1, "cid_vars": "all"})
    assert not surely_valid(props, {"eps": 0.0})  # exclusiveMinimum
    assert not surely_valid(props, {"eps": float("inf")})
    assert not surely_valid(props, {"max_boxes": True})  # a bool is no count
    assert not surely_valid(props, {"cid_vars": "3"})  # the model converts it: ask the model
    assert not surely_valid(props, {"tau_max": 1.0})  # not a field
    assert not surely_valid({"properties": {"s": {"type": "string", "minLength": 2}}}, {"s": "a"})


def args_of(*argv: str) -> argparse.Namespace:
    return build_parser(["solve"]).parse_args(["solve", CIRCLE, *argv])


@pytest.mark.parametrize(
    "argv",
    [
        (),
        ("--max-boxes", "7", "--eps", "1e-6"),
        ("--cid-vars", "all", "--verify", "--no-split-at-zero", "--no-newton-starts"),
    ],
)
def test_surely_valid_options_are_the_models_values(argv):
    """Without the model, the params are what the model makes of the same options."""
    args = args_of(*argv)
    fields = {k: v for k, v in vars(args).items() if k in SolveParams.model_fields}
    assert params_of(args) == SolveParams.model_validate(fields).model_dump()


def _recorded(monkeypatch, call) -> dict:
    import certsolve.solver.branch_and_prune as bp

    seen: dict = {}

    def record(system, **kw):
        seen.update(kw, system=system.variables)
        return bp.SolveResult.unexplored(
            variables=system.variables,
            domain=system.domain,
            status=bp.SearchStatus.COMPLETE,
            eps=1.0,
            time=0.0,
            cpu=0.0,
        )

    monkeypatch.setattr(bp, "solve", record)
    with contextlib.redirect_stdout(io.StringIO()):
        call()
    return seen


@pytest.mark.parametrize(
    "argv",
    [
        (),
        ("--max-boxes", "7", "--eps", "1e-6", "--max-solutions", "2", "--max-pending", "9"),
        ("--cid-vars", "all", "--verify", "--max-undecided", "0"),
        ("--no-split-at-zero",),
        ("--no-newton-starts",),
        ("--cid-vars", "3"),  # not surely valid: through the model
    ],
)
def test_cli_calls_the_solver_as_the_job_does(monkeypatch, argv):
    from certsolve.expr.minibex import load_minibex

    cli = _recorded(monkeypatch, lambda: main(["solve", CIRCLE, "--json", *argv]))
    params = SolveParams.model_validate(
        {k: v for k, v in vars(args_of(*argv)).items() if k in SolveParams.model_fields}
    )
    ctx = RunContext(max_boxes=params.max_boxes, progress=None, executor="auto")
    job = _recorded(monkeypatch, lambda: run_solve(params, load_minibex(CIRCLE), ctx))
    assert cli == job and cli["max_boxes"] == params.max_boxes


def _modules_after(code: str) -> set[str]:
    probe = f"import sys, json, contextlib, io\n{code}\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    return set(json.loads(out.stdout.splitlines()[-1]))


def _heavy(mods: set[str]) -> set[str]:
    return {
        m
        for m in mods
        if m.split(".")[0] == "pydantic"
        or m.startswith(("certsolve.jobs.kinds", "certsolve.robot"))
    }


def test_a_valid_solve_imports_no_pydantic():
    cli = _modules_after(
        "from certsolve.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main(['solve', {CIRCLE!r}, '--max-boxes', '1', '--eps', '1e-9']) == 0"
    )
    assert "certsolve.solver.branch_and_prune" in cli and not _heavy(cli), _heavy(cli)
    lib = _modules_after(
        f"import certsolve\nassert certsolve.solve({CIRCLE!r}, timeout=5, max_boxes=3).stats.boxes"
    )
    assert not _heavy(lib), _heavy(lib)


def test_a_refused_option_still_names_itself(capsys):
    assert main(["solve", CIRCLE, "--eps", "0"]) == 2
    assert capsys.readouterr().err.startswith("error: --eps: must be greater than 0")
