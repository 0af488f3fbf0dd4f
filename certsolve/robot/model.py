"""A validated robot as numpy arrays: what the kinematics and force code compute with."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .schema import RobotFileError, RobotSource, RobotSpec, load_robot_spec

__all__ = ["Robot", "RobotIntervals", "default_domain"]


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


@dataclass(frozen=True, kw_only=True)
class RobotIntervals:
    """The interval of every number of a robot with tolerances (:mod:`.tolerance`): for each
    array of :class:`Robot` among :attr:`FIELDS`, a pair ``(lo, hi)`` of arrays of its
    shape (``lo == hi`` for an exact number); ``mass`` is a pair of floats.  Every robot of
    the set has its numbers inside these bounds (outward rounded)."""

    #: the arrays that may carry a tolerance, by their name in :class:`Robot`
    FIELDS: ClassVar[tuple[str, ...]] = ("A", "B", "k", "K", "V", "L0", "com")

    A: tuple[np.ndarray, np.ndarray]
    B: tuple[np.ndarray, np.ndarray]
    k: tuple[np.ndarray, np.ndarray]
    K: tuple[np.ndarray, np.ndarray]
    V: tuple[np.ndarray, np.ndarray]
    L0: tuple[np.ndarray, np.ndarray]
    com: tuple[np.ndarray, np.ndarray]
    mass: tuple[float, float]

    def exact(self, name: str) -> np.ndarray:
        """Mask of the numbers of ``name`` (or ``mass``) known exactly (a number the file
        does not give, NaN, has no tolerance)."""
        lo, hi = (np.asarray(a) for a in getattr(self, name))
        return (lo == hi) | (np.isnan(lo) & np.isnan(hi))


#: file field (:mod:`.paths`) -> its array in :class:`Robot`
_ARRAY_OF = {
    "base": "A", "platform": "B", "k": "k", "K": "K", "V": "V", "L0": "L0",
    "center_of_mass": "com", "mass": "mass",
}  # fmt: skip


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

    # -- tolerances ---------------------------------------------------------------------------
    @property
    def toleranced(self) -> bool:
        """Whether some number is known only within a (non-zero) interval."""
        return any(lo != hi for lo, hi in self.spec.tolerance_intervals().values())

    @functools.cached_property
    def _intervals(self) -> RobotIntervals:
        pairs: dict[str, Any] = {
            f: (getattr(self, f).copy(), getattr(self, f).copy()) for f in RobotIntervals.FIELDS
        }
        mass = [self.mass, self.mass]
        for (field, entry), (lo, hi) in self.spec.tolerance_intervals().items():
            name = _ARRAY_OF[field]
            if name == "mass":
                mass = [lo, hi]
                continue
            pairs[name][0][entry] = lo
            pairs[name][1][entry] = hi
        for a, b in pairs.values():
            a.flags.writeable = b.flags.writeable = False
        return RobotIntervals(**pairs, mass=(mass[0], mass[1]))

    def bounds(self) -> RobotIntervals:
        """The interval of every number (the nominal arrays of this object are unchanged;
        without tolerances every interval is a point)."""
        return self._intervals

    def weight_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the weight ``mass × gravity`` (N) over the set, rounded outward where
        the mass is toleranced (the nominal :attr:`weight` otherwise)."""
        lo, hi = self.bounds().mass
        if lo == hi:
            return self.weight, self.weight
        from ..interval import arith

        g = self.gravity
        wlo, whi = arith.scale(np.full_like(g, lo), np.full_like(g, hi), g)
        return np.where(g == 0, 0.0, wlo), np.where(g == 0, 0.0, whi)

    def nominal(self) -> Robot:
        """The robot of the file's numbers, without its tolerances."""
        if not self.spec.tolerances:
            return self
        return Robot.from_spec(self.spec.model_copy(update={"tolerances": []}))

    def realization(self, values: dict[str, Any]) -> Robot:
        """The robot of the set whose numbers are ``values`` (``{"A": (m, d) array, "k": ...,
        "mass": float}``, any of :attr:`RobotIntervals.FIELDS` and ``mass``; the others
        nominal), without tolerances; it is validated as a robot file."""
        data = self.spec.model_dump(mode="json", exclude_none=True)
        data["tolerances"] = []
        key = {v: k for k, v in _ARRAY_OF.items()}
        for name, arr in values.items():
            field = key[name]
            if name == "mass":
                data["platform"]["mass"] = float(arr)
            elif name == "com":
                data["platform"]["center_of_mass"] = np.asarray(arr, float).tolist()
            else:
                for i, w in enumerate(data["wires"]):
                    w[field] = np.asarray(arr, float)[i].tolist()
        return Robot.load(data)

    def draw(self, rng: np.random.Generator, *, corner: bool = False) -> Robot:
        """A robot of the set: every toleranced number uniform in its interval (``corner``:
        at one of its two ends, each chosen at random)."""
        b = self.bounds()
        values: dict[str, Any] = {}
        for name in (*RobotIntervals.FIELDS, "mass"):
            lo, hi = (np.asarray(t, dtype=float) for t in getattr(b, name))
            if np.all(b.exact(name)):
                continue
            t = rng.integers(0, 2, lo.shape) if corner else rng.random(lo.shape)
            values[name] = np.clip(lo + t * (hi - lo), lo, hi)
        return self.realization(values)

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
