"""Size of the job store per thousand jobs, and what a purge gives back.

Fills a fresh :class:`certsolve.jobs.store.JobStore` with N finished jobs of three kinds,
each with the request and result a real run stores (computed once, here):

* ``solve`` of ``examples/systems/circle-line.mbx`` (2 certified solutions);
* ``fk`` of the planar robot at u = 0 (the robot file travels in the request);
* a ``solve`` stopped by its time limit with pending boxes, stored bounded
  (:func:`certsolve.jobs.partial.stored_result` with ``--max-items``, 20 000 by default as
  in the service);

then reports the bytes of the database file and of its write-ahead log per thousand jobs,
after a ``wal_checkpoint(TRUNCATE)``, and after purging them all (the file keeps what
SQLite cannot give back; new stores use ``auto_vacuum = INCREMENTAL``).

Usage::

    python benchmarks/store_bench.py [--jobs 2000] [--max-items 20000]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())
LINE = (
    "Variables\n x in [-1e6, 1e6];\n y in [-1e6, 1e6];\n"
    "Constraints\n x - y = 0;\n 2*x - 2*y = 0;\nend\n"
)


def samples(max_items: int) -> dict[str, tuple[str, str]]:
    """``kind: (request JSON, result JSON)`` as a worker would store them."""
    from certsolve.jobs.jsonutil import dumps
    from certsolve.jobs.kinds import RunContext, request_adapter
    from certsolve.jobs.kinds.registry import KINDS
    from certsolve.jobs.partial import stored_result

    adapter = request_adapter()
    out = {}
    jobs = {
        "solve": {"kind": "solve", "system": CIRCLE},
        "fk": {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0]}},
        "stopped solve": {"kind": "solve", "system": LINE, "params": {"eps": 1e-12}},
    }
    for name, job in jobs.items():
        req = adapter.validate_python(job)
        limit = 2.0 if name == "stopped solve" else 60.0
        kind = KINDS[req.kind]
        raw = kind.run(
            req.params, kind.input_of(req), RunContext(time_limit=limit, max_boxes=10**8)
        )
        out[name] = (req.model_dump_json(), dumps(stored_result(raw, max_items)))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=2000, help="jobs of each kind")
    ap.add_argument("--max-items", type=int, default=20_000, help="result list cap")
    args = ap.parse_args()
    from certsolve.jobs.status import JobStatus
    from certsolve.jobs.store import JobStore, NewJob

    rows = []
    for name, (request, result) in samples(args.max_items).items():
        with tempfile.TemporaryDirectory(prefix="certsolve-store-") as tmp:
            store = JobStore(Path(tmp) / "jobs.sqlite3")
            limits = {"timeout": 600.0, "max_boxes": 50_000_000, "memory_mb": 4096}
            t0 = time.perf_counter()
            for _ in range(0, args.jobs, 500):
                jobs = [
                    NewJob(kind="solve", request=request, limits=limits, max_attempts=2)
                    for _ in range(500)
                ]
                store.add(jobs)
                for _ in jobs:
                    job, lease = store.claim(1)
                    store.finish(job.id, lease, JobStatus.DONE, result=result)
            fill = time.perf_counter() - t0
            store.checkpoint()
            full = store.file_sizes()
            t0 = time.perf_counter()
            deleted = store.purge(time.time() + 1)
            purge = time.perf_counter() - t0
            empty = store.file_sizes()
            store.close()
        n = (args.jobs + 499) // 500 * 500
        assert deleted == n
        rows.append((name, len(request) + len(result), n, full, empty, fill, purge))

    print(f"job store, {rows[0][2]} finished jobs per kind (result lists cut at {args.max_items})")
    print()
    head = f"{'kind':<15} {'bytes/job':>10} {'MB/1000 jobs':>13} {'wal':>6}"
    print(head + f" {'after purge MB':>15} {'fill s':>7} {'purge s':>8}")
    for name, size, n, full, empty, fill, purge in rows:
        per_k = full["db"] / n * 1000 / 2**20
        print(
            f"{name:<15} {size:>10} {per_k:>13.2f} {full['wal']:>6} "
            f"{empty['db'] / 2**20:>15.2f} {fill:>7.1f} {purge:>8.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
