"""Poses, platform points, wire vectors and the wrench matrix (Merlet 2007, eqs. 3-4).

All functions are vectorised over ``P`` poses: positions ``(P, d)``, rotations ``(P, d, d)``.

* Orientation of spatial platforms: Z-Y-X Euler angles (yaw ψ about z, then pitch θ about
  the new y, then roll φ about the new x), ``R = Rz(ψ) Ry(θ) Rx(φ)``; planar platforms use
  one angle θ.  Angles are in degrees at the user boundary, radians inside.
* ``n_i = (A_i - B_i) / ρ_i`` is the unit vector from the platform attachment towards the
  base anchor: a wire with tension ``τ_i >= 0`` pulls the platform with force ``τ_i n_i``.
* The wrench matrix ``H`` (called the inverse Jacobian transpose in the papers) has columns
  ``H_i = (n_i, CB_i × n_i)`` with ``C`` the platform frame origin (eq. 4); for planar
  rigid platforms the moment is the scalar 2-D cross product, for point platforms ``H_i =
  n_i``.  Equilibrium of the platform under an external wrench ``w`` reads ``H τ + w = 0``;
  gravity gives ``w_g = (m g, CG × m g)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .model import Robot

__all__ = [
    "Pose",
    "rotation_zyx",
    "euler_zyx",
    "rotation_2d",
    "parse_pose",
    "platform_points",
    "wire_geometry",
    "wrench_matrix",
    "wrenches",
    "gravity_wrench",
]


def rotation_zyx(yaw: ArrayLike, pitch: ArrayLike, roll: ArrayLike) -> np.ndarray:
    """``Rz(yaw) Ry(pitch) Rx(roll)`` for arrays of angles in radians; shape ``(..., 3, 3)``."""
    yaw, pitch, roll = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (yaw, pitch, roll))
    )
    cz, sz = np.cos(yaw), np.sin(yaw)
    cy, sy = np.cos(pitch), np.sin(pitch)
    cx, sx = np.cos(roll), np.sin(roll)
    R = np.empty(yaw.shape + (3, 3))
    R[..., 0, 0] = cz * cy
    R[..., 0, 1] = cz * sy * sx - sz * cx
    R[..., 0, 2] = cz * sy * cx + sz * sx
    R[..., 1, 0] = sz * cy
    R[..., 1, 1] = sz * sy * sx + cz * cx
    R[..., 1, 2] = sz * sy * cx - cz * sx
    R[..., 2, 0] = -sy
    R[..., 2, 1] = cy * sx
    R[..., 2, 2] = cy * cx
    return R


def euler_zyx(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`rotation_zyx`: ``(..., 3)`` angles (yaw, pitch, roll) in radians."""
    R = np.asarray(R, dtype=float)
    pitch = np.arcsin(np.clip(-R[..., 2, 0], -1.0, 1.0))
    yaw = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    roll = np.arctan2(R[..., 2, 1], R[..., 2, 2])
    return np.stack([yaw, pitch, roll], axis=-1)


def rotation_2d(theta: ArrayLike) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    R = np.empty(theta.shape + (2, 2))
    R[..., 0, 0] = c
    R[..., 0, 1] = -s
    R[..., 1, 0] = s
    R[..., 1, 1] = c
    return R


@dataclass(frozen=True)
class Pose:
    """One platform pose: position of the platform frame origin and rotation matrix."""

    position: np.ndarray  # (d,)
    rotation: np.ndarray  # (d, d)

    @classmethod
    def from_params(cls, dof: int, params: Sequence[float] | np.ndarray) -> Pose:
        """From ``x,y,z,yaw,pitch,roll`` (dof 6), ``x,y,theta`` (dof 3), ``x,y`` (dof 2).

        Lengths in cm, angles in degrees; missing angles are 0.
        """
        p = [float(v) for v in params]
        if dof == 6:
            if len(p) not in (3, 6):
                raise ValueError("a spatial pose is x,y,z[,yaw,pitch,roll] (cm, degrees)")
            ang = np.radians(p[3:6]) if len(p) == 6 else np.zeros(3)
            return cls(np.array(p[:3]), rotation_zyx(*ang))
        if dof == 3:
            if len(p) not in (2, 3):
                raise ValueError("a planar pose is x,y[,theta] (cm, degrees)")
            th = np.radians(p[2]) if len(p) == 3 else 0.0
            return cls(np.array(p[:2]), rotation_2d(th))
        if len(p) != 2:
            raise ValueError("a point pose is x,y (cm)")
        return cls(np.array(p), np.eye(2))

    def params(self, dof: int) -> list[float]:
        """Inverse of :meth:`from_params` (angles in degrees)."""
        if dof == 6:
            return list(self.position) + list(np.degrees(euler_zyx(self.rotation)))
        if dof == 3:
            th = np.degrees(np.arctan2(self.rotation[1, 0], self.rotation[0, 0]))
            return list(self.position) + [float(th)]
        return list(self.position)


def parse_pose(dof: int, text: str) -> Pose:
    """Parse ``"x,y,z,yaw,pitch,roll"`` style text (see :meth:`Pose.from_params`)."""
    try:
        vals = [float(t) for t in text.replace(" ", "").split(",") if t != ""]
    except ValueError:
        raise ValueError(f"pose {text!r}: expected comma-separated numbers") from None
    return Pose.from_params(dof, vals)


def _batch(positions, rotations):
    p = np.asarray(positions, dtype=float)
    R = np.asarray(rotations, dtype=float)
    if p.ndim == 1:
        p = p[None]
    if R.ndim == 2:
        R = np.broadcast_to(R, (p.shape[0],) + R.shape)
    return p, R


def platform_points(robot: Robot, positions: ArrayLike, rotations: ArrayLike) -> np.ndarray:
    """World coordinates of every attachment B_i: ``(P, m, d)``."""
    p, R = _batch(positions, rotations)
    return p[:, None, :] + np.einsum("pij,mj->pmi", R, robot.B)


def wire_geometry(
    robot: Robot, positions: ArrayLike, rotations: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rho, n, CB)``: lengths ``(P, m)``, unit vectors B->A ``(P, m, d)``, and the
    attachment vectors from the platform origin in world axes ``(P, m, d)``."""
    p, R = _batch(positions, rotations)
    CB = np.einsum("pij,mj->pmi", R, robot.B)
    AB = robot.A[None] - (p[:, None, :] + CB)
    rho = np.linalg.norm(AB, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = AB / rho[:, :, None]
    return rho, n, CB


def _cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def wrench_matrix(robot: Robot, positions: ArrayLike, rotations: ArrayLike) -> np.ndarray:
    """``H`` of shape ``(P, w, m)``: column i is the wrench of a unit tension in wire i."""
    _, n, CB = wire_geometry(robot, positions, rotations)
    return wrenches(n, CB, robot.dof)


def wrenches(n: np.ndarray, CB: np.ndarray, dof: int) -> np.ndarray:
    """:func:`wrench_matrix` from :func:`wire_geometry`'s unit vectors ``n`` and attachment
    vectors ``CB``: forces ``n_i``, moments ``CB_i × n_i`` about the platform origin."""
    if dof == 2:
        return np.transpose(n, (0, 2, 1))
    if dof == 3:
        mom = _cross2(CB, n)[:, None, :]
        return np.concatenate([np.transpose(n, (0, 2, 1)), mom], axis=1)
    mom = np.cross(CB, n)
    return np.concatenate([np.transpose(n, (0, 2, 1)), np.transpose(mom, (0, 2, 1))], axis=1)


def gravity_wrench(robot: Robot, rotations: ArrayLike) -> np.ndarray:
    """External wrench of the weight on the platform, about the platform origin: ``(P, w)``."""
    R = np.asarray(rotations, dtype=float)
    if R.ndim == 2:
        R = R[None]
    f = np.broadcast_to(robot.weight, (R.shape[0], robot.dim))
    if robot.dof == 2:
        return f.copy()
    cg = np.einsum("pij,j->pi", R, robot.com)
    if robot.dof == 3:
        return np.concatenate([f, _cross2(cg, f)[:, None]], axis=1)
    return np.concatenate([f, np.cross(cg, f)], axis=1)
