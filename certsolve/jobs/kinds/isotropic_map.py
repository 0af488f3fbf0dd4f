"""Kind ``isotropic-map``: the maximum isotropic force over a grid of positions
(``certsolve.force.isotropic_map``); and the quick call ``POST /v1/isotropic`` at one pose
(``certsolve.force.isotropic_force``)."""

from __future__ import annotations

from math import comb
from typing import Any, ClassVar, Literal

from pydantic import Field, model_validator

from ...robot.inputs import IsotropicOptions
from ...robot.schema import RobotSpec
from .base import (
    POSE_LENGTH,
    Coord,
    Job,
    Kind,
    Orientation,
    Params,
    QuickCall,
    Request,
    RunContext,
    Wrench,
    angles_schema,
    check_angles,
    check_count,
    check_pose,
    check_wire_lengths,
    orientation_arg,
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
    "QUICK",
    "call_isotropic",
    "isotropic_cost",
    "run_isotropic_map",
]

MAX_GRID_POINTS = 250_000  # nx * ny of an isotropic map
KRUT_MAX_SYSTEMS = 1_000_000  # = certsolve.force.krut.krut_polytope's max_combinations
MAX_GRID_SIDE = 2000


def check_external(robot: RobotSpec, external: list[float] | None) -> None:
    check_count(external, wrench_dim(robot), "external", "wrench components")


class IsotropicMapParams(Params):
    """A grid of ``nx`` x ``ny`` positions.  The service's ceilings: ``nx``, ``ny`` <=
    ``MAX_GRID_SIDE`` and ``nx * ny`` <= :attr:`max_grid_points` (a subclass with larger
    ones is how ``certsolve isotropic --grid`` runs the same operation on its own machine:
    ``cli.force.CliGridParams``)."""

    #: the ceiling of ``nx * ny`` (a class's own, not a field)
    max_grid_points: ClassVar[int] = MAX_GRID_POINTS

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
        limit = type(self).max_grid_points
        if self.nx * self.ny > limit:
            raise ValueError(f"nx * ny = {self.nx * self.ny} points; at most {limit}")
        return self

    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        shapes: dict[str, Any] = {"external": dof, "orientation": angles_schema(dof, ranges=False)}
        if dof != 6:
            shapes["z"] = None
        return shapes

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        if self.z is not None and robot.dof != 6:
            raise ValueError(f"z: a dof-{robot.dof} robot is planar (no z)")
        check_external(robot, self.external)
        check_angles(robot, self.orientation, "orientation", ranges=False)


class IsotropicMapJob(Job):
    kind: Literal["isotropic-map"]
    robot: RobotSpec
    params: IsotropicMapParams


def isotropic_map() -> Any:
    """The library function of kind ``isotropic-map``."""
    from ...force.maps import isotropic_map

    return isotropic_map


def run_isotropic_map(p: IsotropicMapParams, spec: RobotSpec, ctx: RunContext) -> Any:
    """The force over the ``nx`` x ``ny`` grid: :func:`~certsolve.force.isotropic_map`
    (no limits: the worker stops it through its time limit)."""
    import numpy as np

    from ...force.maps import isotropic_map

    xmin, xmax, ymin, ymax = p.grid
    xs = np.linspace(xmin, xmax, p.nx)
    ys = np.linspace(ymin, ymax, p.ny)
    rotation = orientation_arg(p.orientation)
    return isotropic_map(robot_model(spec), xs, ys, z=p.z, rotation=rotation, external=p.external)


KIND = Kind(
    name="isotropic-map",
    model=IsotropicMapJob,
    params=IsotropicMapParams,
    run=run_isotropic_map,
    function=isotropic_map,
    summary="isotropic force over a grid of positions",
)


# -- the quick call: one pose ---------------------------------------------------------------------
class PoseParams(IsotropicOptions, Params):  # the library's options as params
    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        return {"pose": POSE_LENGTH[dof], "external": dof}

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        check_pose(robot, self.pose, "pose")
        check_wire_lengths(robot, self.pose, "pose")  # a wire with no direction: no H
        check_external(robot, self.external)


class IsotropicCall(Request):
    """Body of ``POST /v1/isotropic``."""

    robot: RobotSpec
    params: PoseParams


def isotropic_force() -> Any:
    """The library function of the quick call ``isotropic``."""
    from ...force.isotropic import isotropic_force

    return isotropic_force


def call_isotropic(p: PoseParams, spec: RobotSpec, *, ellipse: bool = False) -> Any:
    """The isotropic force at ``p.pose``: :func:`~certsolve.force.isotropic_force`
    (``ellipse``: also its force ellipse, for ``certsolve isotropic --at --ellipse``)."""
    from ...force.isotropic import isotropic_force
    from ...robot.geometry import Pose

    robot = robot_model(spec)
    pose = Pose.from_params(robot.dof, p.pose)
    return isotropic_force(robot, pose, algorithm=p.algorithm, external=p.external, ellipse=ellipse)


def isotropic_cost(req: IsotropicCall) -> float:
    """Seconds, roughly (fitted on the project's 2-core machine, random robots).

    Hyperplane shifting finds ``F = 2 C(m, w - 1)`` facet planes and removes duplicates in
    ``O(F^2)`` (7e-6 s per pair: 5.7 s for 11 wires, dof 6); the force section of dof 3
    and 6 enumerates the ``2^m`` vertices of the tension box (about ``m 2^m`` 1e-6 s: 18 s
    for 20 wires, dof 3); Krut's algorithm solves ``C(2^m, w)`` linear systems (4e-5 s
    each: 21 s for 10 wires, dof 2) and refuses more than a million at once.
    """
    m, w = len(req.robot.wires), req.robot.dof
    planes = 2 * comb(m, w - 1)
    cost = 0.05 + 7e-6 * planes * planes
    if w != 2:
        cost += 1e-6 * m * 2.0**m
    if req.params.algorithm == "krut":
        systems = comb(2**m, w)
        cost += 4e-5 * systems if systems <= KRUT_MAX_SYSTEMS else 0.0  # else refused at once
    return cost


QUICK = QuickCall(
    name="isotropic",
    model=IsotropicCall,
    run=call_isotropic,
    function=isotropic_force,
    cost=isotropic_cost,
    job='a job of kind "isotropic-map" (a grid of one point) for the force value',
)
