"""Constant external loads and the centre of the isotropic-force ball (the bias).

Equilibrium of the platform is ``H τ + w_ext + w_d = 0`` (:mod:`certsolve.robot.geometry`),
with ``w_ext`` the known constant wrench (the weight, plus an optional user wrench) and
``w_d`` the disturbance to resist.  The disturbance is a **force ``f`` applied at the
platform frame origin with no moment**, ``w_d = (f, 0)`` (for a point platform, dof 2,
``w_d = f``).  It is resisted iff some admissible ``τ`` gives

    H_f τ = -w_ext,f - f,     H_m τ = -w_ext,m =: μ      (force rows f, moment rows m),

i.e. iff ``x0 - f ∈ F(μ)`` where ``x0 = -w_ext,f`` and ``F(μ)`` is the force section of
the wrench polytope at the moment ``μ`` required by the load (:mod:`.section`).  The set of
resisted forces is ``x0 - F(μ)``, so the largest ball of disturbances centred at 0 that is
resisted has the radius of the largest ball **centred at the bias point ``x0 = -w_ext,f``**
inside ``F(μ)``: that radius is the maximum isotropic force reported everywhere in
:mod:`certsolve.force`.  Without loads (``w_ext = 0``, the paper's case) it is the ball
centred at the origin of Krut et al. (2004), eq. (19).

Planar files have no gravity (the schema forbids it), so their bias is 0 unless a user
wrench is given.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..robot import Robot, gravity_wrench

__all__ = ["force_rows", "external_wrench", "FORCE_ROWS"]

#: number of force rows of the wrench (the rest are moments), by dof
FORCE_ROWS = {2: 2, 3: 2, 6: 3}


def force_rows(robot: Robot) -> int:
    return FORCE_ROWS[robot.dof]


def external_wrench(
    robot: Robot, rotations: ArrayLike, extra: ArrayLike | None = None
) -> np.ndarray:
    """``w_ext`` of shape ``(P, w)``: the weight's wrench about the platform origin plus ``extra``.

    ``extra`` is an optional constant wrench ``(w,)`` (N, and N·cm for moments).
    """
    R = np.asarray(rotations, dtype=float)
    if R.ndim == 2:
        R = R[None]
    w = gravity_wrench(robot, R)
    if extra is not None:
        e = np.asarray(extra, dtype=float).reshape(-1)
        if e.shape != (robot.wrench_dim,):
            raise ValueError(
                f"external wrench: expected {robot.wrench_dim} components, got {e.size}"
            )
        if not np.all(np.isfinite(e)):
            raise ValueError("external wrench: components must be finite")
        w = w + e
    return w
