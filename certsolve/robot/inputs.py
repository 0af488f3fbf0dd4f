"""What the robot functions take from a user, checked once: poses as plain numbers, and
the options models of forward kinematics, tracking, inverse kinematics and the isotropic
force.

``certsolve.forward_kinematics``, ``track``, ``inverse_kinematics`` and
``isotropic_force`` validate their options with these models (:func:`certsolve.inputs.
checked`); the job kinds' params models derive from them (``FkParams(FkOptions,
Params)``), and the command line builds those, so Python, HTTP and the command line refuse
the same values with the same messages.  The checks against a robot that need no model
are here too (:func:`check_controls`, :func:`as_pose`); they raise
:class:`~certsolve.inputs.InputError` naming the field.

A pose is a :class:`~.geometry.Pose`, or its parameters as a list, tuple or 1-D array
(``x,y,z[,yaw,pitch,roll]`` for dof 6, ``x,y[,theta]`` for dof 3, ``x,y`` for dof 2; cm and
degrees), or the same as comma-separated text.  Each coordinate is finite and within
``±MAX_COORD``, as the robot file's.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from ..inputs import (
    MAX_COORD,
    MAX_FORCE,
    Coord,
    InputError,
    StrictModel,
    check_count,
    checked_value,
    value_type,
)
from .geometry import Pose, parse_pose
from .schema import MAX_WIRES

__all__ = [
    "Formulation",
    "FkOptions",
    "ALG1_TIMEOUT",
    "IK_METHOD_OPTIONS",
    "IkOptions",
    "IsotropicOptions",
    "PoseValues",
    "TrackOptions",
    "TrajectoryOptions",
    "Wrench",
    "as_pose",
    "check_controls",
    "check_trajectory",
]

#: = certsolve.kinematics.fk_systems.FORMULATIONS (tested)
Formulation = Literal[
    "auto", "frame", "pose", "planar-10", "general-19", "T-16", "almost-planar-13",
    "points",
]  # fmt: skip

PoseValues = Annotated[
    list[Coord],
    Field(
        min_length=2,
        max_length=6,
        description="x,y,z,yaw,pitch,roll (dof 6), x,y,theta (dof 3) or x,y (dof 2); cm, deg",
    ),
]
_POSE_VALUES = value_type(PoseValues)
Controls = Annotated[
    list[Coord],
    Field(min_length=1, max_length=MAX_WIRES, description="actuator values (cm), one per wire"),
]
Wrench = Annotated[
    list[Annotated[float, Field(ge=-MAX_FORCE, le=MAX_FORCE)]],
    Field(min_length=2, max_length=6, description="extra constant wrench (N, N*cm)"),
]


class FkOptions(StrictModel):
    """Options of :func:`certsolve.forward_kinematics` (and of the ``fk`` job)."""

    u: Controls
    eps: float = Field(default=1e-8, gt=0, le=1e9)
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1)
    max_solutions: int | None = Field(
        default=None, ge=1, le=10**9, description="stop after this many certified poses"
    )
    tau_max: float | None = Field(default=None, ge=0, le=MAX_FORCE, description="tension cap")
    formulation: Formulation = Field(
        default="auto", description="the FK equations (docs: README, forward kinematics)"
    )
    seed_planar: bool = False
    seeded_only: bool = False
    seed_minima: bool = Field(
        default=True,
        description="spatial robots: search around the energy's local minima (the stable "
        "poses) first; same answer, found sooner",
    )
    stable_only: bool = Field(
        default=False,
        description="stable equilibria only; complete then means no other stable one exists",
    )
    newton_starts: bool = Field(
        default=True,
        description="float Newton from random points, the points it reaches proven: the "
        "poses early, the same complete answer (not with stable_only)",
    )


class TrackOptions(StrictModel):
    """Options of :func:`certsolve.track` (and of ``POST /v1/fk/track``)."""

    u: list[Coord] = Field(min_length=1, max_length=MAX_WIRES)
    near_pose: PoseValues = Field(description="see IkParams.pose")
    half_width: float = Field(default=0.1, gt=0, le=1e4)


#: most rows of a trajectory (``certsolve track``, the ``trajectory`` job)
MAX_TRAJECTORY_ROWS = 100_000


class TrajectoryOptions(StrictModel):
    """Options of :func:`certsolve.track_trajectory` (and of the ``trajectory`` job and
    ``certsolve track``)."""

    controls: list[Controls] = Field(
        min_length=1,
        max_length=MAX_TRAJECTORY_ROWS,
        description="the path: one control vector u per row (cm), one value per wire",
    )
    start: PoseValues = Field(
        description="a pose near the equilibrium at the first row (see IkParams.pose)"
    )
    half_width: float = Field(
        default=0.1, gt=0, le=1e4, description="half-width (cm) of each step's box"
    )
    formulation: Formulation = Field(default="auto", description="the FK equations")
    tau_max: float | None = Field(default=None, ge=0, le=MAX_FORCE, description="tension cap")


#: the options each method of :func:`certsolve.inverse_kinematics` takes from
#: :class:`IkOptions` (the keywords of ``ik_tension_first``, ``ik_algorithm1``,
#: ``ik_algorithm2``; a test binds them to those signatures)
IK_METHOD_OPTIONS: dict[str, tuple[str, ...]] = {
    "tension": ("distribution", "check_lp"),
    "alg1": ("u_last", "window", "timeout", "max_boxes"),
    "alg2": ("u_last", "window", "fixed_wire", "tau_fixed", "solve"),
}
#: Algorithm 1's time limit (s) when ``timeout`` is not given
ALG1_TIMEOUT = 10.0


class IkOptions(StrictModel):
    """Options of :func:`certsolve.inverse_kinematics` (and of the ``ik`` job and
    ``certsolve ik``).

    Each method reads its own (:data:`IK_METHOD_OPTIONS`); ``u_last`` and ``window`` are
    refused with ``tension`` (it has no search window), and another method's option given
    a value other than its default is refused (it would be ignored).  ``fixed_wire`` is
    1-based and checked against the robot by the job (``IkParams.check_robot``), as
    ``u_last``'s length.
    """

    pose: PoseValues
    method: Literal["tension", "alg1", "alg2"] = "tension"
    u_last: Controls | None = Field(
        default=None,
        description="alg1: centre of the search window; alg2: Newton start and window centre (cm)",
    )
    window: float | None = Field(
        default=None,
        gt=0,
        le=MAX_COORD,
        description="alg1/alg2: full width (cm) of the window around u_last (alg1: 0.1)",
    )
    fixed_wire: int = Field(default=1, ge=1, le=MAX_WIRES, description="alg2: wire fixed (1-based)")
    tau_fixed: float | None = Field(
        default=None,
        ge=-MAX_FORCE,
        le=MAX_FORCE,
        description="alg2: tension of the fixed wire (N; default: middle of its range)",
    )
    solve: Literal["tau", "newton"] = Field(
        default="tau", description="alg2: one linear solve in the tensions, or Newton in u"
    )
    timeout: float | None = Field(
        default=None, gt=0, description=f"alg1: time limit (s; default {ALG1_TIMEOUT:g})"
    )
    max_boxes: int = Field(default=20000, ge=1, description="alg1: limit on processed boxes")
    distribution: Literal["auto", "closed-form", "lp"] = Field(
        default="auto", description="tension: how the tensions are chosen"
    )
    check_lp: bool = Field(
        default=False, description="tension: also solve the LP and report the difference"
    )

    @model_validator(mode="after")
    def _options_of_the_method(self) -> IkOptions:
        if self.method == "tension":
            for name in ("u_last", "window"):
                if getattr(self, name) is not None:
                    raise ValueError(f"{name}: applies to method alg1 or alg2")
        # another method's option, given a value of its own, would be silently ignored
        for name in ("distribution", "check_lp", "fixed_wire", "tau_fixed", "solve"):
            field = type(self).model_fields[name]
            if name in IK_METHOD_OPTIONS[self.method] or name not in self.model_fields_set:
                continue
            if getattr(self, name) != field.default:
                owner = next(m for m, names in IK_METHOD_OPTIONS.items() if name in names)
                raise ValueError(f"{name}: applies to method {owner}, not {self.method}")
        return self

    def method_options(self) -> dict[str, Any]:
        """The keywords of this method's function (:data:`IK_METHOD_OPTIONS`), limits
        aside: the caller bounds ``timeout`` and ``max_boxes``."""
        return {name: getattr(self, name) for name in IK_METHOD_OPTIONS[self.method]}


class IsotropicOptions(StrictModel):
    """Options of :func:`certsolve.isotropic_force` (and of ``POST /v1/isotropic``)."""

    pose: PoseValues = Field(description="see IkParams.pose")
    algorithm: Literal["shifting", "krut"] = "shifting"
    external: Wrench | None = None


def check_controls(m: int, u: Sequence[float], field: str = "u") -> None:
    """One control per wire."""
    check_count(u, m, field, "values (one per wire)")


def check_trajectory(m: int, controls: Sequence[Sequence[float]], field: str = "controls") -> None:
    """One control per wire on every row (the first bad row named: ``controls.3``, from 0)."""
    for i, row in enumerate(controls):
        check_controls(m, row, f"{field}.{i}")


def pose_values(pose: Any, field: str = "pose") -> list[float]:
    """Pose parameters (a list, tuple or 1-D array), checked as the pose fields of the
    options models check them."""
    if isinstance(pose, np.ndarray):
        if pose.ndim != 1:
            raise InputError(field, f"expected a list of numbers, got shape {pose.shape}")
        pose = pose.tolist()
    return checked_value(_POSE_VALUES, pose, field)


def as_pose(dof: int, pose: Any, field: str = "pose") -> Pose:
    """A :class:`Pose` with float64 arrays for a robot of ``dof`` from what a user gives
    (module docstring); :class:`~certsolve.inputs.InputError` at ``field`` otherwise."""
    d = 3 if dof == 6 else 2
    if isinstance(pose, Pose):
        p = np.asarray(pose.position, dtype=float)
        R = np.asarray(pose.rotation, dtype=float)
        if p.shape != (d,) or R.shape != (d, d):
            raise InputError(
                field, f"a dof-{dof} robot needs a {d}-D position and a {d}x{d} rotation"
            )
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(R))):
            raise InputError(field, "position and rotation must be finite")
        if p is pose.position and R is pose.rotation:
            return pose
        return Pose(p, R)
    try:
        if isinstance(pose, str):
            return parse_pose(dof, pose)
        return Pose.from_params(dof, pose_values(pose, field))
    except InputError:
        raise
    except ValueError as exc:
        raise InputError(field, str(exc).removeprefix("pose ")) from None
