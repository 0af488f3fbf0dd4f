"""Kind ``ik``: actuator values and tensions at a pose
(``certsolve.kinematics.inverse_kinematics``); the same as the quick call ``POST /v1/ik``."""

from __future__ import annotations

from typing import Any, Literal

from ...robot.inputs import ALG1_TIMEOUT, IkOptions
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
    check_wires,
    require_elastic,
    robot_model,
)

__all__ = ["KIND", "QUICK", "IkCall", "IkJob", "IkParams", "ik_cost", "run_ik"]


class IkParams(IkOptions, Params):  # the library's options as job params
    @classmethod
    def schema_variants(cls, dof: int) -> list[tuple[dict, dict[str, Any]]]:
        """The tension method takes any robot (and no search window: ``u_last`` and
        ``window`` absent); Algorithms 1 and 2 need the elastic model."""
        tension = {"const": "tension", "default": "tension", "type": "string"}
        algorithms = Required({"enum": ["alg1", "alg2"], "type": "string"})
        no_window = {"u_last": None, "window": None}
        return [
            (robot_dof_schema(dof), {"pose": POSE_LENGTH[dof], "method": tension, **no_window}),
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
        if self.u_last is not None:
            check_wires(robot, self.u_last, "u_last")
        m = len(robot.wires)
        if self.method == "alg2" and not self.fixed_wire <= m:
            raise ValueError(f"fixed_wire: the robot has wires 1..{m}")
        if robot.tolerances:  # a set of robots (docs/tolerances.md)
            from ...kinematics.ik_tolerance import check_tolerant_ik
            from ...robot.geometry import Pose

            model = robot_model(robot)
            if model.toleranced:
                pose = Pose.from_params(model.dof, self.pose)
                check_tolerant_ik(model, self.method, self.solve, pose)


class IkJob(Job):
    kind: Literal["ik"]
    robot: RobotSpec
    params: IkParams


def inverse_kinematics() -> Any:
    """The library function of kind ``ik`` (and of ``POST /v1/ik``)."""
    from ...kinematics.ik import inverse_kinematics

    return inverse_kinematics


def run_ik(p: IkParams, spec: RobotSpec, ctx: RunContext | None = None) -> Any:
    """Actuator values and tensions at ``p.pose``:
    :func:`~certsolve.kinematics.inverse_kinematics` with the options of ``p.method``
    (:meth:`~certsolve.robot.inputs.IkOptions.method_options`).  Algorithm 1's time and
    box limits are its own (``timeout``, default 10 s; ``max_boxes``) within ``ctx``'s."""
    from ...kinematics.ik import inverse_kinematics
    from ...robot.geometry import Pose

    robot = robot_model(spec)
    pose = Pose.from_params(robot.dof, p.pose)
    options = p.method_options()
    if p.method == "alg1":
        ctx = ctx or RunContext()
        options["timeout"] = _within(p.timeout or ALG1_TIMEOUT, ctx.time_limit)
        options["max_boxes"] = int(_within(p.max_boxes, ctx.max_boxes))
    return inverse_kinematics(robot, pose, method=p.method, **options)


def _within(value: float, limit: float | None) -> float:
    return value if limit is None else min(value, limit)


KIND = Kind(
    name="ik",
    model=IkJob,
    params=IkParams,
    run=run_ik,
    function=inverse_kinematics,
    summary="inverse kinematics: actuator values and tensions at a pose",
)


class IkCall(Request):
    """Body of ``POST /v1/ik``."""

    robot: RobotSpec
    params: IkParams


def ik_cost(req: IkCall) -> float:
    """Seconds, roughly: Algorithm 1 searches until its time limit (``timeout``, default
    10 s); the others take milliseconds."""
    p = req.params
    return (p.timeout or ALG1_TIMEOUT) if p.method == "alg1" else 0.05


QUICK = QuickCall(
    name="ik",
    model=IkCall,
    run=run_ik,
    function=inverse_kinematics,
    cost=ik_cost,
    job='a job of kind "ik"',
    cost_field="params.method",
)
