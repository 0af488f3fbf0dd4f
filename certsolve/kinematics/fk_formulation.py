"""What every FK formulation owns: its system, its search box for ``u``, its decoding and its
solver parts (the protocol :class:`FKFormulation`).

A formulation is built once per robot (:mod:`.fk_systems` maps names to builders) and is
read-only afterwards: :class:`.FKSolver` compiles ``system`` once and assembles a solver
for each control vector ``u`` from the parts asked here, passing ``u`` as the values of
the system's parameters ``u1..um`` (:meth:`FKFormulation.parameters_for`) and the search
box of eq. (7) as the search's domain (:meth:`FKFormulation.search_domain`).

The coordinate kinds are in :mod:`.fk_points` (the paper's points, the platform frame)
and :mod:`.fk_pose` (position and Euler angles); the physics they share is
:mod:`.fk_equations`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..expr import System
from ..expr.node import Expr
from ..robot.model import Robot
from ..solver.bisectors import SmearSumRelative
from .fk_equations import rho_domain, tolerance_parameters

__all__ = ["HULL_ORIENTATION", "HULL_POSITION", "FKFormulation"]

#: the polytope hull contracts every box whose split edge vectors are narrower than this
#: share of the longest edge, and whose reference point is narrower than
#: :data:`HULL_POSITION` of it (:meth:`FKFormulation.hull_widths`); 4 cm and 10 cm on
#: ``marionet.json`` (edges of 21 cm)
HULL_ORIENTATION = 0.19
HULL_POSITION = 0.47


@dataclass(kw_only=True)
class FKFormulation(ABC):
    """A forward-kinematics system and everything the solver and the reader of its
    solutions need to know about it.

    ``name``: the name results report (``frame-T-16``, ``planar-10``, ``pose`` ...);
    ``system``: the equations in the variables of this kind (the wire lengths ``ρ`` last),
    the control entering as the parameters ``u1..um``, its domain the search box at
    ``u = 0``; ``determined``: variables fixed by the others through equations, never
    split.
    """

    #: the coordinate kind, as fingerprints and reports name it
    kind: ClassVar[str]

    name: str
    robot: Robot
    system: System
    determined: tuple[int, ...] = ()

    # -- the control u ------------------------------------------------------------------------
    def parameters_for(self, u) -> dict[str, float | tuple[float, float]]:
        """The system's parameter values for control ``u`` (and the intervals of a robot's
        toleranced numbers, :func:`.fk_equations.tolerance_parameters`)."""
        u = np.asarray(u, dtype=float)
        return {f"u{i + 1}": float(v) for i, v in enumerate(u)} | tolerance_parameters(self.robot)

    def search_domain(self, u) -> tuple[np.ndarray, bool]:
        """The search box for control ``u`` and whether it is non-empty: the system's
        domain with every ``ρ_i`` in the range the tension limits allow (eq. 7), intersected
        with the distances from ``A_i`` to the robot's domain."""
        robot = self.robot
        lo, hi = rho_domain(robot, np.asarray(u, dtype=float), robot.domain)
        dom = self.system.domain.copy()
        if not any(v.startswith("rho") for v in self.system.variables):
            return dom, bool(np.all(lo <= hi))
        dom[-robot.m :, 0] = lo
        dom[-robot.m :, 1] = np.maximum(hi, lo)  # an empty range: reported, not searched
        return dom, bool(np.all(lo <= hi))

    # -- reading a solution -------------------------------------------------------------------
    @abstractmethod
    def decode(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(position, rotation, platform_points)`` at a point ``x`` of the variables: the
        platform frame's origin ``(d,)``, ``R`` ``(d, d)`` and every ``B_i`` ``(m, d)``."""

    def pose_box(
        self, position: np.ndarray, rotation: np.ndarray, radius: float, domain: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """A box of ``domain`` around the pose ``(position, rotation)``: its pose variables
        within ``radius`` of the pose's (centres rounded to 1e-6, so that a checkpoint's
        initial boxes do not depend on the last bits of a float search), the wire lengths
        as in ``domain``; ``None`` if it misses the domain or this formulation cannot write
        a pose (the seeds of :meth:`.FKSolver.solve`)."""
        c = self.encode(np.asarray(position, dtype=float), np.asarray(rotation, dtype=float))
        if c is None:
            return None
        lo, hi = domain[:, 0].copy(), domain[:, 1].copy()
        c = np.round(c, 6)
        k = c.size
        lo[:k] = np.maximum(lo[:k], c - radius)
        hi[:k] = np.minimum(hi[:k], c + radius)
        return (lo, hi) if np.all(lo <= hi) else None

    def encode(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray | None:
        """The pose variables (those before the wire lengths) of a pose, or ``None`` if
        this formulation does not write poses (the inverse of :meth:`decode`)."""
        return None

    @abstractmethod
    def levers(self) -> tuple[list[Expr], list[list[Expr]]]:
        """``G`` and ``r_i = B_i - G`` as expressions of the variables (enclosures of the
        exact ones: inexact coefficients are outward-rounded interval constants); the
        energy's Hessian (:mod:`.stability`) is written on them."""

    # -- solver parts ---------------------------------------------------------------------------
    def bisect_mask(self) -> np.ndarray:
        """The variables a bisection may split: not the wire lengths (fixed by the pose
        through the length equations), nor the :attr:`determined` ones."""
        mask = np.array([not v.startswith("rho") for v in self.system.variables])
        mask[list(self.determined)] = False
        return mask

    def bisector(self, domain: np.ndarray) -> Any:
        """The bisector for a search of ``domain`` (a new one per search).  Smear: the FK
        systems' figures (docs/fk-cost.md) were measured with it."""
        return SmearSumRelative()

    def subsystems(self) -> list[tuple[list[int], list[int]]]:
        """Square sub-systems ``(equations, variables)`` contracted by partial Newton."""
        return []

    def newton_groups(self) -> list[np.ndarray]:
        """Variable groups for Hansen's mixed Jacobian: edge vectors, reference point, wire
        lengths.

        Group ``k``'s columns are enclosed with the later groups at the box midpoint, so the
        pose columns see each wire's weight ``w_i = τ_i / ρ_i`` at the midpoint length: the
        tension, whose range over a box (~1.6 N per mm of length at 60 N) is the widest
        factor of the equilibrium equations, becomes a point in 12 of the 19 columns.
        Measured against the order wire lengths first (their ``A_i - B_i`` factor a point
        instead): general-19 at 60 N u~S(2) 164,109 -> 156,910 boxes, u~S(3) 201,974 ->
        190,602, random-general-0 3.21M -> 2.83M, at 10 N 130,749 -> 128,672; T-16 u=2 at
        60 N 284,674 -> 271,875, almost-planar-13 39,406 -> 38,882, T-16 at 10 N 1,577 ->
        1,692.
        """
        names = self.system.variables
        rho = np.array([v.startswith("rho") for v in names])
        edge = np.array([v.startswith("e") for v in names])
        groups = [edge, ~rho & ~edge, rho]
        return [g for g in groups if g.any()]

    def hull_widths(self) -> np.ndarray | None:
        """Per variable, the width below which every box gets the polytope hull (``inf``:
        any width), or ``None`` (no edge vectors: the hull's learnt share alone decides).

        In the platform frame the hull's yield follows the box's width: on general-19 at
        60 N, u = IK(P), P1 within 6 cm of the pose (the hull on each of 116,814 boxes
        after the fixpoint), it empties 75 % of the boxes whose split edge vectors are
        1-2 cm wide, 52 % at 2-3 cm, 34 % at 3-5 cm, 18 % at 5-10 cm and 2 % wider; 16-28 %
        of the boxes whose reference point is wider than 10 cm.  The learnt share
        (:class:`~certsolve.solver.relaxation.HullShare`) averages these over a batch, and
        there sits near its threshold: it turns the hull on and off batch by batch.  With
        these widths for the boxes it pays on, and the share for the others:
        docs/fk-cost.md, "Real control vectors at 60 N: the cost of a box".
        """
        names = self.system.variables
        edge = np.array([v.startswith("e") for v in names]) & self.bisect_mask()
        if not edge.any():
            return None
        dom = self.system.domain
        longest = float(np.max(dom[edge, 1] - dom[edge, 0])) / 2.0  # domain: ±|E_j|
        point = np.array([v in ("x1", "y1", "z1") for v in names])
        widths = np.full(len(names), np.inf)
        widths[edge] = HULL_ORIENTATION * longest
        widths[point] = HULL_POSITION * longest
        return widths

    def rho_columns(self) -> list[int]:
        """The columns of the wire lengths, in wire order."""
        return [j for j, v in enumerate(self.system.variables) if v.startswith("rho")]
