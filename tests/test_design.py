"""Certified design (Krut 2004, IV-B): every box proven good is checked on robots sampled in
it and a dense grid of the workspace (float isotropic force >= F, and >= F + margin); every
box proven bad on robots sampled in it at poses of its witness box (force < F); the
parameter paths, the interval robot arrays, the spec errors and the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from certsolve.cli import main
from certsolve.force import isotropic_values
from certsolve.force.design import PARTS, design
from certsolve.force.design_spec import DesignSpecError
from certsolve.robot import Robot
from certsolve.robot.params import AffineRobot, ParameterDef

KRUT3 = "examples/robots/krut-3.json"
PLANAR = "examples/robots/planar.json"

KRUT_PARAMS = [
    {"name": "base_half_width", "path": "wires[*].base[0]", "mode": "half-width",
     "range": [60, 140]},
    {"name": "tau_max", "path": "wires[*].tau[1]", "range": [200, 800]},
]  # fmt: skip
PLANAR_PARAMS = [
    {"name": "platform_size", "path": "wires[*].platform[*]", "mode": "half-width",
     "range": [4, 20]},
    {"name": "tau_max", "path": "wires[*].tau[1]", "range": [5, 40]},
]  # fmt: skip


def spec(robot, parameters, workspace, min_force, **options) -> dict:
    """A design spec (``design``'s one argument)."""
    return {"robot": robot, "parameters": parameters, "workspace": workspace,
            "min_force": min_force, **options}  # fmt: skip


def samples(box: np.ndarray, n: int, rng) -> np.ndarray:
    """The corners, the centre and ``n`` random points of a parameter box ``(k, 2)``."""
    k = box.shape[0]
    corners = np.array(np.meshgrid(*box, indexing="ij")).reshape(k, -1).T
    rand = box[:, 0] + rng.random((n, k)) * (box[:, 1] - box[:, 0])
    return np.vstack([corners, box.mean(axis=1)[None], rand])


def grid(W: np.ndarray, n: int) -> np.ndarray:
    axes = [np.linspace(lo, hi, n) for lo, hi in W]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, len(W))


def affine_of(res, robot, params) -> AffineRobot:
    return AffineRobot(robot, [ParameterDef(**{**p, "range": tuple(p["range"])}) for p in params])


@pytest.fixture(scope="module")
def krut_result():
    return design(spec(KRUT3, KRUT_PARAMS, [-20, 20, -20, 20], 150.0, eps=1 / 8, workspace_eps=2.5))


def test_krut_classes_cover_the_parameter_box(krut_result):
    res = krut_result
    assert res.complete and res.pairs > 0
    assert len(res.good) and len(res.bad) and len(res.margin) == len(res.good)
    total = sum(res.share(c) for c in PARTS)
    assert total == pytest.approx(1.0, abs=1e-12)
    allb = np.concatenate([getattr(res, c) for c in PARTS])
    assert np.all(allb[..., 0] >= res.ranges[:, 0]) and np.all(allb[..., 1] <= res.ranges[:, 1])
    # boxes do not overlap: their volumes add up to the whole box and no two share an interior
    lo, hi = allb[..., 0], allb[..., 1]
    inter = np.all(np.minimum(hi[:, None], hi[None]) > np.maximum(lo[:, None], lo[None]), axis=2)
    assert np.array_equal(inter, np.eye(len(allb), dtype=bool))


def test_krut_good_boxes_hold_on_a_dense_grid(krut_result):
    res = krut_result
    aff = affine_of(res, KRUT3, KRUT_PARAMS)
    rng = np.random.default_rng(0)
    pts = grid(res.workspace, 41)
    worst = np.inf
    for box, margin in zip(res.good, res.margin, strict=True):
        assert margin >= 0
        for theta in samples(box, 3, rng):
            f, status = isotropic_values(aff.robot_at(theta), pts)
            assert np.all(status == 0)
            worst = min(worst, float(np.min(f - (res.min_force + margin))))
    assert worst >= -1e-9 * res.min_force


def test_krut_bad_boxes_fail_on_their_witness(krut_result):
    res = krut_result
    aff = affine_of(res, KRUT3, KRUT_PARAMS)
    rng = np.random.default_rng(1)
    assert len(res.witness) == len(res.bad)
    for box, wit in zip(res.bad, res.witness, strict=True):
        assert np.all(wit[:, 0] >= res.workspace[:, 0]) and np.all(wit[:, 1] <= res.workspace[:, 1])
        poses = np.vstack([grid(wit, 3), samples(wit, 4, rng)])
        for theta in samples(box, 3, rng):
            f, _ = isotropic_values(aff.robot_at(theta), poses)
            assert np.all(f < res.min_force)


def test_best_robot_is_the_centre_of_the_best_box(krut_result, tmp_path):
    res = krut_result
    assert res.best is not None and res.margin[res.best] == res.margin.max()
    robot = Robot.load(res.best_robot)
    box = res.good[res.best]
    centre = box.mean(axis=1)
    hw = np.max(np.abs(robot.A[:, 0]))
    assert hw == pytest.approx(centre[0], rel=1e-12)
    assert np.all(robot.tau_max == centre[1])
    f, _ = isotropic_values(robot, grid(res.workspace, 61))
    assert f.min() >= res.min_force + res.margin[res.best] - 1e-9


def test_planar_platform_size_and_tension(tmp_path):
    """A rigid platform (dof 3): platform size and tension limit as design parameters."""
    res = design(spec(PLANAR, PLANAR_PARAMS, [85, 95, 55, 65], 5.0, eps=1 / 8, workspace_eps=2.0))
    assert res.complete and len(res.good)
    aff = affine_of(res, PLANAR, PLANAR_PARAMS)
    rng = np.random.default_rng(2)
    pts = grid(res.workspace, 21)
    for box, margin in zip(res.good, res.margin, strict=True):
        for theta in samples(box, 1, rng):
            f, _ = isotropic_values(aff.robot_at(theta), pts)
            assert f.min() >= res.min_force + margin - 1e-9
    for box, wit in zip(res.bad, res.witness, strict=True):
        for theta in samples(box, 2, rng):
            f, _ = isotropic_values(aff.robot_at(theta), grid(wit, 3))
            assert np.all(f < res.min_force)


def test_affine_robot_paths_and_bounds():
    params = [
        ParameterDef(name="hw", path="wires[*].base[0]", mode="half-width", range=(60, 140)),
        ParameterDef(name="tmax", path="wires[0,2].tau[1]", range=(300, 700)),
    ]
    aff = AffineRobot(KRUT3, params)
    base = Robot.load(KRUT3)
    r = aff.robot_at([120.0, 400.0])
    assert np.allclose(r.A[:, 0], base.A[:, 0] * 120 / np.max(np.abs(base.A[:, 0])))
    assert np.array_equal(r.A[:, 1], base.A[:, 1])
    assert list(r.tau_max) == [400.0, 500.0, 400.0]
    lo, hi = np.array([[90.0, 350.0]]), np.array([[100.0, 450.0]])
    b = aff.bounds(lo, hi)
    rng = np.random.default_rng(3)
    for theta in lo + rng.random((50, 2)) * (hi - lo):
        rt = aff.robot_at(theta)
        for arr, (blo, bhi) in ((rt.A, b.A), (rt.tau_max, b.tau_max), (rt.tau_min, b.tau_min)):
            assert np.all(blo[..., 0] <= arr) and np.all(arr <= bhi[..., 0])
    mid = aff.robot_at([95.0, 400.0])
    assert np.all(b.A_mid[0][..., 0] <= mid.A) and np.all(mid.A <= b.A_mid[1][..., 0])
    assert np.allclose(b.radius[:, 0], [5.0, 50.0])


@pytest.mark.parametrize(
    "params, message",
    [
        ([{"name": "a", "path": "wires[*].bse[0]", "range": [1, 2]}], "parameters[0].path"),
        ([{"name": "a", "path": "wires[9].base[0]", "range": [1, 2]}], "wire index 9"),
        ([{"name": "a", "path": "wires[*].tau[1]", "range": [600, 900]},
          {"name": "b", "path": "wires[0].tau[1]", "range": [1, 2]}], "already set by"),
        ([{"name": "a", "path": "wires[*].tau[1]", "range": [10, 900]}], "invalid"),
        ([{"name": "a", "path": "wires[*].tau[1]", "mode": "half-width", "range": [1, 2]}],
         "parameters[0].mode"),
        ([{"name": "a", "path": "wires[*].platform[0]", "range": [1, 2]}], "point platform"),
    ],
)  # fmt: skip
def test_parameter_errors_name_the_field(params, message):
    ok = {"name": "z", "path": "wires[1].base[1]", "range": [40, 60]}
    with pytest.raises(DesignSpecError, match=message.replace("[", r"\[").replace("]", r"\]")):
        design(spec(KRUT3, params + [ok], [-1, 1, -1, 1], 10.0))


def test_stopping_leaves_pending_boxes():
    res = design(spec(KRUT3, KRUT_PARAMS, [-20, 20, -20, 20], 150.0, eps=1 / 16), max_boxes=3000)
    assert res.status == "max_boxes" and len(res.pending)
    assert sum(res.share(c) for c in PARTS) == pytest.approx(1.0, abs=1e-12)
    calls = []

    def progress(info):
        calls.append(info.extra["pairs"])
        return False

    res = design(spec(KRUT3, KRUT_PARAMS, [-20, 20, -20, 20], 150.0), progress=progress)
    assert res.status == "cancelled" and len(calls) == 1


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def write_spec(tmp_path, **over):
    """A spec file in ``tmp_path`` with the robot beside it (a path relative to the spec)."""
    (tmp_path / "robot.json").write_text(Path(KRUT3).read_text())
    spec = {
        "robot": "robot.json",
        "parameters": KRUT_PARAMS,
        "workspace": [-20, 20, -20, 20],
        "min_force": 150,
        "eps": 0.125,
    }
    spec.update(over)
    p = tmp_path / "spec.json"
    p.write_text(json.dumps(spec))
    return p


def test_cli_design(capsys, tmp_path):
    spec = write_spec(tmp_path)
    png, best = tmp_path / "p.png", tmp_path / "best.json"
    code, out, err = run(
        capsys, "design", str(spec), "--plot", str(png), "--emit-robot", str(best), "--json"
    )
    assert code == 0 and err == ""
    d = json.loads(out)
    assert d["status"] == "complete" and d["counts"]["good"] > 0 and d["emitted_robot"] == str(best)
    assert d["best"]["min_force_bound"] >= 150
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    robot = Robot.load(best)
    assert robot.name == "krut-3-design"
    code, out, _ = run(capsys, "design", str(spec), "--no-boxes")
    assert code == 0 and "best box:" in out and "good" in out


@pytest.mark.parametrize(
    "over, message",
    [
        ({"min_force": -1}, "min_force"),
        ({"workspace": [1, 2, 3]}, "workspace"),
        ({"parameters": KRUT_PARAMS[:1]}, "parameters"),
        ({"robot": "missing.json"}, "robot: "),
        ({"extra": 1}, "extra"),
        ({"eps": 0}, "eps"),
    ],
)
def test_cli_spec_errors(capsys, tmp_path, over, message):
    spec = write_spec(tmp_path, **over)
    code, out, err = run(capsys, "design", str(spec))
    assert code == 2 and out == "" and err.startswith("error: ") and message in err
    assert err.count("\n") == 1


def test_cli_option_errors(capsys, tmp_path):
    spec = write_spec(tmp_path)
    for argv, message in (
        (["--eps", "2"], "--eps"),
        (["--axes", "1,3"], "--axes"),
        (["--timeout", "-1"], "--timeout"),
    ):
        code, _, err = run(capsys, "design", str(spec), *argv)
        assert code == 2 and message in err and "Traceback" not in err


@pytest.mark.parametrize(
    "path, params, centre, pose",
    [
        (PLANAR, PLANAR_PARAMS, [10.0, 30.0], [90.0, 60.0]),
        (
            "examples/robots/marionet.json",
            [
                {"name": "hw", "path": "wires[*].base[0]", "mode": "half-width",
                 "range": [80, 100]},
                {"name": "ps", "path": "wires[*].platform[*]", "mode": "half-width",
                 "range": [5, 15]},
                {"name": "tm", "path": "wires[*].tau[1]", "range": [5, 40]},
            ],
            [90.0, 10.0, 20.0],
            [110.0, 57.0, 106.0],
        ),
    ],
)  # fmt: skip
def test_slack_enclosures_with_interval_robots(path, params, centre, pose):
    """Small boxes of robots × poses, F just below / above the force at the centre: the
    enclosure decides both, and sampled robots and poses agree with the decision (and with
    the proven lower bound ``F + min_k glo_k / norm_k``)."""
    from certsolve.force.enclosure import slack_enclosures

    aff = affine_of(None, path, params)
    c = np.array(centre)
    rad = 0.002 * (aff.box[:, 1] - aff.box[:, 0])
    pbox = np.stack([np.array(pose) - 0.25, np.array(pose) + 0.25], axis=1)
    bounds = aff.bounds((c - rad)[None], (c + rad)[None])
    f0 = isotropic_values(aff.robot_at(c), np.array([pose]))[0][0]
    rng = np.random.default_rng(4)
    robots = [aff.robot_at(t) for t in samples(np.stack([c - rad, c + rad], 1), 4, rng)]
    poses = np.vstack([grid(pbox, 3), samples(pbox, 6, rng)])
    f = np.concatenate([isotropic_values(r, poses)[0] for r in robots])
    for F, expect_inside in ((0.9 * f0, True), (1.1 * f0, False)):
        glo, ghi, full_rank, ok, nhi = slack_enclosures(
            aff.robot, pbox[:, :1], pbox[:, 1:], F, params=bounds, norms=True
        )
        inside = bool(np.all(glo >= 0) and full_rank[0] and ok[0])
        outside = bool(np.any(ghi < 0) and ok[0])
        assert (inside, outside) == (expect_inside, not expect_inside)
        if inside:
            assert np.all(f >= F + np.min(glo / nhi) - 1e-9)
        else:
            assert np.all(f < F)


def test_cli_help_default_matches_the_library():
    from certsolve.cli import design as cli_design
    from certsolve.force.design_spec import DEFAULT_EPS

    assert cli_design.DEFAULT_EPS == DEFAULT_EPS


def test_resumed_design_gives_the_serial_answer(krut_result, tmp_path):
    """The design on the driver: stopped by ``cancel`` (Ctrl-C's way) and by ``max_boxes``,
    saved to a file and resumed, it ends with the boxes, verdicts, margins, witnesses and
    counters of the uninterrupted serial run."""
    import threading

    from certsolve.solver.checkpoint import Checkpoint

    ref = krut_result
    assert ref.stats.executor == "serial" and ref.stats.resumed == 0
    path = tmp_path / "design.ckpt"
    problem = spec(KRUT3, KRUT_PARAMS, [-20, 20, -20, 20], 150.0, eps=1 / 8, workspace_eps=2.5)
    cancel = threading.Event()

    def stop_after_two(p) -> bool:
        if p.boxes >= 2 * 1024:
            cancel.set()
        return True

    res = design(problem, progress=stop_after_two, cancel=cancel, checkpoint=Checkpoint.file(path))
    assert res.status == "cancelled" and len(res.pending) and path.exists()
    runs = 1
    while res.status != "complete":
        res = design(problem, max_boxes=5000, checkpoint=Checkpoint.file(path))
        runs += 1
        assert res.status in ("complete", "max_boxes") and runs < 40
    assert runs >= 3 and res.resumed_from > 0 and res.stats.resumed == runs - 1
    assert res.pairs == ref.pairs and res.parameter_boxes == ref.parameter_boxes
    assert res.stats.boxes == ref.stats.boxes
    for key in ("good", "bad", "undecided", "pending", "margin", "witness"):
        assert np.array_equal(getattr(res, key), getattr(ref, key)), key
    assert res.best == ref.best and res.best_robot == ref.best_robot


def test_pair_queue_is_first_in_first_out():
    """The design's buffer: rows come out in the order they went in, across growth and
    partial pops, and a snapshot pushed into a new queue rebuilds it."""
    from certsolve.force.design_step import PairQueue

    q = PairQueue(2, capacity=4)
    rows = np.arange(40.0).reshape(20, 2)
    q.push(rows[:3], rows[:3] + 0.5)
    lo, hi = q.pop(2)
    assert np.array_equal(lo, rows[:2]) and np.array_equal(hi, rows[:2] + 0.5)
    q.push(rows[3:20], rows[3:20] + 0.5)  # grows, keeping the unpopped row first
    assert len(q) == 18
    again = PairQueue(2)
    again.push(*q.snapshot())
    for queue in (q, again):
        lo, hi = queue.pop(100)
        assert np.array_equal(lo, rows[2:]) and np.array_equal(hi, rows[2:] + 0.5)
        assert len(queue) == 0 and queue.pop(3)[0].shape == (0, 2)
