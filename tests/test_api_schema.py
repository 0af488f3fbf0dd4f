"""Property-based run of the whole OpenAPI schema (schemathesis) against the app in process.

Every operation gets schema-conforming (positive) and non-conforming (negative) requests,
with a valid admin token, and every answer is checked:

* never a server error (the only 5xx allowed is 501 from a quick call whose library
  function is not in this build);
* the answer conforms to the schema: a documented status code, content type, body
  (``ErrorBody`` for every error) and headers;
* **positive data is accepted**: a request the schema says is valid gets 2xx (or 404 for
  an unknown job id, 409, 429);
* a request without a token gets 401 (``ignored_auth``).

JSON Schema cannot state every rule the validation enforces; :func:`repair` makes the
generated positive bodies obey those (and only those) rules, listed in
``docs/reliability.md``: ``lo <= hi`` of intervals, ``tau_max < k``, ``u`` with one value
per wire, Minibex grammar, attachment points that span the FK frame, no zero-length wire
at an IK pose, design parameter and tolerance paths that exist in the robot (and no
seeding or stable-only FK of a robot with tolerances), ``nx * ny`` of a grid,
workspace angle ranges, the cost estimate of quick calls, and the sweep form of batches
(whose params must be the params of its kind).  The app runs without workers (queued
jobs stay queued).  The schema is loaded inside the tests, so collecting this module
costs nothing when they are deselected.
"""

import copy
import json
import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis.errors import Unsatisfiable

from certsolve.api.app import create_app
from certsolve.jobs import ServiceSettings
from certsolve.jobs.access import load_access

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
TOKEN = "schemathesis-admin-token-0123"
#: examples per operation and mode in the default run (``test_job_submission``): a
#: schema-conforming job body costs hypothesis about a second to draw (the robot and its
#: parameters are large objects), so 15 made that test the suite's slowest (55 s of 900
#: here); ``test_whole_schema`` (slow) draws 60 of each operation
N_EXAMPLES = 5


# -- the rules JSON Schema cannot state ----------------------------------------------------------
def _pairs(values):
    """Each ``[lo, hi]`` in order."""
    return [sorted(v) if isinstance(v, list) and len(v) == 2 else v for v in values]


def _repair_robot(robot: dict, kind: str | None) -> None:
    dim = 3 if robot.get("dof") == 6 else 2
    if robot.get("tolerances"):  # a path this robot has, on no number twice
        robot["tolerances"] = [dict(robot["tolerances"][0], path="wires[*].base[*]")]
    for i, w in enumerate(robot.get("wires", [])):
        w["tau"] = sorted(w["tau"])
        if w.get("u") is not None:
            w["u"] = sorted(w["u"])
        if w.get("k") is not None and not w["tau"][1] < w["k"]:
            w["k"] = min(1e12, max(abs(w["tau"][1]) * 2, 1.0) + 1.0)
        if kind in ("fk", "fk/track", "ik-sweep", "trajectory") and robot["dof"] != 2:
            # attachment points that span the FK frame: a non-degenerate simplex
            corner = [[10, 0, 0], [0, 10, 0], [0, 0, 10], [-7, -7, 3]][i % 4][:dim]
            w["platform"] = [c + 0.5 * (i // 4) for c in corner]
            w["base"] = [100.0 * math.cos(i + 1), 100.0 * math.sin(i + 1), 50.0 * (i % 3)][:dim]
    if robot.get("domain"):
        robot["domain"]["points"] = _pairs(robot["domain"]["points"])


def _no_zero_wire(robot: dict, pose: list) -> None:
    """Move an anchor that the platform touches at ``pose`` (an IK pose)."""
    from certsolve.jobs.kinds.base import check_wire_lengths
    from certsolve.robot.schema import RobotSpec

    for i in range(len(robot["wires"])):
        try:
            check_wire_lengths(RobotSpec.model_validate(robot), pose, "pose")
            return
        except ValueError:
            robot["wires"][i]["base"][0] += 1.0 if robot["wires"][i]["base"][0] < 0 else -1.0


def _ik_of_a_set(robot: dict, params: dict) -> None:
    """What the IK of a set does not take (alg1, Newton, fewer wires than equations, a
    wire that may reach length 0 for a robot of the set): a robot without tolerances."""
    from certsolve.jobs.kinds.ik import IkParams
    from certsolve.robot.schema import RobotSpec

    try:
        IkParams.model_validate(params).check_robot(RobotSpec.model_validate(robot))
    except ValueError:
        robot.pop("tolerances", None)


def _repair_params(kind: str, robot: dict | None, params: dict) -> None:
    m = len(robot["wires"]) if robot else 0
    if kind in ("fk", "fk/track"):
        params["u"] = (list(params["u"]) + [0.0] * m)[:m]
        params.pop("formulation", None)  # which ones a robot admits depends on its geometry
        if robot and robot.get("tolerances"):  # options the FK of a set does not take
            for option in ("seed_planar", "seeded_only", "stable_only"):
                params.pop(option, None)
    if kind == "ik":  # another method's options keep their defaults
        from certsolve.robot.inputs import IK_METHOD_OPTIONS

        own = IK_METHOD_OPTIONS[params.get("method", "tension")]
        for name in {n for names in IK_METHOD_OPTIONS.values() for n in names} - set(own):
            if name not in ("timeout", "max_boxes"):
                params.pop(name, None)
    if kind in ("trajectory", "fk/track") and robot:  # tracking takes one robot, not a set
        robot.pop("tolerances", None)
    if kind == "trajectory":
        params["controls"] = [(list(row) + [0.0] * m)[:m] for row in params["controls"]]
        params.pop("formulation", None)  # as fk's
    if kind == "ik" and params.get("method") == "alg1" and (params.get("timeout") or 0) > 5.0:
        params["timeout"] = 5.0  # Algorithm 1 searches that long: within a quick call's cost
    if kind == "ik" and robot and m != robot["dof"] + 1:  # closed form: m = w + 1 wires
        params.pop("distribution", None)
    if kind == "ik" and robot and params.get("tau_fixed") is not None:  # eq. 5: tau < k
        ks = [w["k"] for w in robot["wires"] if w.get("k") is not None]
        if ks and params["tau_fixed"] >= min(ks):
            params.pop("tau_fixed")
    if kind == "ik" and m:
        if params.get("u_last") is not None:
            params["u_last"] = (list(params["u_last"]) + [0.0] * m)[:m]
        params["fixed_wire"] = min(params.get("fixed_wire", 1), m)
    if kind in ("ik", "ik-sweep", "isotropic") and robot is not None:
        _no_zero_wire(robot, params["pose"])
    if kind == "ik" and robot and robot.get("tolerances"):
        _ik_of_a_set(robot, params)
    if kind == "ik-sweep":
        params["joint"] = min(params.get("joint", 1), m)
    if kind == "isotropic":
        from certsolve.jobs.kinds import IsotropicCall
        from certsolve.jobs.kinds.isotropic_map import isotropic_cost

        call = IsotropicCall.model_validate({"robot": robot, "params": params})
        while isotropic_cost(call) > 5.0 and len(robot["wires"]) > robot["dof"]:
            robot["wires"].pop()  # within the cost a quick call may have
            call = IsotropicCall.model_validate({"robot": robot, "params": params})
        if (
            params.get("algorithm") == "krut"
            and math.comb(2 ** len(robot["wires"]), robot["dof"]) > 10**6
        ):
            params["algorithm"] = "shifting"
    if kind == "isotropic-map":
        params["grid"] = [*sorted(params["grid"][:2]), *sorted(params["grid"][2:])]
        params["ny"] = min(params.get("ny", 41), max(1, 250_000 // params.get("nx", 41)))
    if kind == "workspace":
        params["box"] = _pairs(params["box"])
        o = params.get("orientation")
        if isinstance(o, list):
            o = [sorted(a) if isinstance(a, list) else a for a in o]
            params["orientation"] = [
                [a[0], min(a[1], a[0] + 360)] if isinstance(a, list) else a for a in o
            ]
            if robot["dof"] == 3 and len(o) == 2 and not isinstance(o[0], list):
                params["orientation"] = [o[0], min(o[1], o[0] + 360)]
    if kind == "design":
        ws = params["workspace"]
        params["workspace"] = [v for pair in zip(ws[::2], ws[1::2]) for v in sorted(pair)]
        for w in robot["wires"]:  # room for the tau_max range below 1e9 N
            w["tau"] = [min(w["tau"][0], 1e8), max(w["tau"][1], min(w["tau"][0], 1e8))]
        low = max(w["tau"][0] for w in robot["wires"]) + 1.0
        for w in robot["wires"]:
            if w.get("k") is not None:
                w["k"] = max(w["k"], low + 10.0)
        params["parameters"] = [  # paths that exist in every robot, on no shared number
            {"name": "tau_max", "path": "wires[*].tau[1]", "range": [low, low + 1.0]},
            {"name": "x0", "path": "wires[0].base[0]", "range": [-1.0, 1.0]},
        ]


def repair(path: str, body):
    """A positive body made to obey the rules the schema cannot state (module docstring)."""
    if not isinstance(body, dict):
        return body
    body = copy.deepcopy(body)
    quick = {"/v1/ik": "ik", "/v1/isotropic": "isotropic", "/v1/fk/track": "fk/track"}
    if path in quick:
        _repair_robot(body["robot"], quick[path])
        _repair_params(quick[path], body["robot"], body["params"])
    elif path == "/v1/jobs":
        _repair_job(body)
    elif path == "/v1/jobs/batch" and isinstance(body.get("jobs"), list):
        for job in body["jobs"]:
            _repair_job(job)
    return body


def _repair_job(job: dict) -> None:
    kind = job.get("kind")
    if kind == "solve":
        from certsolve.jobs.kinds.solve import check_system

        try:
            check_system(job["system"])
        except ValueError:
            job["system"] = CIRCLE  # Minibex grammar
        return
    if "robot" in job:
        _repair_robot(job["robot"], kind)
        _repair_params(kind, job["robot"], job["params"])


def _sweep_form(path: str, body) -> bool:
    return path == "/v1/jobs/batch" and isinstance(body, dict) and "params" in body


# -- the run ------------------------------------------------------------------------------------
def _schema(tmp_path, *, positive: bool):
    schemathesis = pytest.importorskip("schemathesis")
    tokens = {"admin": {"token": TOKEN, "admin": True, "requests_per_minute": 10**9}}
    access = load_access(None, {"CERTSOLVE_TOKENS": json.dumps(tokens)})
    app = create_app(
        ServiceSettings(
            data_dir=tmp_path, workers=0, max_queued=10**7, quota_queued=10**7, access=access
        )
    )
    schema = schemathesis.openapi.from_asgi("/openapi.json", app)
    if positive:

        @schema.hook
        def map_body(ctx, body):
            return repair(ctx.operation.path, body)

        @schema.hook
        def filter_body(ctx, body):
            return not _sweep_form(ctx.operation.path, body)

    return schema


def _checks():
    from schemathesis.checks import (
        content_type_conformance,
        not_a_server_error,
        response_headers_conformance,
        response_schema_conformance,
        status_code_conformance,
    )
    from schemathesis.specs.openapi.checks import ignored_auth, positive_data_acceptance

    return [
        not_a_server_error,
        status_code_conformance,
        content_type_conformance,
        response_schema_conformance,
        response_headers_conformance,
        positive_data_acceptance,
        ignored_auth,
    ]


def _run(op, mode, counter, n=N_EXAMPLES):
    checks = _checks()
    headers = {"Authorization": f"Bearer {TOKEN}"}

    @settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        phases=[Phase.explicit, Phase.generate],
    )
    @given(case=op.as_strategy(generation_mode=mode))
    def run(case):
        response = case.call(headers=headers)
        counter.append(response.status_code)
        if response.status_code == 501:
            return  # a library function this build lacks
        case.validate_response(response, checks=checks, headers=headers)

    try:
        run()
    except Unsatisfiable:  # nothing to make invalid (an operation without inputs)
        assert mode.name == "NEGATIVE"


def _operations(schema, where=None):
    ops = [r.ok() for r in schema.get_all_operations()]
    assert len(ops) >= 13
    return [op for op in ops if where is None or where(op)]


@pytest.mark.slow
def test_whole_schema(tmp_path, capsys):
    """Every operation, positive and negative (docs/reliability.md has the figures)."""
    from schemathesis.generation import GenerationMode

    counts = []
    for positive, mode in ((True, GenerationMode.POSITIVE), (False, GenerationMode.NEGATIVE)):
        schema = _schema(tmp_path / mode.name, positive=positive)
        for op in _operations(schema):
            _run(op, mode, counts, n=60)
    with capsys.disabled():
        print(f"\nschemathesis: {len(counts)} requests, statuses {sorted(set(counts))}")


@pytest.mark.parametrize("positive", [True, False])
def test_job_submission(tmp_path, positive):
    """The default run: the two job-submission operations, one generation mode each."""
    from schemathesis.generation import GenerationMode

    schema = _schema(tmp_path, positive=positive)
    chosen = _operations(
        schema, lambda op: op.method.upper() == "POST" and op.path.startswith("/v1/jobs")
    )
    assert len(chosen) == 2
    mode = GenerationMode.POSITIVE if positive else GenerationMode.NEGATIVE
    for op in chosen:
        _run(op, mode, [])


# -- what the schema publishes beyond the models ------------------------------------------------
def test_a_batch_kind_is_one_of_the_services_kinds(tmp_path):
    """The sweep form's ``kind`` is published as an enum of the kinds this service runs
    (the hidden test kind only when enabled), and a wrong one is a 422 at ``kind``."""
    from fastapi.testclient import TestClient

    from certsolve.jobs.kinds import public_kinds

    for hidden in (False, True):
        settings = ServiceSettings(data_dir=tmp_path / str(hidden), workers=0,
                                   enable_test_kinds=hidden)  # fmt: skip
        with TestClient(create_app(settings), base_url="http://localhost") as c:
            schema = c.get("/openapi.json").json()
            kind = schema["components"]["schemas"]["BatchRequest"]["properties"]["kind"]
            (branch,) = [b for b in kind["anyOf"] if b.get("type") == "string"]
            assert branch["enum"] == public_kinds(hidden)
            assert ("sleep" in branch["enum"]) is hidden
            for bad in ("", "nope", *(() if hidden else ("sleep",))):
                r = c.post("/v1/jobs/batch", json={"kind": bad, "params": [{}]})
                assert r.status_code == 422, (bad, r.text)
                (d,) = r.json()["detail"]
                assert d["field"] == "kind" and d["msg"].startswith("must be one of 'solve'")


def test_the_cross_field_rules_are_in_the_operations_descriptions(tmp_path):
    from fastapi.testclient import TestClient

    settings = ServiceSettings(data_dir=tmp_path, workers=0)
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        paths = c.get("/openapi.json").json()["paths"]
    for path in ("/v1/jobs", "/v1/jobs/batch"):
        text = paths[path]["post"]["description"]
        assert "`params.u` has one value per wire" in text, path
        assert "`lo <= hi`" in text and "tau_max" in text, path


def test_the_sweep_form_of_a_batch_is_published_per_kind(tmp_path):
    """``{"kind", robot or system, "params": [...]}``: the schema states each kind's params
    (one variant per kind and robot dof), so what it accepts the service accepts, and a
    params object of the wrong kind is refused by both."""
    from fastapi.testclient import TestClient

    jsonschema_rs = pytest.importorskip("jsonschema_rs")
    planar = json.loads((ROOT / "examples/robots/planar.json").read_text())
    settings = ServiceSettings(data_dir=tmp_path, workers=0)
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        components = c.get("/openapi.json").json()["components"]
        root = {"components": components, "$ref": "#/components/schemas/BatchRequest"}
        valid = jsonschema_rs.Draft202012Validator(root).is_valid
        good = [
            {"kind": "fk", "robot": planar, "params": [{"u": [0, 0, 0, 0]}, {"u": [1, 1, 1, 1]}]},
            {"kind": "solve", "system": CIRCLE, "params": [{"eps": 1e-6}, {}]},
        ]
        bad = [
            {"kind": "fk", "robot": planar, "params": [{"eps": 0.1}]},  # no u
            {"kind": "fk", "robot": planar, "params": [{"u": [0, 0, 0, 0], "grid": [0, 1]}]},
            {"kind": "solve", "system": CIRCLE, "robot": planar, "params": [{}]},
            {"kind": "workspace", "robot": planar, "params": [{"u": [0, 0, 0, 0]}]},
            {"kind": "fk", "system": CIRCLE, "params": [{"u": [0, 0, 0, 0]}]},
        ]
        for body in good:
            assert valid(body), body
            assert c.post("/v1/jobs/batch", json=body).status_code == 202, body
        for body in bad:
            assert not valid(body), body
            assert c.post("/v1/jobs/batch", json=body).status_code == 422, body
