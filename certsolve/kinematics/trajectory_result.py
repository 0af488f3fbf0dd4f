"""The result of following a control path (:mod:`.trajectory`): plain data.

:class:`TrajectoryResult` says how the path ended (:class:`TrajectoryStatus`), where and
why it was lost (:class:`LostReason`) and holds each step (:class:`TrajectoryStep`), each
with ``to_dict()`` for JSON.  :func:`tension_enclosure` is eq. (6) in interval arithmetic,
the check of the tension limits over a step's proven box.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ..interval import arith
from ..robot.model import Robot
from .fk_solver import FKPose

__all__ = [
    "LostReason",
    "TrajectoryResult",
    "TrajectoryStatus",
    "TrajectoryStep",
    "tension_enclosure",
]


class TrajectoryStatus(StrEnum):
    """``complete``: every step certified and joined; ``lost``: stopped at ``lost_at``."""

    COMPLETE = "complete"
    LOST = "lost"


class LostReason(StrEnum):
    """Why a path was lost (the result's ``reason`` says it in words)."""

    NEWTON = "newton"  # float Newton did not converge
    SINGULAR = "singular"  # the Jacobian is singular (or nearly) at the step
    TENSION = "tension"  # a wire's tension is not proven inside its bounds
    CERTIFICATE = "certificate"  # the step's Krawczyk test failed
    LINK = "link"  # the link from the previous step could not be proven


@dataclass(kw_only=True)
class TrajectoryStep:
    """One row of the path.

    ``certified``: the step's box holds exactly one equilibrium for ``u``, within the
    tension bounds, and (after step 0) it is ``joined``: the link from the previous step
    is proven (module docstring).  ``halvings``: how deep that link had to be cut.
    ``pose``: at the Newton point (None where Newton failed); its ``box`` is the proven
    ``E_k`` when certified, the point itself otherwise.
    """

    index: int
    u: np.ndarray
    certified: bool
    joined: bool | None  # None for step 0 (no previous step)
    pose: FKPose | None
    halvings: int = 0

    def to_dict(self) -> dict:
        p = self.pose
        return {
            "index": self.index,
            "u": self.u.tolist(),
            "certified": self.certified,
            "joined": self.joined,
            "halvings": self.halvings,
            "pose": None
            if p is None
            else {"position": p.position.tolist(), "euler": p.euler_deg.tolist()},
            "platform_points": None if p is None else p.platform_points.tolist(),
            "tensions": None if p is None else p.tau.tolist(),
            "box": None if p is None else p.box,
        }


@dataclass(kw_only=True)
class TrajectoryResult:
    """A followed path: ``status``, ``lost_at`` (the first step not certified, None when
    complete), ``reason`` (words) and ``lost_reason`` (:class:`LostReason`), the
    ``steps`` up to and including ``lost_at``, and counters: ``chunks`` proven,
    ``chunk_failures`` (chunks split), ``halvings`` (links cut), ``own_proofs`` (steps
    proven with their own Jacobian), the wall ``time`` (s)."""

    robot: str
    formulation: str
    half_width: float
    status: TrajectoryStatus
    lost_at: int | None
    reason: str
    lost_reason: LostReason | None
    steps: list[TrajectoryStep]
    chunks: int
    chunk_failures: int
    halvings: int
    own_proofs: int
    time: float

    @property
    def certified(self) -> int:
        return sum(s.certified for s in self.steps)

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "formulation": self.formulation,
            "half_width": self.half_width,
            "status": str(self.status),
            "lost_at": self.lost_at,
            "reason": self.reason,
            "lost_reason": None if self.lost_reason is None else str(self.lost_reason),
            "certified": self.certified,
            "steps": [s.to_dict() for s in self.steps],
            "stats": {
                "chunks": self.chunks,
                "chunk_failures": self.chunk_failures,
                "halvings": self.halvings,
                "own_proofs": self.own_proofs,
                "time": self.time,
            },
        }


def tension_enclosure(
    robot: Robot, rlo: np.ndarray, rhi: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Rigorous bounds of eq. (6) ``τ = k - k L0 / (ρ + V + K u)`` for ``ρ ∈ [rlo, rhi]``
    (outward-rounded interval arithmetic; shapes ``(..., m)``).  ``L`` not provably
    positive gives ``[-inf, inf]``."""
    ku = arith.mul(robot.K, robot.K, u, u)
    w = arith.add(robot.V, robot.V, *ku)
    llo, lhi = arith.add(rlo, rhi, *w)
    kl0 = arith.mul(robot.k, robot.k, robot.L0, robot.L0)
    qlo, qhi = arith.div_nonzero(*kl0, llo, lhi)
    tlo, thi = arith.sub(robot.k, robot.k, qlo, qhi)
    bad = ~(llo > 0.0)
    return np.where(bad, -np.inf, tlo), np.where(bad, np.inf, thi)
