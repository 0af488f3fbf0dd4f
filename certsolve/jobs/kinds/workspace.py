"""Kind ``workspace``: the certified paving of ``{f_min >= min_force}`` over a box of
positions (``certsolve.force.certified_workspace``)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator

from ...robot.schema import RobotSpec
from .base import (
    MAX_FORCE,
    Coord,
    Job,
    Kind,
    Orientation,
    Params,
    RunContext,
    Wrench,
    angles_schema,
    check_angles,
    check_count,
    orientation_arg,
    robot_model,
)
from .isotropic_map import check_external

__all__ = ["KIND", "WorkspaceJob", "WorkspaceParams", "run_workspace"]


class WorkspaceParams(Params):
    min_force: float = Field(gt=0, le=MAX_FORCE, description="required force (N)")
    box: list[tuple[Coord, Coord]] = Field(
        min_length=1, max_length=6, description="box of positions, [lo, hi] per axis (cm)"
    )
    eps: float = Field(gt=0, le=1e9, description="boxes narrower stop (cm)")
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1, description="limit on processed boxes")
    orientation: Orientation = None
    eps_angle: float = Field(default=1.0, gt=0, le=360, description="angle width to stop (deg)")
    external: Wrench | None = None

    @field_validator("box")
    @classmethod
    def _box(cls, v):
        for i, (lo, hi) in enumerate(v):
            if lo > hi:
                raise ValueError(f"box[{i}]: need lo <= hi")
        return v

    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        return {
            "box": 3 if dof == 6 else 2,
            "external": dof,
            "orientation": angles_schema(dof, ranges=True),
        }

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        check_count(self.box, robot.dim, "box", "intervals, [lo, hi] per axis")
        check_external(robot, self.external)
        check_angles(robot, self.orientation, "orientation", ranges=True)


class WorkspaceJob(Job):
    kind: Literal["workspace"]
    robot: RobotSpec
    params: WorkspaceParams


def certified_workspace() -> Any:
    """The library function of kind ``workspace``."""
    from ...force.certified import certified_workspace

    return certified_workspace


def run_workspace(p: WorkspaceParams, spec: RobotSpec, ctx: RunContext) -> Any:
    """The certified paving: :func:`~certsolve.force.certified_workspace`."""
    from ...force.certified import certified_workspace

    result = certified_workspace(
        robot_model(spec),
        p.min_force,
        [list(b) for b in p.box],
        p.eps,
        progress=ctx.progress,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        orientation=orientation_arg(p.orientation),
        eps_angle=p.eps_angle,
        external=p.external,
        executor=ctx.executor,
        cancel=ctx.cancel,
        checkpoint=ctx.checkpoint,
    )
    return result


KIND = Kind(
    name="workspace",
    model=WorkspaceJob,
    params=WorkspaceParams,
    run=run_workspace,
    function=certified_workspace,
    summary="certified workspace where the isotropic force is at least min_force",
)
