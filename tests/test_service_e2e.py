"""End to end: a real ``certsolve serve`` (uvicorn) process with worker processes.

Covers a solve job from submission to certified result, cancellation of a running solve
through the progress callback, a worker killed with ``kill -9`` mid-job, memory and time
limits, a service killed and restarted with running and queued jobs, and the
``submit`` / ``status`` / ``result`` / ``cancel`` client commands.
"""

import contextlib
import io
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from certsolve.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())
FINAL = ("done", "failed", "cancelled")


def hard_system(n: int = 8) -> str:
    """3^n real solutions in [-2, 2]^n: minutes of work for the solver."""
    decls = "\n".join(f"  x{i} in [-2, 2];" for i in range(n))
    eqs = "\n".join(f"  x{i}^3 - x{i} - 0.01*x{(i + 1) % n} = 0;" for i in range(n))
    return f"Variables\n{decls}\nConstraints\n{eqs}\nend\n"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """``certsolve serve`` in its own session; ``close`` kills whatever is left of it."""

    def __init__(self, data_dir: Path, workers: int, *extra: str):
        self.data_dir = data_dir
        self.port = free_port()
        self.base = f"http://127.0.0.1:{self.port}"
        self.log = open(data_dir.parent / f"server-{self.port}.log", "wb")  # noqa: SIM115
        cmd = [
            sys.executable,
            "-c",
            "import sys; from certsolve.cli import main; sys.exit(main())",
            "serve",
            "--port",
            str(self.port),
            "--workers",
            str(workers),
            "--data-dir",
            str(data_dir),
            "--log-level",
            "warning",
            "--enable-test-kinds",
            *extra,
        ]
        self.proc = subprocess.Popen(
            cmd, cwd=ROOT, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True
        )
        self.http = httpx.Client(base_url=self.base, timeout=30, trust_env=False)
        deadline = time.monotonic() + 60
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError(f"server exited: {self.read_log()}")
            try:
                if self.http.get("/healthz").status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(f"server did not start: {self.read_log()}")
            time.sleep(0.1)

    def read_log(self) -> str:
        self.log.flush()
        return (Path(self.log.name)).read_text(errors="replace")[-3000:]

    def submit(self, job: dict) -> str:
        r = self.http.post("/v1/jobs", json=job)
        assert r.status_code == 202, r.text
        return r.json()["id"]

    def job(self, job_id: str) -> dict:
        r = self.http.get(f"/v1/jobs/{job_id}")
        assert r.status_code == 200, r.text
        return r.json()

    def wait(self, job_id: str, until=lambda j: j["status"] in FINAL, timeout=90.0) -> dict:
        deadline = time.monotonic() + timeout
        while True:
            j = self.job(job_id)
            if until(j):
                return j
            if time.monotonic() > deadline:
                raise AssertionError(f"job {job_id} stuck: {j}\n{self.read_log()}")
            time.sleep(0.05)

    def stop(self, sig=signal.SIGTERM) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                pass

    def close(self) -> None:
        self.http.close()
        self.stop()
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.proc.pid, signal.SIGKILL)  # stragglers of the session
        self.proc.wait(10)
        self.log.close()


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie is dead for our purpose
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = Server(tmp_path_factory.mktemp("svc") / "data", 2)
    yield s
    s.close()


# -- the always-available path: solve -------------------------------------------------------------
def test_solve_job_end_to_end(server):
    job_id = server.submit({"kind": "solve", "system": CIRCLE, "params": {"eps": 1e-10}})
    j = server.wait(job_id)
    assert j["status"] == "done", j
    res = j["result"]
    assert res["status"] == "complete" and res["variables"] == ["x", "y"]
    mids = sorted(tuple(s["midpoint"]) for s in res["solutions"])
    assert len(mids) == 2
    r = 0.5**0.5
    for (x, y), sign in zip(mids, (-1, 1)):
        assert abs(x - sign * r) < 1e-9 and abs(y - sign * r) < 1e-9
    for s in res["solutions"]:
        assert s["certificate"] == "unique"
        (xl, xh), (yl, yh) = s["box"]
        assert xl <= xh and yl <= yh
    assert j["attempts"] == 1 and j["error"] is None and j["elapsed"] >= 0
    assert j["progress"]["boxes"] >= 1
    assert server.http.get(f"/v1/jobs/{job_id}/result").json() == res
    done = server.http.get("/v1/jobs?status=done").json()["items"]
    assert job_id in [d["id"] for d in done]


def test_fk_job_end_to_end(server):
    kin = pytest.importorskip("certsolve.kinematics")
    if not (hasattr(kin, "forward_kinematics") and hasattr(kin, "inverse_kinematics")):
        pytest.skip("certsolve.kinematics.forward_kinematics is not in this build yet")
    from certsolve.robot import Pose, Robot

    robot = Robot.load(PLANAR)
    pose = [90.0, 60.0, 0.0]
    ik = kin.inverse_kinematics(robot, Pose.from_params(robot.dof, pose))
    u = getattr(ik, "u", None)
    if u is None:
        u = ik.to_dict()["u"]
    u = [float(v) for v in u]
    job_id = server.submit(
        {"kind": "fk", "robot": PLANAR, "params": {"u": u, "eps": 1e-9, "timeout": 60}}
    )
    j = server.wait(job_id, timeout=120)
    assert j["status"] == "done", j
    res = j["result"]
    assert res["status"] == "complete" and res["solutions"], res
    # one certified pose is the one the controls were computed for
    assert any(
        abs(sol["position"][0] - pose[0]) < 1e-3
        and abs(sol["position"][1] - pose[1]) < 1e-3
        and abs(sol["euler"][0] - pose[2]) < 1e-3
        and sol["certificate"] == "unique"
        for sol in res["solutions"]
    ), res["solutions"]


# -- cancellation, crashes, limits ------------------------------------------------------------
def test_cancel_running_solve(server):
    job_id = server.submit(
        {"kind": "solve", "system": hard_system(), "params": {"eps": 1e-12, "timeout": 300}}
    )
    server.wait(job_id, until=lambda j: j["status"] == "running" and j["progress"])
    r = server.http.delete(f"/v1/jobs/{job_id}")
    assert r.status_code == 202 and r.json()["cancel_requested"]
    j = server.wait(job_id)
    assert j["status"] == "cancelled"
    # stopped by the progress callback (not killed): the partial result is there
    res = j["result"]
    assert res["stats"]["stopped_by"] == "cancelled" and res["status"] == "cancelled"
    assert res["pending"] and len(res["solutions"]) == j["progress"]["solutions"]
    r = server.http.get(f"/v1/jobs/{job_id}/result")
    assert r.status_code == 200 and r.headers["certsolve-job-status"] == "cancelled"
    assert r.json() == res
    assert server.http.delete(f"/v1/jobs/{job_id}").status_code == 200


def test_worker_killed_mid_job(server):
    victim = server.submit({"kind": "sleep", "params": {"seconds": 120}})
    j = server.wait(victim, until=lambda j: j["status"] == "running" and j["worker_pid"])
    pid = j["worker_pid"]
    os.kill(pid, signal.SIGKILL)
    # the job is retried (attempt 2) -- or failed if it had no attempts left
    j = server.wait(victim, until=lambda j: j["attempts"] >= 2 or j["status"] == "failed")
    assert j["status"] in ("queued", "running", "failed")
    if j["status"] != "failed":
        assert "killed by SIGKILL" in (j["error"] or "")
    # the service still answers and another job completes
    assert server.http.get("/healthz").status_code == 200
    other = server.submit({"kind": "solve", "system": CIRCLE})
    assert server.wait(other)["status"] == "done"
    h = server.http.get("/healthz").json()
    assert h["workers"]["restarts"] >= 1
    server.http.delete(f"/v1/jobs/{victim}")
    assert server.wait(victim)["status"] in ("cancelled", "failed")


def test_crashing_job_fails_alone(server):
    job_id = server.submit({"kind": "sleep", "params": {"seconds": 0.4, "crash": True}})
    j = server.wait(job_id)
    assert j["status"] == "failed" and j["attempts"] == 2  # retried once, then given up
    assert "exit status 17" in j["error"]
    assert server.wait(server.submit({"kind": "solve", "system": CIRCLE}))["status"] == "done"


def test_memory_limit(server):
    job_id = server.submit(
        {"kind": "sleep", "params": {"allocate_mb": 4000}, "limits": {"memory_mb": 600}}
    )
    j = server.wait(job_id)
    assert j["status"] == "failed" and "memory limit exceeded (600 MiB)" in j["error"]
    assert server.wait(server.submit({"kind": "sleep", "params": {"seconds": 0}}))["status"] == (
        "done"
    )


def test_memory_stop_keeps_the_partial_result(server):
    """A job whose memory grows stops through its progress callback at 85 % of its limit:
    done, with its partial result, instead of failed on a memory error."""
    j = server.wait(
        server.submit(
            {
                "kind": "sleep",
                "params": {"seconds": 60, "grow_mb": 20},
                "limits": {"memory_mb": 1024},
            }
        )
    )
    assert j["status"] == "done", j
    assert j["result"]["stopped_by"] == "memory" and j["progress"]["stopped_by"] == "memory"
    assert server.http.get(f"/v1/jobs/{j['id']}/result").status_code == 200


def test_time_limited_search_keeps_a_bounded_result(server):
    """The issue's reproducer (defect 3): a search that leaves hundreds of thousands of
    pending boxes, stopped by its time limit, ends done -- not killed -- with a result
    that lists a bounded number of them and counts the rest."""
    line = (
        "Variables\n x in [-1e6, 1e6];\n y in [-1e6, 1e6];\n"
        "Constraints\n x - y = 0;\n 2*x - 2*y = 0;\nend\n"
    )
    job_id = server.submit(
        {"kind": "solve", "system": line, "params": {"eps": 1e-12, "timeout": 8}}
    )
    j = server.wait(job_id, timeout=60)
    assert j["status"] == "done" and j["result"]["status"] == "timeout", j["error"]
    res = j["result"]
    listed = len(res["pending"])
    total = res.get("pending_total") or res.get("truncated", {}).get("pending") or listed
    assert listed <= 20_000 and total >= listed and total > 1000
    assert j["elapsed"] < 8 + 5  # within the time limit and the kill grace
    r = server.http.get(f"/v1/jobs/{job_id}/result")
    assert r.status_code == 200 and len(r.content) < 5_000_000


def test_time_limits(server):
    # a cooperative job stops itself at its limit (done, reported as such)
    j = server.wait(
        server.submit({"kind": "sleep", "params": {"seconds": 30}, "limits": {"timeout": 0.3}})
    )
    assert j["status"] == "done" and j["result"]["stopped_by"] == "timeout"
    # a solve passes its limit to the solver
    j = server.wait(
        server.submit(
            {"kind": "solve", "system": hard_system(), "params": {"eps": 1e-12, "timeout": 0.5}}
        )
    )
    assert j["status"] == "done" and j["result"]["stats"]["stopped_by"] == "timeout"


def test_cancel_uncooperative_job_kills_its_worker(server):
    job_id = server.submit({"kind": "sleep", "params": {"seconds": 60, "cooperative": False}})
    j = server.wait(job_id, until=lambda j: j["status"] == "running")
    server.http.delete(f"/v1/jobs/{job_id}")
    j = server.wait(job_id)
    assert j["status"] == "cancelled" and "worker was stopped" in j["error"]
    assert server.wait(server.submit({"kind": "solve", "system": CIRCLE}))["status"] == "done"


@pytest.mark.slow
def test_time_limit_kills_uncooperative_job(server):
    job_id = server.submit(
        {"kind": "sleep", "params": {"seconds": 60, "cooperative": False}, "limits": {"timeout": 1}}
    )
    j = server.wait(job_id)
    assert j["status"] == "failed" and "time limit exceeded" in j["error"]


def test_batch_over_http(server):
    r = server.http.post(
        "/v1/jobs/batch",
        json={"kind": "solve", "system": CIRCLE, "params": [{"eps": 10.0**-k} for k in (4, 8)]},
    )
    assert r.status_code == 202
    batch = r.json()
    for job_id in batch["ids"]:
        assert server.wait(job_id)["status"] == "done"
    st = server.http.get(f"/v1/batches/{batch['batch']}").json()
    assert st["finished"] and st["counts"]["done"] == 2


# -- the client commands ------------------------------------------------------------------------
def run_cli(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli_main(list(argv))
    return code, out.getvalue(), err.getvalue()


def test_client_commands(server, tmp_path):
    mbx = ROOT / "examples/systems/circle-line.mbx"
    code, out, _ = run_cli(
        "submit", "--kind", "solve", "--system", str(mbx), "-p", "eps=1e-9", "--wait",
        "--server", server.base, "--json",
    )  # fmt: skip
    assert code == 0
    rec = json.loads(out)
    assert rec["status"] == "done" and len(rec["result"]["solutions"]) == 2
    code, out, _ = run_cli("status", rec["id"], "--server", server.base)
    assert code == 0 and rec["id"] in out and "done" in out
    code, out, _ = run_cli("result", rec["id"], "--server", server.base)  # certsolve solve's report
    assert code == 0 and out.startswith(f"job {rec['id']}: complete, 2 solution(s)"), out
    code, out, _ = run_cli("result", rec["id"], "--server", server.base, "--json")
    assert code == 0 and json.loads(out)["result"] == rec["result"]
    # a job file, then cancel it
    job = tmp_path / "job.json"
    job.write_text(json.dumps({"kind": "sleep", "params": {"seconds": 60}}))
    code, out, _ = run_cli("submit", str(job), "--server", server.base)
    job_id = out.strip()
    assert code == 0 and len(job_id) == 24
    code, out, _ = run_cli("result", job_id, "--server", server.base)
    assert code == 1 and out == ""
    code, out, _ = run_cli("cancel", job_id, "--server", server.base, "--json")
    assert code == 0 and json.loads(out)["cancel_requested"]
    code, out, err = run_cli("result", job_id, "--wait", "--poll", "0.1", "--server", server.base)
    assert code == 1 and "cancelled" in err
    code, out, _ = run_cli("status", "--server", server.base, "--json", "--limit", "3")
    assert code == 0 and len(json.loads(out)["items"]) == 3
    # errors: one line, no traceback
    code, _, err = run_cli("submit", "--kind", "solve", "-p", "eps=-1", "--server", server.base)
    assert code == 2 and err.startswith("error: ") and "Traceback" not in err
    code, _, err = run_cli("status", "nope", "--server", server.base)
    assert code == 2 and "404" in err and "no job nope" in err
    code, _, err = run_cli("status", "--server", f"http://127.0.0.1:{free_port()}")
    assert code == 2 and "cannot reach" in err


# -- restarts -------------------------------------------------------------------------------------
def test_restart_requeues_running_and_runs_queued(tmp_path):
    data = tmp_path / "data"
    first = Server(data, 1)
    try:
        running = first.submit({"kind": "sleep", "params": {"seconds": 2}})
        queued = first.submit({"kind": "solve", "system": CIRCLE})
        j = first.wait(running, until=lambda j: j["status"] == "running" and j["worker_pid"])
        worker = j["worker_pid"]
        first.stop(signal.SIGKILL)  # the service dies; its worker must follow
        deadline = time.monotonic() + 15
        while pid_alive(worker):
            assert time.monotonic() < deadline, "worker survived its service"
            time.sleep(0.05)
    finally:
        first.close()
    second = Server(data, 1)
    try:
        j = second.wait(running)
        assert j["status"] == "done" and j["attempts"] == 2
        assert second.wait(queued)["status"] == "done"
    finally:
        second.close()


def test_data_dir_is_locked(server):
    code, _, err = run_cli("serve", "--data-dir", str(server.data_dir), "--port", str(free_port()))
    assert code == 2 and "in use by another certsolve service" in err


@pytest.mark.slow
def test_orderly_restart_with_queued_job(tmp_path):
    data = tmp_path / "data"
    first = Server(data, 0)  # accepts jobs, runs none
    try:
        job_id = first.submit({"kind": "solve", "system": CIRCLE})
        assert first.job(job_id)["status"] == "queued"
    finally:
        first.close()  # SIGTERM: an orderly shutdown
    second = Server(data, 1)
    try:
        j = second.wait(job_id)
        assert j["status"] == "done" and j["attempts"] == 1
        assert len(j["result"]["solutions"]) == 2
    finally:
        second.close()


def test_force_jobs_end_to_end(server):
    force = pytest.importorskip("certsolve.force")
    if not all(hasattr(force, f) for f in ("isotropic_map", "certified_workspace")):
        pytest.skip("certsolve.force is not complete in this build")
    grid = server.submit(
        {
            "kind": "isotropic-map",
            "robot": PLANAR,
            "params": {"grid": [20, 160, 20, 100], "nx": 5, "ny": 4},
        }
    )
    ws = server.submit(
        {
            "kind": "workspace",
            "robot": PLANAR,
            "params": {"min_force": 1.0, "box": [[20, 160], [20, 100]], "eps": 10.0},
        }
    )
    j = server.wait(grid)
    assert j["status"] == "done", j
    assert len(j["result"]["xs"]) == 5 and len(j["result"]["ys"]) == 4
    j = server.wait(ws)
    assert j["status"] == "done", j
    assert j["result"]["status"] == "complete" and j["progress"]["boxes"] >= 1
    r = server.http.post("/v1/isotropic", json={"robot": PLANAR, "params": {"pose": [90, 60, 0]}})
    assert r.status_code == 200 and "isotropic_force" in r.json()
