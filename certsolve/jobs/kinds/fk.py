"""Kind ``fk``: every equilibrium pose for actuator values ``u``
(``certsolve.kinematics.forward_kinematics``); and the quick call ``POST /v1/fk/track``
(one certified tracking step near a known pose, ``certsolve.kinematics.track``)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from ...robot.schema import MAX_WIRES, RobotSpec
from .base import (
    MAX_FORCE,
    Coord,
    Job,
    Kind,
    Params,
    QuickCall,
    Request,
    RunContext,
    check_pose,
    check_wires,
    library_function,
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
    "run_fk",
    "track_cost",
]


class FkParams(Params):
    u: list[Coord] = Field(
        min_length=1, max_length=MAX_WIRES, description="actuator values (cm), one per wire"
    )
    eps: float = Field(default=1e-8, gt=0, le=1e9)
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1)
    tau_max: float | None = Field(default=None, ge=0, le=MAX_FORCE, description="tension cap")
    formulation: str = Field(default="auto", max_length=32, pattern=r"^[A-Za-z0-9_-]+$")
    seed_planar: bool = False
    seeded_only: bool = False

    def check_robot(self, robot: RobotSpec) -> None:
        check_wires(robot, self.u, "u")


class FkJob(Job):
    kind: Literal["fk"]
    robot: RobotSpec
    params: FkParams


def run_fk(job: FkJob, ctx: RunContext) -> Any:
    fk = library_function("fk", "certsolve.kinematics", "forward_kinematics")
    p = job.params
    result = fk(
        robot_model(job.robot),
        list(p.u),
        eps=p.eps,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        tau_max=p.tau_max,
        formulation=p.formulation,
        seed_planar=p.seed_planar,
        seeded_only=p.seeded_only,
        progress=ctx.progress,
    )
    return result


KIND = Kind(
    name="fk",
    model=FkJob,
    params=FkParams,
    run=run_fk,
    library=("certsolve.kinematics", "forward_kinematics"),
    summary="forward kinematics: every pose for the actuator values u",
)


# -- the quick call: one tracking step ------------------------------------------------------------
class TrackParams(Params):
    u: list[Coord] = Field(min_length=1, max_length=MAX_WIRES)
    near_pose: list[Coord] = Field(min_length=2, max_length=6, description="see IkParams.pose")
    half_width: float = Field(default=0.1, gt=0, le=1e4)

    def check_robot(self, robot: RobotSpec) -> None:
        check_wires(robot, self.u, "u")
        check_pose(robot, self.near_pose, "near_pose")


class TrackCall(Request):
    """Body of ``POST /v1/fk/track``."""

    robot: RobotSpec
    params: TrackParams


def call_track(req: TrackCall) -> Any:
    fn = library_function("fk/track", "certsolve.kinematics", "track")
    from ...robot.geometry import Pose

    robot = robot_model(req.robot)
    p = req.params
    near = Pose.from_params(robot.dof, p.near_pose)
    return fn(robot, list(p.u), near, half_width=p.half_width)


def track_cost(req: TrackCall) -> float:
    """Seconds, roughly: compiling the tracking system grows with the wires; one Newton
    and Krawczyk step is milliseconds."""
    return 0.2 + 0.02 * len(req.robot.wires)


QUICK = QuickCall(
    name="fk/track",
    model=TrackCall,
    run=call_track,
    cost=track_cost,
    library=("certsolve.kinematics", "track"),
    job='a job of kind "fk"',
)
