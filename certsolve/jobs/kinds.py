"""Job kinds: for each, the pydantic model of its request and the function that runs it.

A job request is ``{"kind": ..., "robot": {...} | "system": "...", "params": {...},
"limits": {...}}``; the same models validate HTTP bodies, lines of ``certsolve batch``
files and the ``certsolve submit`` command line.  Kinds map one-to-one onto library calls:

==============  ==============================================  ===========================
kind            library call                                    input
==============  ==============================================  ===========================
solve           ``certsolve.solver.solve``                      ``system`` (Minibex text)
fk              ``certsolve.kinematics.forward_kinematics``     ``robot``
ik              ``certsolve.kinematics.inverse_kinematics``     ``robot``
isotropic-map   ``certsolve.force.isotropic_map``               ``robot``
workspace       ``certsolve.force.certified_workspace``         ``robot``
==============  ==============================================  ===========================

The library modules are imported lazily inside the runners: a build without one of them
still serves the others, and such jobs fail with "kind X is not available in this build".
The hidden kind ``sleep`` (test settings only) sleeps, reports progress and can crash.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import logging
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, field_validator, model_validator

from ..robot.schema import MAX_WIRES, RobotSpec

__all__ = [
    "KINDS",
    "Kind",
    "KindUnavailable",
    "JobLimits",
    "RunContext",
    "SolveParams",
    "FkParams",
    "IkParams",
    "IsotropicMapParams",
    "WorkspaceParams",
    "SleepParams",
    "IkCall",
    "IsotropicCall",
    "TrackCall",
    "job_request_type",
    "request_adapter",
    "library_function",
    "public_kinds",
    "call_ik",
    "call_isotropic",
    "call_track",
    "MAX_SYSTEM_CHARS",
    "MAX_VARIABLES",
    "MAX_GRID_POINTS",
]

log = logging.getLogger("certsolve.jobs")

MAX_SYSTEM_CHARS = 200_000  # Minibex text of a solve job
MAX_VARIABLES = 100
MAX_GRID_POINTS = 250_000  # nx * ny of an isotropic map
MAX_GRID_SIDE = 2000
_MAX_COORD = 1e6  # cm, the robot schema's bound
_MAX_FORCE = 1e9  # N

Coord = Annotated[float, Field(ge=-_MAX_COORD, le=_MAX_COORD)]
Angle = Annotated[float, Field(ge=-1e4, le=1e4)]  # degrees
Wrench = Annotated[
    list[Annotated[float, Field(ge=-_MAX_FORCE, le=_MAX_FORCE)]],
    Field(min_length=2, max_length=6, description="extra constant wrench (N, N*cm)"),
]
Orientation = Annotated[
    Angle | list[Angle | tuple[Angle, Angle]] | None,
    Field(description="theta (dof 3) or [yaw, pitch, roll] (dof 6), degrees; [lo, hi] ranges"),
]


class KindUnavailable(Exception):
    """The library function behind a kind is missing from this build."""


# -- parameters ---------------------------------------------------------------------------------
class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class JobLimits(_Model):
    """Per-job resource limits; unset ones take the service defaults, within its ceilings."""

    timeout: float | None = Field(default=None, gt=0, description="wall-time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1, description="limit on processed boxes")
    memory_mb: int | None = Field(default=None, ge=1, description="address-space limit (MiB)")


class SolveParams(_Model):
    eps: float = Field(default=1e-8, gt=0, le=1e9, description="boxes narrower stop")
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1, description="limit on processed boxes")
    verify: bool = Field(default=False, description="re-prove solutions with mpmath")


class FkParams(_Model):
    u: list[Coord] = Field(
        min_length=1, max_length=MAX_WIRES, description="actuator values (cm), one per wire"
    )
    eps: float = Field(default=1e-8, gt=0, le=1e9)
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1)
    tau_max: float | None = Field(default=None, ge=0, le=_MAX_FORCE, description="tension cap")
    formulation: str = Field(default="auto", max_length=32, pattern=r"^[A-Za-z0-9_-]+$")
    seed_planar: bool = False
    seeded_only: bool = False


class IkParams(_Model):
    pose: list[Coord] = Field(
        min_length=2,
        max_length=6,
        description="x,y,z,yaw,pitch,roll (dof 6), x,y,theta (dof 3) or x,y (dof 2); cm, deg",
    )
    method: Literal["tension", "alg1", "alg2"] = "tension"


class IsotropicMapParams(_Model):
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


class WorkspaceParams(_Model):
    min_force: float = Field(gt=0, le=_MAX_FORCE, description="required force (N)")
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


class SleepParams(_Model):
    seconds: float = Field(default=1.0, ge=0, le=3600)
    crash: bool = Field(default=False, description="exit the worker abruptly halfway")
    fail: str | None = Field(default=None, max_length=200, description="raise this error")
    allocate_mb: int = Field(default=0, ge=0, le=1_000_000, description="allocate memory first")
    cooperative: bool = Field(default=True, description="report progress, honour limits")


class PoseParams(_Model):
    pose: list[Coord] = Field(min_length=2, max_length=6, description="see IkParams.pose")
    algorithm: Literal["shifting", "krut"] = "shifting"
    external: Wrench | None = None


class TrackParams(_Model):
    u: list[Coord] = Field(min_length=1, max_length=MAX_WIRES)
    near_pose: list[Coord] = Field(min_length=2, max_length=6, description="see IkParams.pose")
    half_width: float = Field(default=0.1, gt=0, le=1e4)


# -- job requests -------------------------------------------------------------------------------
class _Job(_Model):
    limits: JobLimits | None = Field(default=None, description="resource limits of this job")


def _check_system(text: str) -> str:
    from ..expr.minibex import MinibexError, parse_minibex

    try:
        system = parse_minibex(text)
    except MinibexError as exc:
        raise ValueError(str(exc)) from None
    except RecursionError:
        raise ValueError("expression nested too deeply") from None
    if len(system.variables) > MAX_VARIABLES:
        raise ValueError(f"{len(system.variables)} variables; at most {MAX_VARIABLES}")
    return text


def _check_pose(robot: RobotSpec, values: list[float], what: str) -> None:
    from ..robot.geometry import Pose

    try:
        Pose.from_params(robot.dof, values)
    except ValueError as exc:
        raise ValueError(f"{what}: {exc}") from None


def _check_u(robot: RobotSpec, u: list[float]) -> None:
    if len(u) != len(robot.wires):
        raise ValueError(
            f"params.u: expected {len(robot.wires)} values (one per wire), got {len(u)}"
        )


class SolveJob(_Job):
    kind: Literal["solve"]
    system: str = Field(
        min_length=1, max_length=MAX_SYSTEM_CHARS, description="the system, Minibex text"
    )
    params: SolveParams = Field(default_factory=SolveParams)

    @field_validator("system")
    @classmethod
    def _system(cls, v: str) -> str:
        return _check_system(v)


class FkJob(_Job):
    kind: Literal["fk"]
    robot: RobotSpec
    params: FkParams

    @model_validator(mode="after")
    def _u(self):
        _check_u(self.robot, self.params.u)
        return self


class IkJob(_Job):
    kind: Literal["ik"]
    robot: RobotSpec
    params: IkParams

    @model_validator(mode="after")
    def _pose(self):
        _check_pose(self.robot, self.params.pose, "params.pose")
        return self


class IsotropicMapJob(_Job):
    kind: Literal["isotropic-map"]
    robot: RobotSpec
    params: IsotropicMapParams


class WorkspaceJob(_Job):
    kind: Literal["workspace"]
    robot: RobotSpec
    params: WorkspaceParams


class SleepJob(_Job):
    kind: Literal["sleep"]
    params: SleepParams = Field(default_factory=SleepParams)


class IkCall(_Model):
    """Body of ``POST /v1/ik``."""

    robot: RobotSpec
    params: IkParams

    @model_validator(mode="after")
    def _pose(self):
        _check_pose(self.robot, self.params.pose, "params.pose")
        return self


class IsotropicCall(_Model):
    """Body of ``POST /v1/isotropic``."""

    robot: RobotSpec
    params: PoseParams

    @model_validator(mode="after")
    def _pose(self):
        _check_pose(self.robot, self.params.pose, "params.pose")
        return self


class TrackCall(_Model):
    """Body of ``POST /v1/fk/track``."""

    robot: RobotSpec
    params: TrackParams

    @model_validator(mode="after")
    def _check(self):
        _check_u(self.robot, self.params.u)
        _check_pose(self.robot, self.params.near_pose, "params.near_pose")
        return self


# -- running ------------------------------------------------------------------------------------
@dataclass
class RunContext:
    """What a runner gets besides its request: limits and the progress callback.

    ``progress(p)`` takes the library's progress object (``boxes``, ``pending``,
    ``solutions``, ``undecided``, ``elapsed``) and returns False when the job must stop
    (cancelled, or over its box limit); runners pass it to the library calls.
    """

    time_limit: float
    max_boxes: int
    progress: Callable[[Any], bool] = field(default=lambda p: True)


def library_function(kind: str, module: str, name: str) -> Callable:
    """Import ``module.name`` or raise :class:`KindUnavailable`."""
    try:
        mod = importlib.import_module(module)
        return getattr(mod, name)
    except Exception as exc:  # ImportError, AttributeError, or a module that does not load
        if not isinstance(exc, (ImportError, AttributeError)):
            log.warning("importing %s failed: %s: %s", module, type(exc).__name__, exc)
        raise KindUnavailable(f"kind {kind} is not available in this build") from None


def _plain(result) -> Any:
    return result.to_dict() if hasattr(result, "to_dict") else result


def _call(fn: Callable, *args, **options) -> Any:
    """``fn(*args, **options)`` without the options its signature lacks (when unset)."""
    try:
        accepted = inspect.signature(fn).parameters
    except (TypeError, ValueError):  # pragma: no cover - builtins
        return fn(*args, **options)
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted.values()):
        return fn(*args, **options)
    kwargs = {}
    for name, value in options.items():
        if name in accepted:
            kwargs[name] = value
        elif value is not None and name not in _ADVISORY:
            raise ValueError(f"params.{name} is not supported by this build")
    return fn(*args, **kwargs)


# passed when the library takes them, else enforced by the worker (progress callback, kill)
_ADVISORY = frozenset({"timeout", "max_boxes", "progress"})


def _orientation(value):
    if isinstance(value, list):
        return [tuple(v) if isinstance(v, tuple) else v for v in value]
    return value


def _robot(spec: RobotSpec):
    from ..robot.model import Robot

    return Robot.from_spec(spec)


def run_solve(job: SolveJob, ctx: RunContext) -> Any:
    solve = library_function("solve", "certsolve.solver", "solve")
    from ..expr.minibex import parse_minibex

    p = job.params
    system = parse_minibex(job.system)
    result = solve(
        system,
        eps=p.eps,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        workers=1,
        verify=p.verify,
        progress=ctx.progress,
    )
    return _plain(result)


def run_fk(job: FkJob, ctx: RunContext) -> Any:
    fk = library_function("fk", "certsolve.kinematics", "forward_kinematics")
    p = job.params
    result = fk(
        _robot(job.robot),
        list(p.u),
        eps=p.eps,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        tau_max=p.tau_max,
        formulation=p.formulation,
        seed_planar=p.seed_planar,
        seeded_only=p.seeded_only,
        progress=ctx.progress,
    )
    return _plain(result)


def run_ik(job: IkJob, ctx: RunContext) -> Any:
    ik = library_function("ik", "certsolve.kinematics", "inverse_kinematics")
    from ..robot.geometry import Pose

    robot = _robot(job.robot)
    pose = Pose.from_params(robot.dof, job.params.pose)
    return _plain(ik(robot, pose, method=job.params.method))


def run_isotropic_map(job: IsotropicMapJob, ctx: RunContext) -> Any:
    imap = library_function("isotropic-map", "certsolve.force", "isotropic_map")
    import numpy as np

    p = job.params
    xmin, xmax, ymin, ymax = p.grid
    xs = np.linspace(xmin, xmax, p.nx)
    ys = np.linspace(ymin, ymax, p.ny)
    robot = _robot(job.robot)
    return _plain(
        _call(imap, robot, xs, ys, z=p.z, rotation=_orientation(p.orientation), external=p.external)
    )


def run_workspace(job: WorkspaceJob, ctx: RunContext) -> Any:
    ws = library_function("workspace", "certsolve.force", "certified_workspace")
    p = job.params
    result = _call(
        ws,
        _robot(job.robot),
        p.min_force,
        [list(b) for b in p.box],
        p.eps,
        progress=ctx.progress,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        orientation=_orientation(p.orientation),
        eps_angle=p.eps_angle,
        external=p.external,
    )
    return _plain(result)


@dataclass
class _SleepProgress:
    boxes: int
    pending: int
    solutions: int
    undecided: int
    elapsed: float


def run_sleep(job: SleepJob, ctx: RunContext) -> Any:
    p = job.params
    ballast = bytearray(p.allocate_mb * 2**20) if p.allocate_mb else None
    if p.fail:
        raise ValueError(p.fail)
    t0 = time.monotonic()
    ticks = 0
    stopped = None
    while (elapsed := time.monotonic() - t0) < p.seconds:
        if p.crash and elapsed >= p.seconds / 2:
            os._exit(17)
        if not p.cooperative:  # like a library call that never checks its limits
            time.sleep(min(0.02, max(0.0, p.seconds - elapsed)))
            continue
        if elapsed >= ctx.time_limit:
            stopped = "timeout"
            break
        ticks += 1
        if ctx.progress(_SleepProgress(ticks, 0, 0, 0, elapsed)) is False:
            stopped = "cancelled"
            break
        time.sleep(min(0.02, max(0.0, p.seconds - elapsed)))
    del ballast
    return {"slept": time.monotonic() - t0, "ticks": ticks, "stopped_by": stopped}


# -- the registry -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Kind:
    name: str
    model: type[_Job]
    params: type[_Model]
    run: Callable[[Any, RunContext], Any]
    library: tuple[str, str]
    summary: str
    hidden: bool = False

    @property
    def has_timeout(self) -> bool:
        return "timeout" in self.params.model_fields

    @property
    def has_max_boxes(self) -> bool:
        return "max_boxes" in self.params.model_fields


KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind(
            "solve",
            SolveJob,
            SolveParams,
            run_solve,
            ("certsolve.solver", "solve"),
            "all solutions of a Minibex system, certified",
        ),
        Kind(
            "fk",
            FkJob,
            FkParams,
            run_fk,
            ("certsolve.kinematics", "forward_kinematics"),
            "forward kinematics: every pose for the actuator values u",
        ),
        Kind(
            "ik",
            IkJob,
            IkParams,
            run_ik,
            ("certsolve.kinematics", "inverse_kinematics"),
            "inverse kinematics: actuator values and tensions at a pose",
        ),
        Kind(
            "isotropic-map",
            IsotropicMapJob,
            IsotropicMapParams,
            run_isotropic_map,
            ("certsolve.force", "isotropic_map"),
            "isotropic force over a grid of positions",
        ),
        Kind(
            "workspace",
            WorkspaceJob,
            WorkspaceParams,
            run_workspace,
            ("certsolve.force", "certified_workspace"),
            "certified workspace where the isotropic force is at least min_force",
        ),
        Kind(
            "sleep",
            SleepJob,
            SleepParams,
            run_sleep,
            ("time", "sleep"),
            "test kind: sleep, report progress, optionally crash",
            hidden=True,
        ),
    )
}


def public_kinds(include_hidden: bool = False) -> list[str]:
    return [k.name for k in KINDS.values() if include_hidden or not k.hidden]


@functools.cache
def job_request_type(include_hidden: bool = False):
    """The request type: a union of the kinds' models, discriminated by ``kind``."""
    models = tuple(KINDS[name].model for name in public_kinds(include_hidden))
    return Annotated[Union[models], Field(discriminator="kind")]  # noqa: UP007


@functools.cache
def request_adapter(include_hidden: bool = False) -> TypeAdapter:
    """Validates a job request (dict or JSON) into the kind's model."""
    return TypeAdapter(job_request_type(include_hidden))


# -- the quick synchronous calls ----------------------------------------------------------------
def call_ik(req: IkCall) -> Any:
    return run_ik(IkJob(kind="ik", robot=req.robot, params=req.params), RunContext(0, 0))


def call_isotropic(req: IsotropicCall) -> Any:
    fn = library_function("isotropic", "certsolve.force", "isotropic_force")
    from ..robot.geometry import Pose

    robot = _robot(req.robot)
    p = req.params
    pose = Pose.from_params(robot.dof, p.pose)
    return _plain(_call(fn, robot, pose, algorithm=p.algorithm, external=p.external))


def call_track(req: TrackCall) -> Any:
    fn = library_function("fk/track", "certsolve.kinematics", "track")
    from ..robot.geometry import Pose

    robot = _robot(req.robot)
    p = req.params
    near = Pose.from_params(robot.dof, p.near_pose)
    return _plain(fn(robot, list(p.u), near, half_width=p.half_width))
