"""The maximum isotropic force over a grid of positions (the paper's Fig. 9 and 10).

The grid is ``xs × ys`` (plus a fixed ``z`` for dof 6) at one fixed orientation; every pose
is evaluated by :func:`~.isotropic.isotropic_values`, vectorised over all poses of the grid
(chunks of a few thousand poses, no Python loop per pose).  ``values[j, i]`` is the index at
``(xs[i], ys[j])``: rows follow ``y`` as in an image.  Negative values are poses outside
the wrench-feasible workspace (drawn white by :func:`~.plots.plot_map`), NaN marks
degenerate poses (flat polytope, or a platform point on an anchor).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..robot import Robot
from ..robot.geometry import rotation_2d, rotation_zyx
from .isotropic import DEGENERATE, INSIDE, OUTSIDE, isotropic_values, set_force_floor

__all__ = ["IsotropicMap", "isotropic_map", "resolve_rotation"]


def resolve_rotation(
    robot: Robot, rotation: ArrayLike | None
) -> tuple[np.ndarray, list[float] | None]:
    """A ``(d, d)`` matrix from ``None`` (identity), a matrix, or angles in degrees.

    Angles: dof 3 one ``θ``; dof 6 ``(yaw, pitch, roll)`` (Z-Y-X, as
    :func:`certsolve.robot.geometry.rotation_zyx`).
    """
    d = robot.dim
    if rotation is None:
        return np.eye(d), ([0.0] if robot.dof == 3 else [0.0] * 3 if robot.dof == 6 else None)
    r = np.asarray(rotation, dtype=float)
    if r.shape == (d, d):
        if not np.all(np.isfinite(r)):
            raise ValueError("rotation: entries must be finite")
        return r, None
    if robot.dof == 2:
        raise ValueError("rotation: a point platform (dof 2) has no orientation")
    ang = r.reshape(-1)
    n = 1 if robot.dof == 3 else 3
    if ang.size != n or not np.all(np.isfinite(ang)):
        raise ValueError(
            f"rotation: expected a {d}x{d} matrix or {n} angle(s) in degrees "
            + ("(theta)" if n == 1 else "(yaw, pitch, roll)")
        )
    rad = np.radians(ang)
    R = rotation_2d(rad[0]) if robot.dof == 3 else rotation_zyx(*rad)
    return R, [float(a) for a in ang]


@dataclass
class IsotropicMap:
    robot: str
    dof: int
    xs: np.ndarray  # (nx,)
    ys: np.ndarray  # (ny,)
    z: float | None
    rotation: np.ndarray
    angles: list[float] | None
    values: np.ndarray  # (ny, nx) N; NaN where degenerate
    status: np.ndarray  # (ny, nx) int8: 0 inside, 1 outside, 2 degenerate
    anchors: np.ndarray  # (m, d) base anchors
    time: float
    #: a robot with tolerances: certified lower bounds over the set (N; NaN: not proven >= 0)
    set_force_lo: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def poses(self) -> int:
        return int(self.values.size)

    def summary(self) -> dict:
        v = self.values
        ok = self.status == INSIDE
        out: dict[str, Any] = {
            "poses": self.poses,
            "inside": int(ok.sum()),
            "outside": int((self.status == 1).sum()),
            "degenerate": int((self.status == DEGENERATE).sum()),
            "max": None,
            "argmax": None,
            "time": self.time,
            "poses_per_second": self.poses / self.time if self.time > 0 else None,
        }
        if ok.any():
            j, i = np.unravel_index(np.nanargmax(np.where(ok, v, -np.inf)), v.shape)
            out["max"] = float(v[j, i])
            out["argmax"] = [float(self.xs[i]), float(self.ys[j])]
        if len(self.xs) > 1 and len(self.ys) > 1:
            cell = abs(self.xs[1] - self.xs[0]) * abs(self.ys[1] - self.ys[0])
            out["inside_area_estimate"] = float(ok.sum() * cell)
        if self.set_force_lo is not None:
            lo = self.set_force_lo
            out["set_inside"] = int(np.sum(lo > 0))
            out["set_max"] = float(np.nanmax(lo)) if np.any(np.isfinite(lo)) else None
        return out

    def to_dict(self, values: bool = True) -> dict:
        out = {
            "robot": self.robot,
            "dof": self.dof,
            "xs": [float(x) for x in self.xs],
            "ys": [float(y) for y in self.ys],
            "z": self.z,
            "rotation": self.rotation.tolist(),
            "angles": self.angles,
            "units": {"force": "N", "length": "cm", "angle": "deg"},
            "summary": self.summary(),
        }
        if values:
            out["isotropic_force"] = _rows(self.values)
            if self.set_force_lo is not None:
                out["set_force_lo"] = _rows(self.set_force_lo)
        if self.notes:
            out["notes"] = list(self.notes)
        return out

    @classmethod
    def from_dict(cls, data: dict, anchors: ArrayLike) -> IsotropicMap:
        """The map back from :meth:`to_dict` (with its values) and the robot's anchors.

        ``status`` is read off the values as :func:`~.isotropic.isotropic_values` sets it:
        ``null`` degenerate, negative outside, otherwise inside.
        """
        if data.get("isotropic_force") is None:
            raise ValueError("the map was saved without its values")
        values = np.array(
            [[np.nan if v is None else float(v) for v in row] for row in data["isotropic_force"]]
        ).reshape(len(data["ys"]), len(data["xs"]))
        status = np.where(np.isnan(values), DEGENERATE, np.where(values >= 0, INSIDE, OUTSIDE))
        return cls(
            robot=data["robot"],
            dof=int(data["dof"]),
            xs=np.asarray(data["xs"], dtype=float),
            ys=np.asarray(data["ys"], dtype=float),
            z=data.get("z"),
            rotation=np.asarray(data["rotation"], dtype=float),
            angles=data.get("angles"),
            values=values,
            status=status.astype(np.int8),
            anchors=np.asarray(anchors, dtype=float),
            time=float(data.get("summary", {}).get("time") or 0.0),
            set_force_lo=None
            if data.get("set_force_lo") is None
            else np.array(
                [[np.nan if v is None else float(v) for v in row] for row in data["set_force_lo"]]
            ).reshape(values.shape),
            notes=list(data.get("notes", [])),
        )


def isotropic_map(
    robot: Robot,
    xs: ArrayLike,
    ys: ArrayLike,
    z: float | None = None,
    rotation: ArrayLike | None = None,
    external: ArrayLike | None = None,
) -> IsotropicMap:
    """The maximum isotropic force at every ``(x, y)`` of the grid ``xs × ys``.

    ``z`` (dof 6 only) defaults to the middle of the robot's domain in z; ``rotation`` is
    ``None`` (identity), a matrix or angles in degrees (:func:`resolve_rotation`);
    ``external`` an optional extra constant wrench.
    """
    t0 = time.perf_counter()
    xs = np.asarray(xs, dtype=float).reshape(-1)
    ys = np.asarray(ys, dtype=float).reshape(-1)
    if xs.size == 0 or ys.size == 0:
        raise ValueError("grid: xs and ys must not be empty")
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
        raise ValueError("grid: coordinates must be finite")
    R, angles = resolve_rotation(robot, rotation)
    X, Y = np.meshgrid(xs, ys)
    if robot.dof == 6:
        if z is None:
            z = float(0.5 * (robot.domain[2, 0] + robot.domain[2, 1]))
        if not np.isfinite(z):
            raise ValueError("z must be finite")
        P = np.stack([X.ravel(), Y.ravel(), np.full(X.size, float(z))], axis=1)
    else:
        if z is not None:
            raise ValueError(f"z: a dof-{robot.dof} robot is planar, give x and y only")
        P = np.stack([X.ravel(), Y.ravel()], axis=1)
    f, st = isotropic_values(robot, P, R, external)
    floor, notes = None, []
    if robot.toleranced:
        floor = set_force_floor(robot, P, R if robot.dof != 2 else None, external)
        notes.append(
            "robot with tolerances: isotropic_force is the nominal robot's; set_force_lo is a "
            f"certified lower bound over every robot of the set ({int(np.sum(floor > 0))} of "
            f"{floor.size} points proven > 0; null: not proven)"
        )
        floor = floor.reshape(X.shape)
    return IsotropicMap(
        robot=robot.name,
        dof=robot.dof,
        xs=xs,
        ys=ys,
        z=None if z is None else float(z),
        rotation=R,
        angles=angles,
        values=f.reshape(X.shape),
        status=st.reshape(X.shape),
        anchors=robot.A.copy(),
        time=time.perf_counter() - t0,
        set_force_lo=floor,
        notes=notes,
    )


def _rows(a: np.ndarray) -> list[list[float | None]]:
    """A grid of values as JSON rows (None where not finite)."""
    return [[None if not np.isfinite(t) else float(t) for t in row] for row in a]
