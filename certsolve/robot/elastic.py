"""The elastic wire model of MARIONET (Merlet 2007, eqs. 1, 2, 5, 6, 7).

Hooke's law ``τ = k (L - L0) / L`` (1) with the total wire length ``L = ρ + V + K u`` (2):

* :func:`tension`  -- eq. (6): ``τ = k (ρ + V - L0 + K u) / (ρ + V + K u)``;
* :func:`control`  -- eq. (5): ``u = k L0 / (K (k - τ)) - (ρ + V) / K``;
* :func:`length`   -- eq. (7): ``ρ = k L0 / (k - τ) - V - K u``.

Each is monotone in its varying argument (``τ`` increases with ``ρ`` and with ``u``), so
bounds map to bounds: :func:`length_bounds` gives the range of ``ρ`` allowed by the
tension limits for a control ``u`` (the FK search box).  All functions broadcast over
wires and poses.
"""

from __future__ import annotations

import numpy as np

from .model import Robot

__all__ = ["tension", "control", "length", "length_bounds", "control_bounds"]


def tension(robot: Robot, rho: np.ndarray | float, u: np.ndarray | float) -> np.ndarray:
    """Eq. (6)."""
    L = rho + robot.V + robot.K * u
    return robot.k * (L - robot.L0) / L


def control(robot: Robot, rho: np.ndarray | float, tau: np.ndarray | float) -> np.ndarray:
    """Eq. (5)."""
    return robot.k * robot.L0 / (robot.K * (robot.k - tau)) - (rho + robot.V) / robot.K


def length(robot: Robot, tau: np.ndarray | float, u: np.ndarray | float) -> np.ndarray:
    """Eq. (7)."""
    return robot.k * robot.L0 / (robot.k - tau) - robot.V - robot.K * u


def length_bounds(robot: Robot, u: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """``[ρ_min, ρ_max]`` per wire from ``[τ_min, τ_max]`` at control ``u`` (eq. 7)."""
    return length(robot, robot.tau_min, u), length(robot, robot.tau_max, u)


def control_bounds(robot: Robot, rho: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """``[u_lo, u_hi]`` per wire keeping the tension within its limits at length ``ρ`` (eq. 5)."""
    return control(robot, rho, robot.tau_min), control(robot, rho, robot.tau_max)
