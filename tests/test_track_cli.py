"""``certsolve track``: the CSV path, the JSON report, the plot, one ``error:`` line for a
bad file; the ``trajectory`` job and its picture."""

from __future__ import annotations

import json

import numpy as np
import pytest

import certsolve
from certsolve.cli import main

PLANAR = "examples/robots/planar.json"
START = "90,60,0"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def path_to_slack(rows: int = 80) -> np.ndarray:
    """Wire 3 of the planar robot shortened row by row until it goes slack."""
    robot = certsolve.load_robot(PLANAR)
    u0 = np.asarray(certsolve.inverse_kinematics(robot, [90, 60, 0]).u, dtype=float)
    return u0 - 0.05 * np.arange(rows)[:, None] * np.eye(4)[2]


def write_csv(path, rows, header=True):
    lines = ["u1,u2,u3,u4"] if header else []
    lines += [",".join(f"{v:.12g}" for v in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_json_report_and_plot(capsys, tmp_path):
    csv = write_csv(tmp_path / "u.csv", path_to_slack())
    png = tmp_path / "path.png"
    code, out, err = run(
        capsys, "track", PLANAR, "--trajectory", csv, "--start", START, "--json", "--plot",
        str(png),
    )  # fmt: skip
    assert code == 0 and err == ""
    d = json.loads(out)
    assert d["status"] == "lost" and d["lost_reason"] == "tension"
    assert "wire 3" in d["reason"] and "minimum 0 N" in d["reason"]
    k = d["lost_at"]
    assert [s["index"] for s in d["steps"]] == list(range(k + 1))
    assert all(s["certified"] for s in d["steps"][:k]) and not d["steps"][k]["certified"]
    assert all(s["joined"] for s in d["steps"][1:k])
    for s in d["steps"][:k]:
        assert len(s["u"]) == 4 and len(s["tensions"]) == 4 and len(s["platform_points"]) == 4
        assert min(s["tensions"]) > 0.0
        assert all(lo <= hi for lo, hi in s["box"])
    assert d["plot"] == str(png) and png.stat().st_size > 10_000


def test_text_report_without_header(capsys, tmp_path):
    rows = path_to_slack(12)[:5]
    csv = write_csv(tmp_path / "u.csv", rows, header=False)
    code, out, err = run(capsys, "track", PLANAR, "--trajectory", csv, "--start", START)
    assert code == 0 and err == ""
    assert "complete, 5 certified and joined" in out
    assert len([ln for ln in out.splitlines() if ln[:6].strip().isdigit()]) == 5


@pytest.mark.parametrize(
    "text, message",
    [
        ("u1,u2,u3,u4\n0,0,0,0\n0,0,x,0\n", "u.csv row 3, column 3: 'x' is not a number"),
        ("0,0,0,0\n\n0,0,0\n", "u.csv row 3: expected 4 values (one per wire), got 3"),
        ("0,0,0,0\n0,nan,0,0\n", "u.csv row 2, column 2: 'nan' is not finite"),
        ("u1,u2,u3,u4\n", "u.csv: no control rows"),
    ],
)
def test_a_bad_file_is_one_error_line(capsys, tmp_path, text, message):
    (tmp_path / "u.csv").write_text(text)
    code, out, err = run(
        capsys, "track", PLANAR, "--trajectory", str(tmp_path / "u.csv"), "--start", START
    )
    assert code == 2 and out == ""
    assert err.strip() == f"error: {message}"


def test_bad_options_name_the_option(capsys, tmp_path):
    csv = write_csv(tmp_path / "u.csv", path_to_slack(3))
    code, _, err = run(capsys, "track", PLANAR, "--trajectory", csv, "--start", "90")
    assert code == 2 and err.startswith("error: --start")
    code, _, err = run(
        capsys, "track", PLANAR, "--trajectory", csv, "--start", START, "--half-width", "0"
    )
    assert code == 2 and err.strip() == "error: --half-width: must be greater than 0"
    code, _, err = run(
        capsys, "track", PLANAR, "--trajectory", csv, "--start", START, "--formulation", "pose"
    )
    assert code == 2 and err.startswith("error: --formulation: tracking uses the paper's point")


def test_the_trajectory_job_runs_and_draws_its_picture(tmp_path):
    from certsolve.jobs.jsonutil import plain
    from certsolve.jobs.kinds.base import RunContext
    from certsolve.jobs.kinds.registry import KINDS, request_adapter
    from certsolve.jobs.pictures import _DRAW, PICTURES

    robot = json.load(open(PLANAR))
    rows = path_to_slack(80).tolist()
    req = request_adapter().validate_python(
        {"kind": "trajectory", "robot": robot, "params": {"controls": rows, "start": [90, 60, 0]}}
    )
    kind = KINDS["trajectory"]
    result = plain(kind.run(req.params, kind.input_of(req), RunContext()).to_dict())
    assert result["status"] == "lost" and "wire 3" in result["reason"]
    assert PICTURES["trajectory"] == ("path",)
    out = tmp_path / "path.png"
    _DRAW["path"]({"robot": robot, "params": {}}, result, None, out)
    assert out.stat().st_size > 10_000
    bad = {
        "kind": "trajectory",
        "robot": robot,
        "params": {"controls": [[0, 0, 0]], "start": [90, 60, 0]},
    }
    with pytest.raises(ValueError, match="controls.0"):
        req = request_adapter().validate_python(bad)
        req.params.check_robot(req.robot)


def test_the_trajectory_job_through_the_service(tmp_path):
    """Submitted, run as a worker runs it, stored as JSON with its steps cut to the
    service's max_result_items (the count of the rest kept), and its picture drawn."""
    from certsolve.jobs import JobService, ServiceSettings
    from certsolve.jobs.pictures import Pictures
    from certsolve.jobs.worker import run_job

    svc = JobService(ServiceSettings(data_dir=tmp_path, workers=0, max_result_items=5))
    try:
        robot = json.load(open(PLANAR))
        rows = path_to_slack(80).tolist()
        req = {
            "kind": "trajectory",
            "robot": robot,
            "params": {"controls": rows, "start": [90, 60, 0]},
        }
        (job_id,) = svc.submit([svc.validate(req)])
        job, lease = svc.store.claim(worker_pid=1)
        run_job(svc.store, job, lease, svc.settings)
        row = svc.store.get(job_id)
        assert row.status == "done", row.error
        result = json.loads(row.result)
        assert result["status"] == "lost" and "wire 3" in result["reason"]
        assert len(result["steps"]) == 5 and result["truncated"]["steps"] == result["lost_at"] + 1
        png = Pictures(svc.store, tmp_path / "pictures").png(job_id, "path")
        assert png.stat().st_size > 10_000
    finally:
        svc.close()
