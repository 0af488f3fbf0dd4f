"""What inverse kinematics answers: :class:`IKResult`, its certificate and limit violations.

Plain data, shared by the three methods (:mod:`.ik_first`, :mod:`.ik_alg1`, :mod:`.ik_alg2`)
and the sweep (:mod:`.ik_sweep`).  A *violation* is a tension outside ``[τ_min, τ_max]``, a
control outside its stroke ``[u_min, u_max]`` or outside the search window, by more than
:data:`LIMIT_TOL`; :func:`limit_violations` is the one place that lists them.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike

from ..robot.geometry import Pose
from ..robot.model import Robot

__all__ = [
    "IKStatus",
    "IKResult",
    "Certificate",
    "Violation",
    "LIMIT_TOL",
    "limit_violations",
    "window_violations",
    "no_certificate",
    "unique_in_box",
    "json_float",
    "json_floats",
    "box_list",
]

LIMIT_TOL = 1e-9  # N or cm: a limit is violated when exceeded by more than this


class IKStatus(StrEnum):
    """The outcome of one IK call (equal to its string: ``status == "ok"`` holds)."""

    OK = "ok"  # equilibrium, limits respected (and certified for alg1 / alg2)
    LIMITS_VIOLATED = "limits-violated"  # a tension or control outside its limits
    BOUNDARY = "boundary"  # the best tensions touch a limit (margin 0)
    INFEASIBLE = "infeasible"  # no admissible tension / proven: no control in the box
    NOT_EQUILIBRIUM = "not-equilibrium"  # over-determined pose that is no equilibrium
    NO_SOLUTION = "no-solution"  # no control can produce the tensions needed
    UNCERTIFIED = "uncertified"  # a point, but no proof
    SINGULAR = "singular"  # the free wires' wrench matrix is singular


def json_float(x: float) -> float | None:
    """JSON-ready float (None for NaN/inf)."""
    x = float(x)
    return x if np.isfinite(x) else None


def json_floats(a: ArrayLike | None) -> list[float | None] | None:
    return None if a is None else [json_float(v) for v in np.asarray(a, dtype=float)]


def box_list(lo: Iterable[float], hi: Iterable[float]) -> list[list[float]]:
    return [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]


def _jsonable(o):
    if isinstance(o, dict):
        return {str(k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return _jsonable(o.tolist())
    if isinstance(o, (bool, np.bool_)):
        return bool(o)
    if isinstance(o, (int, np.integer)):
        return int(o)
    if isinstance(o, (float, np.floating)):
        return json_float(o)
    return o


@dataclass(kw_only=True)
class Violation:
    """A limit exceeded by the returned tensions or controls."""

    wire: int  # 1-based wire number
    quantity: str  # "tau" (tension), "u" (stroke), "u-window" (search window)
    bound: str  # "min" | "max"
    value: float | None  # None: undefined (the tension would need to reach k)
    limit: float
    excess: float  # how far beyond the limit (> 0); inf when the value is undefined

    def to_dict(self) -> dict:
        return {
            "wire": self.wire,
            "index": self.wire - 1,
            "quantity": self.quantity,
            "bound": self.bound,
            "value": None if self.value is None else json_float(self.value),
            "limit": json_float(self.limit),
            "excess": json_float(self.excess),
        }

    def describe(self) -> str:
        what = {"tau": "tension", "u": "control", "u-window": "control"}[self.quantity]
        side = "below" if self.bound == "min" else "above"
        if self.value is None:
            return f"wire {self.wire}: {what} undefined (tension would reach k)"
        lim = {"tau": "tension limit", "u": "stroke", "u-window": "search window"}[self.quantity]
        unit = "N" if self.quantity == "tau" else "cm"
        return (
            f"wire {self.wire}: {what} {self.value:.6g} {unit} is {self.excess:.3g} {unit} "
            f"{side} the {lim} ({self.bound} {self.limit:.6g})"
        )


def _outside(values, lo, hi, quantity: str, tol: float) -> list[Violation]:
    """Every ``values[i]`` below ``lo[i] - tol`` or above ``hi[i] + tol``."""
    out = []
    below = np.flatnonzero(values < lo - tol)
    above = np.flatnonzero(values > hi + tol)
    for bound, idx in (("min", below), ("max", above)):
        for i in idx:
            limit = float(lo[i] if bound == "min" else hi[i])
            value = float(values[i])
            excess = limit - value if bound == "min" else value - limit
            out.append(
                Violation(
                    wire=int(i) + 1, quantity=quantity, bound=bound, value=value, limit=limit,
                    excess=excess,
                )
            )  # fmt: skip
    return out


def limit_violations(
    robot: Robot, tau: np.ndarray | None, u: np.ndarray | None, tol: float = LIMIT_TOL
) -> list[Violation]:
    """Every tension outside ``[τ_min, τ_max]`` and control outside its stroke (a NaN
    control -- the tension would reach ``k`` -- is reported as undefined)."""
    out: list[Violation] = []
    if tau is not None:
        out += _outside(np.asarray(tau, dtype=float), robot.tau_min, robot.tau_max, "tau", tol)
    if u is not None:
        u = np.asarray(u, dtype=float)
        for i in np.flatnonzero(~np.isfinite(u)):
            out.append(
                Violation(
                    wire=int(i) + 1, quantity="u", bound="max", value=None,
                    limit=float(robot.u_max[i]), excess=np.inf,
                )
            )  # fmt: skip
        out += _outside(u, robot.u_min, robot.u_max, "u", tol)
    out.sort(key=lambda v: (v.wire, v.quantity))
    return out


def window_violations(
    u: ArrayLike, u_last: np.ndarray, window: float, tol: float = LIMIT_TOL
) -> list[Violation]:
    """Every control outside the search window ``u_last ± window / 2``."""
    half = 0.5 * window
    out = _outside(np.asarray(u, dtype=float), u_last - half, u_last + half, "u-window", tol)
    return sorted(out, key=lambda v: v.wire)


@dataclass(kw_only=True)
class Certificate:
    """What was proved about the returned controls."""

    kind: str  # "unique-in-box" | "none"
    statement: str
    box: tuple[np.ndarray, np.ndarray] | None = None  # (m,) u: exactly one solution in it
    enclosure: tuple[np.ndarray, np.ndarray] | None = None  # (m,) u: the solution is in it
    fixed: dict[int, float] = field(default_factory=dict)  # wire (1-based) -> exact u

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "statement": self.statement,
            "box": None if self.box is None else box_list(*self.box),
            "enclosure": None if self.enclosure is None else box_list(*self.enclosure),
            "fixed": {str(k): float(v) for k, v in self.fixed.items()},
        }


def no_certificate() -> Certificate:
    return Certificate(kind="none", statement="floating-point result, not certified")


def unique_in_box(
    u: np.ndarray,
    F: np.ndarray,
    S: np.ndarray | slice,
    xlo: np.ndarray,
    xhi: np.ndarray,
    klo: np.ndarray,
    khi: np.ndarray,
    slo: np.ndarray | None = None,
    shi: np.ndarray | None = None,
) -> Certificate:
    """Certificate from the unicity box ``[xlo, xhi]`` and a Krawczyk image ``[klo, khi]`` of
    a box ``[slo, shi]`` (default: the same box) inside it, over the free wires ``S``; the
    wires ``F`` are fixed at ``u[F]``."""
    slo = xlo if slo is None else slo
    shi = xhi if shi is None else shi
    # the four bounds as the rows of one array (four copies of u, then the free wires)
    blo, bhi, elo, ehi = b = np.array((u, u, u, u))
    b[0, S], b[1, S], b[2, S], b[3, S] = xlo, xhi, np.maximum(klo, slo), np.minimum(khi, shi)
    fixed = {int(j) + 1: float(u[j]) for j in F}
    if fixed:
        fx = ", ".join(f"u_{j} = {v!r}" for j, v in fixed.items())
        stmt = (
            f"with {fx} fixed, the equilibrium equations have exactly one solution in the "
            "other controls inside 'box' (Krawczyk), and it lies in 'enclosure'"
        )
    else:
        stmt = (
            "the equilibrium equations have exactly one solution inside 'box' (Krawczyk), "
            "and it lies in 'enclosure'"
        )
    return Certificate(
        kind="unique-in-box", statement=stmt, box=(blo, bhi), enclosure=(elo, ehi), fixed=fixed
    )


@dataclass(kw_only=True)
class IKResult:
    """The controls (and tensions) that hold the platform at a pose, with what is known.

    ``status`` (:class:`IKStatus`): ``ok`` means equilibrium with every limit respected (and,
    for ``alg1`` / ``alg2``, a certified solution); ``feasible`` is ``status == "ok"``.
    ``u`` is ``None`` when unavailable (no elastic model, no solution).  ``margin`` is the
    smallest distance of ``τ`` to its limits (N; negative: violated), ``residual`` the max
    ``|H τ + w_g|`` at the returned tensions (float evaluation), ``time`` in seconds.
    """

    robot: str
    dof: int
    method: str
    pose: Pose
    status: IKStatus
    feasible: bool
    u: np.ndarray | None  # (m,) cm
    tau: np.ndarray | None  # (m,) N
    rho: np.ndarray  # (m,) cm
    margin: float | None = None
    residual: float | None = None
    violations: list[Violation] = field(default_factory=list)
    certificate: Certificate = field(default_factory=no_certificate)
    messages: list[str] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    time: float = 0.0

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "dof": self.dof,
            "method": self.method,
            "pose": [float(v) for v in self.pose.params(self.dof)],
            "status": str(self.status),
            "feasible": bool(self.feasible),
            "u": json_floats(self.u),
            "tau": json_floats(self.tau),
            "rho": json_floats(self.rho),
            "margin": None if self.margin is None else json_float(self.margin),
            "residual": None if self.residual is None else json_float(self.residual),
            "violations": [v.to_dict() for v in self.violations],
            "certificate": self.certificate.to_dict(),
            "messages": list(self.messages),
            "details": _jsonable(self.details),
            "time": float(self.time),
        }
