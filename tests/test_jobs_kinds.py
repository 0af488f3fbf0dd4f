"""Job kinds, limits and the worker's job runner, in-process (no worker processes)."""

import inspect
import json
import sys
from pathlib import Path

import pytest
from pydantic import ValidationError

from certsolve.jobs import JobService, LimitError, ServiceSettings
from certsolve.jobs.errors import describe_validation_error, validation_details
from certsolve.jobs.jsonutil import dumps, plain, truncate_lists
from certsolve.jobs.kinds import KINDS, QUICK_CALLS, RunContext, public_kinds, request_adapter
from certsolve.jobs.worker import JobMonitor, progress_dict, run_job
from certsolve.robot import load_robot_spec
from certsolve.solver import Progress

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())
MARIONET = ROOT / "examples/robots/marionet.json"
DESIGN = json.loads((ROOT / "examples/design/planar-spec.json").read_text())


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
    assert set(KINDS) == {
        "solve",
        "fk",
        "ik",
        "ik-sweep",
        "isotropic-map",
        "workspace",
        "design",
        "trajectory",
        "sleep",
    }
    assert KINDS["sleep"].hidden and not KINDS["solve"].hidden
    assert KINDS["solve"].has_timeout and KINDS["solve"].has_max_boxes
    assert KINDS["ik"].has_timeout  # Algorithm 1's own time limit
    assert not KINDS["isotropic-map"].has_timeout
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
        KINDS["fk"].load()
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
    # the partial result of a cancelled job is its result, with the job's status
    assert service.result_text(job_id) == ("cancelled", row.result)


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
        "Variables\n x in [-3, 3];\n y in [-3, 3];\n"
        "Constraints\n x^3 - x = 0.01*y;\n y^3 - y = 0.01*x;\nend\n"
    )
    row = run_one(service, {"kind": "solve", "system": text, "params": {"max_boxes": 5}})
    res = json.loads(row.result)
    assert row.status == "done" and res["status"] == "max_boxes"
    assert len(res["pending"]) == 3 and res["truncated"]["pending"] > 3


LINE = (
    "Variables\n x in [-1e6, 1e6];\n y in [-1e6, 1e6];\n"
    "Constraints\n x - y = 0;\n 2*x - 2*y = 0;\nend\n"
)


def listed_and_counted(res: dict) -> tuple[int, int]:
    """Pending boxes listed in a stored result, and how many the search left (the count
    a bounded result keeps: ``truncated.pending``, or a summary's ``pending_total``)."""
    listed = len(res["pending"])
    total = res.get("pending_total") or res.get("truncated", {}).get("pending") or listed
    return listed, total


def test_stopped_search_keeps_a_bounded_result(service):
    """The issue's line system at eps 1e-12 leaves a pending box per step along the line:
    stopped by its time limit, the job is done with a result of bounded size that counts
    what it does not list."""
    row = run_one(
        service, {"kind": "solve", "system": LINE, "params": {"eps": 1e-12, "timeout": 1}}
    )
    res = json.loads(row.result)
    assert row.status == "done" and res["status"] == "timeout"
    assert res["stats"]["stopped_by"] == "timeout"
    listed, total = listed_and_counted(res)
    assert listed <= service.settings.max_result_items < total
    assert len(row.result) < 20_000  # max_result_items = 3 boxes, and the rest of the result
    assert row.finished_at - row.started_at < 1 + service.settings.kill_grace


def test_memory_stop_keeps_the_result(tmp_path):
    """Past memory_stop of its memory limit a job stops through its progress callback and
    is done with its partial result, marked stopped_by memory."""
    settings = ServiceSettings(
        data_dir=tmp_path, workers=0, enable_test_kinds=True, memory_stop=1e-6
    )
    with JobService(settings) as svc:
        row = run_one(svc, {"kind": "sleep", "params": {"seconds": 30}})
    res = json.loads(row.result)
    assert row.status == "done" and row.error is None
    assert res["stopped_by"] == "memory" and row.progress["stopped_by"] == "memory"
    assert res["slept"] < 10


def test_monitor_memory_guard(service):
    (job_id,) = service.submit([service.validate({"kind": "sleep"})])
    job, lease = service.store.claim(1)
    mon = JobMonitor(
        service.store, job, lease, interval=0, parent_pid=None, memory_stop_bytes=2**60
    )
    assert mon(Progress(1, 2, 0, 0, 0.1)) is True and mon.stopped_by is None
    used = mon.address_space()
    assert used is not None and used > 2**20
    mon.memory_stop_bytes = used // 2
    assert mon(Progress(2, 2, 0, 0, 0.2)) is False and mon.stopped_by == "memory"


def test_batch_expansion_in_the_service(service):
    from certsolve.jobs.service import BatchError, BatchRequest

    sweep = BatchRequest(kind="fk", robot=PLANAR, params=[{"u": [0, 0, 0, i]} for i in range(4)])
    batch_id, ids = service.submit_batch(sweep)
    assert len(ids) == 4 and service.store.counts(batch=batch_id)["queued"] == 4
    bad = sweep.model_copy(update={"params": [{"u": [0, 0, 0, 0]}, {"u": [1, 2]}]})
    with pytest.raises(BatchError) as info:
        service.submit_batch(bad)
    assert [d["field"] for d in info.value.details] == ["params.1.u"]
    assert not info.value.too_large
    many = BatchRequest(jobs=[{"kind": "sleep"}] * (service.settings.max_batch + 1))
    with pytest.raises(BatchError) as info:
        service.expand_batch(many)
    assert info.value.too_large
    with pytest.raises(BatchError, match="either jobs"):
        service.expand_batch(BatchRequest(jobs=[{"kind": "sleep"}], kind="sleep"))
    over = BatchRequest(jobs=[{"kind": "sleep", "limits": {"timeout": 1e5}}])
    with pytest.raises(BatchError) as info:
        service.expand_batch(over)
    assert info.value.details[0]["field"] == "jobs.0.limits.timeout"


def test_housekeeping_purges_old_finished_jobs(tmp_path):
    import time

    from certsolve.jobs.retention import Housekeeper

    settings = ServiceSettings(data_dir=tmp_path, workers=0, keep_days=1e-6)  # 86 ms
    with JobService(settings) as svc:
        old, new = svc.submit([svc.validate({"kind": "solve", "system": CIRCLE})] * 2)
        svc.cancel(old)
        time.sleep(0.2)
        assert Housekeeper(svc.store, settings).run_once() == 1
        assert svc.store.get(old) is None and svc.store.get(new).status == "queued"
        assert svc.store.file_sizes()["wal"] == 0


def test_progress_dict_reads_the_driver_extra():
    """The workspace paving reports inside / inside_share in the driver's ``extra``."""
    from certsolve.solver.search import Progress

    p = Progress(boxes=9, pending=3, solutions=2, undecided=0, elapsed=0.5)
    p.extra.update({"inside": 2, "inside_share": 0.25})
    d = progress_dict(p, 0.0)
    assert d["boxes"] == 9 and d["inside"] == 2 and d["inside_share"] == 0.25


# -- each operation calls its library function with options it takes ------------------------------
# one valid request per kind and quick call (a kind missing here fails the first test)
SAMPLES = {
    "solve": {"kind": "solve", "system": CIRCLE},
    "fk": {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0], "tau_max": 20}},
    "ik": {"kind": "ik", "robot": PLANAR, "params": {"pose": [90, 60, 0], "method": "alg2"}},
    "ik-sweep": {
        "kind": "ik-sweep",
        "robot": PLANAR,
        "params": {"pose": [90, 60, 0], "start": -1, "stop": 1, "count": 3},
    },
    "isotropic-map": {
        "kind": "isotropic-map",
        "robot": PLANAR,
        "params": {"grid": [80, 100, 50, 70], "nx": 2, "ny": 2, "orientation": 0},
    },
    "workspace": {
        "kind": "workspace",
        "robot": PLANAR,
        "params": {"min_force": 1, "box": [[80, 100], [50, 70]], "eps": 5, "external": [0, 1, 0]},
    },
    "design": {
        "kind": "design",
        "robot": PLANAR,
        "params": {k: v for k, v in DESIGN.items() if k != "robot"},
    },
    "trajectory": {
        "kind": "trajectory",
        "robot": PLANAR,
        "params": {"controls": [[0, 0, 0, 0], [0.01, 0.01, 0.01, 0.01]], "start": [90, 60, 0]},
    },
}
QUICK_SAMPLES = {
    "ik": {"pose": [90, 60, 0]},
    "isotropic": {"pose": [90, 60, 0], "algorithm": "krut", "external": [0, 1, 0]},
    "fk/track": {"u": [0, 0, 0, 0], "near_pose": [90, 60, 0], "half_width": 0.2},
}
# functions with **options, and where those go
FORWARDED = {
    "solve": ("certsolve.solver.branch_and_prune:Solver.default",),
    "ik": (  # by method: test_ik_passes_each_option_to_its_methods_function
        "certsolve.kinematics.ik_first:ik_tension_first",
        "certsolve.kinematics.ik_alg1:ik_algorithm1",
        "certsolve.kinematics.ik_alg2:Algorithm2",  # ik_algorithm2 takes its options
    ),
}


def _named(fn) -> set[str]:
    return {
        n
        for n, p in inspect.signature(fn).parameters.items()
        if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)
    }


def _forwarded(name: str) -> set[str]:
    named: set[str] = set()
    for path in FORWARDED.get(name, ()):
        module, attr = path.split(":")
        obj = sys.modules[module] if module in sys.modules else __import__(module, fromlist=["_"])
        for part in attr.split("."):
            obj = getattr(obj, part)
        named |= _named(obj)
    return named


def _replace_function(monkeypatch, real, accepted: set[str]) -> list:
    """Replace ``real`` where it is defined by a recorder that binds each call to its
    signature (an option it does not take is a TypeError) and to ``accepted``."""
    calls: list = []
    signature = inspect.signature(real)

    def fake(*args, **kwargs):
        signature.bind(*args, **kwargs)
        unknown = set(kwargs) - accepted
        assert not unknown, f"{real.__name__} does not take {sorted(unknown)}"
        calls.append(kwargs)
        return {"fake": True}

    monkeypatch.setattr(sys.modules[real.__module__], real.__name__, fake)
    return calls


def test_every_public_kind_has_a_sample():
    assert set(SAMPLES) == set(public_kinds())
    assert set(QUICK_SAMPLES) == set(QUICK_CALLS) - {"sleep"}


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_each_operation_passes_only_options_its_function_takes(name, monkeypatch):
    """The recipe of a kind: ``run(params, input, ctx)`` calls ``function()`` (the same
    function, imported where it is defined) once, with options of its signature only."""
    kind = KINDS[name]
    real = kind.load()
    calls = _replace_function(monkeypatch, real, _named(real) | _forwarded(name))
    req = request_adapter().validate_python(SAMPLES[name])
    assert type(req) is kind.model and type(req.params) is kind.params
    ctx = RunContext(time_limit=1.0, max_boxes=10, cancel=None, executor=None)
    assert kind.run(req.params, kind.input_of(req), ctx) == {"fake": True}
    assert len(calls) == 1


# each ik method with every option it reads set away from its default (MARIONET: 7 wires)
IK_SAMPLES = {
    "tension": {"distribution": "lp", "check_lp": True},
    "alg1": {"u_last": [0.3] * 7, "window": 0.5, "timeout": 2.0, "max_boxes": 50},
    "alg2": {"u_last": [0.3] * 7, "window": 0.5, "fixed_wire": 3, "tau_fixed": 5.0,
             "solve": "newton"},
}  # fmt: skip


@pytest.mark.parametrize("method", sorted(IK_SAMPLES))
def test_ik_passes_each_option_to_its_methods_function(method, monkeypatch):
    """``run_ik`` hands ``inverse_kinematics`` the options of ``method`` only, and they
    bind to that method's function; every option of the params reaches some method."""
    from certsolve.kinematics import ik as ik_module
    from certsolve.kinematics.ik_alg1 import ik_algorithm1
    from certsolve.kinematics.ik_alg2 import ik_algorithm2
    from certsolve.kinematics.ik_first import ik_tension_first
    from certsolve.robot.inputs import IK_METHOD_OPTIONS

    functions = {"tension": ik_tension_first, "alg1": ik_algorithm1, "alg2": ik_algorithm2}
    calls: list = []

    def fake(robot, pose, method, **options):
        inspect.signature(functions[method]).bind(robot, pose, **options)
        calls.append(options)
        return {"fake": True}

    monkeypatch.setattr(ik_module, "inverse_kinematics", fake)
    spec = load_robot_spec(MARIONET)
    params = KINDS["ik"].params.model_validate(
        {"pose": [111, 58, 107, 0, 0, 0], "method": method, **IK_SAMPLES[method]}
    )
    params.check_robot(spec)
    ctx = RunContext(time_limit=1.0, max_boxes=10)
    assert KINDS["ik"].run(params, spec, ctx) == {"fake": True}
    (options,) = calls
    expected = {**IK_SAMPLES[method]}
    if method == "alg1":  # within the job's limits
        expected.update(timeout=1.0, max_boxes=10)
    assert options == expected
    fields = set(KINDS["ik"].params.model_fields) - {"pose", "method"}
    assert fields == set().union(*IK_METHOD_OPTIONS.values())


@pytest.mark.parametrize("name", sorted(QUICK_SAMPLES))
def test_each_quick_call_passes_only_options_its_function_takes(name, monkeypatch):
    call = QUICK_CALLS[name]
    real = call.load()
    calls = _replace_function(monkeypatch, real, _named(real) | _forwarded(name))
    req = call.model.model_validate({"robot": PLANAR, "params": QUICK_SAMPLES[name]})
    assert call.run(req.params, req.robot) == {"fake": True}
    assert len(calls) == 1


def test_the_worker_trusts_the_stored_request(service, monkeypatch):
    """The request is checked against the robot once, when the service takes it; the
    worker parses the stored request without checking it again."""
    from certsolve.jobs.kinds import fk

    seen = []
    check = fk.FkParams.check_robot
    monkeypatch.setattr(fk.FkParams, "check_robot", lambda *a: seen.append(1) or check(*a))
    request = {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0], "eps": 1e-3}}
    row = run_one(service, request)
    assert row.status == "done" and seen == [1]
