"""Tension-first inverse kinematics: the max-margin tensions, then ``u`` by eq. (5).

Choose the tensions (max-margin distribution: exact closed form on the line of solutions
when ``m = w + 1``, the LP otherwise; :mod:`.ik_tension`), then the controls by eq. (5) of
Merlet (2007).  Limits on ``τ`` hold by construction when the pose is wrench-feasible;
strokes are *checked* and every ``u`` outside its stroke is reported.  Floating point, no
certificate.
"""

from __future__ import annotations

import time

import numpy as np

from ..robot.geometry import Pose
from ..robot.model import Robot
from .ik_enclose import enclose_pose, float_geometry, is_elastic
from .ik_inputs import check_pose, controls, overdetermined_note
from .ik_result import LIMIT_TOL, IKResult, IKStatus, limit_violations
from .ik_tension import distribute_tensions

__all__ = ["ik_tension_first"]


def _status(ch, violations, u, messages: list[str]) -> IKStatus:
    """The status of a tension distribution ``ch`` (appends the explanation to ``messages``)."""
    if not ch.equilibrium:
        return IKStatus.NOT_EQUILIBRIUM
    if ch.margin < -LIMIT_TOL:
        messages.append(
            f"no admissible tension: the best distribution misses the limits by "
            f"{-ch.margin:.4g} N (the pose is outside the wrench-feasible workspace)"
        )
        return IKStatus.INFEASIBLE
    if ch.margin <= LIMIT_TOL:
        messages.append(
            "the best tensions touch a limit (margin 0): the pose is on the boundary of the "
            "wrench-feasible workspace" + (" (all wires slack)" if not np.any(ch.tau) else "")
        )
        return IKStatus.BOUNDARY
    if u is not None and violations:
        messages.append("tensions are admissible but some controls are outside the strokes")
    return IKStatus.LIMITS_VIOLATED if violations else IKStatus.OK


def ik_tension_first(
    robot: Robot,
    pose: Pose,
    *,
    distribution: str = "auto",
    check_lp: bool = False,
) -> IKResult:
    """Max-margin tensions, then ``u`` by eq. (5) (see the module docstring)."""
    t0 = time.perf_counter()
    with np.errstate(all="ignore"):
        rho, H, wg = float_geometry(robot, pose.position, pose.rotation)
        if not (rho.min() > 0.0 and np.isfinite(H).all()):
            check_pose(pose, enclose_pose(robot, pose.position, pose.rotation))
    ch = distribute_tensions(
        H, wg, robot.tau_min, robot.tau_max, mode=distribution, check_lp=check_lp
    )
    messages = list(ch.notes)
    elastic = is_elastic(robot)
    tau = ch.tau if np.all(np.isfinite(ch.tau)) else None
    u = None
    if elastic and tau is not None:
        u = controls(robot, rho, tau)
    elif not elastic:
        messages.append(
            f"robot {robot.name!r} has no elastic model (k, K, V, L0, u): tensions only, "
            "the controls u are unavailable"
        )
    violations = limit_violations(robot, tau, u)
    details: dict = {
        "distribution": ch.method,
        "rank": ch.rank,
        "null_space_dimension": ch.null_dim,
    }
    if ch.lam_range is not None:
        details["lambda_range"] = list(ch.lam_range)
        details["null_vector"] = ch.null_vector
    if ch.lp_check is not None:
        details["lp_check"] = ch.lp_check
    if robot.m < H.shape[0]:
        messages.append(overdetermined_note(robot, H.shape[0]))
        if ch.equilibrium:
            messages.append(
                f"the pose is an equilibrium up to a residual of {ch.residual:.3g} "
                "(checked numerically, relative tolerance 1e-9)"
            )
    status = _status(ch, violations, u, messages)
    return IKResult(
        robot=robot.name,
        dof=robot.dof,
        method="tension",
        pose=pose,
        status=status,
        feasible=status == IKStatus.OK,
        u=u,
        tau=tau,
        rho=rho,
        margin=ch.margin if np.isfinite(ch.margin) else None,
        residual=ch.residual if np.isfinite(ch.residual) else None,
        violations=violations,
        messages=messages,
        details=details,
        time=time.perf_counter() - t0,
    )
