"""The table of FK formulations (Merlet 2007): names -> builders.

========================  =====  ===========================================================
name                      dof    system
========================  =====  ===========================================================
``auto``, ``frame``       3, 6   the paper's system for this robot in a platform frame
                                 (:class:`.FrameFormulation`, named ``frame-<paper system>``)
``general-19``            6      4 non-coplanar points + ρ (:class:`.PointsFormulation`)
``T-16``                  6      3 points of a planar platform + 7 ρ
``almost-planar-13``      6      3 points of a planar platform + 4 ρ
``planar-10``             3      3 points in the plane + 4 ρ
``points``                6      the paper's 3-point system for a planar platform
``pose``                  3, 6   position, Z-Y-X Euler angles + ρ (:class:`.PoseFormulation`)
========================  =====  ===========================================================

Each entry (a builder) has the dofs it is written for, ``check(robot)``: its geometric
precondition -- the robot's dof, the elastic model, a planar platform, enough distinct and
affinely independent attachment points -- which builds no expression
(:func:`check_formulation`, the judge of a job's formulation at submission), and
``build(robot)``, which checks the same and writes the system (:func:`build_formulation`).
The equations are :mod:`.fk_equations`; the coordinates :mod:`.fk_points` and
:mod:`.fk_pose`; what a formulation owns :mod:`.fk_formulation`.  A new formulation is one
class (or a builder of an existing one) and one line here (docs/architecture.md, "Adding an
FK formulation").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from ..robot.model import Robot
from .fk_formulation import FKFormulation
from .fk_geometry import PlatformPoints, papers_system, planar_platform, platform_points
from .fk_points import FrameFormulation, PointsFormulation
from .fk_pose import PoseFormulation

__all__ = [
    "FORMULATIONS",
    "Builder",
    "FKFormulation",
    "build_formulation",
    "check_formulation",
    "papers_system",
]


class Builder(Protocol):
    """One entry of :data:`FORMULATIONS`."""

    @property
    def dofs(self) -> tuple[int, ...]:
        """The robot dofs the formulation is written for."""
        ...

    def check(self, robot: Robot) -> object:
        """``ValueError`` if the formulation cannot be written for ``robot`` (no expression
        is built)."""
        ...

    def build(self, robot: Robot) -> FKFormulation: ...


@dataclass(frozen=True, kw_only=True)
class PaperSystem:
    """One of the paper's point systems: ``k`` chosen points, for robots of dof ``dof``,
    ``planar``: on a planar platform only (attachments and centre of mass coplanar)."""

    name: str
    k: int
    dof: int
    planar: bool = False

    @property
    def dofs(self) -> tuple[int, ...]:
        return (self.dof,)

    def check(self, robot: Robot) -> PlatformPoints:
        if robot.dof != self.dof:
            kind = "planar robots (dof 3)" if self.dof == 3 else "spatial robots (dof 6)"
            raise ValueError(f"{self.name} is for {kind}")
        if self.planar and not planar_platform(robot):
            raise ValueError(
                f"{self.name} needs a planar platform (attachments and centre of mass "
                "coplanar); use general-19"
            )
        robot.require_elastic("forward kinematics")
        return platform_points(robot, self.name, self.k)

    def build(self, robot: Robot) -> PointsFormulation:
        return PointsFormulation.build(robot, self.name, self.check(robot))


@dataclass(frozen=True, kw_only=True)
class PlatformFrame:
    """The paper's system for the robot (:func:`.papers_system`) in the platform frame."""

    dofs: tuple[int, ...] = (3, 6)

    def check(self, robot: Robot) -> tuple[str, PlatformPoints]:
        paper = papers_system(robot)
        robot.require_elastic("forward kinematics")
        name = f"frame-{paper}"
        return name, platform_points(robot, name, 4 if paper == "general-19" else 3, frame=True)

    def build(self, robot: Robot) -> FrameFormulation:
        name, platform = self.check(robot)
        return FrameFormulation.build(robot, name, platform)


@dataclass(frozen=True, kw_only=True)
class Pose:
    """Position and Euler angles (any elastic robot with a platform)."""

    dofs: tuple[int, ...] = (3, 6)

    def check(self, robot: Robot) -> None:
        robot.require_elastic("forward kinematics")
        if robot.toleranced:  # its rotation writes the anchors as floats
            raise ValueError("pose does not take tolerances; use auto or frame")

    def build(self, robot: Robot) -> PoseFormulation:
        self.check(robot)
        return PoseFormulation.build(robot)


#: every formulation by name, in the order the CLI lists them (``auto``: the default)
FORMULATIONS: dict[str, Builder] = {
    "auto": PlatformFrame(),
    "general-19": PaperSystem(name="general-19", k=4, dof=6),
    "T-16": PaperSystem(name="T-16", k=3, dof=6, planar=True),
    "almost-planar-13": PaperSystem(name="almost-planar-13", k=3, dof=6, planar=True),
    "planar-10": PaperSystem(name="planar-10", k=3, dof=3),
    "points": PaperSystem(name="points", k=3, dof=6, planar=True),
    "frame": PlatformFrame(),
    "pose": Pose(),
}


def _builder(name: str) -> Builder:
    try:
        return FORMULATIONS[name]
    except KeyError:
        raise ValueError(
            f"unknown formulation {name!r}; choose from {', '.join(FORMULATIONS)}"
        ) from None


def check_formulation(robot: Robot, name: str = "auto") -> None:
    """``ValueError`` if formulation ``name`` cannot be written for ``robot``: the geometric
    precondition of its builder, without building an expression (milliseconds)."""
    _builder(name).check(robot)


def build_formulation(robot: Robot, name: str = "auto") -> FKFormulation:
    """Build the named formulation (``auto``: the paper's system for this robot, in the
    platform frame)."""
    return _builder(name).build(robot)
