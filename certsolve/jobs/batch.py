"""Offline batches: a JSON-lines file of jobs in, a JSON-lines file of results out.

Each input line is a job exactly as ``POST /v1/jobs`` takes it.  Each output line is

``{"line": 3, "input_sha": "...", "id": "...", "kind": "solve", "status": "done",
"error": null, "elapsed": 0.03, "attempts": 1, "result": {...}}``

written (and flushed) as soon as the job ends, so the output is in completion order.
Re-running the same command skips the lines whose latest output record is ``done`` with
the same input text (``input_sha``), and appends records for the others: an interrupted
batch resumes where it stopped.  Invalid lines get a ``failed`` record at once.

The jobs run on a private :class:`.JobService` (temporary store, supervised workers), so a
crashing job is retried or failed alone, and time / memory limits apply as in the service.
"""

from __future__ import annotations

import hashlib
import json
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from pydantic import ValidationError

from .jsonutil import dumps
from .service import JobService, LimitError
from .settings import ServiceSettings
from .status import JobStatus
from .store import JobRow

__all__ = ["BatchSummary", "run_batch", "default_output", "line_sha"]


@dataclass
class BatchSummary:
    lines: int = 0  # jobs in the input (non-blank lines)
    skipped: int = 0  # already done in the output file
    invalid: int = 0
    submitted: int = 0
    done: int = 0
    failed: int = 0
    cancelled: int = 0
    elapsed: float = 0.0
    output: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def default_output(path: str | Path) -> Path:
    """``jobs.jsonl`` -> ``jobs.results.jsonl``."""
    p = Path(path)
    stem = p.name[: -len(".jsonl")] if p.name.endswith(".jsonl") else p.stem
    return p.with_name(stem + ".results.jsonl")


def line_sha(text: str) -> str:
    return hashlib.sha256(text.strip().encode()).hexdigest()[:16]


def _done_lines(out: Path) -> dict[int, str]:
    """``{line: input_sha}`` of the lines whose latest record in ``out`` is done."""
    done: dict[int, str] = {}
    if not out.exists():
        return done
    with out.open("rb") as fh:
        for raw in fh:
            try:
                rec = json.loads(raw)
                line = int(rec["line"])
            except (ValueError, KeyError, TypeError):
                continue  # a torn last line, or not ours
            if rec.get("status") == JobStatus.DONE and isinstance(rec.get("input_sha"), str):
                done[line] = rec["input_sha"]
            else:
                done.pop(line, None)
    return done


def _record(row: JobRow, line: int, sha: str) -> str:
    elapsed = None
    if row.started_at is not None and row.finished_at is not None:
        elapsed = round(row.finished_at - row.started_at, 6)
    head = {
        "line": line,
        "input_sha": sha,
        "id": row.id,
        "kind": row.kind,
        "status": row.status,
        "error": row.error,
        "elapsed": elapsed,
        "attempts": row.attempts,
    }
    return dumps(head)[:-1] + ',"result":' + (row.result or "null") + "}"


def run_batch(
    input_path: str | Path,
    out_path: str | Path | None = None,
    *,
    settings: ServiceSettings | None = None,
    progress: Callable[[BatchSummary], None] | None = None,
) -> BatchSummary:
    """Run every not-yet-done job of ``input_path``; append results to ``out_path``."""
    t0 = time.monotonic()
    settings = settings or ServiceSettings()
    input_path = Path(input_path)
    out = Path(out_path) if out_path is not None else default_output(input_path)
    summary = BatchSummary(output=str(out))
    done = _done_lines(out)
    text = input_path.read_text()
    if out.exists() and out.stat().st_size and not out.read_bytes().endswith(b"\n"):
        with out.open("ab") as fh:  # a torn last line: start a fresh one
            fh.write(b"\n")

    with tempfile.TemporaryDirectory(prefix="certsolve-batch-") as tmp:
        service = JobService(settings.with_(data_dir=Path(tmp)))
        pending: dict[str, tuple[int, str]] = {}
        try:
            with out.open("a", encoding="utf-8") as text_out:

                def emit(line: str) -> None:
                    text_out.write(line + "\n")
                    text_out.flush()

                chunk = []
                for number, raw in enumerate(text.splitlines(), 1):
                    if not raw.strip():
                        continue
                    summary.lines += 1
                    sha = line_sha(raw)
                    if done.get(number) == sha:
                        summary.skipped += 1
                        continue
                    try:
                        req = service.validate(json.loads(raw))
                        job = service.prepare(req)
                    except json.JSONDecodeError as exc:
                        error = f"invalid JSON: {exc.msg} (column {exc.colno})"
                    except ValidationError as exc:
                        error = "invalid job: " + _one_line(exc)
                    except LimitError as exc:
                        error = f"invalid job: {exc}"
                    else:
                        chunk.append(job)
                        pending[job.id] = (number, sha)
                        if len(chunk) >= 500:
                            service.store.add(chunk)
                            chunk = []
                        continue
                    summary.invalid += 1
                    summary.failed += 1
                    emit(
                        dumps(
                            {
                                "line": number,
                                "input_sha": sha,
                                "status": JobStatus.FAILED,
                                "error": error,
                                "result": None,
                            }
                        )
                    )
                if chunk:
                    service.store.add(chunk)
                summary.submitted = len(pending)
                if pending:
                    service.start()
                fseq = 0
                while pending:
                    rows = service.store.finished_since(fseq)
                    for row in rows:
                        fseq = max(fseq, row.fseq or 0)
                        where = pending.pop(row.id, None)
                        if where is None:
                            continue
                        emit(_record(row, *where))
                        setattr(summary, row.status.value, getattr(summary, row.status.value) + 1)
                    if progress is not None:
                        summary.elapsed = time.monotonic() - t0
                        progress(summary)
                    if not rows:
                        time.sleep(0.05)
        finally:
            service.close()
    summary.elapsed = time.monotonic() - t0
    return summary


def _one_line(exc: ValidationError) -> str:
    from .errors import describe_validation_error

    return describe_validation_error(exc)
