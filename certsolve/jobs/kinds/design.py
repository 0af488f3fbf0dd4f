"""Kind ``design``: parameter boxes proven to give the isotropic force ``min_force`` over a
workspace (``certsolve.force.design.design``; Krut et al. 2004, IV-B; ``certsolve design
SPEC.json``).

The request is a design spec with the robot inline: ``robot`` (a robot object, never a
file path on the server) beside ``params`` = the spec's other fields
(:class:`~certsolve.force.design_spec.DesignOptions`: ``parameters``, ``workspace``,
``min_force``, ``orientation``, ``eps``, ``workspace_eps``) and the limits.  At submission
the parameters are applied to the robot (:class:`~certsolve.robot.params.AffineRobot`:
paths that exist, numbers no two parameters share, a valid robot at every corner of the
parameter box), so a bad spec is a 422 naming ``params.parameters.1.path`` rather than a
failed job.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from ...force.design_spec import DEFAULT_EPS, MAX_PARAMETERS, DesignOptions, ParameterSpec
from ...robot.schema import RobotSpec, robot_dof_schema
from .base import (
    MAX_FORCE,
    Angle,
    Coord,
    Job,
    Kind,
    Params,
    RunContext,
    angles_schema,
    check_angles,
    check_count,
    wrench_dim,
)

__all__ = ["KIND", "PATH_PATTERN", "DesignJob", "DesignParameter", "DesignParams", "run_design"]

# wires[W].FIELD[C] (certsolve.robot.params): W, C = *, an index or a comma list
_INDEX = r" *(\*|\d+( *, *\d+)*) *"
PATH_PATTERN = rf"^ *wires *\[{_INDEX}\] *\. *(base|platform|tau) *\[{_INDEX}\] *$"
Bound = Annotated[float, Field(gt=-1e9, lt=1e9)]


class DesignParameter(ParameterSpec):
    """A design parameter (:class:`~certsolve.force.design_spec.ParameterSpec`), with the
    bounds its validation enforces written into the schema."""

    path: str = Field(
        max_length=200,
        pattern=PATH_PATTERN,
        description="numbers of the robot it sets: wires[W].base[C], wires[W].platform[C] "
        "or wires[W].tau[0|1]; W, C = *, an index or a comma list (0-based)",
    )
    range: tuple[Bound, Bound] = Field(description="[lo, hi], lo < hi")
    centre: list[Coord] | None = Field(
        default=None,
        min_length=1,
        max_length=3,
        description="'half-width' only: centre of the scaling (default: mid-range)",
    )


class DesignParams(Params, DesignOptions):
    parameters: list[DesignParameter] = Field(  # type: ignore[assignment]
        min_length=2, max_length=MAX_PARAMETERS
    )
    workspace: list[Coord] = Field(
        min_length=4, max_length=6, description="xmin, xmax, ymin, ymax[, zmin, zmax] (cm)"
    )
    min_force: float = Field(gt=0, le=MAX_FORCE, description="required isotropic force F (N)")
    orientation: Angle | list[Angle] | None = Field(
        default=None,
        description="fixed platform angle: theta (dof 3) or [yaw, pitch, roll] (dof 6), deg",
    )
    eps: float = Field(
        default=DEFAULT_EPS, gt=0, le=1, description="parameter boxes stop at this fraction"
    )
    workspace_eps: float | None = Field(
        default=None, gt=0, le=1e6, description="pose boxes stop at this width (cm)"
    )
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(
        default=None, ge=1, description="limit on evaluated (parameter, pose) pairs"
    )

    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        return {
            "workspace": 6 if dof == 6 else 4,
            "orientation": angles_schema(dof, ranges=False),
        }

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        return robot_dof_schema(dof, min_wires=dof)

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        from ...robot.params import AffineRobot

        check_count(self.workspace, 2 * robot.dim, "workspace", "numbers, [lo, hi] per axis")
        check_angles(robot, self.orientation, "orientation", ranges=False)
        if len(robot.wires) < wrench_dim(robot):
            raise ValueError(
                f"robot.wires: {len(robot.wires)} wires cannot resist a force in every direction"
            )
        try:
            AffineRobot(robot, self.definitions())
        except ValueError as exc:  # "parameters[1].path: ..." or a robot at a corner
            raise ValueError(str(exc).replace("\n", "; ")) from None


class DesignJob(Job):
    kind: Literal["design"]
    robot: RobotSpec
    params: DesignParams


def design() -> Any:
    """The library function of kind ``design``."""
    from ...force.design import design

    return design


def run_design(p: DesignParams, robot: RobotSpec | str | dict, ctx: RunContext) -> Any:
    """The certified design of the spec ``p`` on ``robot`` (a robot spec, or what a spec
    file's ``robot`` holds: a path or a robot object): :func:`~certsolve.force.design.
    design`."""
    from ...force.design import design

    data = robot.model_dump(exclude_none=True) if isinstance(robot, RobotSpec) else robot
    return design(
        p.spec(data),
        progress=ctx.progress,
        cancel=ctx.cancel,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        checkpoint=ctx.checkpoint,
    )


KIND = Kind(
    name="design",
    model=DesignJob,
    params=DesignParams,
    run=run_design,
    function=design,
    summary="certified design: parameter boxes proven to give min_force over a workspace",
)
