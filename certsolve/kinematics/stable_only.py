"""The stable-only search: a contractor that drops boxes holding no stable equilibrium.

A stable equilibrium is one where the Hessian of the potential energy is positive definite
(:mod:`.stability`).  For a box ``X`` of the formulation's variables, every equilibrium
``X*`` in ``X`` has its Hessian ``H(X*)`` in the interval enclosure ``[H](X)``
(:class:`.EnergyHessian`: ``G`` and the levers are affine in the chosen points, so the
enclosure over ``X`` covers them at ``X*`` whether or not ``X`` itself is rigid).  If every
member of ``[H](X)`` is proven *not* positive definite (:func:`.not_positive_definite`: a
diagonal entry < 0, a 2×2 principal minor < 0, or ``vᵀ H v < 0`` along the midpoint's
eigenvector), no equilibrium in ``X`` is stable and ``X`` is dropped.  Only boxes whose
tension ranges are narrow enough for the test to succeed are tested
(:data:`TESTED_TENSION_SHARE`): a choice of work, not of soundness.  A search with this
contractor is complete when every stable equilibrium of the domain is among its solutions;
unstable equilibria it meets are still certified, and dropped from the answer by their
verdict (:meth:`.FKSolver.solve`).
"""

from __future__ import annotations

import numpy as np

from ..expr import CompiledSystem
from ..robot.model import Robot
from ..solver.batch import Batch
from .stability import EnergyHessian, not_positive_definite

__all__ = ["StableOnly"]


#: a box is tested only if every wire's tension range over it is at most this share of the
#: wire's [τ_min, τ_max]: wider ranges include low tensions, where the elastic stiffness
#: keeps every curvature positive, and the test never succeeds there (measured on the first
#: 60k boxes at 60 N, u = IK(111, 58, 107): general-19 drops 1,075 of 56,974 boxes, all
#: with tension ranges <= 30 N, which are 25 % of the boxes; T-16 1,051 of 48,343, 78 %
#: of them with ranges <= 40 N, 45 % of the boxes).  Re-measured on the whole T-16 search
#: (2026-11-28, docs/fk-cost.md): 0.5 324,479 boxes / 22.2 CPU s, 2/3 318,182 / 21.4, 1 (no
#: gate) 314,602 / 26.2
TESTED_TENSION_SHARE = 2.0 / 3.0


class StableOnly:
    """``contract(lo, hi) -> (lo, hi, empty)``: ``empty`` where no stable equilibrium can be.

    The boxes are not narrowed.  The control ``u`` is read from the compiled system's
    parameters at each call (:meth:`.FKSolver.solve` sets them), so one contractor serves
    every ``u``.  ``rho``: the columns of the wire lengths, in wire order.
    """

    def __init__(self, hessian: EnergyHessian, csys: CompiledSystem, robot: Robot, rho):
        self.hessian = hessian
        self.csys = csys
        self.order = np.array([csys.param_names.index(p) for p in hessian.parameters])
        self.rho = np.asarray(rho, dtype=np.int64)
        self.kL0 = robot.k * robot.L0
        self.wire_V, self.wire_K = robot.V, robot.K
        self.max_width = TESTED_TENSION_SHARE * (robot.tau_max - robot.tau_min)

    def apply(self, batch: Batch) -> None:
        """The solver's contractor protocol (:mod:`certsolve.solver.batch`)."""
        batch.lo, batch.hi, empty = self.contract(batch.lo, batch.hi)
        batch.empty |= empty

    def describe(self) -> str:
        """Its entry in the solver's fingerprint: a stable-only search's checkpoint is not a
        full search's."""
        return f"StableOnly(tension_share={TESTED_TENSION_SHARE!r})"

    def tension_ranges(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Each wire's tension range ``(B, m)`` over the boxes: ``τ = k (1 - L0 / L)`` is
        increasing in ``ρ`` (a float estimate: it only chooses the boxes to test)."""
        off = self.wire_V + self.wire_K * self.csys.param_mid[self.order]
        with np.errstate(all="ignore"):
            return self.kL0 * (1.0 / (lo[:, self.rho] + off) - 1.0 / (hi[:, self.rho] + off))

    def contract(self, lo: np.ndarray, hi: np.ndarray):
        c, k = self.csys, self.order
        test = np.flatnonzero(np.all(self.tension_ranges(lo, hi) <= self.max_width, axis=1))
        empty = np.zeros(lo.shape[0], dtype=bool)
        if test.size:
            Hlo, Hhi = self.hessian.enclose(lo[test], hi[test], c.param_lo[k], c.param_hi[k])
            empty[test] = not_positive_definite(Hlo, Hhi)
        return lo, hi, empty
