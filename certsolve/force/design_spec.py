"""The design specification (``certsolve design SPEC.json``): pydantic models and loading.

A spec is a JSON object::

    {"robot": "../robots/krut-3.json",            // a path (relative to the spec file) or
                                                  // an inline robot object
     "parameters": [                              // two or more design parameters
       {"name": "base_half_width", "path": "wires[*].base[0]", "mode": "half-width",
        "range": [60, 140]},
       {"name": "tau_max", "path": "wires[*].tau[1]", "range": [200, 800]}],
     "workspace": [-20, 20, -20, 20],             // xmin, xmax, ymin, ymax (+ zmin, zmax)
     "min_force": 150,                            // N
     "orientation": 0,                            // optional fixed platform angle(s), degrees
     "eps": 0.0625,                               // optional: parameter boxes stop at this
                                                  // fraction of each range
     "workspace_eps": 2.5}                        // optional: pose boxes stop at this width (cm)

Paths and modes are those of :mod:`certsolve.robot.params`.  Errors name the field
(``parameters[1].range: ...``) and are raised as :class:`DesignSpecError`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from ..robot.params import ParameterDef
from ..robot.schema import format_validation_error
from .certified import parse_box

__all__ = [
    "DesignOptions",
    "DesignSpec",
    "ParameterSpec",
    "DesignSpecError",
    "load_design_spec",
]

DEFAULT_EPS = 1.0 / 16
MAX_PARAMETERS = 6


class DesignSpecError(ValueError):
    """A design specification that cannot be used; the message names the field."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ParameterSpec(_Strict):
    name: str = Field(min_length=1, max_length=64, description="parameter name")
    path: str = Field(description="numbers of the robot file it sets: wires[W].FIELD[C]")
    mode: Literal["set", "half-width"] = Field(
        default="set", description="'set': the numbers equal the value; 'half-width': scaled"
    )
    range: tuple[float, float] = Field(description="[lo, hi]")
    centre: list[float] | None = Field(
        default=None, description="'half-width' only: centre of the scaling (default: mid-range)"
    )

    @field_validator("range")
    @classmethod
    def _range(cls, v):
        lo, hi = v
        if not (abs(lo) < 1e9 and abs(hi) < 1e9):
            raise ValueError("bounds must be finite")
        if not lo < hi:
            raise ValueError("need lo < hi")
        return v

    def definition(self) -> ParameterDef:
        return ParameterDef(
            name=self.name,
            path=self.path,
            mode=self.mode,
            range=(float(self.range[0]), float(self.range[1])),
            centre=None if self.centre is None else tuple(float(c) for c in self.centre),
        )


class DesignOptions(_Strict):
    """Everything of a design spec but its robot (the ``design`` job's params take these
    fields and validators, with the robot beside them)."""

    parameters: list[ParameterSpec] = Field(min_length=2, max_length=MAX_PARAMETERS)
    workspace: list[float] = Field(description="xmin, xmax, ymin, ymax[, zmin, zmax] (cm)")
    min_force: float = Field(gt=0, description="required isotropic force F (N)")
    orientation: float | list[float] | None = Field(
        default=None, description="fixed platform angle: theta (dof 3) or yaw, pitch, roll"
    )
    eps: float = Field(
        default=DEFAULT_EPS, gt=0, le=1, description="parameter boxes stop at this fraction"
    )
    workspace_eps: float | None = Field(
        default=None, gt=0, description="pose boxes stop at this width (cm)"
    )

    @field_validator("workspace")
    @classmethod
    def _workspace(cls, v):
        if len(v) not in (4, 6):
            raise ValueError("expected xmin, xmax, ymin, ymax (planar) or also zmin, zmax")
        try:
            parse_box(v, len(v) // 2)
        except ValueError as exc:
            raise ValueError(str(exc).removeprefix("box: ")) from None
        return v

    @field_validator("parameters")
    @classmethod
    def _names(cls, v):
        names = [p.name for p in v]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"duplicate parameter names: {', '.join(dup)}")
        return v

    def definitions(self) -> list[ParameterDef]:
        return [p.definition() for p in self.parameters]

    def spec(self, robot: str | dict) -> DesignSpec:
        """The design spec of these fields with ``robot`` (a path or a robot object): what
        :func:`~.design.design` takes.  Only the fields of :class:`DesignOptions` are
        taken (a subclass's others, such as a job's limits, are not the spec's)."""
        fields = self.model_dump(include=set(DesignOptions.model_fields), exclude_none=True)
        try:
            return DesignSpec.model_validate({**fields, "robot": robot})
        except ValidationError as exc:
            raise DesignSpecError(format_validation_error(exc).replace("\n", "; ")) from None


class DesignSpec(DesignOptions):
    robot: str | dict = Field(description="robot file path (relative to the spec) or object")


def load_design_spec(source: DesignSpec | str | Path | Mapping[str, Any]) -> DesignSpec:
    """From a path, JSON text, dict or :class:`DesignSpec`; a relative robot path is read
    relative to the spec file.  Raises :class:`DesignSpecError`."""
    if isinstance(source, DesignSpec):
        return source
    base = None
    if isinstance(source, (str, Path)) and not str(source).lstrip().startswith("{"):
        path = Path(source)
        try:
            text = path.read_text()
        except OSError as exc:
            raise DesignSpecError(f"{path}: cannot read design spec ({exc.strerror})") from None
        base = path.parent
        source = text
    if isinstance(source, str):
        try:
            data = json.loads(source)
        except json.JSONDecodeError as exc:
            raise DesignSpecError(f"invalid JSON at line {exc.lineno}: {exc.msg}") from None
    else:
        data = source
    try:
        spec = DesignSpec.model_validate(data)
    except ValidationError as exc:
        raise DesignSpecError(format_validation_error(exc).replace("\n", "; ")) from None
    robot = spec.robot
    if (
        base is not None
        and isinstance(robot, str)
        and not robot.lstrip().startswith("{")
        and not Path(robot).is_absolute()
    ):
        spec = spec.model_copy(update={"robot": str(base / robot)})
    return spec
