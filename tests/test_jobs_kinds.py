"""Job kinds, limits and the worker's job runner, in-process (no worker processes)."""

import json
from pathlib import Path

import pytest
from pydantic import ValidationError

from certsolve.jobs import JobService, LimitError, ServiceSettings
from certsolve.jobs.errors import describe_validation_error, validation_details
from certsolve.jobs.jsonutil import dumps, plain, truncate_lists
from certsolve.jobs.kinds import KINDS, library_function, request_adapter
from certsolve.jobs.worker import JobMonitor, progress_dict, run_job
from certsolve.solver import Progress

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())


@pytest.fixture
def service(tmp_path):
    svc = JobService(
        ServiceSettings(
            data_dir=tmp_path, workers=0, enable_test_kinds=True, max_timeout=50.0,
            default_timeout=20.0, max_result_items=3,
        )
    )  # fmt: skip
    yield svc
    svc.close()


def run_one(service, request: dict):
    """Queue one job and run it in this process, as a worker would."""
    (job_id,) = service.submit([service.validate(request)])
    job, lease = service.store.claim(worker_pid=1)
    assert job.id == job_id
    run_job(service.store, job, lease, service.settings)
    return service.store.get(job_id)


def test_registry_and_models():
    assert set(KINDS) == {"solve", "fk", "ik", "isotropic-map", "workspace", "sleep"}
    assert KINDS["sleep"].hidden and not KINDS["solve"].hidden
    assert KINDS["solve"].has_timeout and KINDS["solve"].has_max_boxes
    assert not KINDS["ik"].has_timeout
    public = request_adapter(False)
    with pytest.raises(ValidationError):
        public.validate_python({"kind": "sleep"})
    req = public.validate_python({"kind": "solve", "system": CIRCLE})
    assert req.params.eps == 1e-8 and req.limits is None
    # a request survives the store's JSON round trip
    again = request_adapter(True).validate_json(req.model_dump_json())
    assert again == req
    fk = public.validate_python({"kind": "fk", "robot": PLANAR, "params": {"u": [1, 2, 3, 4]}})
    assert fk.robot.dof == 3 and fk.params.formulation == "auto"


def test_error_paths():
    bad = json.loads(json.dumps(PLANAR))
    bad["wires"][3]["tau"] = [5, 1]
    with pytest.raises(ValidationError) as info:
        request_adapter().validate_python(
            {"kind": "fk", "robot": bad, "params": {"u": [0, 0, 0, 0]}}
        )
    assert describe_validation_error(info.value) == "robot.wires.3.tau: tau_min must be <= tau_max"
    with pytest.raises(ValidationError) as info:
        request_adapter().validate_python({"kind": "solve", "system": "Variables\n x in [0;"})
    (d,) = validation_details(info.value.errors(), ("body",))
    assert d["field"] == "system" and d["msg"].startswith("line 2, column")
    assert d["loc"] == ["body", "system"]


def test_limits(service):
    v = service.validate
    lim = service.limits_for(v({"kind": "solve", "system": CIRCLE}))
    assert lim == {"timeout": 20.0, "max_boxes": 50_000_000, "memory_mb": 4096}
    lim = service.limits_for(
        v({"kind": "solve", "system": CIRCLE, "params": {"timeout": 5, "max_boxes": 10},
           "limits": {"timeout": 3, "memory_mb": 700}})
    )  # fmt: skip
    assert lim == {"timeout": 3.0, "max_boxes": 10, "memory_mb": 700}
    with pytest.raises(LimitError) as info:
        service.limits_for(v({"kind": "solve", "system": CIRCLE, "params": {"timeout": 51}}))
    assert info.value.field == "params.timeout"
    with pytest.raises(LimitError) as info:
        service.limits_for(v({"kind": "sleep", "limits": {"memory_mb": 100}}))
    assert info.value.field == "limits.memory_mb"


def test_run_solve_job(service):
    row = run_one(service, {"kind": "solve", "system": CIRCLE, "params": {"eps": 1e-10}})
    assert row.status == "done" and row.error is None
    res = json.loads(row.result)
    assert res["status"] == "complete" and len(res["solutions"]) == 2
    assert row.progress["solutions"] == 2 and row.progress["boxes"] >= 1


def test_run_job_failures(service):
    row = run_one(service, {"kind": "sleep", "params": {"fail": "bad input here"}})
    assert row.status == "failed" and row.error == "bad input here"
    # the limit on boxes is enforced through the progress callback for kinds without one
    row = run_one(service, {"kind": "sleep", "params": {"seconds": 5}, "limits": {"max_boxes": 3}})
    assert row.status == "done" and row.progress["stopped_by"] == "max_boxes"
    try:
        library_function("fk", "certsolve.kinematics", "forward_kinematics")
    except Exception:
        row = run_one(service, {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0]}})
        assert row.status == "failed" and row.error == "kind fk is not available in this build"


def test_cancel_through_the_monitor(service):
    (job_id,) = service.submit([service.validate({"kind": "sleep", "params": {"seconds": 30}})])
    job, lease = service.store.claim(1)
    service.cancel(job_id)  # requested before the first progress report
    run_job(service.store, job, lease, service.settings)
    row = service.store.get(job_id)
    assert row.status == "cancelled" and json.loads(row.result)["stopped_by"] == "cancelled"


def test_monitor_throttles_and_notices_lost_jobs(service):
    (job_id,) = service.submit([service.validate({"kind": "sleep"})])
    job, lease = service.store.claim(1)
    mon = JobMonitor(service.store, job, lease, interval=3600, parent_pid=None)
    assert mon(Progress(1, 2, 0, 0, 0.1)) is True  # first call writes
    assert service.store.get(job_id).progress["boxes"] == 1
    assert mon(Progress(2, 2, 0, 0, 0.2)) is True  # throttled: not written
    assert service.store.get(job_id).progress["boxes"] == 1
    service.store.release("gone", worker_pids=[1])  # the job was taken away
    assert mon.check() is False and mon.lost


def test_json_helpers():
    np = pytest.importorskip("numpy")
    obj = {"a": np.array([1.0, np.inf]), "b": (np.float64(2.5), np.int64(3)), "c": float("nan")}
    assert plain(obj) == {"a": [1.0, None], "b": [2.5, 3], "c": None}
    assert dumps(plain(obj)) == '{"a":[1.0,null],"b":[2.5,3],"c":null}'
    out = truncate_lists({"pending": list(range(10)), "x": [1]}, 4)
    assert out == {"pending": [0, 1, 2, 3], "x": [1], "truncated": {"pending": 10}}
    assert progress_dict({"boxes": np.int64(4), "elapsed": 1.5, "junk": "x"}, 0.0) == {
        "boxes": 4,
        "elapsed": 1.5,
    }


def test_results_are_truncated(service):
    # a search stopped after a few boxes leaves pending boxes: at most 3 are kept
    text = (
        "Variables\n x, y in [-3, 3];\nConstraints\n x^3 - x = 0.01*y;\n y^3 - y = 0.01*x;\nend\n"
    )
    row = run_one(service, {"kind": "solve", "system": text, "params": {"max_boxes": 5}})
    res = json.loads(row.result)
    assert row.status == "done" and res["status"] == "max_boxes"
    assert len(res["pending"]) == 3 and res["truncated"]["pending"] > 3
