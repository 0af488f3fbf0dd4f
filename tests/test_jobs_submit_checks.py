"""Submit-time validation and the job kinds ik-sweep and design: what cannot run is a 422
naming the field (Minibex line and column, the robot field, the parameter), and what is
accepted runs to the library's own answer."""

import copy
import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from certsolve.api.app import create_app
from certsolve.jobs import JobService, ServiceSettings
from certsolve.jobs.kinds import fk as fk_kind
from certsolve.jobs.worker import run_job

ROOT = Path(__file__).resolve().parents[1]
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())
MARIONET = json.loads((ROOT / "examples/robots/marionet.json").read_text())
ALMOST = json.loads((ROOT / "examples/robots/almost-planar.json").read_text())
KRUT3 = json.loads((ROOT / "examples/robots/krut-3.json").read_text())
SPEC = json.loads((ROOT / "examples/design/krut3-spec.json").read_text())
DESIGN = {k: v for k, v in SPEC.items() if k != "robot"} | {"eps": 0.25, "workspace_eps": 5}
SWEEP = {"pose": [85, 65, 3], "joint": 1, "start": 0.1, "stop": 10, "count": 8}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = ServiceSettings(data_dir=tmp_path_factory.mktemp("checks"), workers=0)
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        yield c


def fields(resp) -> dict[str, dict]:
    assert resp.status_code == 422, resp.text
    return {d["field"]: d for d in resp.json()["detail"]}


def submit(client, kind, robot, params):
    return client.post("/v1/jobs", json={"kind": kind, "robot": robot, "params": params})


def changed(robot, fn):
    r = copy.deepcopy(robot)
    fn(r)
    return r


# -- Minibex: undefined constants and syntax, with line and column -------------------------------
def _parser_checks_constants() -> bool:
    from certsolve.expr.minibex import MinibexError, parse_minibex

    try:
        parse_minibex("Constants\n a = 1/0;\nVariables\n x in [0, 1];\nConstraints\n x = a;\nend")
    except MinibexError:
        return True
    return False


@pytest.mark.skipif(
    not _parser_checks_constants(),
    reason="this build's Minibex parser does not yet refuse undefined constants",
)
@pytest.mark.parametrize(
    "text, line",
    [
        ("Constants\n a = 1/0;\nVariables\n x in [0, 1];\nConstraints\n x = a;\nend", 2),
        ("Variables\n x in [0, 1];\nConstraints\n x = log(0);\nend", 4),
        ("Variables\n x in [0, 1];\nConstraints\n x - sqrt(-1) = 0;\nend", 4),
    ],
)
def test_undefined_constants_are_refused_at_submission(client, text, line):
    d = fields(client.post("/v1/jobs", json={"kind": "solve", "system": text}))["system"]
    assert d["line"] == line and d["column"] >= 1 and d["msg"].startswith(f"line {line},")


def test_minibex_syntax_errors_have_line_and_column(client):
    text = "Variables\n x in [0, 1];\nConstraints\n x + * 2 = 0;\nend"
    d = fields(client.post("/v1/jobs", json={"kind": "solve", "system": text}))["system"]
    assert (d["line"], d["column"]) == (4, 6)


# -- robot geometry ---------------------------------------------------------------------------
def test_fk_geometry_is_checked_at_submission(client):
    u4 = {"u": [0, 0, 0, 0]}
    same = changed(PLANAR, lambda r: [w.update(platform=[0, 0]) for w in r["wires"]])
    d = fields(submit(client, "fk", same, u4))
    assert "needs 3 distinct attachment points" in d["robot.wires"]["msg"]
    flat = changed(MARIONET, lambda r: [w["platform"].__setitem__(2, 0) for w in r["wires"]])
    d = fields(submit(client, "fk", flat, {"u": [0] * 7, "formulation": "general-19"}))
    assert "robot.wires" in d
    d = fields(submit(client, "fk", PLANAR, {**u4, "formulation": "general-19"}))
    assert "spatial robots" in d["params.formulation"]["msg"]
    assert "params.formulation" in fields(submit(client, "fk", PLANAR, {**u4, "formulation": "x"}))
    assert "robot.dof" in fields(submit(client, "fk", KRUT3, {"u": [0, 0, 0]}))
    rigid = changed(PLANAR, lambda r: r["wires"][2].pop("k"))
    assert fields(submit(client, "fk", rigid, u4))["robot.wires.2.k"]["msg"].startswith("required")
    # the quick tracking call checks the same
    body = {"robot": same, "params": {"u": [0] * 4, "near_pose": [90, 60, 0]}}
    assert "robot.wires" in fields(client.post("/v1/fk/track", json=body))
    assert submit(client, "fk", PLANAR, u4).status_code == 202


def test_zero_length_wires_and_elastic_model(client):
    d = fields(submit(client, "ik", PLANAR, {"pose": [10, 5, 0]}))  # B_1 on A_1
    assert "wire 1 has zero length" in d["params.pose"]["msg"]
    r = client.post("/v1/ik", json={"robot": PLANAR, "params": {"pose": [10, 5, 0]}})
    assert "params.pose" in fields(r)
    # found by schemathesis: the force polytope at a pose on an anchor (was a 422 from
    # scipy's linprog about NaN, naming nothing)
    anchor = KRUT3["wires"][0]["base"]
    r = client.post("/v1/isotropic", json={"robot": KRUT3, "params": {"pose": anchor}})
    assert "wire 1 has zero length" in fields(r)["params.pose"]["msg"]
    assert "robot.wires.0.k" in fields(
        submit(client, "ik", KRUT3, {"pose": [0, 0], "method": "alg2"})
    )
    assert submit(client, "ik", KRUT3, {"pose": [0, 0]}).status_code == 202  # tension: no k


def test_a_batch_on_one_robot_checks_its_geometry_once(tmp_path, monkeypatch):
    calls = []
    real = fk_kind._fk_geometry_problem
    monkeypatch.setattr(fk_kind, "_fk_geometry_problem", lambda *a: calls.append(1) or real(*a))
    from certsolve.jobs.service import BatchRequest

    with JobService(ServiceSettings(data_dir=tmp_path, workers=0)) as svc:
        batch = BatchRequest(
            kind="fk", robot=PLANAR, params=[{"u": [0, 0, 0, i]} for i in range(40)]
        )
        _, ids = svc.submit_batch(batch)
    assert len(ids) == 40 and len(calls) == 1


# -- ik-sweep -----------------------------------------------------------------------------------
def test_ik_sweep_refusals_name_the_field(client):
    assert submit(client, "ik-sweep", PLANAR, SWEEP).status_code == 202
    assert "params.joint" in fields(submit(client, "ik-sweep", PLANAR, {**SWEEP, "joint": 9}))
    assert "params.count" in fields(submit(client, "ik-sweep", PLANAR, {**SWEEP, "count": 1}))
    assert "params.u_start" in fields(submit(client, "ik-sweep", PLANAR, {**SWEEP, "u_start": [0]}))
    assert "params.pose" in fields(
        submit(client, "ik-sweep", PLANAR, {**SWEEP, "pose": [10, 5, 0]})
    )
    d = fields(submit(client, "ik-sweep", ALMOST, {**SWEEP, "pose": [90, 60, -1, 0, 0, 0]}))
    assert "m = w + 1 = 7 wires" in d["robot.wires"]["msg"]
    assert "robot.dof" in fields(submit(client, "ik-sweep", KRUT3, {**SWEEP, "pose": [0, 0]}))
    assert "params.stop" in fields(submit(client, "ik-sweep", PLANAR, {**SWEEP, "stop": 1e7}))


def run_one(svc, request):
    (job_id,) = svc.submit([svc.validate(request)])
    job, lease = svc.store.claim(worker_pid=1)
    run_job(svc.store, job, lease, svc.settings)
    return svc.store.get(job_id)


def test_ik_sweep_job_gives_the_library_answer(tmp_path):
    from certsolve.kinematics.ik_sweep import ik_sweep

    with JobService(ServiceSettings(data_dir=tmp_path, workers=0)) as svc:
        row = run_one(svc, {"kind": "ik-sweep", "robot": PLANAR, "params": {**SWEEP, "joint": 2}})
    assert row.status == "done", row.error
    got = json.loads(row.result)
    want = ik_sweep(PLANAR, SWEEP["pose"], joint=2, start=0.1, stop=10, count=8).to_dict()
    assert got["joint"] == 2 and got["counts"] == want["counts"]
    assert [p["value"] for p in got["points"]] == [p["value"] for p in want["points"]]
    assert [p["u"] for p in got["points"]] == [p["u"] for p in want["points"]]
    assert row.progress["points"] == 8 and row.progress["total"] == 8


# -- design -------------------------------------------------------------------------------------
def test_design_refusals_name_the_field(client):
    assert submit(client, "design", KRUT3, DESIGN).status_code == 202
    bad = copy.deepcopy(DESIGN)
    bad["parameters"][1]["path"] = "wires[7].tau[1]"
    d = fields(submit(client, "design", KRUT3, bad))
    assert "wire index 7" in d["params.parameters.1.path"]["msg"]
    bad["parameters"][1]["path"] = "wires[*].length"
    assert "params.parameters.1.path" in fields(submit(client, "design", KRUT3, bad))
    bad = copy.deepcopy(DESIGN)
    bad["parameters"][1]["name"] = bad["parameters"][0]["name"]
    assert "duplicate" in fields(submit(client, "design", KRUT3, bad))["params.parameters"]["msg"]
    bad = {**DESIGN, "workspace": [-20, 20, -20, 20, 0, 1]}
    assert "params.workspace" in fields(submit(client, "design", KRUT3, bad))
    bad = {**DESIGN, "workspace": [20, -20, -20, 20]}
    assert "params.workspace" in fields(submit(client, "design", KRUT3, bad))
    assert "params.orientation" in fields(
        submit(client, "design", KRUT3, {**DESIGN, "orientation": 5})
    )
    assert "params.min_force" in fields(submit(client, "design", KRUT3, {**DESIGN, "min_force": 0}))
    bad = copy.deepcopy(DESIGN)
    bad["parameters"][0]["range"] = [140, 60]
    assert "params.parameters.0.range" in fields(submit(client, "design", KRUT3, bad))


def test_design_job_gives_the_library_answer(tmp_path):
    from certsolve.force.design import design

    with JobService(ServiceSettings(data_dir=tmp_path, workers=0)) as svc:
        row = run_one(svc, {"kind": "design", "robot": KRUT3, "params": DESIGN})
    assert row.status == "done", row.error
    got = json.loads(row.result)
    fields = {k: DESIGN[k] for k in ("parameters", "workspace", "min_force")}
    want = design({"robot": KRUT3, **fields, "eps": 0.25, "workspace_eps": 5}).to_dict()
    assert got["status"] == "complete" and got["counts"] == want["counts"]
    assert got["good_boxes"] == want["good_boxes"] and got["best"] == want["best"]
    assert got["counts"]["good"] >= 1


def test_flat_polytope_with_krut_algorithm(client):
    """Found by schemathesis: Krut's algorithm on fewer wires than wrench components was a
    422 from numpy's SVD ('Last 2 dimensions of the array must be square'); the polytope
    is flat, as hyperplane shifting already said."""
    one = {"dof": 3, "wires": [{"base": [0.0, 0.0], "platform": [1.0, 0.0], "tau": [0.0, 1.0]}]}
    for algorithm in ("krut", "shifting"):
        body = {"robot": one, "params": {"pose": [5, 5, 0], "algorithm": algorithm}}
        r = client.post("/v1/isotropic", json=body)
        assert r.status_code == 200 and r.json()["status"] == "degenerate", r.text


def test_fk_formulations_are_the_librarys():
    from typing import get_args

    from certsolve.kinematics.fk_systems import FORMULATIONS
    from certsolve.robot.inputs import Formulation

    names = fk_kind.FORMULATIONS + fk_kind.PLANAR_FORMULATIONS + fk_kind.SPATIAL_FORMULATIONS
    assert set(get_args(Formulation)) == set(names) == set(FORMULATIONS)
