"""``certsolve batch``: JSON lines in, JSON lines out, resumable."""

import contextlib
import io
import json
from pathlib import Path

from certsolve.cli import main as cli_main
from certsolve.jobs.batch import default_output

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = (ROOT / "examples/systems/circle-line.mbx").read_text()


def run_cli(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli_main(list(argv))
    return code, out.getvalue(), err.getvalue()


def records(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def test_batch_runs_and_resumes(tmp_path):
    jobs = tmp_path / "jobs.jsonl"
    out = tmp_path / "out.jsonl"
    lines = [
        json.dumps({"kind": "solve", "system": CIRCLE}),
        json.dumps({"kind": "solve", "system": CIRCLE, "params": {"eps": 1e-6}}),
        "{not json",
        json.dumps({"kind": "solve", "system": "Variables x in [0, 1]; end"}),
        "",
        json.dumps({"kind": "sleep", "params": {"seconds": 0.2, "crash": True}}),
    ]
    jobs.write_text("\n".join(lines) + "\n")
    argv = ["batch", str(jobs), "--out", str(out), "--workers", "1", "--json"]
    code, stdout, _ = run_cli(*argv, "--enable-test-kinds")
    summary = json.loads(stdout)
    assert code == 1  # some jobs failed
    assert summary["lines"] == 5 and summary["done"] == 2 and summary["failed"] == 3
    assert summary["invalid"] == 2 and summary["skipped"] == 0
    recs = {r["line"]: r for r in records(out)}
    assert set(recs) == {1, 2, 3, 4, 6}
    assert recs[1]["status"] == "done" and len(recs[1]["result"]["solutions"]) == 2
    assert recs[2]["kind"] == "solve" and recs[2]["result"]["eps"] == 1e-6
    assert recs[3]["error"].startswith("invalid JSON")
    assert recs[4]["error"].startswith("invalid job: system: line 1")
    assert recs[6]["status"] == "failed" and "exit status 17" in recs[6]["error"]
    assert recs[6]["attempts"] == 2

    # resume: done lines are skipped, a changed line runs again, a torn last line is harmless
    lines[1] = json.dumps({"kind": "solve", "system": CIRCLE, "params": {"eps": 1e-7}})
    lines[5] = ""
    jobs.write_text("\n".join(lines) + "\n")
    with out.open("a") as fh:
        fh.write('{"line": 1, "status": "do')
    code, stdout, _ = run_cli(*argv)
    summary = json.loads(stdout)
    assert summary["skipped"] == 1 and summary["done"] == 1 and summary["invalid"] == 2
    recs = records_after_torn(out)
    latest = {}
    for r in recs:
        latest[r["line"]] = r
    assert latest[2]["status"] == "done" and latest[2]["result"]["eps"] == 1e-7
    assert [r["line"] for r in recs].count(1) == 1  # line 1 was not run again


def records_after_torn(path: Path) -> list[dict]:
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except ValueError:
            assert line.startswith('{"line": 1, "status": "do')
    return out


def test_batch_cli_errors(tmp_path):
    code, _, err = run_cli("batch", str(tmp_path / "missing.jsonl"))
    assert code == 2 and "no such file" in err
    code, _, err = run_cli("batch", str(tmp_path), "--workers", "0")
    assert code == 2 and err.startswith("error:")
    assert default_output("runs/jobs.jsonl") == Path("runs/jobs.results.jsonl")
    # nothing to do: no workers are started
    empty = tmp_path / "empty.jsonl"
    empty.write_text("\n\n")
    code, stdout, _ = run_cli("batch", str(empty), "--json")
    assert code == 0 and json.loads(stdout)["lines"] == 0
