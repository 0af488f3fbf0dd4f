"""A validated robot as numpy arrays: what the kinematics and force code compute with."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from .schema import RobotFileError, RobotSource, RobotSpec, load_robot_spec

__all__ = ["Robot", "default_domain"]


def default_domain(A: np.ndarray) -> np.ndarray:
    """Bounding box of the base anchors, widened along flat directions.

    A direction along which the anchors span less than 10 % of the largest extent (the
    almost-planar robot: every anchor at z = 0) is widened to ±10 % of the largest extent
    around the anchors' mean, so that a platform hanging or lifted slightly off the plane is
    inside the search box.
    """
    lo = A.min(axis=0)
    hi = A.max(axis=0)
    ext = hi - lo
    big = float(ext.max()) if ext.size else 1.0
    big = big if big > 0 else 1.0
    flat = ext < 0.1 * big
    mid = 0.5 * (lo + hi)
    lo = np.where(flat, mid - 0.1 * big, lo)
    hi = np.where(flat, mid + 0.1 * big, hi)
    return np.stack([lo, hi], axis=1)


@dataclass(frozen=True, eq=False)
class Robot:
    """Arrays over the ``m`` wires (``d`` = 3 for dof 6, 2 for planar robots)."""

    spec: RobotSpec
    A: np.ndarray  # (m, d) base anchors, reference frame
    B: np.ndarray  # (m, d) attachments, platform frame
    k: np.ndarray  # (m,) NaN where not given
    K: np.ndarray
    V: np.ndarray
    L0: np.ndarray
    tau_min: np.ndarray
    tau_max: np.ndarray
    u_min: np.ndarray  # -inf/inf where not given
    u_max: np.ndarray
    mass: float
    com: np.ndarray  # (d,) centre of mass, platform frame
    gravity: np.ndarray  # (d,) m/s²
    domain: np.ndarray  # (d, 2) bounds of platform points, world frame

    @classmethod
    def from_spec(cls, spec: RobotSpec) -> Robot:
        d = spec.dim
        w = spec.wires
        nan = np.nan

        def arr(vals):
            return np.array([nan if v is None else float(v) for v in vals])

        A = np.array([x.base for x in w], dtype=float)
        B = np.array([x.platform if x.platform is not None else [0.0] * d for x in w], float)
        com = spec.platform.center_of_mass
        dom = (
            np.array(spec.domain.points, dtype=float)
            if spec.domain is not None
            else default_domain(A)
        )
        return cls(
            spec=spec,
            A=A,
            B=B,
            k=arr(x.k for x in w),
            K=arr(x.K for x in w),
            V=arr(x.V for x in w),
            L0=arr(x.L0 for x in w),
            tau_min=np.array([x.tau[0] for x in w], dtype=float),
            tau_max=np.array([x.tau[1] for x in w], dtype=float),
            u_min=np.array([x.u[0] if x.u else -np.inf for x in w], dtype=float),
            u_max=np.array([x.u[1] if x.u else np.inf for x in w], dtype=float),
            mass=float(spec.platform.mass),
            com=np.zeros(d) if com is None else np.array(com, dtype=float),
            gravity=np.zeros(d) if spec.gravity is None else np.array(spec.gravity, dtype=float),
            domain=dom,
        )

    @classmethod
    def load(cls, source: RobotSource) -> Robot:
        """From a path, JSON text, dict or :class:`RobotSpec` (raises :class:`RobotFileError`)."""
        return cls.from_spec(load_robot_spec(source))

    # -- facts --------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def dof(self) -> int:
        return self.spec.dof

    @property
    def dim(self) -> int:
        return self.spec.dim

    @property
    def m(self) -> int:
        return self.A.shape[0]

    @property
    def wrench_dim(self) -> int:
        """Rows of the wrench matrix: 6 (dof 6), 3 (dof 3), 2 (dof 2)."""
        return {6: 6, 3: 3, 2: 2}[self.dof]

    @functools.cached_property
    def derived(self) -> dict[str, Any]:
        """Data that higher layers compute from this robot and keep with it, keyed by the
        computing module's name (e.g. the IK's rounding-error constants,
        :mod:`certsolve.kinematics.ik_enclose`).  The robot does not change, so they never
        go stale; a modified copy (``dataclasses.replace``) starts empty."""
        return {}

    @functools.cached_property
    def wire_splits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """For each wire ``j`` (0-based): ``([j], the other wires)`` as read-only index arrays.

        Computed once per robot object (IK Algorithm 2 fixes one wire at every call).
        """
        out = []
        for j in range(self.m):
            fixed = np.array([j])
            free = np.array([i for i in range(self.m) if i != j])
            fixed.flags.writeable = False
            free.flags.writeable = False
            out.append((fixed, free))
        return tuple(out)

    @property
    def weight(self) -> np.ndarray:
        """Weight vector in N (mass × gravity)."""
        return self.mass * self.gravity

    @property
    def is_elastic(self) -> bool:
        return all(w.elastic for w in self.spec.wires)

    def require_elastic(self, what: str) -> None:
        """Raise a clear error if some wire lacks the elastic model needed by ``what``."""
        for i, w in enumerate(self.spec.wires):
            for f in ("k", "K", "V", "L0", "u"):
                if getattr(w, f) is None:
                    raise RobotFileError(
                        f"wires[{i}].{f}: required for {what}",
                        field=f"robot.wires.{i}.{f}",
                        reason=f"required for {what}",
                    )

    def attachment_groups(self, tol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
        """Distinct platform attachment points and, per wire, the index of its point.

        The T-platform of Merlet (2007) has 7 wires on 3 distinct points.
        """
        pts: list[np.ndarray] = []
        idx = np.empty(self.m, dtype=np.int64)
        for i, b in enumerate(self.B):
            for j, p in enumerate(pts):
                if np.max(np.abs(p - b)) <= tol:
                    idx[i] = j
                    break
            else:
                idx[i] = len(pts)
                pts.append(b)
        return np.array(pts), idx
