"""Inputs of inverse kinematics: robots and poses as the methods need them, search windows.

Shared by :mod:`.ik_first`, :mod:`.ik_alg1`, :mod:`.ik_alg2` and :mod:`.ik_sweep`: the
checks that turn what a user passes (a robot file, a pose string, ``u_last`` and a window)
into float64 arrays, with clear errors.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..robot.geometry import Pose
from ..robot.inputs import as_pose as pose_of
from ..robot.model import Robot
from ..robot.schema import RobotFileError, RobotSource
from .ik_enclose import PoseEnclosure
from .ik_search import control_point

__all__ = [
    "as_pose",
    "as_robot",
    "check_pose",
    "controls",
    "search_window",
    "require_elastic",
    "overdetermined_note",
]


def as_pose(robot: Robot, pose: Any) -> Pose:
    """A :class:`Pose` with float64 arrays of the robot's dimension, from a pose, its
    parameters or their text (:func:`certsolve.robot.inputs.as_pose`)."""
    return pose_of(robot.dof, pose)


def check_pose(pose: Pose, enc: PoseEnclosure) -> None:
    """Clear errors for a pose whose geometry is undefined."""
    if enc.valid:
        return
    if not (np.all(np.isfinite(pose.position)) and np.all(np.isfinite(pose.rotation))):
        raise ValueError("pose: position and rotation must be finite")
    raise ValueError("pose: a platform attachment coincides with its base anchor (ρ = 0)")


def as_robot(robot: Robot | RobotSource) -> Robot:
    return robot if isinstance(robot, Robot) else Robot.load(robot)


def controls(robot: Robot, rho: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Eq. (5); NaN where the tension reaches ``k`` (no length can produce it)."""
    u = control_point(robot, rho, tau)
    return np.where(tau < robot.k, u, np.nan)


def search_window(
    robot: Robot, u_last: ArrayLike | None, window: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Control box: strokes ∩ ``u_last ± window / 2`` (window in cm, full width).

    Returns ``(lo, hi, u_last)`` with ``u_last`` checked (``None`` when not given).
    """
    lo, hi = robot.u_min.copy(), robot.u_max.copy()
    if u_last is None:
        return lo, hi, None
    u_last = np.asarray(u_last, dtype=float).ravel()
    if u_last.shape != (robot.m,):
        raise ValueError(f"u_last: expected {robot.m} values, got {u_last.size}")
    if not np.all(np.isfinite(u_last)):
        raise ValueError("u_last: values must be finite")
    if window is None:
        return lo, hi, u_last
    if not window > 0:
        raise ValueError("window must be positive (cm)")
    return np.maximum(lo, u_last - 0.5 * window), np.minimum(hi, u_last + 0.5 * window), u_last


def require_elastic(robot: Robot, method: str) -> None:
    """Raise :class:`RobotFileError` when ``method`` needs the elastic model the robot lacks."""
    try:
        robot.require_elastic(f"inverse kinematics {method}")
    except RobotFileError as exc:
        raise RobotFileError(
            f"robot {robot.name!r} has no elastic wire model ({exc}); method {method} needs "
            "k, K, V, L0 and the stroke u of every wire -- use method 'tension' for the "
            "tensions only"
        ) from None


def overdetermined_note(robot: Robot, w: int) -> str:
    return (
        f"{w} equilibrium equations for {robot.m} tensions: the pose is over-determined; "
        "it is an equilibrium only at poses the robot can reach (forward kinematics), and "
        "such a solution cannot be certified by a square Krawczyk test"
    )
