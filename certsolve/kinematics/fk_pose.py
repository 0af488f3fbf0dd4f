"""Pose coordinates of the FK system: position and Z-Y-X Euler angles of the platform + ρ.

The classical parameterisation (``6 + m`` unknowns in space, ``3 + m`` in the plane), for
comparison with the point systems (:mod:`.fk_points`): ``B_i = p + R b_i`` and ``G = p +
R c`` with ``R`` from the angles; the lengths and the equilibrium are those of
:mod:`.fk_equations` (moments about the domain centre), and every attachment lies in the
robot's domain (checked constraints).  Angles range over ``yaw, roll ∈ [-π, π]``, ``pitch ∈
[-π/2, π/2]`` (``θ ∈ [-π, π]`` in the plane).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..expr import Constraint, System, const, cos, esum, sin, sqr, var
from ..expr.node import Expr
from ..robot.geometry import rotation_2d, rotation_zyx
from ..robot.model import Robot
from .fk_equations import (
    absolute_forces_and_moments,
    coefficient,
    difference,
    rho_domain,
    wire_weights,
)
from .fk_formulation import FKFormulation

__all__ = ["PoseFormulation", "rotation"]


def rotation(d: int) -> list[list[Expr]]:
    """``R`` of the pose's angles (``yaw, pitch, roll``, Z-Y-X; or ``theta`` in the plane)."""
    if d == 2:
        t = var("theta")
        return [[cos(t), -sin(t)], [sin(t), cos(t)]]
    cz, sz = cos(var("yaw")), sin(var("yaw"))
    cy, sy = cos(var("pitch")), sin(var("pitch"))
    cx, sx = cos(var("roll")), sin(var("roll"))
    return [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]


def _apply(R: list[list[Expr]], lo: np.ndarray, hi: np.ndarray) -> list[Expr]:
    """``R b`` for ``b`` in the box ``[lo, hi]`` (a point when ``lo == hi``)."""
    d = len(R)
    nz = [c for c in range(d) if lo[c] != 0.0 or hi[c] != 0.0]
    if not nz:
        return [const(0.0)] * d
    return [esum(coefficient(lo[c], hi[c]) * R[r][c] for c in nz) for r in range(d)]


@dataclass(kw_only=True)
class PoseFormulation(FKFormulation):
    """Variables ``x, y, z, yaw, pitch, roll`` (or ``x, y, theta``) and ``rho1..rhom``."""

    kind: ClassVar[str] = "pose"

    @classmethod
    def build(cls, robot: Robot) -> PoseFormulation:
        d = robot.dim
        rho = [var(f"rho{i + 1}") for i in range(robot.m)]
        dom = robot.domain
        if d == 3:
            names = ["x", "y", "z", "yaw", "pitch", "roll"]
            ang_dom = [[-np.pi, np.pi], [-np.pi / 2, np.pi / 2], [-np.pi, np.pi]]
        else:
            names = ["x", "y", "theta"]
            ang_dom = [[-np.pi, np.pi]]
        p = [var(a) for a in names[:d]]
        R = rotation(d)

        def world(b):
            return [
                p[r] + esum(float(b[c]) * R[r][c] for c in range(d) if b[c] != 0.0)
                if np.any(b != 0)
                else p[r]
                for r in range(d)
            ]

        B = [world(robot.B[i]) for i in range(robot.m)]
        G = world(robot.com)
        eqs = [
            esum(sqr(B[i][c] - float(robot.A[i, c])) for c in range(d)) - sqr(rho[i])
            for i in range(robot.m)
        ]
        w = wire_weights(robot, rho)
        eqs += absolute_forces_and_moments(robot, B, G, w, dom.mean(axis=1))
        constraints = []
        for i in range(robot.m):
            for c in range(d):
                constraints.append(Constraint(B[i][c], float(dom[c, 0]), float(dom[c, 1])))
        names = names + [f"rho{i + 1}" for i in range(robot.m)]
        domain = np.vstack([dom, np.array(ang_dom), np.zeros((robot.m, 2))])
        lo, hi = rho_domain(robot, np.zeros(robot.m), dom)  # u = 0; per u: search_domain
        domain[-robot.m :, 0] = lo
        domain[-robot.m :, 1] = np.maximum(hi, lo)
        params = {f"u{i + 1}": 0.0 for i in range(robot.m)}
        system = System(names, domain, eqs, constraints, name="pose", parameters=params)
        return cls(name="pose", robot=robot, system=system)

    def decode(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self.robot.dim == 3:
            pos, R = x[:3].copy(), rotation_zyx(x[3], x[4], x[5])
        else:
            pos, R = x[:2].copy(), rotation_2d(x[2])
        return pos, R, pos + self.robot.B @ R.T

    def levers(self) -> tuple[list[Expr], list[list[Expr]]]:
        """``G = p + R c`` and ``r_i = R (b_i - c)``, ``b_i - c`` outward rounded."""
        robot = self.robot
        R = rotation(robot.dim)
        axes = "xyz"[: robot.dim]
        G = [var(a) + g for a, g in zip(axes, _apply(R, robot.com, robot.com), strict=True)]
        return G, [_apply(R, *difference(robot.B[i], robot.com)) for i in range(robot.m)]
