"""Forward kinematics with the Newton-starts phases (:data:`.fk_solver.FK_STARTS`): every
equilibrium of a real control vector early, the same complete answer, and none in the
searches where a phase has no place (stable only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from certsolve.kinematics import inverse_kinematics
from certsolve.kinematics.fk import FKSolver, with_tau_max
from certsolve.kinematics.stability import Stability
from certsolve.robot import Robot

ROBOTS = Path(__file__).resolve().parent.parent / "examples" / "robots"
REAL_POSE = [111.0, 58.0, 107.0, 0.0, 0.0, 0.0]


def _general19_real_u():
    base = Robot.load(ROBOTS / "marionet.json")
    return with_tau_max(base, 60.0), inverse_kinematics(base, REAL_POSE, method="alg2").u


def test_the_phases_find_the_equilibria_of_a_real_control_vector_in_the_first_boxes():
    """general-19 at 60 N, u = IK(P): 6 equilibria, one stable; the complete search takes
    ~5M boxes.  After 500 boxes the search with the phases holds at least 5 (all 6 on this
    machine), each certified, the stable one at P; the search alone holds the seeded stable
    pose only."""
    robot, u = _general19_real_u()
    on = FKSolver(robot).solve(u, max_boxes=500, workers=1)
    off = FKSolver(robot, newton_starts=False).solve(u, max_boxes=500, workers=1)
    assert on.status == off.status == "max_boxes"
    assert len(on.solutions) >= 5 > len(off.solutions)
    assert on.solve.stats.started >= 4 and off.solve.stats.started == 0
    centres = np.array([np.mean(p.box, axis=1) for p in on.solutions])
    assert (
        np.min(np.ptp(centres[:, None] - centres[None], axis=2)[np.triu_indices(len(centres), 1)])
        > 1e-3
    )
    stable = [p for p in on.solutions if p.stability.stability == Stability.STABLE]
    assert len(stable) == 1 and all(p.certificate == "unique" for p in on.solutions)
    assert np.allclose(stable[0].position, REAL_POSE[:3], atol=1e-6)
    assert np.all((stable[0].tau >= 0.0) & (stable[0].tau <= 60.0))


def test_the_phases_leave_a_complete_answer_as_it_was():
    """T-16 at 60 N, u = IK(P), in a box of 6 cm around the pose: the same certified
    poses with and without the phases."""
    base = Robot.load(ROBOTS / "marionet-t.json")
    robot = with_tau_max(base, 60.0)
    u = inverse_kinematics(base, REAL_POSE, method="alg2").u
    answers = []
    for on in (True, False):
        fk = FKSolver(robot, newton_starts=on)
        box = fk.form.pose_box(np.array(REAL_POSE[:3]), np.eye(3), 6.0, fk.search_box(u))
        assert box is not None
        res = fk.solve(u, boxes=(box[0][None], box[1][None]), workers=1)
        assert res.status == "complete"
        answers.append(sorted(tuple(np.round(p.position, 6)) for p in res.solutions))
    assert answers[0] == answers[1] and answers[0]


def test_no_phase_in_a_stable_only_search():
    """A phase proves unstable poses too (which ``max_solutions`` would count): the
    stable-only search runs none."""
    robot, _ = _general19_real_u()
    assert not FKSolver(robot, stable_only=True).newton_starts
    assert FKSolver(robot).newton_starts


def test_the_command_line_turns_the_phases_off(capsys):
    """``certsolve fk`` runs the phases by default; ``--no-newton-starts`` is the search
    alone (general-19, 60 N, u = IK(P), 500 boxes: at least 5 poses, and 1)."""
    import json

    from certsolve.cli import main

    _, u = _general19_real_u()
    argv = ["fk", str(ROBOTS / "marionet.json"), "--u", ",".join(f"{v:.17g}" for v in u)]
    argv += ["--tau-max", "60", "--max-boxes", "500", "--workers", "1", "--json"]
    counts = []
    for flag in ((), ("--no-newton-starts",)):
        main([*argv, *flag])
        counts.append(len(json.loads(capsys.readouterr().out)["solutions"]))
    assert counts[0] >= 5 > counts[1]
