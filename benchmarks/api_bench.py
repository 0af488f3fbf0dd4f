"""Throughput and overhead of the job service, against a real ``certsolve serve``.

* jobs per second for small jobs (``solve`` of ``examples/systems/circle-line.mbx``,
  2 certified solutions in a few milliseconds) with 1 and 2 workers: a batch of N jobs is
  posted and the clock stops when the last one is done (median of --repeat runs);
* the overhead of one job over the direct library call (median): a job is posted, its
  status polled every --poll seconds until done, one job at a time; compared with
  ``parse_minibex`` + ``solve`` in this process.

Usage::

    python benchmarks/api_bench.py [--jobs 200] [--latency-jobs 40] [--workers 1,2]
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
SYSTEM = (ROOT / "examples/systems/circle-line.mbx").read_text()
JOB = {"kind": "solve", "system": SYSTEM}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    def __init__(self, workers: int):
        self.tmp = tempfile.TemporaryDirectory(prefix="certsolve-bench-")
        port = free_port()
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-c",
                "import sys; from certsolve.cli import main; sys.exit(main())",
                "serve",
                "--port",
                str(port),
                "--workers",
                str(workers),
                "--data-dir",
                self.tmp.name,
                "--log-level",
                "warning",
            ],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        self.http = httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=60, trust_env=False)
        deadline = time.monotonic() + 60
        while True:
            try:
                h = self.http.get("/healthz").json()
                if h["workers"]["alive"] == workers:
                    break
            except httpx.TransportError:
                pass
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise RuntimeError("the server did not start")
            time.sleep(0.1)
        # warm-up: every worker has imported the solver
        ids = self.http.post("/v1/jobs/batch", json={"jobs": [JOB] * (4 * workers)}).json()["ids"]
        for i in ids:
            self.wait(i, 0.01)

    def wait(self, job_id: str, poll: float) -> dict:
        while True:
            j = self.http.get(f"/v1/jobs/{job_id}", params={"result": "false"}).json()
            if j["status"] in ("done", "failed", "cancelled"):
                return j
            time.sleep(poll)

    def close(self) -> None:
        self.http.close()
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
        self.tmp.cleanup()


def throughput(server: Server, n: int) -> float:
    t0 = time.perf_counter()
    reply = server.http.post("/v1/jobs/batch", json={"jobs": [JOB] * n}).json()
    batch = reply["batch"]
    while True:
        st = server.http.get(f"/v1/batches/{batch}").json()
        if st["finished"]:
            break
        time.sleep(0.02)
    dt = time.perf_counter() - t0
    assert st["counts"]["done"] == n, st
    return n / dt


def latencies(server: Server, n: int, poll: float) -> tuple[list[float], list[float]]:
    client, worker = [], []
    for _ in range(n):
        t0 = time.perf_counter()
        job_id = server.http.post("/v1/jobs", json=JOB).json()["id"]
        j = server.wait(job_id, poll)
        client.append(time.perf_counter() - t0)
        worker.append(j["elapsed"])
        assert j["status"] == "done"
    return client, worker


def direct(n: int) -> list[float]:
    from certsolve.expr.minibex import parse_minibex
    from certsolve.solver import solve

    out = []
    for _ in range(n + 3):
        t0 = time.perf_counter()
        r = solve(parse_minibex(SYSTEM), workers=1)
        out.append(time.perf_counter() - t0)
        assert len(r.solutions) == 2
    return out[3:]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=200, help="jobs per throughput run")
    ap.add_argument("--repeat", type=int, default=3, help="throughput runs (median)")
    ap.add_argument("--latency-jobs", type=int, default=40, help="jobs for the overhead")
    ap.add_argument("--workers", default="1,2", help="worker counts to compare")
    ap.add_argument("--poll", type=float, default=0.002, help="status poll interval (s)")
    args = ap.parse_args()
    counts = [int(w) for w in args.workers.split(",")]

    rows = []
    lat = None
    for w in counts:
        server = Server(w)
        try:
            rates = [throughput(server, args.jobs) for _ in range(args.repeat)]
            if lat is None:
                lat = latencies(server, args.latency_jobs, args.poll)
        finally:
            server.close()
        rows.append((w, statistics.median(rates), min(rates), max(rates)))
    d = direct(args.latency_jobs)

    print(f"certsolve job service, {os.cpu_count()} cores (shared), small solve jobs")
    print()
    print(f"{'workers':>8} {'jobs/s (median)':>16} {'min':>8} {'max':>8}")
    for w, med, lo, hi in rows:
        print(f"{w:>8} {med:>16.1f} {lo:>8.1f} {hi:>8.1f}")
    print()
    assert lat is not None
    client, worker = lat
    md, mc, mw = (statistics.median(x) * 1e3 for x in (d, client, worker))
    print(f"{'one job, median of ' + str(len(d)):<44} {'ms':>8}")
    print(f"{'direct library call (parse + solve)':<44} {md:>8.2f}")
    print(f"{'job, run time inside the worker':<44} {mw:>8.2f}")
    print(f"{'job, POST to done as seen by the client':<44} {mc:>8.2f}")
    print(f"{'overhead of a job over the direct call':<44} {mc - md:>8.2f}")
    print(f"(client polls every {args.poll * 1e3:g} ms; 1-worker server)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
