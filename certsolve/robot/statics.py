"""Static equilibrium of the platform: wrench-feasible tension distributions.

At a pose with wrench matrix ``H`` (``w × m``) and external wrench ``w_ext`` (gravity),
equilibrium is ``H τ + w_ext = 0`` with ``τ_min <= τ <= τ_max``.  With ``m > w`` wires the
tensions are not unique; the *max-margin* distribution maximises the smallest distance to
the limits::

    max t   subject to   H τ = -w_ext,   τ_min + t <= τ <= τ_max - t,

a linear program (scipy's HiGHS).  ``t < 0`` at the optimum means no admissible tension
exists: the pose is outside the wrench-feasible workspace.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linprog

__all__ = ["TensionDistribution", "max_margin_tensions"]


@dataclass
class TensionDistribution:
    tau: np.ndarray  # (m,) tensions (NaN if the equilibrium equations have no solution)
    margin: float  # smallest distance to a tension limit (negative: infeasible)
    feasible: bool  # margin >= 0


def max_margin_tensions(
    H: ArrayLike, w_ext: ArrayLike, tau_min: ArrayLike, tau_max: ArrayLike
) -> TensionDistribution:
    """Solve the max-margin LP above for one pose."""
    H = np.asarray(H, dtype=float)
    w_ext = np.asarray(w_ext, dtype=float)
    tau_min = np.asarray(tau_min, dtype=float)
    tau_max = np.asarray(tau_max, dtype=float)
    w, m = H.shape
    # variables: (tau_1..tau_m, t); minimise -t
    c = np.zeros(m + 1)
    c[-1] = -1.0
    A_eq = np.hstack([H, np.zeros((w, 1))])
    b_eq = -w_ext
    eye = np.eye(m)
    ones = np.ones((m, 1))
    A_ub = np.vstack([np.hstack([-eye, ones]), np.hstack([eye, ones])])
    b_ub = np.concatenate([-tau_min, tau_max])
    span = float(np.max(tau_max - tau_min)) if m else 1.0
    bounds = [(None, None)] * m + [(-10.0 * max(span, 1.0) - 1e6, None)]
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0:
        return TensionDistribution(np.full(m, np.nan), -np.inf, False)
    tau = res.x[:m]
    margin = float(np.min(np.minimum(tau - tau_min, tau_max - tau)))
    return TensionDistribution(tau, margin, margin >= -1e-9)
