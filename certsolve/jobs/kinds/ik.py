"""Kind ``ik``: actuator values and tensions at a pose
(``certsolve.kinematics.inverse_kinematics``); the same as the quick call ``POST /v1/ik``."""

from __future__ import annotations

from typing import Any, Literal

from ...robot.inputs import IkOptions
from ...robot.schema import RobotSpec, robot_dof_schema
from .base import (
    POSE_LENGTH,
    Job,
    Kind,
    Params,
    QuickCall,
    Request,
    Required,
    RunContext,
    check_pose,
    check_wire_lengths,
    library_function,
    require_elastic,
    robot_model,
)

__all__ = ["KIND", "QUICK", "IkCall", "IkJob", "IkParams", "call_ik", "ik_cost", "run_ik"]


class IkParams(IkOptions, Params):  # the library's options as job params
    @classmethod
    def schema_variants(cls, dof: int) -> list[tuple[dict, dict[str, Any]]]:
        """The tension method takes any robot; Algorithms 1 and 2 need the elastic model."""
        tension = {"const": "tension", "default": "tension", "type": "string"}
        algorithms = Required({"enum": ["alg1", "alg2"], "type": "string"})
        return [
            (robot_dof_schema(dof), {"pose": POSE_LENGTH[dof], "method": tension}),
            (robot_dof_schema(dof, elastic=True), {"pose": POSE_LENGTH[dof], "method": algorithms}),
        ]

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        check_pose(robot, self.pose, "pose")
        check_wire_lengths(robot, self.pose, "pose")
        if self.method != "tension":
            require_elastic(
                robot,
                f"inverse kinematics ({self.method})",
                "; use method 'tension' for the tensions only",
            )


class IkJob(Job):
    kind: Literal["ik"]
    robot: RobotSpec
    params: IkParams


def run_ik(job: IkJob, ctx: RunContext) -> Any:
    ik = library_function("ik", "certsolve.kinematics", "inverse_kinematics")
    from ...robot.geometry import Pose

    robot = robot_model(job.robot)
    pose = Pose.from_params(robot.dof, job.params.pose)
    return ik(robot, pose, method=job.params.method)


KIND = Kind(
    name="ik",
    model=IkJob,
    params=IkParams,
    run=run_ik,
    library=("certsolve.kinematics", "inverse_kinematics"),
    summary="inverse kinematics: actuator values and tensions at a pose",
)


class IkCall(Request):
    """Body of ``POST /v1/ik``."""

    robot: RobotSpec
    params: IkParams


def call_ik(req: IkCall) -> Any:
    job = IkJob(kind="ik", robot=req.robot, params=req.params)
    return run_ik(job, RunContext(time_limit=0, max_boxes=0))


def ik_cost(req: IkCall) -> float:
    """Seconds, roughly: Algorithm 1 searches until its time limit (10 s); the others take
    milliseconds."""
    return 10.0 if req.params.method == "alg1" else 0.05


QUICK = QuickCall(
    name="ik",
    model=IkCall,
    run=call_ik,
    cost=ik_cost,
    library=("certsolve.kinematics", "inverse_kinematics"),
    job='a job of kind "ik"',
    cost_field="params.method",
)
