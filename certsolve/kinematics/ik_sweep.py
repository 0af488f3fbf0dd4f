"""Inverse kinematics along a sweep of one control, by continuation (Merlet 2007, Fig. 3).

At a fixed pose the equilibrium equations ``f(u) = H τ(u) + w_g = 0`` (eqs. 3, 4, 6; the
wire lengths ``ρ`` follow from the pose) have ``w`` equations in ``m = w + 1`` controls.
Fixing the control ``u_J`` of one wire leaves a square system in the others (Algorithm 2).
:func:`ik_sweep` fixes ``u_J`` at ``count`` evenly spaced values from ``start`` to ``stop``
and follows the other controls from one value to the next:

* **predictor**: linear extrapolation (secant) through the last two solved points (the
  solution of the previous point when only one is known; the middle of the strokes, or
  ``u_start``, for the first point);
* **corrector**: Newton in the free controls on ``f(u) = 0`` with ``u_J`` fixed, started at
  the prediction (:func:`~.ik.ik_algorithm2` with ``solve="newton"``);
* **certificate**: the Krawczyk test of :class:`~.ik_enclose.SquareSystem` proves that a
  box around the Newton point holds exactly one solution and gives a tight enclosure of it;
  the tensions over that enclosure are then bounded rigorously
  (:func:`~.ik_enclose.tension_range`).

Each point gets a status:

``certified``
    the Krawczyk test succeeded, and the rigorous enclosures of the solution's tensions and
    controls lie inside ``[τ_min, τ_max]`` and the strokes: a proof that an admissible
    control vector with this ``u_J`` exists, unique in the certificate's box;
``infeasible``
    a tension or a control of the (floating-point) solution is outside its limits by more
    than :data:`~.ik_result.LIMIT_TOL`, or no control can produce the tension a wire needs
    (``τ ≥ k``); ``reason`` names the wire, the value and the limit;
``uncertified``
    Newton did not converge, the Krawczyk test failed, or a limit is met within rounding so
    the enclosure cannot decide it; ``reason`` says which.

As Merlet observes, the curves are close to straight lines: with ``m = w + 1`` the
tensions are ``τ = λ v`` along the null vector ``v`` of ``H`` (planar robots, no gravity) or an
affine function of ``τ_J`` (with gravity), and eq. (6) is nearly linear in ``u`` when
``K u ≪ ρ + V``.  Wire numbers are 1-based; lengths in cm, forces in N.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..robot.geometry import Pose
from ..robot.model import Robot
from ..robot.schema import RobotSource
from ..solver.search import SearchStatus
from .ik_alg2 import ik_algorithm2
from .ik_enclose import enclose_pose, tension_range
from .ik_inputs import as_pose, as_robot
from .ik_result import Violation, json_float, json_floats

__all__ = ["PointStatus", "SweepPoint", "SweepProgress", "IKSweepResult", "ik_sweep"]

MAX_POINTS = 100_000


class PointStatus(StrEnum):
    """What is known about one point of a sweep (module docstring)."""

    CERTIFIED = "certified"
    UNCERTIFIED = "uncertified"
    INFEASIBLE = "infeasible"


@dataclass(kw_only=True)
class SweepPoint:
    """One value of the swept control and the other controls found for it."""

    value: float  # u_J (cm), the exact float used
    u: np.ndarray | None  # (m,) all controls (u[J-1] == value); None if Newton failed
    tau: np.ndarray | None  # (m,) float tensions at u (N)
    status: PointStatus
    reason: str  # why the point is not certified ("" when it is)
    enclosure: tuple[np.ndarray, np.ndarray] | None  # (m,) proven enclosure of the solution
    tension_bounds: tuple[np.ndarray, np.ndarray] | None  # (m,) rigorous τ over `enclosure`
    predicted: np.ndarray | None  # (m,) the predictor (Newton's starting point)
    iterations: int  # Newton iterations of the corrector
    violations: list[Violation] = field(default_factory=list)

    def to_dict(self) -> dict:
        def box(b):
            return (
                None
                if b is None
                else [[json_float(a), json_float(c)] for a, c in zip(*b, strict=True)]
            )

        return {
            "value": float(self.value),
            "u": json_floats(self.u),
            "tau": json_floats(self.tau),
            "status": str(self.status),
            "reason": self.reason,
            "enclosure": box(self.enclosure),
            "tension_bounds": box(self.tension_bounds),
            "predicted": json_floats(self.predicted),
            "iterations": int(self.iterations),
            "violations": [v.to_dict() for v in self.violations],
        }


@dataclass(kw_only=True)
class SweepProgress:
    """Passed to the ``progress`` callback after every point."""

    points: int  # points done
    total: int  # points requested
    certified: int
    elapsed: float  # seconds


@dataclass(kw_only=True)
class IKSweepResult:
    """A sweep of ``u_joint`` at a fixed pose.

    ``status`` is a search's (:class:`~certsolve.solver.search.SearchStatus`): ``complete``
    (every requested point computed), ``timeout`` or ``cancelled`` (the progress callback
    returned ``False``); ``points`` then holds the points computed before the stop, in
    sweep order.
    """

    robot: str
    dof: int
    pose: Pose
    joint: int  # 1-based wire whose control is swept
    start: float
    stop: float
    count: int
    points: list[SweepPoint]
    status: SearchStatus
    time: float  # seconds

    @property
    def counts(self) -> dict[str, int]:
        out = {str(s): 0 for s in PointStatus}
        for p in self.points:
            out[str(p.status)] += 1
        return out

    @property
    def values(self) -> np.ndarray:
        """``(n,)`` the swept values ``u_J`` of the computed points."""
        return np.array([p.value for p in self.points])

    def controls(self) -> np.ndarray:
        """``(n, m)`` controls per point (rows of NaN where Newton failed)."""
        return self._stack("u")

    def tensions(self) -> np.ndarray:
        """``(n, m)`` tensions per point (rows of NaN where Newton failed)."""
        return self._stack("tau")

    def _stack(self, attr: str) -> np.ndarray:
        m = next((getattr(p, attr).size for p in self.points if getattr(p, attr) is not None), 0)
        out = np.full((len(self.points), m), np.nan)
        for i, p in enumerate(self.points):
            if getattr(p, attr) is not None:
                out[i] = getattr(p, attr)
        return out

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "dof": self.dof,
            "pose": [float(v) for v in self.pose.params(self.dof)],
            "joint": self.joint,
            "start": float(self.start),
            "stop": float(self.stop),
            "count": int(self.count),
            "status": str(self.status),
            "counts": self.counts,
            "points": [p.to_dict() for p in self.points],
            "time": float(self.time),
            "units": {"u": "cm", "tau": "N"},
        }


def _predict(done: list[tuple[float, np.ndarray]], value: float) -> np.ndarray | None:
    """Secant extrapolation through the last two solved points (or the last one)."""
    if not done:
        return None
    t1, u1 = done[-1]
    if len(done) == 1 or done[-2][0] == t1:
        return u1.copy()
    t0, u0 = done[-2]
    return u1 + (value - t1) / (t1 - t0) * (u1 - u0)


def _rigorous_limits(robot: Robot, enc, elo, ehi) -> tuple[tuple, str]:
    """Rigorous tension range over the enclosure, and why the limits are not proven ("")."""
    tlo, thi = tension_range(robot, enc, elo, ehi)
    bad = []
    for i in np.flatnonzero(~((tlo >= robot.tau_min) & (thi <= robot.tau_max))):
        bad.append(f"wire {i + 1}: tension in [{tlo[i]:.9g}, {thi[i]:.9g}] N")
    for i in np.flatnonzero(~((elo >= robot.u_min) & (ehi <= robot.u_max))):
        bad.append(f"wire {i + 1}: control in [{elo[i]:.9g}, {ehi[i]:.9g}] cm")
    reason = ""
    if bad:
        reason = "a limit is met within rounding, not proven: " + "; ".join(bad)
    return (tlo, thi), reason


def ik_sweep(
    robot: Robot | RobotSource,
    pose: Any,
    *,
    joint: int = 1,
    start: float,
    stop: float,
    count: int,
    u_start: ArrayLike | None = None,
    box_radius: float = 1e-4,
    progress: Callable[[SweepProgress], bool | None] | None = None,
    timeout: float | None = None,
) -> IKSweepResult:
    """Controls of every wire as ``u_joint`` goes from ``start`` to ``stop`` (module docstring).

    ``robot``: :class:`~certsolve.robot.Robot` or anything :meth:`Robot.load` accepts (it
    needs the elastic model and ``m = w + 1`` wires: dof 3 with 4 wires, dof 6 with 7);
    ``pose``: a :class:`~certsolve.robot.Pose`, parameters or text as for
    :func:`~.ik.inverse_kinematics`; ``joint``: 1-based wire; ``count`` points (at least 2)
    evenly spaced in ``[start, stop]`` (cm); ``u_start``: the Newton start of the first
    point (default: the middle of the strokes); ``box_radius``: relative half-width of the
    box of the uniqueness certificate (as Algorithm 2).  ``progress`` is called after every
    point with a :class:`SweepProgress`; returning ``False`` stops the sweep.
    """
    t0 = time.perf_counter()
    robot = as_robot(robot)
    pose = as_pose(robot, pose)
    robot.require_elastic("an IK sweep")
    w = robot.wrench_dim
    if robot.m != w + 1:
        raise ValueError(
            f"robot {robot.name!r}: a sweep of one control needs m = w + 1 wires "
            f"({w + 1} for dof {robot.dof}), it has {robot.m}"
        )
    if isinstance(joint, bool) or not isinstance(joint, (int, np.integer)):
        raise ValueError("joint: expected a wire number")
    if not 1 <= joint <= robot.m:
        raise ValueError(f"joint {joint}: the robot has wires 1..{robot.m}")
    if not (np.isfinite(start) and np.isfinite(stop)):
        raise ValueError("start and stop must be finite (cm)")
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)):
        raise ValueError("count: expected an integer")
    if not 2 <= count <= MAX_POINTS:
        raise ValueError(f"count must be between 2 and {MAX_POINTS}")
    if timeout is not None and not timeout > 0:
        raise ValueError("timeout must be positive (seconds)")
    if u_start is not None:
        u_start = np.asarray(u_start, dtype=float).reshape(-1)
        if u_start.shape != (robot.m,) or not np.all(np.isfinite(u_start)):
            raise ValueError(f"u_start: expected {robot.m} finite values")
    with np.errstate(all="ignore"):
        enc = enclose_pose(robot, pose.position, pose.rotation)
    if not enc.valid:
        raise ValueError("pose: a platform attachment coincides with its base anchor (ρ = 0)")

    values = np.linspace(float(start), float(stop), int(count))
    points: list[SweepPoint] = []
    done: list[tuple[float, np.ndarray]] = []  # (value, u) of the solved points
    status = SearchStatus.COMPLETE
    for value in values.tolist():
        if timeout is not None and time.perf_counter() - t0 > timeout:
            status = SearchStatus.TIMEOUT
            break
        pred = _predict(done, value)
        guess = pred if pred is not None else u_start
        if guess is not None:
            guess = guess.copy()
            guess[joint - 1] = value
        points.append(_point(robot, pose, enc, joint, value, guess, pred, box_radius))
        if points[-1].u is not None:
            done.append((value, points[-1].u))
        if progress is not None:
            info = SweepProgress(
                points=len(points),
                total=int(count),
                certified=sum(p.status is PointStatus.CERTIFIED for p in points),
                elapsed=time.perf_counter() - t0,
            )
            if progress(info) is False:
                status = SearchStatus.CANCELLED if len(points) < count else SearchStatus.COMPLETE
                break
    return IKSweepResult(
        robot=robot.name,
        dof=robot.dof,
        pose=pose,
        joint=int(joint),
        start=float(start),
        stop=float(stop),
        count=int(count),
        points=points,
        status=status,
        time=time.perf_counter() - t0,
    )


def _point(robot, pose, enc, joint, value, guess, pred, box_radius) -> SweepPoint:
    res = ik_algorithm2(
        robot,
        pose,
        fixed_wire=joint,
        u_fixed=value,
        solve="newton",
        u_last=guess,
        box_radius=box_radius,
    )
    its = int(res.details.get("iterations", 0))
    common = {"value": value, "predicted": pred, "iterations": its}
    if res.u is None:  # Newton failed, or no control produces the needed tension
        reason = "; ".join(res.messages) or f"no solution ({res.status})"
        infeasible = any("tension >= k" in m for m in res.messages)
        return SweepPoint(
            u=None,
            tau=None,
            status=PointStatus.INFEASIBLE if infeasible else PointStatus.UNCERTIFIED,
            reason=reason,
            enclosure=None,
            tension_bounds=None,
            **common,
        )
    cert = res.certificate
    enclosure = cert.enclosure if cert.kind == "unique-in-box" else None
    bounds = None
    limit_reason = ""
    if enclosure is not None:
        bounds, limit_reason = _rigorous_limits(robot, enc, *enclosure)
    violations = [v for v in res.violations if v.quantity in ("tau", "u")]
    if violations:
        status = PointStatus.INFEASIBLE
        reason = "; ".join(v.describe() for v in violations)
    elif enclosure is None:
        status = PointStatus.UNCERTIFIED
        reason = "; ".join(res.messages) or "the Krawczyk test failed"
    elif limit_reason:
        status = PointStatus.UNCERTIFIED
        reason = limit_reason
    else:
        status, reason = PointStatus.CERTIFIED, ""
    return SweepPoint(
        u=res.u,
        tau=res.tau,
        status=status,
        reason=reason,
        enclosure=enclosure,
        tension_bounds=bounds,
        violations=violations,
        **common,
    )
