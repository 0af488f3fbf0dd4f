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
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

__all__ = [
    "WireSpec",
    "PlatformSpec",
    "DomainSpec",
    "RobotSpec",
    "RobotFileError",
    "format_validation_error",
    "load_robot_spec",
    "robot_json_schema",
    "MAX_WIRES",
]

MAX_WIRES = 32
_MAX_COORD = 1e6  # cm: anything larger is a unit mistake


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


def _finite_vector(v: list[float], what: str) -> list[float]:
    for x in v:
        if not (abs(x) <= _MAX_COORD):
            raise ValueError(f"{what} coordinates must be finite and within ±{_MAX_COORD:g} cm")
    return v


class WireSpec(_Strict):
    base: list[float] = Field(description="anchor A_i in the reference frame (cm)")
    platform: list[float] | None = Field(
        default=None, description="attachment B_i in the platform frame (cm); 0 if omitted"
    )
    k: float | None = Field(default=None, gt=0, description="wire material constant (N), eq. 1")
    K: float | None = Field(default=None, gt=0, description="pulley amplification, eq. 2")
    V: float | None = Field(default=None, ge=0, description="fixed length from A to F (cm)")
    L0: float | None = Field(default=None, gt=0, description="unloaded wire length (cm)")
    tau: tuple[float, float] = Field(description="[tau_min, tau_max] (N)")
    u: tuple[float, float] | None = Field(default=None, description="actuator stroke (cm)")

    @field_validator("base")
    @classmethod
    def _base(cls, v):
        return _finite_vector(v, "base")

    @field_validator("platform")
    @classmethod
    def _platform(cls, v):
        return v if v is None else _finite_vector(v, "platform")

    @field_validator("tau")
    @classmethod
    def _tau(cls, v):
        lo, hi = v
        if not (abs(lo) < 1e9 and abs(hi) < 1e9):
            raise ValueError("tensions must be finite")
        if lo > hi:
            raise ValueError("tau_min must be <= tau_max")
        return v

    @field_validator("u")
    @classmethod
    def _u(cls, v):
        if v is None:
            return v
        lo, hi = v
        if not (abs(lo) < _MAX_COORD and abs(hi) < _MAX_COORD):
            raise ValueError("stroke bounds must be finite")
        if lo > hi:
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
    center_of_mass: list[float] | None = Field(
        default=None, description="centre of mass in the platform frame (cm); origin if omitted"
    )


class DomainSpec(_Strict):
    points: list[tuple[float, float]] = Field(
        description="bounds of the world coordinates of every platform point, per axis (cm)"
    )

    @field_validator("points")
    @classmethod
    def _points(cls, v):
        for lo, hi in v:
            if not (abs(lo) <= _MAX_COORD and abs(hi) <= _MAX_COORD):
                raise ValueError(f"domain bounds must be finite and within ±{_MAX_COORD:g} cm")
            if lo > hi:
                raise ValueError("each domain interval must have lo <= hi")
        return v


class RobotSpec(_Strict):
    name: str = Field(default="robot", max_length=200)
    dof: Literal[2, 3, 6]
    gravity: list[float] | None = Field(default=None, description="gravity vector (m/s²)")
    platform: PlatformSpec = Field(default_factory=PlatformSpec)
    wires: list[WireSpec] = Field(min_length=1, max_length=MAX_WIRES)
    domain: DomainSpec | None = None

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
            elif any(not abs(g) < 1e4 for g in self.gravity):
                errors.append("gravity: components must be finite")
            elif self.dof != 6 and any(g != 0 for g in self.gravity):
                errors.append("gravity: planar robots (dof 2, 3) have no gravity in the plane")
        if self.domain is not None and len(self.domain.points) != d:
            errors.append(f"domain.points: expected {d} intervals, got {len(self.domain.points)}")
        if errors:
            raise ValueError("; ".join(errors))
        return self


class RobotFileError(ValueError):
    """A robot description that cannot be used; the message names the offending field."""


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


def load_robot_spec(source) -> RobotSpec:
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


def robot_json_schema() -> dict:
    """The JSON Schema of robot files (published by ``certsolve schema robot``)."""
    return RobotSpec.model_json_schema()
