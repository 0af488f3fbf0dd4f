"""Kind ``ik-sweep``: the controls of every wire while ``u_joint`` sweeps a range at a fixed
pose, each point certified (``certsolve.kinematics.ik_sweep.ik_sweep``; Merlet 2007,
Fig. 3; ``certsolve ik --pose ... --sweep J=START:STOP:N``).

The robot needs the elastic model and ``m = w + 1`` wires (4 for dof 3, 7 for dof 6: one
control more than equations), and no wire may have zero length at the pose; all of this is
checked when the job is submitted.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from ...robot.schema import MAX_WIRES, RobotSpec, robot_dof_schema
from .base import (
    POSE_LENGTH,
    Coord,
    Job,
    Kind,
    Params,
    RunContext,
    check_count,
    check_pose,
    check_wire_lengths,
    require_elastic,
    robot_model,
    wrench_dim,
)

__all__ = ["KIND", "MAX_SWEEP_POINTS", "IkSweepJob", "IkSweepParams", "run_ik_sweep"]

MAX_SWEEP_POINTS = 100_000  # = certsolve.kinematics.ik_sweep.MAX_POINTS


class IkSweepParams(Params):
    pose: list[Coord] = Field(
        min_length=2,
        max_length=6,
        description="x,y,z,yaw,pitch,roll (dof 6), x,y,theta (dof 3); cm, degrees",
    )
    joint: int = Field(default=1, ge=1, le=MAX_WIRES, description="wire whose u is swept (1-based)")
    start: Coord = Field(description="first value of u_joint (cm)")
    stop: Coord = Field(description="last value of u_joint (cm)")
    count: int = Field(ge=2, le=MAX_SWEEP_POINTS, description="values, evenly spaced")
    u_start: list[Coord] | None = Field(
        default=None,
        min_length=1,
        max_length=MAX_WIRES,
        description="Newton start of the first point, one per wire (default: mid-strokes)",
    )
    box_radius: float = Field(
        default=1e-4, gt=0, le=1, description="relative half-width of the certificate's box"
    )
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")

    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        return None if dof == 2 else {"pose": POSE_LENGTH[dof], "u_start": dof + 1}

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        return robot_dof_schema(dof, elastic=True, wires=dof + 1)

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        m, w = len(robot.wires), wrench_dim(robot)
        if robot.dof == 2:
            raise ValueError("robot.dof: a sweep needs a rigid platform (dof 3 or 6)")
        if m != w + 1:
            raise ValueError(
                f"robot.wires: a sweep of one control needs m = w + 1 = {w + 1} wires for "
                f"dof {robot.dof}, the robot has {m}"
            )
        require_elastic(robot, "an IK sweep")
        if self.joint > m:
            raise ValueError(f"joint: the robot has wires 1..{m}")
        check_count(self.u_start, m, "u_start", "values (one per wire)")
        check_pose(robot, self.pose, "pose")
        check_wire_lengths(robot, self.pose, "pose")


class IkSweepJob(Job):
    kind: Literal["ik-sweep"]
    robot: RobotSpec
    params: IkSweepParams


def ik_sweep() -> Any:
    """The library function of kind ``ik-sweep``."""
    from ...kinematics.ik_sweep import ik_sweep

    return ik_sweep


def run_ik_sweep(p: IkSweepParams, spec: RobotSpec, ctx: RunContext) -> Any:
    """The sweep of ``u_joint``: :func:`~certsolve.kinematics.ik_sweep.ik_sweep`."""
    from ...kinematics.ik_sweep import ik_sweep
    from ...robot.geometry import Pose

    robot = robot_model(spec)
    return ik_sweep(
        robot,
        Pose.from_params(robot.dof, p.pose),
        joint=p.joint,
        start=p.start,
        stop=p.stop,
        count=p.count,
        u_start=p.u_start,
        box_radius=p.box_radius,
        progress=ctx.progress,
        timeout=ctx.time_limit,
    )


KIND = Kind(
    name="ik-sweep",
    model=IkSweepJob,
    params=IkSweepParams,
    run=run_ik_sweep,
    function=ik_sweep,
    summary="IK sweep: the controls as one control sweeps a range, each point certified",
)
