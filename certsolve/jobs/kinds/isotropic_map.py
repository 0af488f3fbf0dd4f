"""Kind ``isotropic-map``: the maximum isotropic force over a grid of positions
(``certsolve.force.isotropic_map``); and the quick call ``POST /v1/isotropic`` at one pose
(``certsolve.force.isotropic_force``)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from ...robot.schema import RobotSpec
from .base import (
    Coord,
    Job,
    Kind,
    Orientation,
    Params,
    Request,
    RunContext,
    Wrench,
    call_supported,
    check_count,
    check_pose,
    library_function,
    orientation_arg,
    plain_result,
    robot_model,
    wrench_dim,
)

__all__ = [
    "KIND",
    "MAX_GRID_POINTS",
    "MAX_GRID_SIDE",
    "IsotropicCall",
    "IsotropicMapJob",
    "IsotropicMapParams",
    "PoseParams",
    "call_isotropic",
    "run_isotropic_map",
]

MAX_GRID_POINTS = 250_000  # nx * ny of an isotropic map
MAX_GRID_SIDE = 2000


def check_external(robot: RobotSpec, external: list[float] | None) -> None:
    check_count(external, wrench_dim(robot), "external", "wrench components")


class IsotropicMapParams(Params):
    grid: tuple[Coord, Coord, Coord, Coord] = Field(description="[xmin, xmax, ymin, ymax] (cm)")
    nx: int = Field(default=41, ge=1, le=MAX_GRID_SIDE)
    ny: int = Field(default=41, ge=1, le=MAX_GRID_SIDE)
    z: Coord | None = Field(default=None, description="height of the map (dof 6)")
    orientation: Orientation = None
    external: Wrench | None = None

    @model_validator(mode="after")
    def _grid(self):
        xmin, xmax, ymin, ymax = self.grid
        if xmin > xmax or ymin > ymax:
            raise ValueError("grid: need xmin <= xmax and ymin <= ymax")
        if self.nx * self.ny > MAX_GRID_POINTS:
            raise ValueError(f"nx * ny = {self.nx * self.ny} points; at most {MAX_GRID_POINTS}")
        return self

    def check_robot(self, robot: RobotSpec) -> None:
        if self.z is not None and robot.dof != 6:
            raise ValueError(f"z: a dof-{robot.dof} robot is planar (no z)")
        check_external(robot, self.external)


class IsotropicMapJob(Job):
    kind: Literal["isotropic-map"]
    robot: RobotSpec
    params: IsotropicMapParams


def run_isotropic_map(job: IsotropicMapJob, ctx: RunContext) -> Any:
    imap = library_function("isotropic-map", "certsolve.force", "isotropic_map")
    import numpy as np

    p = job.params
    xmin, xmax, ymin, ymax = p.grid
    xs = np.linspace(xmin, xmax, p.nx)
    ys = np.linspace(ymin, ymax, p.ny)
    robot = robot_model(job.robot)
    rotation = orientation_arg(p.orientation)
    return plain_result(
        call_supported(imap, robot, xs, ys, z=p.z, rotation=rotation, external=p.external)
    )


KIND = Kind(
    name="isotropic-map",
    model=IsotropicMapJob,
    params=IsotropicMapParams,
    run=run_isotropic_map,
    library=("certsolve.force", "isotropic_map"),
    summary="isotropic force over a grid of positions",
)


# -- the quick call: one pose ---------------------------------------------------------------------
class PoseParams(Params):
    pose: list[Coord] = Field(min_length=2, max_length=6, description="see IkParams.pose")
    algorithm: Literal["shifting", "krut"] = "shifting"
    external: Wrench | None = None

    def check_robot(self, robot: RobotSpec) -> None:
        check_pose(robot, self.pose, "pose")
        check_external(robot, self.external)


class IsotropicCall(Request):
    """Body of ``POST /v1/isotropic``."""

    robot: RobotSpec
    params: PoseParams


def call_isotropic(req: IsotropicCall) -> Any:
    fn = library_function("isotropic", "certsolve.force", "isotropic_force")
    from ...robot.geometry import Pose

    robot = robot_model(req.robot)
    p = req.params
    pose = Pose.from_params(robot.dof, p.pose)
    return plain_result(call_supported(fn, robot, pose, algorithm=p.algorithm, external=p.external))
