"""Kind ``trajectory``: follow a control path from a start pose, every step certified and
joined to the previous one (``certsolve.track_trajectory``; ``certsolve track``).

The request carries the path as ``params.controls`` (one control vector per row, the rows
of ``certsolve track``'s CSV) and the start pose.  At submission the robot must admit the
FK equations (as the ``fk`` kind checks them), every row must hold one value per wire and
the start pose must be of the robot's dof.
"""

from __future__ import annotations

from typing import Any, Literal

from ...robot.inputs import TrajectoryOptions, check_trajectory
from ...robot.schema import RobotSpec
from .base import POSE_LENGTH, Job, Kind, Params, RunContext, check_pose, robot_model
from .fk import (
    FORMULATIONS,
    PLANAR_FORMULATIONS,
    SPATIAL_FORMULATIONS,
    check_fk_geometry,
    check_one_robot,
    fk_robot_schema,
)

__all__ = ["KIND", "NOT_POINTS", "TrajectoryJob", "TrajectoryParams", "run_trajectory"]

#: formulations that are not on the paper's chosen points: the tracker cannot use them
NOT_POINTS = ("frame", "pose")


class TrajectoryParams(TrajectoryOptions, Params):  # the library's options as job params
    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        if dof == 2:
            return None
        names = tuple(f for f in FORMULATIONS if f not in NOT_POINTS) + (
            PLANAR_FORMULATIONS if dof == 3 else SPATIAL_FORMULATIONS
        )
        return {
            "start": POSE_LENGTH[dof],
            "formulation": {"enum": list(names), "default": "auto", "type": "string"},
        }

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        return fk_robot_schema(dof)

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        if self.formulation in NOT_POINTS:
            raise ValueError(
                f"formulation: tracking uses the paper's point formulations, not "
                f"{self.formulation!r} (auto picks the paper's for the robot)"
            )
        check_one_robot(robot)
        check_trajectory(len(robot.wires), self.controls)
        check_pose(robot, self.start, "start")
        check_fk_geometry(robot, self.formulation, memo)


class TrajectoryJob(Job):
    kind: Literal["trajectory"]
    robot: RobotSpec
    params: TrajectoryParams


def track_trajectory() -> Any:
    """The library function of kind ``trajectory``."""
    from ...kinematics.trajectory import track_trajectory

    return track_trajectory


def run_trajectory(p: TrajectoryParams, spec: RobotSpec, ctx: RunContext) -> Any:
    """The path from ``p.start``: :func:`~certsolve.kinematics.trajectory.track_trajectory`."""
    from ...kinematics.trajectory import track_trajectory

    return track_trajectory(
        robot_model(spec),
        p.controls,
        p.start,
        half_width=p.half_width,
        formulation=p.formulation,
        tau_max=p.tau_max,
    )


KIND = Kind(
    name="trajectory",
    model=TrajectoryJob,
    params=TrajectoryParams,
    run=run_trajectory,
    function=track_trajectory,
    summary="trajectory: follow a control path, each step certified and joined to the last",
)
