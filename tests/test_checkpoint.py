"""Checkpoints: a search stopped (limit, kill, Ctrl-C) and resumed gives the answer of an
uninterrupted run.

Every comparison is against an uninterrupted search computed here.  A serial search
resumed from a snapshot replays the same batches, so the solutions, the undecided boxes
and even the processed-box count are equal -- a resume that lost or repeated work would
change the count.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_search_driver import FlakyExecutor

from certsolve.expr.minibex import load_minibex
from certsolve.force import certified_workspace
from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.robot import Robot
from certsolve.solver import Solver
from certsolve.solver.checkpoint import Checkpoint, CheckpointError, decode, encode
from certsolve.solver.result import Undecided

ROOT = Path(__file__).resolve().parents[1]
K5 = str(ROOT / "examples/systems/katsura-5.mbx")  # 16 solutions, ~3900 boxes
K6 = str(ROOT / "examples/systems/katsura-6.mbx")  # 32 solutions, ~21700 boxes
ROBOTS = ROOT / "examples/robots"


class Memory:
    """A checkpoint sink in memory that keeps every snapshot written."""

    def __init__(self):
        self.saved: list[bytes] = []

    def save(self, data: bytes) -> None:
        self.saved.append(data)

    def load(self) -> bytes | None:
        return self.saved[-1] if self.saved else None

    def checkpoint(self, **kw) -> Checkpoint:
        return Checkpoint(self.save, self.load, **kw)


def boxes_of(items) -> list:
    return [x.box for x in items]


def same_solutions(a, b) -> bool:
    """The same solutions, found in another order (workers): existence boxes may differ
    in the last bits, so each box of ``a`` must meet its counterpart in ``b``."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if not (np.all(x.lo <= y.hi) and np.all(y.lo <= x.hi)):
            return False
    return True


@pytest.fixture(scope="module")
def k5():
    solver = Solver.default(load_minibex(K5))
    return solver, solver.solve()


def test_codec_round_trip_without_pickle():
    arrays: list = []
    value = (
        [(np.arange(3.0), np.ones(3), "ok"), (np.zeros(3), np.ones(3), "alias")],
        [Undecided(np.zeros(2), np.ones(2), "eps"), Undecided(np.ones(2), np.ones(2), "eps", 3)],
        [np.zeros((2, 3, 2)), np.ones((5, 3, 2))],
        {"n": 3, "x": None, "f": 1.5},
        [],
        np.int64(7),
    )
    back = decode(json.loads(json.dumps(encode(value, arrays))), arrays)
    assert len(arrays) == 5  # columns and concatenations, not one array per item
    (entries, und, parts, meta, empty, seven) = back
    assert [e[2] for e in entries] == ["ok", "alias"] and np.all(entries[0][0] == [0, 1, 2])
    assert und[1].boxes == 3 and isinstance(und[0], Undecided) and np.all(und[1].lo == 1)
    assert [p.shape for p in parts] == [(2, 3, 2), (5, 3, 2)] and np.all(parts[1] == 1)
    assert meta == {"n": 3, "x": None, "f": 1.5} and empty == [] and seven == 7
    with pytest.raises(TypeError):
        encode([object()], [])
    with pytest.raises(CheckpointError, match="unknown record type"):
        decode({"$d": "os:system", "f": {}}, [])


def test_solver_resumed_after_each_box_limit_equals_the_uninterrupted_run(k5):
    solver, ref = k5
    mem = Memory()
    runs = 0
    while True:
        cp = mem.checkpoint(interval=1e9)  # written only when each run stops
        res = solver.solve(max_boxes=400, checkpoint=cp)
        runs += 1
        assert res.stats.resumed == runs - 1
        if res.status == "complete":
            break
        assert res.status == "max_boxes" and res.pending_total > 0 and runs < 50
    assert runs >= 5 and cp.resumed_from > 0
    assert boxes_of(res.solutions) == boxes_of(ref.solutions) and len(ref.solutions) == 16
    assert boxes_of(res.undecided) == boxes_of(ref.undecided)
    assert res.stats.boxes == ref.stats.boxes and res.stats.bisections == ref.stats.bisections


def test_learnt_cid_count_is_saved_with_the_search():
    """cid_vars="auto": the count ACID learns is part of the search state, so a search
    resumed after each box limit replays the uninterrupted run exactly, and a worker task
    starts from the count its search has learnt."""
    # katsura-6: katsura-5's search (3,900 boxes) ends before ACID's first learning phase
    solver = Solver.default(load_minibex(K6), cid_vars="auto")
    ref = solver.solve()
    mem = Memory()
    for _ in range(50):
        res = solver.solve(max_boxes=2000, checkpoint=mem.checkpoint(interval=1e9))
        if res.status == "complete":
            break
    assert res.stats.resumed >= 5 and res.status == "complete"
    assert boxes_of(res.solutions) == boxes_of(ref.solutions)
    assert res.stats.boxes == ref.stats.boxes and res.stats.bisections == ref.stats.bisections
    state = solver.start()
    dom = solver.domain
    state.stack.push(dom[:, 0][None], dom[:, 1][None])
    assert state.acid is not None
    while len(state.stack) and state.acid.phases == 0:  # one learning phase: ~1000 boxes
        solver.process(*state.stack.pop(solver.batch_size), state)
    assert state.acid.phases >= 1  # it has learnt
    assert state.acid.count < solver.n
    task = solver.start(solver.known(state))
    assert task.acid == state.acid and task.acid is not state.acid
    # so is the polytope hull's share (relaxation.HullShare)
    assert state.hull is not None and state.hull.boxes > 0
    assert task.hull == state.hull and task.hull is not state.hull


def test_resume_from_snapshots_taken_mid_search(k5):
    """Snapshots written after batches of one run (as a killed process would leave them):
    each resumed to the end gives the uninterrupted answer."""
    solver, ref = k5
    mem = Memory()
    solver.solve(checkpoint=mem.checkpoint(interval=0.0))  # a snapshot after every batch
    assert len(mem.saved) > 20
    for k in (len(mem.saved) // 5, (3 * len(mem.saved)) // 4):
        one = Memory()
        one.saved.append(mem.saved[k])
        cp = one.checkpoint(interval=1e9)
        res = solver.solve(checkpoint=cp)
        assert 0 < cp.resumed_from < ref.stats.boxes
        assert res.status == "complete" and res.stats.resumed == 1
        assert boxes_of(res.solutions) == boxes_of(ref.solutions)
        assert res.stats.boxes == ref.stats.boxes


def test_snapshots_with_tasks_in_flight_keep_the_handed_out_boxes(k5):
    """A snapshot taken while workers hold slices of the buffer lists those slices as
    pending: resuming serially from it still finds every solution."""
    _, ref = k5
    # the warm-up grows to a batch per slot
    solver = Solver.default(load_minibex(K5), batch_size=256)
    mem = Memory()
    tasks_here = FlakyExecutor(slice_size=64, task_max_boxes=256, grow=0.25)  # none lost
    run = solver.solve(executor=tasks_here, checkpoint=mem.checkpoint(interval=0.0))
    assert run.stats.tasks > 10 and same_solutions(run.solutions, ref.solutions)
    mid = mem.saved[len(mem.saved) // 2]
    one = Memory()
    one.saved.append(mid)
    cp = one.checkpoint()
    res = solver.solve(checkpoint=cp)
    assert res.status == "complete" and res.stats.resumed == 1 and cp.resumed_from > 0
    assert same_solutions(res.solutions, ref.solutions)
    assert boxes_of(res.undecided) == boxes_of(ref.undecided) == []


def test_a_checkpoint_of_another_search_is_refused(k5, tmp_path):
    solver, _ = k5
    path = tmp_path / "k5.ck"
    solver.solve(max_boxes=100, checkpoint=Checkpoint.file(path))
    assert path.exists()
    other = Solver.default(load_minibex(str(ROOT / "examples/systems/eco-7.mbx")))
    with pytest.raises(CheckpointError, match="another search"):
        other.solve(checkpoint=Checkpoint.file(path))
    coarser = Solver.default(load_minibex(K5), eps=1e-6)
    with pytest.raises(CheckpointError, match="another search"):
        coarser.solve(checkpoint=Checkpoint.file(path))
    path.write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="unreadable"):
        solver.solve(max_boxes=10, checkpoint=Checkpoint.file(path))

    # a write that fails (disk full ...) is skipped: the search goes on and says why
    def full(data):
        raise OSError(28, "No space left on device")

    cp = Checkpoint(full, interval=0.0)
    res = solver.solve(max_boxes=600, checkpoint=cp)
    assert res.status == "max_boxes" and cp.writes == 0 and "No space" in cp.error
    # not strict (the job service): an unusable snapshot is ignored, the search starts afresh
    cp = Checkpoint(lambda d: None, lambda: b"junk", strict=False)
    res = solver.solve(max_boxes=10, checkpoint=cp)
    assert cp.ignored and cp.resumed_from is None and res.stats.resumed == 0


def test_forward_kinematics_t16_resumes_to_the_same_poses():
    robot = with_tau_max(Robot.load(ROBOTS / "marionet-t.json"), 10.0)
    u = np.zeros(7)
    ref = FKSolver(robot).solve(u)
    mem = Memory()
    runs = 0
    while True:
        res = FKSolver(robot).solve(u, max_boxes=150, checkpoint=mem.checkpoint())
        runs += 1
        if res.status == "complete":
            break
        assert runs < 40
    assert runs >= 3 and res.stats.resumed == runs - 1
    assert len(ref.solutions) >= 1
    assert [s.box for s in res.solutions] == [s.box for s in ref.solutions]
    assert res.stats.boxes == ref.stats.boxes
    # another control vector is another problem
    with pytest.raises(CheckpointError):
        FKSolver(robot).solve(u + 0.5, checkpoint=mem.checkpoint())


def test_workspace_paving_resumes_to_the_same_paving():
    robot = Robot.load(ROBOTS / "krut-3.json")

    def pave(**kw):
        return certified_workspace(robot, 100.0, [-100, 100, -100, 100], 1.0, batch=64, **kw)

    ref = pave()
    mem = Memory()
    runs = 0
    while True:
        ws = pave(max_boxes=400, checkpoint=mem.checkpoint())
        runs += 1
        if ws.status == "complete":
            break
        assert ws.status == "max_boxes" and runs < 40
    assert runs >= 3 and ws.stats.resumed == runs - 1 and ws.boxes == ref.boxes
    for key in ("inside", "outside", "boundary"):
        a, b = getattr(ws, key), getattr(ref, key)
        assert len(a) == len(b) > 0 or key == "boundary"
        assert np.array_equal(a, b)
    assert ws.inside_measure == ref.inside_measure


# -- the command line ---------------------------------------------------------------------------
def cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "certsolve.cli", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT)


def test_cli_solve_reruns_until_complete(k5, tmp_path):
    _, ref = k5
    ck = str(tmp_path / "k5.ck")
    base = ["solve", K5, "--workers", "1", "--json", "--checkpoint", ck]
    # the whole command: about a second of search, or a third of the ~3900 boxes if faster
    out = cli(*base, "--timeout", "1", "--max-boxes", "1300")
    first = json.loads(out.stdout)
    assert out.returncode == 0 and first["status"] in ("timeout", "max_boxes")
    seen = [first["stats"]["boxes"]]
    data = first
    for _ in range(20):
        if data["status"] == "complete":
            break
        out = cli(*base, "--max-boxes", "1000")
        assert out.returncode == 0, out.stderr
        data = json.loads(out.stdout)
        assert "resumed from" in out.stderr and data["stats"]["resumed"] == len(seen)
        assert data["stats"]["resumed_boxes"] == seen[-1]  # went on from the last run
        seen.append(data["stats"]["boxes"])
    assert data["status"] == "complete" and len(seen) >= 2
    assert [s["box"] for s in data["solutions"]] == boxes_of(ref.solutions)
    assert data["stats"]["boxes"] == ref.stats.boxes
    # the finished checkpoint answers at once; another problem is refused
    again = json.loads(cli(*base).stdout)
    assert again["stats"]["boxes"] == ref.stats.boxes and again["solutions"] == data["solutions"]
    bad = cli("solve", str(ROOT / "examples/systems/eco-7.mbx"), "--checkpoint", ck)
    assert bad.returncode == 2 and "another search" in bad.stderr


def _start_and_wait_for_checkpoint(args, ck: Path, writes: int = 2):
    """Start the CLI; return it once ``ck`` has been written ``writes`` times."""
    cmd = [sys.executable, "-m", "certsolve.cli", *args]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    seen, last = 0, None
    deadline = time.monotonic() + 120
    while seen < writes and time.monotonic() < deadline and proc.poll() is None:
        try:
            stamp = os.stat(ck).st_mtime_ns
        except FileNotFoundError:
            stamp = None
        if stamp is not None and stamp != last:
            seen, last = seen + 1, stamp
        time.sleep(0.005)
    return proc


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_cli_killed_or_interrupted_mid_search_resumes(k5, tmp_path, sig):
    """kill -9: the rerun resumes from the last periodic save; Ctrl-C: the search stops
    after its batch, prints its partial answer (exit 130) and saves; either way the rerun
    completes with the uninterrupted answer."""
    _, ref = k5
    ck = tmp_path / "k5.ck"
    args = ["solve", K5, "--workers", "1", "--json", "--checkpoint", str(ck)]
    proc = _start_and_wait_for_checkpoint([*args, "--checkpoint-interval", "0.05"], ck)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert ck.exists(), err
    if sig == signal.SIGKILL:
        assert proc.returncode == -signal.SIGKILL
    else:
        assert proc.returncode == 130, err
        part = json.loads(out)
        assert part["status"] == "cancelled" and part["pending_total"] > 0
    res = cli(*args)
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["status"] == "complete" and data["stats"]["resumed"] == 1
    assert 0 < data["stats"]["resumed_boxes"] < ref.stats.boxes  # did not start from zero
    assert [s["box"] for s in data["solutions"]] == boxes_of(ref.solutions)
    assert data["stats"]["boxes"] == ref.stats.boxes


# -- the job service ----------------------------------------------------------------------------
def test_job_resumes_from_its_checkpoint_after_its_worker_is_killed(k5, tmp_path):
    """A worker killed with SIGKILL mid-job: the job is queued again, the next worker
    resumes its search from the checkpoint in the store (not from zero) and the result
    is the uninterrupted one."""
    from certsolve.jobs import JobService, ServiceSettings

    _, ref = k5
    settings = ServiceSettings(
        data_dir=tmp_path, workers=1, checkpoint_interval=0.05, max_attempts=2
    )
    with JobService(settings) as svc:
        request = {"kind": "solve", "system": Path(K5).read_text()}
        (job_id,) = svc.submit([svc.validate(request)])
        deadline = time.monotonic() + 120
        while svc.store.search_checkpoint(job_id) is None:
            assert time.monotonic() < deadline and not svc.store.get(job_id).final
            time.sleep(0.005)
        os.kill(svc.store.get(job_id).worker_pid, signal.SIGKILL)
        row = svc.store.get(job_id)
        while not row.final:
            assert time.monotonic() < deadline
            time.sleep(0.05)
            row = svc.store.get(job_id)
        assert svc.store.search_checkpoint(job_id) is None  # dropped with the final status
    assert row.status == "done" and row.attempts == 2, row.error
    res = json.loads(row.result)
    assert res["status"] == "complete" and res["stats"]["resumed"] == 1
    assert 0 < res["stats"]["resumed_boxes"] < ref.stats.boxes  # did not start from zero
    assert [s["box"] for s in res["solutions"]] == boxes_of(ref.solutions)
    assert res["stats"]["boxes"] == ref.stats.boxes


def test_design_resumes_to_the_same_classification():
    """The certified design is a step of the driver; it saves and resumes the same way."""
    from certsolve.force.design import design
    from certsolve.force.design_spec import load_design_spec

    krut3 = load_design_spec(ROOT / "examples/design/krut3-spec.json")
    spec = krut3.model_copy(update={"eps": 1 / 8, "workspace_eps": 2.5})
    kw = {"batch": 256}
    ref = design(spec=spec, **kw)
    mem = Memory()
    runs = 0
    while True:
        res = design(spec=spec, max_boxes=1500, checkpoint=mem.checkpoint(), **kw)
        runs += 1
        if res.status == "complete":
            break
        assert res.status == "max_boxes" and len(res.pending) and runs < 40
    assert runs >= 3 and res.resumed_from > 0 and res.pairs == ref.pairs
    for key in ("good", "bad", "undecided", "margin", "witness"):
        assert np.array_equal(getattr(res, key), getattr(ref, key)), key
    assert len(ref.good) and len(ref.bad) and res.best_robot == ref.best_robot
    with pytest.raises(CheckpointError):
        design(spec.model_copy(update={"eps": 1 / 4}), **kw, checkpoint=mem.checkpoint())
