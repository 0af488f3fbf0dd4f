"""What every job kind is made of: strict request models, the one check of parameters
against the robot, the run context, and the operation (:class:`Kind`) every front end calls.

An operation is a params model, a cheap ``check`` (:meth:`Params.check_robot`: the
preconditions that need the robot, no heavy building) and ``run(params, input, ctx)``,
which imports its library function with a normal import and calls it with exactly the
options it takes (``tests/test_jobs_kinds.py`` binds every call to the function's
signature: an option the function lacks is a test failure, never a silent drop).  The
worker, the quick calls, ``certsolve batch`` and the command line all call ``run``
(``certsolve solve`` makes ``run_solve``'s call itself, without importing the kinds, for
its start-up: ``tests/test_cli_solve_options.py`` compares the two calls).

Requests are pydantic models with ``extra="forbid"`` and no NaN / Infinity; every bound
the validation enforces on a single value (finite, range, length) is written as a
``Field`` constraint, so the published JSON Schema states it.  The params of a kind whose
library function checks its own options derive from that function's options model
(``FkParams(FkOptions, Params)``: :mod:`certsolve.robot.inputs`,
:mod:`certsolve.solver.options`), so Python refuses what a job refuses, with the same
message.  What needs the robot (``u`` has one value per wire, a pose has the robot's
length, no wire has zero length at an IK pose, the FK equations can be written for the
platform ...) is checked in one place (``check_wires`` and ``check_pose`` call the
library's own checks):
:meth:`Params.check_robot`, called by :class:`Request` for every job and quick call that
carries a robot -- and by the command line, which builds the same parameter models.  Its
errors name a params field (``u: ...``) or a robot field (``robot.wires: ...``).  A check
that costs milliseconds may keep its answers in ``memo``, a dict the caller passes as the
validation context ``{"memo": {}}`` (a batch of jobs on one robot checks it once).
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Annotated, Any, ClassVar, Self, TypeVar

from pydantic import Field, ValidationError, ValidationInfo, model_validator
from pydantic_core import InitErrorDetails

from ...inputs import MAX_COORD, MAX_FORCE, Coord, StrictModel, check_count
from ...robot.inputs import Wrench, as_pose, check_controls
from ...robot.schema import RobotSpec, array_length, robot_dof_schema

__all__ = [
    "ANGLES",
    "MAX_FORCE",
    "MAX_COORD",
    "POSE_LENGTH",
    "Angle",
    "Coord",
    "Job",
    "JobLimits",
    "Kind",
    "KindUnavailable",
    "Model",
    "Orientation",
    "Params",
    "QuickCall",
    "Request",
    "Required",
    "RunContext",
    "Wrench",
    "angles_schema",
    "check_angles",
    "check_count",
    "check_pose",
    "check_wire_lengths",
    "check_wires",
    "deferred",
    "load_function",
    "trusted",
    "orientation_arg",
    "require_elastic",
    "robot_model",
    "wrench_dim",
]

log = logging.getLogger("certsolve.jobs")

POSE_LENGTH = {2: 2, 3: 3, 6: 6}  # pose parameters by dof: x,y / x,y,theta / x,y,z,yaw,pitch,roll
ANGLES = {2: 0, 3: 1, 6: 3}  # orientation angles by dof

Angle = Annotated[float, Field(ge=-1e4, le=1e4)]  # degrees
Orientation = Annotated[
    Angle | list[Angle | tuple[Angle, Angle]] | None,
    Field(description="theta (dof 3) or [yaw, pitch, roll] (dof 6), degrees; [lo, hi] ranges"),
]


class KindUnavailable(Exception):
    """The library function behind a kind is missing from this build (its import fails)."""


class Model(StrictModel):
    """A strict request model: unknown fields and non-finite numbers are refused."""


@dataclass(frozen=True)
class Required:
    """A params shape (:meth:`Params.dof_shapes`): this schema, and the field required."""

    schema: dict


class Params(Model):
    """The ``params`` of a kind or quick call.

    For the published JSON Schema, a kind that carries a robot states the shapes that
    depend on the robot's dof (:meth:`dof_shapes`) and what it needs of the robot
    (:meth:`robot_schema`); its request schema is then one variant per dof
    (:meth:`Request.__get_pydantic_json_schema__`).
    """

    @classmethod
    def dof_shapes(cls, dof: int) -> dict[str, Any] | None:
        """The fields whose shape depends on the robot's ``dof``: an exact number of items,
        ``None`` (the field must be absent) or a replacement JSON Schema; ``None`` for a
        dof this kind does not take."""
        return {}

    @classmethod
    def robot_schema(cls, dof: int) -> dict:
        """The JSON Schema of the robots this kind takes of one ``dof``."""
        return robot_dof_schema(dof)

    @classmethod
    def schema_variants(cls, dof: int) -> list[tuple[dict, dict[str, Any]]]:
        """``(robot schema, params shapes)`` of each variant of the request schema for
        one ``dof`` (default: :meth:`robot_schema` and :meth:`dof_shapes`, one variant;
        a kind whose rules differ by some params value has one variant per value)."""
        shapes = cls.dof_shapes(dof)
        return [] if shapes is None else [(cls.robot_schema(dof), shapes)]

    def check_robot(self, robot: RobotSpec, memo: dict | None = None) -> None:
        """Checks that need the robot; raise ``ValueError("field: message")`` for a field
        of the params, ``ValueError("robot.field: message")`` for one of the robot."""


class Request(Model):
    """A job or quick call; when it has a ``robot``, its ``params`` are checked against it.

    The one validator of parameters against the robot (``params.u: expected 4 values ...``).
    A request validated before (the worker reading the stored request the service
    validated) is read with the context ``{"trusted": True}``: its fields are parsed, the
    checks against the robot are not run again.  A :func:`deferred` model parses without
    them; its caller runs them with :meth:`checked` (the HTTP service, off its event loop).
    Its JSON Schema is one variant per dof the kind takes, each with the robot schema of
    that dof and the params shapes for it (:meth:`Params.dof_shapes`).
    """

    @classmethod
    def __get_pydantic_json_schema__(cls, core_schema, handler):
        ref = handler(core_schema)
        params = cls.model_fields.get("params")
        kind = params.annotation if params is not None else None
        if "robot" not in cls.model_fields or not (
            isinstance(kind, type) and issubclass(kind, Params)
        ):
            return ref
        target = handler.resolve_ref_schema(ref)
        base = copy.deepcopy(target)
        params_schema = handler.resolve_ref_schema(base["properties"]["params"])
        variants = []
        for dof in (2, 3, 6):
            for robot, shapes in kind.schema_variants(dof):
                p = copy.deepcopy(params_schema)
                for name, shape in shapes.items():
                    if shape is None:
                        p["properties"].pop(name, None)
                        p["required"] = [r for r in p.get("required", []) if r != name]
                    elif isinstance(shape, int):
                        p["properties"][name] = array_length(p["properties"][name], shape)
                    elif isinstance(shape, Required):
                        p["properties"][name] = shape.schema
                        p["required"] = sorted({*p.get("required", []), name})
                    else:
                        p["properties"][name] = shape
                v = copy.deepcopy(base)
                v["title"] = f"{base.get('title', cls.__name__)} (dof {dof})"
                v["properties"]["robot"] = robot
                v["properties"]["params"] = p
                variants.append(v)
        target.clear()
        target.update({"title": base.get("title", cls.__name__), "oneOf": variants})
        return ref

    #: run the checks against the robot while validating (False: :func:`deferred`)
    checks_robot: ClassVar[bool] = True

    @model_validator(mode="after")
    def _fits_robot(self, info: ValidationInfo):
        if type(self).checks_robot and not trusted(info):
            memo = info.context.get("memo") if isinstance(info.context, dict) else None
            self.check(memo)
        return self

    def check(self, memo: dict | None = None) -> None:
        """The checks against the robot (:meth:`Params.check_robot`); ``ValueError``
        naming ``params.<field>`` or ``robot.<field>``."""
        robot = getattr(self, "robot", None)
        params = getattr(self, "params", None)
        if isinstance(robot, RobotSpec) and isinstance(params, Params):
            try:
                params.check_robot(robot, memo)
            except ValueError as exc:
                msg = str(exc)
                raise ValueError(msg if msg.startswith("robot.") else f"params.{msg}") from None

    def checked(self, memo: dict | None = None) -> Self:
        """This request, once :meth:`check` passed, as an instance of the checked model
        (a :func:`deferred` one's parent: what pickles, for the quick-call processes);
        a refusal is pydantic's ``ValidationError``, as if validating had raised it."""
        try:
            self.check(memo)
        except ValueError as exc:
            line = InitErrorDetails(type="value_error", loc=(), input=None, ctx={"error": exc})
            raise ValidationError.from_exception_data(type(self).__name__, [line]) from None
        if type(self).checks_robot:
            return self
        model: type[Self] = type(self).__mro__[1]  # deferred(model): its one base
        values = {name: getattr(self, name) for name in type(self).model_fields}
        return model.model_construct(self.model_fields_set, **values)


R = TypeVar("R", bound=Request)


def deferred(model: type[R]) -> type[R]:
    """``model`` without the checks against the robot while validating: a subclass of the
    same name and JSON Schema whose instances are checked by :meth:`Request.checked`."""
    namespace = {
        "__module__": model.__module__,
        "__qualname__": model.__qualname__,
        "__doc__": model.__doc__,
        "checks_robot": False,
    }
    return type(model.__name__, (model,), namespace)


def trusted(info: ValidationInfo) -> bool:
    """The validation context says the data was validated before (``{"trusted": True}``)."""
    return isinstance(info.context, dict) and bool(info.context.get("trusted"))


class JobLimits(Model):
    """Per-job resource limits; unset ones take the service defaults, within its ceilings."""

    timeout: float | None = Field(default=None, gt=0, description="wall-time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1, description="limit on processed boxes")
    memory_mb: int | None = Field(default=None, ge=1, description="address-space limit (MiB)")


class Job(Request):
    """A job request: ``kind``, its input, ``params`` and optional ``limits``."""

    limits: JobLimits | None = Field(default=None, description="resource limits of this job")


# -- checks against the robot ---------------------------------------------------------------------
def check_wires(robot: RobotSpec, u: Sequence[float], name: str) -> None:
    """One value per wire (the library's own check, :func:`~certsolve.robot.inputs.
    check_controls`)."""
    check_controls(len(robot.wires), u, name)


def check_pose(robot: RobotSpec, values: Sequence[float], name: str) -> None:
    """A pose of the robot's dof (the library's own check, :func:`~certsolve.robot.inputs.
    as_pose`)."""
    as_pose(robot.dof, values, name)


def check_wire_lengths(robot: RobotSpec, pose: Sequence[float], name: str) -> None:
    """No wire has zero length at ``pose`` (an attachment on its anchor: the wire has no
    direction, the IK equations are undefined)."""
    from ...robot.geometry import Pose, wire_geometry

    p = Pose.from_params(robot.dof, pose)
    model = robot_model(robot)
    rho = wire_geometry(model, p.position[None], p.rotation[None])[0][0]
    scale = 1.0 + float(abs(model.A).max(initial=0.0))
    for i, r in enumerate(rho.tolist()):
        if not r > 1e-12 * scale:
            raise ValueError(
                f"{name}: wire {i + 1} has zero length at this pose (its attachment "
                "coincides with its anchor)"
            )


def require_elastic(robot: RobotSpec, what: str, hint: str = "") -> None:
    """Every wire has the elastic model ``what`` needs (``robot.wires[i].k: ...``)."""
    from ...robot.schema import RobotFileError

    try:
        robot_model(robot).require_elastic(what)
    except RobotFileError as exc:
        raise ValueError(f"robot.{exc}: the robot has no elastic wire model{hint}") from None


def wrench_dim(robot: RobotSpec) -> int:
    """Components of a wrench: 6 (dof 6), 3 (dof 3), 2 (dof 2)."""
    return robot.dof


def check_angles(robot: RobotSpec, value: Any, name: str, *, ranges: bool) -> None:
    """An orientation fits the robot: nothing for dof 2, ``theta`` (or ``[theta]``) for
    dof 3, ``[yaw, pitch, roll]`` for dof 6; ``[lo, hi]`` ranges only where ``ranges``."""
    n = ANGLES[robot.dof]
    if value is None:
        return
    if n == 0:
        raise ValueError(f"{name}: a point platform (dof 2) has no orientation")
    items = [value] if not isinstance(value, list) else value
    if n == 1 and ranges and len(items) == 2 and all(not isinstance(a, tuple) for a in items):
        items = [tuple(items)]  # [lo, hi]: one range of theta
    if len(items) != n:
        raise ValueError(f"{name}: expected {n} angle(s) in degrees, got {len(items)}")
    if not ranges and any(isinstance(a, tuple) for a in items):
        raise ValueError(f"{name}: fixed angles here, not [lo, hi] ranges")


def angles_schema(dof: int, *, ranges: bool) -> dict | None:
    """The JSON Schema of the orientation :func:`check_angles` accepts (None: absent)."""
    n = ANGLES[dof]
    if n == 0:
        return None
    angle = {"type": "number", "minimum": -1e4, "maximum": 1e4}
    item: dict = angle
    if ranges:
        pair = {"type": "array", "prefixItems": [angle, angle], "minItems": 2, "maxItems": 2}
        item = {"anyOf": [angle, pair]}
    listed = {"type": "array", "items": item, "minItems": n, "maxItems": n}
    options = [listed, {"type": "null"}] + ([angle] if n == 1 else [])
    if n == 1 and ranges:
        options.append(pair)
    return {"anyOf": options, "default": None, "description": "degrees"}


# -- running --------------------------------------------------------------------------------------
@dataclass(kw_only=True)
class RunContext:
    """What an operation's ``run`` gets besides its params and input: the limits, the
    progress callback, the search's checkpoint, and what only the command line sets (an
    executor, a cancel event).

    ``progress(p)`` takes the library's progress object (``boxes``, ``pending``,
    ``solutions``, ``undecided``, ``elapsed``) and returns False when the job must stop
    (cancelled, or over its box limit).  ``time_limit`` / ``max_boxes``: None is no limit.
    """

    time_limit: float | None = None
    max_boxes: int | None = None
    progress: Callable[[Any], bool | None] | None = field(default=lambda p: True)
    #: where the search saves itself and resumes from (a
    #: :class:`~certsolve.solver.checkpoint.Checkpoint`; None: not saved)
    checkpoint: Any = None
    #: the search's executor (:func:`~certsolve.solver.executors.resolve_executor`'s
    #: spec; None: this process, as a job's worker runs)
    executor: Any = None
    #: a cancel event the search polls (the command line's Ctrl-C); None: none
    cancel: Any = None
    #: re-prove the solutions in mpmath, for a search whose params have no ``verify``
    #: (the command line's ``fk --verify``)
    verify: bool = False


def orientation_arg(value: Any) -> Any:
    """A validated ``orientation`` as the force library takes it (ranges as tuples)."""
    if isinstance(value, list):
        return [tuple(v) if isinstance(v, tuple) else v for v in value]
    return value


def robot_model(spec: RobotSpec):
    from ...robot.model import Robot

    return Robot.from_spec(spec)


# -- the registry entry ---------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Kind:
    """A job kind, as an operation: its request model, params model, ``run`` and the
    library function ``run`` calls.

    ``run(params, input, ctx)`` calls the library (``input``: the request's robot spec,
    its system text, or None) and returns the library's result object (the worker bounds
    and stores it, :mod:`..partial`).  ``function()`` imports that library function (for
    ``GET /v1/kinds`` and the quick-call processes, which load it before the first call,
    and for the test that binds ``run``'s call to its signature)."""

    name: str
    model: type[Job]
    params: type[Params]
    run: Callable[[Any, Any, RunContext], Any]
    function: Callable[[], Callable]
    summary: str
    hidden: bool = False

    @property
    def input(self) -> str:
        """``system`` or ``robot``: what the request carries besides its params."""
        return "system" if "system" in self.model.model_fields else "robot"

    @property
    def has_timeout(self) -> bool:
        return "timeout" in self.params.model_fields

    @property
    def has_max_boxes(self) -> bool:
        return "max_boxes" in self.params.model_fields

    def input_of(self, request: Any) -> Any:
        """What ``run`` takes as its input from a validated request."""
        return getattr(request, self.input, None)

    def load(self) -> Callable:
        """The library function, or :class:`KindUnavailable` when this build lacks it."""
        return load_function(self.name, self.function)


def load_function(name: str, function: Callable[[], Callable]) -> Callable:
    """``function()`` (an import), or :class:`KindUnavailable` naming ``name``."""
    try:
        return function()
    except Exception as exc:  # ImportError, or a module that does not load
        if not isinstance(exc, ImportError):
            log.warning("loading %s failed: %s: %s", name, type(exc).__name__, exc)
        raise KindUnavailable(f"kind {name} is not available in this build") from None


@dataclass(frozen=True, kw_only=True)
class QuickCall:
    """A quick synchronous call (``POST /v1/<name>``): its request model, the operation
    answering it (``run(params, robot)`` -> the library's result; ``function()`` imports
    its library function), and ``cost(request)``, an estimate of its
    seconds on one core from the request's size alone (wires, dof, method), by which
    :mod:`..quick` puts it in the light or the heavy lane, or refuses it (submit ``job``
    instead)."""

    name: str
    model: type[Request]
    run: Callable[[Any, Any], Any]
    function: Callable[[], Callable]  # loaded when a quick-call process starts
    cost: Callable[[Any], float]
    job: str  # the job that computes the same (for the refusal message)
    cost_field: str = "robot.wires"  # what the cost grows with (where a refusal points)

    def load(self) -> Callable:
        """The library function, or :class:`KindUnavailable`."""
        return load_function(self.name, self.function)
