"""Kind ``fk``: every equilibrium pose for actuator values ``u``
(``certsolve.kinematics.forward_kinematics``); and the quick call ``POST /v1/fk/track``
(one certified tracking step near a known pose, ``certsolve.kinematics.track``).

At submission the robot must admit the FK equations: a rigid platform (dof 3 or 6), the
elastic model on every wire, and attachment points from which the formulation's affine
frame can be built (3 or 4 distinct, affinely independent points).  The judge is the
library's own geometric precondition of the formulation
(:func:`~certsolve.kinematics.fk_systems.check_formulation`: the checks its builder makes,
without building an expression), so what is accepted can be run.
"""

from __future__ import annotations

from typing import Any, Literal

from ...robot.inputs import FkOptions, TrackOptions
from ...robot.schema import RobotSpec, robot_dof_schema
from .base import (
    POSE_LENGTH,
    Job,
    Kind,
    Params,
    QuickCall,
    Request,
    RunContext,
    check_pose,
    check_wires,
    require_elastic,
    robot_model,
)

__all__ = [
    "KIND",
    "QUICK",
    "FkJob",
    "FkParams",
    "TrackCall",
    "TrackParams",
    "call_track",
    "check_fk_geometry",
    "fk_robot_schema",
    "run_fk",
    "track_cost",
]


# certsolve.robot.inputs.Formulation by the dof they are written for
FORMULATIONS = ("auto", "frame", "pose")
PLANAR_FORMULATIONS = ("planar-10",)
SPATIAL_FORMULATIONS = ("general-19", "T-16", "almost-planar-13", "points")


class FkParams(FkOptions, Params):  # the library's options as job params
    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        if dof == 2:
            return None
        names = FORMULATIONS + (PLANAR_FORMULATIONS if dof == 3 else SPATIAL_FORMULATIONS)
        return {"formulation": {"enum": list(names), "default": "auto", "type": "string"}}

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        return fk_robot_schema(dof)

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        check_wires(robot, self.u, "u")
        check_fk_geometry(robot, self.formulation, memo)
        if robot.tolerances:  # a set of robots (docs/tolerances.md)
            from ...kinematics.fk_tolerance import check_tolerant_options

            check_tolerant_options(
                robot_model(robot), self.formulation,
                seed_planar=self.seed_planar, stable_only=self.stable_only,
            )  # fmt: skip


def check_one_robot(robot: RobotSpec) -> None:
    """Tracking (``fk/track``, ``trajectory``) follows one robot: ``ValueError`` at
    ``robot.tolerances`` for a set of robots (the :class:`.Tracker`'s refusal)."""
    if robot.tolerances:
        from ...kinematics.tracking import TOLERANCES_REFUSED

        raise ValueError(f"robot.tolerances: {TOLERANCES_REFUSED}")


def fk_robot_schema(dof: int) -> dict:
    """Robots FK can take: the elastic model, and at least the 3 (planar) or 4 (spatial)
    attachment points of the formulation's frame (that they are distinct and span it is
    checked by :func:`check_fk_geometry`)."""
    return robot_dof_schema(dof, elastic=True, min_wires=3 if dof == 3 else 4)


def check_fk_geometry(robot: RobotSpec, formulation: str, memo: dict | None = None) -> None:
    """The FK equations of ``formulation`` can be written for ``robot`` (module docstring);
    else ``ValueError`` naming ``robot.dof``, ``robot.wires[i].k`` ..., ``robot.wires``
    (the attachment points) or ``formulation`` (a formulation this robot cannot use)."""
    key = ("fk", robot.model_dump_json(), formulation)
    if memo is not None and key in memo:
        if memo[key]:
            raise ValueError(memo[key])
        return
    problem = _fk_geometry_problem(robot, formulation)
    if memo is not None:
        memo[key] = problem
    if problem:
        raise ValueError(problem)


def _fk_geometry_problem(robot: RobotSpec, formulation: str) -> str | None:
    if robot.dof == 2:
        return "robot.dof: a point platform (dof 2) has no pose to find; FK needs dof 3 or 6"
    try:
        require_elastic(robot, "forward kinematics")
    except ValueError as exc:
        return str(exc)
    from ...kinematics.fk_systems import check_formulation as check

    model = robot_model(robot)
    try:
        check(model, formulation)
    except ValueError as exc:
        if formulation in ("auto", "frame"):
            return f"robot.wires: {exc}"
        try:
            check(model, "auto")
        except ValueError as auto:
            return f"robot.wires: {auto}"
        return f"formulation: {exc}"
    return None


class FkJob(Job):
    kind: Literal["fk"]
    robot: RobotSpec
    params: FkParams


def forward_kinematics() -> Any:
    """The library function of kind ``fk``."""
    from ...kinematics.fk import forward_kinematics

    return forward_kinematics


def run_fk(p: FkParams, robot: RobotSpec, ctx: RunContext) -> Any:
    """Every pose for ``p.u``: :func:`~certsolve.kinematics.forward_kinematics`."""
    from ...kinematics.fk import forward_kinematics as fk
    from ...kinematics.fk_solver import with_tau_max

    result = fk(
        with_tau_max(robot, p.tau_max),  # the robot model, built once with its limit
        list(p.u),
        eps=p.eps,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        max_solutions=p.max_solutions,
        formulation=p.formulation,
        seed_planar=p.seed_planar,
        seeded_only=p.seeded_only,
        stable_only=p.stable_only,
        seed_minima=p.seed_minima,
        newton_starts=p.newton_starts,
        progress=ctx.progress,
        executor=ctx.executor,
        cancel=ctx.cancel,
        verify=ctx.verify,
        checkpoint=None if p.seed_planar else ctx.checkpoint,  # one search only
    )
    return result


KIND = Kind(
    name="fk",
    model=FkJob,
    params=FkParams,
    run=run_fk,
    function=forward_kinematics,
    summary="forward kinematics: every pose for the actuator values u",
)


# -- the quick call: one tracking step ------------------------------------------------------------
class TrackParams(TrackOptions, Params):  # the library's options as params
    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        return None if dof == 2 else {"near_pose": POSE_LENGTH[dof]}

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        return fk_robot_schema(dof)

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        check_wires(robot, self.u, "u")
        check_one_robot(robot)
        check_pose(robot, self.near_pose, "near_pose")
        check_fk_geometry(robot, "auto", memo)


class TrackCall(Request):
    """Body of ``POST /v1/fk/track``."""

    robot: RobotSpec
    params: TrackParams


def track() -> Any:
    """The library function of the quick call ``fk/track``."""
    from ...kinematics.tracking import track

    return track


def call_track(p: TrackParams, spec: RobotSpec) -> Any:
    """One tracking step near ``p.near_pose``: :func:`~certsolve.kinematics.track`."""
    from ...kinematics.tracking import track
    from ...robot.geometry import Pose

    robot = robot_model(spec)
    near = Pose.from_params(robot.dof, p.near_pose)
    return track(robot, list(p.u), near, half_width=p.half_width)


def track_cost(req: TrackCall) -> float:
    """Seconds, roughly: compiling the tracking system grows with the wires; one Newton
    and Krawczyk step is milliseconds."""
    return 0.2 + 0.02 * len(req.robot.wires)


QUICK = QuickCall(
    name="fk/track",
    model=TrackCall,
    run=call_track,
    function=track,
    cost=track_cost,
    job='a job of kind "fk"',
)
