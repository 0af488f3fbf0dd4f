"""Throughput and overhead of the job service, against a real ``certsolve serve``.

* jobs per second for small jobs (``solve`` of ``examples/systems/circle-line.mbx``,
  2 certified solutions in a few milliseconds) with 1 and 2 workers: a batch of N jobs is
  posted and the clock stops when the last one is done (median of --repeat runs);
* the overhead of one job over the direct library call (median): a job is posted, its
  status polled every --poll seconds until done, one job at a time; compared with
  ``parse_minibex`` + ``solve`` in this process;
* with ``--dask N``, the same for a service whose jobs run on a ``distributed.LocalCluster``
  of N single-threaded worker processes (``serve --scheduler``; the scheduler runs in this
  process, not in the service's).

Usage::

    python benchmarks/api_bench.py [--jobs 200] [--latency-jobs 40] [--workers 1,2] [--dask 2]
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
    def __init__(self, workers: int, scheduler: str | None = None):
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
                *(["--workers", str(workers)] if scheduler is None else ["--scheduler", scheduler]),
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


def local_cluster(n: int):
    """A LocalCluster of ``n`` single-threaded worker processes (docs/distributed.md)."""
    import logging

    import dask
    import distributed

    env = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
    with dask.config.set(env):
        return distributed.LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        )


def measure(server: Server, args) -> tuple[list[float], tuple[list[float], list[float]]]:
    rates = [throughput(server, args.jobs) for _ in range(args.repeat)]
    return rates, latencies(server, args.latency_jobs, args.poll)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=200, help="jobs per throughput run")
    ap.add_argument("--repeat", type=int, default=3, help="throughput runs (median)")
    ap.add_argument("--latency-jobs", type=int, default=40, help="jobs for the overhead")
    ap.add_argument("--workers", default="1,2", help="worker counts to compare")
    ap.add_argument("--dask", type=int, default=0, help="also on a LocalCluster of N workers")
    ap.add_argument("--poll", type=float, default=0.002, help="status poll interval (s)")
    args = ap.parse_args()
    counts = [int(w) for w in args.workers.split(",") if w]

    rows = []
    for w in counts:
        server = Server(w)
        try:
            rows.append((f"{w} processes", *measure(server, args)))
        finally:
            server.close()
    if args.dask:
        cluster = local_cluster(args.dask)
        try:
            server = Server(args.dask, scheduler=cluster.scheduler_address)
            try:
                rows.append((f"dask, {args.dask} workers", *measure(server, args)))
            finally:
                server.close()
        finally:
            cluster.close()
    d = direct(args.latency_jobs)
    md = statistics.median(d) * 1e3

    print(f"certsolve job service, {os.cpu_count()} cores (shared), small solve jobs")
    print(f"direct library call (parse + solve), median of {len(d)}: {md:.2f} ms")
    print()
    head = ("runner", "jobs/s", "min", "max", "elapsed", "POST->done", "overhead")
    print(
        f"{head[0]:>18} {head[1]:>8} {head[2]:>7} {head[3]:>7} {head[4]:>10} {head[5]:>11}"
        f" {head[6]:>9}"
    )
    for name, rates, (client, worker) in rows:
        mc, mw = (statistics.median(x) * 1e3 for x in (client, worker))
        print(
            f"{name:>18} {statistics.median(rates):>8.1f} {min(rates):>7.1f} {max(rates):>7.1f}"
            f" {mw:>8.2f}ms {mc:>9.2f}ms {mc - md:>7.2f}ms"
        )
    print(
        f"(jobs/s: median of {args.repeat} batches of {args.jobs}; times: median of "
        f"{args.latency_jobs} jobs run one at a time, client polls every {args.poll * 1e3:g} ms;"
        " elapsed: the job's claim to its recorded end)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
