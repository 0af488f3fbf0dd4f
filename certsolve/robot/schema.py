"""The robot file format: pydantic models, validation errors that name the field.

Units: lengths in cm, forces in N, mass in kg, gravity in m/s² (weight = mass × gravity, in
N), so moments are in N·cm.  ``base`` is the anchor A_i in the reference frame, ``platform``
the attachment B_i in the platform frame; ``k`` (N) the wire material constant of Hooke's
law (Merlet eq. 1), ``K`` the pulley amplification, ``V`` (cm) the fixed length between A_i
and the wire's fixed end F, ``L0`` (cm) the unloaded length, ``tau = [tau_min, tau_max]`` the
allowed tension (N), ``u`` the actuator stroke (cm).

``dof`` is 6 (spatial rigid platform, 3-D vectors), 3 (planar rigid platform, 2-D vectors,
no gravity in the plane) or 2 (planar point: every wire is attached to the same point, as
the robots of Krut et al. 2004; elastic fields optional).

Every bound the validation enforces on a single number is a ``Field`` constraint (finite,
coordinates within ±1e6 cm, tensions within ±1e9 N), and the published JSON Schema is one
variant per ``dof`` (:func:`robot_json_schema`) stating the vector lengths and the dof-2 /
planar rules too.  What JSON Schema cannot state is checked by validators: ``lo <= hi`` of
the ``tau``, ``u`` and domain intervals, and ``tau_max < k``.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    GetJsonSchemaHandler,
    TypeAdapter,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic.json_schema import JsonSchemaValue
from pydantic_core import CoreSchema

from . import tolerance

__all__ = [
    "WireSpec",
    "PlatformSpec",
    "DomainSpec",
    "ToleranceSpec",
    "RobotSpec",
    "RobotFileError",
    "RobotSource",
    "format_validation_error",
    "load_robot_spec",
    "array_length",
    "robot_dof_schema",
    "robot_json_schema",
    "MAX_WIRES",
]

MAX_WIRES = 32
_MAX_COORD = 1e6  # cm: anything larger is a unit mistake
_MAX_TENSION = 1e9  # N
_MAX_CONSTANT = 1e12  # k, K, V, L0
_MIN_CONSTANT = 1e-9  # k, K, L0: smaller is a unit mistake (and overflows eqs. 1-2's controls)
#: the shape of a tolerance's path (:mod:`.paths`; which indices exist is the robot's)
_TOLERANCE_PATH = (
    r"^wires\[[^\]]+\]\.((base|platform)\[[^\]]+\]|k|K|V|L0)$"
    r"|^platform\.(mass|center_of_mass\[[^\]]+\])$"
)

Coordinate = Annotated[float, Field(ge=-_MAX_COORD, le=_MAX_COORD)]
Tension = Annotated[float, Field(gt=-_MAX_TENSION, lt=_MAX_TENSION)]
Vector = Annotated[list[Coordinate], Field(min_length=2, max_length=3)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)


class WireSpec(_Strict):
    base: Vector = Field(description="anchor A_i in the reference frame (cm)")
    platform: Vector | None = Field(
        default=None, description="attachment B_i in the platform frame (cm); 0 if omitted"
    )
    k: float | None = Field(
        default=None,
        ge=_MIN_CONSTANT,
        le=_MAX_CONSTANT,
        description="wire material constant (N), eq. 1",
    )
    K: float | None = Field(
        default=None, ge=_MIN_CONSTANT, le=_MAX_CONSTANT, description="pulley amplification, eq. 2"
    )
    V: float | None = Field(
        default=None, ge=0, le=_MAX_CONSTANT, description="fixed length from A to F (cm)"
    )
    L0: float | None = Field(
        default=None, ge=_MIN_CONSTANT, le=_MAX_CONSTANT, description="unloaded wire length (cm)"
    )
    tau: tuple[Tension, Tension] = Field(description="[tau_min, tau_max] (N)")
    u: tuple[Coordinate, Coordinate] | None = Field(
        default=None, description="actuator stroke [u_min, u_max] (cm)"
    )

    @field_validator("tau")
    @classmethod
    def _tau(cls, v):
        if v[0] > v[1]:
            raise ValueError("tau_min must be <= tau_max")
        return v

    @field_validator("u")
    @classmethod
    def _u(cls, v):
        if v is not None and v[0] > v[1]:
            raise ValueError("u_min must be <= u_max")
        return v

    @model_validator(mode="after")
    def _elastic(self):
        if self.k is not None and self.tau[1] >= self.k:
            raise ValueError("tau_max must be < k (eq. 5 divides by k - tau)")
        return self

    @property
    def elastic(self) -> bool:
        return None not in (self.k, self.K, self.V, self.L0, self.u)


class PlatformSpec(_Strict):
    mass: float = Field(default=0.0, ge=0, le=1e6, description="platform mass (kg)")
    center_of_mass: Vector | None = Field(
        default=None, description="centre of mass in the platform frame (cm); origin if omitted"
    )


class DomainSpec(_Strict):
    points: list[tuple[Coordinate, Coordinate]] = Field(
        min_length=2,
        max_length=3,
        description="bounds of the world coordinates of every platform point, per axis (cm)",
    )

    @field_validator("points")
    @classmethod
    def _points(cls, v):
        for lo, hi in v:
            if lo > hi:
                raise ValueError("each domain interval must have lo <= hi")
        return v


class ToleranceSpec(_Strict):
    """How well some numbers of the file are known (:mod:`.tolerance`): every number the
    ``path`` selects lies in ``[x - plus_minus, x + plus_minus]`` or in
    ``[x - relative |x|, x + relative |x|]`` (exactly one of the two)."""

    path: str = Field(max_length=200, description="numbers it applies to: wires[W].base[C] ...")
    plus_minus: float | None = Field(
        default=None, ge=0, le=_MAX_COORD, description="absolute half-width (the field's unit)"
    )
    relative: float | None = Field(
        default=None, ge=0, lt=1, description="half-width as a fraction of the value"
    )

    @model_validator(mode="after")
    def _one(self):
        if (self.plus_minus is None) == (self.relative is None):
            raise ValueError("give exactly one of plus_minus and relative")
        return self


class RobotSpec(_Strict):
    name: str = Field(default="robot", max_length=200)
    dof: Literal[2, 3, 6]
    gravity: list[Annotated[float, Field(gt=-1e4, lt=1e4)]] | None = Field(
        default=None, min_length=2, max_length=3, description="gravity vector (m/s²)"
    )
    platform: PlatformSpec = Field(default_factory=PlatformSpec)
    wires: list[WireSpec] = Field(min_length=1, max_length=MAX_WIRES)
    domain: DomainSpec | None = None
    tolerances: list[ToleranceSpec] = Field(
        default_factory=list,
        max_length=64,
        description="numbers known only within intervals (docs/tolerances.md)",
    )

    @classmethod
    def __get_pydantic_json_schema__(
        cls, core_schema: CoreSchema, handler: GetJsonSchemaHandler
    ) -> JsonSchemaValue:
        ref = handler(core_schema)  # the schema is one variant per dof
        target = handler.resolve_ref_schema(ref)
        target.clear()
        target.update(robot_json_schema())
        return ref

    @property
    def dim(self) -> int:
        """Dimension of the vectors: 3 for dof 6, 2 for planar robots."""
        return 3 if self.dof == 6 else 2

    @model_validator(mode="after")
    def _dimensions(self):
        d = self.dim
        errors = []
        for i, w in enumerate(self.wires):
            if len(w.base) != d:
                errors.append(f"wires[{i}].base: expected {d} coordinates, got {len(w.base)}")
            if w.platform is not None and len(w.platform) != d:
                errors.append(
                    f"wires[{i}].platform: expected {d} coordinates, got {len(w.platform)}"
                )
            if self.dof == 2 and w.platform is not None and any(x != 0 for x in w.platform):
                errors.append(f"wires[{i}].platform: a point platform (dof 2) has B_i = 0")
        com = self.platform.center_of_mass
        if com is not None and len(com) != d:
            errors.append(f"platform.center_of_mass: expected {d} coordinates, got {len(com)}")
        if self.gravity is not None:
            if len(self.gravity) != d:
                errors.append(f"gravity: expected {d} components, got {len(self.gravity)}")
            elif self.dof != 6 and any(g != 0 for g in self.gravity):
                errors.append("gravity: planar robots (dof 2, 3) have no gravity in the plane")
        if self.domain is not None and len(self.domain.points) != d:
            errors.append(f"domain.points: expected {d} intervals, got {len(self.domain.points)}")
        if errors:
            raise ValueError("; ".join(errors))
        return self

    @model_validator(mode="after")
    def _tolerances(self):
        if self.tolerances:
            self.tolerance_intervals()
        return self

    def number(self, field: str, entry: tuple[int, ...]) -> float | None:
        """The file's number at a path entry (:mod:`.paths`); None where not given (a
        missing ``platform`` or centre of mass is 0)."""
        if field == "mass":
            return self.platform.mass
        if field == "center_of_mass":
            com = self.platform.center_of_mass
            return 0.0 if com is None else com[entry[0]]
        wire = self.wires[entry[0]]
        v = getattr(wire, field)
        if field == "platform" and v is None:
            return 0.0
        return v if len(entry) == 1 or v is None else v[entry[1]]

    def tolerance_intervals(self) -> dict[tolerance.Entry, tuple[float, float]]:
        """``{(field, entry): (lo, hi)}`` for every toleranced number (checked:
        :func:`.tolerance.check`)."""
        return tolerance.check(
            self.tolerances, len(self.wires), self.dof, self.number, [w.tau[1] for w in self.wires]
        )


class RobotFileError(ValueError):
    """A robot description that cannot be used; the message names the offending field.

    Where the caller knows it, ``field`` is that field's dotted path among the call's
    arguments (``robot.wires.2.k``) and ``reason`` what is wrong with it (``required for
    ...``), as :class:`~certsolve.inputs.InputError` says them; else both are ``""``."""

    def __init__(self, message: str, *, field: str = "", reason: str = ""):
        super().__init__(message)
        self.field = field
        self.reason = reason


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def format_validation_error(err: ValidationError) -> str:
    """``wires[3].tau: tau_min must be <= tau_max`` style messages, one per line."""
    lines = []
    for e in err.errors():
        loc = _loc(tuple(p for p in e["loc"] if p not in ("function-after",)))
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, ") :]
        # model-level errors already carry their own field names
        lines.append(f"{loc}: {msg}" if loc else msg)
    return "\n".join(lines)


RobotSource = RobotSpec | str | Path | dict[str, Any]
"""What :func:`load_robot_spec` reads: a spec, a path, JSON text or a dict."""


def load_robot_spec(source: RobotSource) -> RobotSpec:
    """Validate a robot from a path, a JSON string or a dict; raise :class:`RobotFileError`."""
    if isinstance(source, RobotSpec):
        return source
    if isinstance(source, (str, Path)) and not str(source).lstrip().startswith("{"):
        path = Path(source)
        try:
            text = path.read_text()
        except OSError as exc:
            raise RobotFileError(f"{path}: cannot read robot file ({exc.strerror})") from None
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise RobotFileError(f"{path}: invalid JSON at line {exc.lineno}: {exc.msg}") from None
    elif isinstance(source, str):
        try:
            data = json.loads(source)
        except json.JSONDecodeError as exc:
            raise RobotFileError(f"invalid JSON at line {exc.lineno}: {exc.msg}") from None
    else:
        data = source
    try:
        return RobotSpec.model_validate(data)
    except ValidationError as exc:
        raise RobotFileError(format_validation_error(exc)) from None


def array_length(prop: dict, n: int) -> dict:
    """A copy of ``prop`` (an array schema, or an ``anyOf`` with one) with exactly ``n``
    items."""
    prop = copy.deepcopy(prop)
    for branch in prop.get("anyOf", [prop]):
        if branch.get("type") == "array":
            branch["minItems"] = branch["maxItems"] = n
    return prop


def _zeros(prop: dict, n: int) -> dict:
    """``prop`` allowing only ``null`` or ``n`` zeros (a point platform, planar gravity)."""
    zeros = {"type": "array", "items": {"const": 0}, "minItems": n, "maxItems": n}
    return {k: v for k, v in prop.items() if k != "anyOf"} | {"anyOf": [zeros, {"type": "null"}]}


def _field_schema(model: type[BaseModel], name: str) -> dict:
    """The JSON Schema of one field of ``model`` (its type and constraints)."""
    info = model.model_fields[name]
    return TypeAdapter(Annotated[info.annotation, info]).json_schema()  # type: ignore[arg-type]


def robot_dof_schema(
    dof: int, *, elastic: bool = False, wires: int | None = None, min_wires: int = 1
) -> dict:
    """The JSON Schema of a robot of one ``dof`` (self-contained, no ``$ref``): vectors of
    its dimension, no attachment coordinates for dof 2, no gravity in the plane.  With
    ``elastic``, every wire has ``k, K, V, L0, u``; with ``wires``, exactly that many;
    at least ``min_wires``."""
    d = 3 if dof == 6 else 2
    wire = WireSpec.model_json_schema()
    props = wire["properties"]
    props["base"] = array_length(props["base"], d)
    props["platform"] = (
        _zeros(props["platform"], d) if dof == 2 else array_length(props["platform"], d)
    )
    if elastic:
        wire["required"] = sorted({*wire.get("required", []), "k", "K", "V", "L0", "u"})
        for name in ("k", "K", "V", "L0", "u"):
            props[name] = next(b for b in props[name]["anyOf"] if b.get("type") != "null")
    platform = PlatformSpec.model_json_schema()
    com = platform["properties"]["center_of_mass"]
    platform["properties"]["center_of_mass"] = array_length(com, d)
    domain = DomainSpec.model_json_schema()
    domain["properties"]["points"] = array_length(domain["properties"]["points"], d)
    gravity = _field_schema(RobotSpec, "gravity")
    wire_list = _field_schema(RobotSpec, "wires") | {"items": wire}
    wire_list.pop("$defs", None)
    tolerance = ToleranceSpec.model_json_schema()
    tolerance["oneOf"] = [  # exactly one of the two half-widths
        {"required": [a], "properties": {a: {"type": "number"}, b: {"type": "null"}}}
        for a, b in (("plus_minus", "relative"), ("relative", "plus_minus"))
    ]
    tolerance["properties"]["path"]["pattern"] = _TOLERANCE_PATH
    tolerances = _field_schema(RobotSpec, "tolerances") | {"items": tolerance}
    tolerances.pop("$defs", None)
    wire_list["minItems"] = max(wire_list.get("minItems", 1), min_wires)
    if wires is not None:
        wire_list["minItems"] = wire_list["maxItems"] = wires
    return {
        "title": f"RobotSpec (dof {dof})",
        "type": "object",
        "additionalProperties": False,
        "required": ["dof", "wires"],
        "properties": {
            "name": _field_schema(RobotSpec, "name"),
            "dof": {"const": dof, "type": "integer", "description": "degrees of freedom"},
            "gravity": array_length(gravity, d) if dof == 6 else _zeros(gravity, d),
            "platform": platform,
            "wires": wire_list,
            "domain": {"anyOf": [domain, {"type": "null"}], "default": None},
            "tolerances": tolerances,
        },
    }


def robot_json_schema() -> dict:
    """The JSON Schema of robot files (published by ``certsolve schema robot``): one
    variant per ``dof`` (:func:`robot_dof_schema`)."""
    return {
        "title": "RobotSpec",
        "description": "a robot file: wires, platform, domain (certsolve.robot.schema)",
        "oneOf": [robot_dof_schema(dof) for dof in (2, 3, 6)],
    }
