"""The stable-only search: a contractor that drops boxes holding no stable equilibrium.

A stable equilibrium is one where the Hessian of the potential energy is positive definite
(:mod:`.stability`).  For a box ``X`` of the formulation's variables, every equilibrium
``X*`` in ``X`` has its Hessian ``H(X*)`` in the interval enclosure ``[H](X)``
(:class:`.EnergyHessian`: ``G`` and the levers are affine in the chosen points, so the
enclosure over ``X`` covers them at ``X*`` whether or not ``X`` itself is rigid).  If every
member of ``[H](X)`` is proven *not* positive definite (:func:`.not_positive_definite`: a
diagonal entry < 0, a 2×2 principal minor < 0, or ``vᵀ H v < 0`` along the midpoint's
eigenvector), no equilibrium in ``X`` is stable and ``X`` is dropped.  A search with this
contractor is complete when every stable equilibrium of the domain is among its solutions;
unstable equilibria it meets are still certified, and dropped from the answer by their
verdict (:meth:`.FKSolver.solve`).
"""

from __future__ import annotations

import numpy as np

from ..expr import CompiledSystem
from .stability import EnergyHessian, not_positive_definite

__all__ = ["StableOnly"]


class StableOnly:
    """``contract(lo, hi) -> (lo, hi, empty)``: ``empty`` where no stable equilibrium can be.

    The boxes are not narrowed.  The control ``u`` is read from the compiled system's
    parameters at each call (:meth:`.FKSolver.solve` sets them), so one contractor serves
    every ``u``.
    """

    #: the solver's fingerprint lists its partial contractors' (equations, variables): none
    #: here, and the extra entry tells a stable-only search's checkpoint from a full one's
    S = np.zeros(0, dtype=np.int64)
    V = np.zeros(0, dtype=np.int64)

    def __init__(self, hessian: EnergyHessian, csys: CompiledSystem):
        self.hessian = hessian
        self.csys = csys
        self.order = np.array([csys.param_names.index(p) for p in hessian.parameters])

    def contract(self, lo: np.ndarray, hi: np.ndarray):
        c, k = self.csys, self.order
        Hlo, Hhi = self.hessian.enclose(lo, hi, c.param_lo[k], c.param_hi[k])
        return lo, hi, not_positive_definite(Hlo, Hhi)
