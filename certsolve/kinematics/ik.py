"""Inverse kinematics of wire robots with elastic wires (Merlet 2007, section II.A).

Given a pose, find the actuator controls ``u`` such that the platform is in equilibrium:
``H(pose) τ(u) + w_g = 0`` with ``τ_i(u_i)`` from eq. (6), tensions within ``[τ_min, τ_max]``
and controls within the strokes ``[u_min, u_max]``.  Three methods,
:func:`inverse_kinematics` ``(robot, pose, method=...)``:

``"tension"`` (tension first)
    choose the tensions (max-margin distribution: exact closed form on the line of solutions
    when ``m = w + 1``, the LP otherwise; :mod:`.ik_tension`), then ``u`` by eq. (5).  Limits
    on ``τ`` hold by construction when the pose is wrench-feasible; strokes are *checked* and
    every ``u`` outside its stroke is reported.  No certificate (floating point).
``"alg1"`` (Algorithm 1)
    interval branch and prune on the under-constrained system in ``u`` inside the strokes (or a
    window around the last ``u``) and the tension limits, stopping at the first certified
    solution (:mod:`.ik_search`).  Can also *prove* that no solution exists in the box.
``"alg2"`` (Algorithm 2)
    fix the control of one wire (default wire 1) from a mid-range tension (eq. 5), solve the
    square system in the others (Newton in the ``τ`` coordinates: one linear solve; or
    classical Newton in ``u`` with ``solve="newton"``), then prove with the Krawczyk test that
    a 1 µm box around the point holds exactly one solution (:mod:`.ik_enclose`).  Tension and
    stroke violations of the result are reported.

**Algorithm 1, design** (details in :mod:`.ik_search`): ``τ_i`` depends on ``u_i`` alone and
is increasing, so boxes of ``u`` and boxes of ``τ`` correspond one to one and the equations are
*linear* in ``τ``.  The branch and prune runs on tension boxes (image of the strokes or window,
intersected with the tension limits): a preconditioned interval Gauss–Seidel contraction
(proves boxes empty), then a certification attempt per box -- the ``m - w`` parametric wires
(left out of the basis by a pivoted QR of ``H``) are fixed at the controls of the box's
mid-tensions, the other controls follow from one linear solve, and the Krawczyk test proves
that exactly one solution of the square system in the other controls lies in a 1e-6 cm box,
inside the strokes/window with tensions within limits -- then bisection.  The fixed controls
are exact floats, so the certified point is an exact solution of the under-constrained system.
For MARIONET the contraction is nearly exact and the root box is certified (or proved empty)
in one round.

Certificates are proofs about the equations for the pose *as given in floating point*
(position ``p`` and the float rotation matrix ``R``) and the robot's floats: every rounding
error of the geometry, of eq. (6) and of the Krawczyk operator is bounded.

Wire numbers in results and options are **1-based** (``u_1 … u_m`` as in the paper; wire
``i`` is ``wires[i-1]`` in the robot file).  Units: cm, N, degrees at the user boundary.

Robots: dof 6 with 7 wires (MARIONET, T-platform; 1-D null space), dof 3 with 4 wires
(planar; no gravity in the plane, so ``τ = λ v``), dof 6 with 4 wires (almost planar: 6
equations for 4 tensions, over-determined -- a generic pose is *not* an equilibrium and the
result says so; at a pose that is, the tensions are unique), dof 2 (Krut: no elastic model,
tensions only).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..robot.geometry import Pose
from ..robot.model import Robot
from ..robot.schema import RobotFileError
from .ik_enclose import SquareSystem, enclose_pose, float_geometry, is_elastic, tension_mr
from .ik_search import control_point, search_controls
from .ik_tension import distribute_tensions, margin_of

__all__ = [
    "IKResult",
    "Certificate",
    "Violation",
    "inverse_kinematics",
    "ik_tension_first",
    "ik_algorithm1",
    "ik_algorithm2",
    "METHODS",
    "LIMIT_TOL",
]

METHODS = ("tension", "alg1", "alg2")
LIMIT_TOL = 1e-9  # N or cm: a limit is violated when exceeded by more than this


def _fl(x):
    """JSON-ready float (None for NaN/inf)."""
    x = float(x)
    return x if np.isfinite(x) else None


def _fl_list(a):
    return None if a is None else [_fl(v) for v in np.asarray(a, dtype=float)]


def _box_list(lo, hi):
    return [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]


@dataclass
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
            "value": None if self.value is None else _fl(self.value),
            "limit": _fl(self.limit),
            "excess": _fl(self.excess),
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


@dataclass
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
            "box": None if self.box is None else _box_list(*self.box),
            "enclosure": None if self.enclosure is None else _box_list(*self.enclosure),
            "fixed": {str(k): float(v) for k, v in self.fixed.items()},
        }


def _no_cert() -> Certificate:
    return Certificate("none", "floating-point result, not certified")


@dataclass
class IKResult:
    """The controls (and tensions) that hold the platform at a pose, with what is known."""

    robot: str
    dof: int
    method: str
    pose: Pose
    status: str  # ok | limits-violated | boundary | infeasible | not-equilibrium |
    #              no-solution | uncertified | singular
    feasible: bool  # equilibrium, all tensions and controls within limits (and, for alg1 /
    #                 alg2, a certified solution)
    u: np.ndarray | None  # (m,) cm; None when unavailable (no elastic model, no solution)
    tau: np.ndarray | None  # (m,) N
    rho: np.ndarray  # (m,) cm
    margin: float | None  # smallest distance of τ to its limits (N); negative: violated
    residual: float | None  # max |H τ + w_g| at the returned tensions (float evaluation)
    violations: list[Violation] = field(default_factory=list)
    certificate: Certificate = field(default_factory=lambda: _no_cert())
    messages: list[str] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    time: float = 0.0  # seconds

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "dof": self.dof,
            "method": self.method,
            "pose": [float(v) for v in self.pose.params(self.dof)],
            "status": self.status,
            "feasible": bool(self.feasible),
            "u": _fl_list(self.u),
            "tau": _fl_list(self.tau),
            "rho": _fl_list(self.rho),
            "margin": None if self.margin is None else _fl(self.margin),
            "residual": None if self.residual is None else _fl(self.residual),
            "violations": [v.to_dict() for v in self.violations],
            "certificate": self.certificate.to_dict(),
            "messages": list(self.messages),
            "details": _jsonable(self.details),
            "time": float(self.time),
        }


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
        return _fl(o)
    return o


# -- helpers -----------------------------------------------------------------------------------
def _as_pose(robot: Robot, pose) -> Pose:
    """A :class:`Pose` with float64 arrays of the robot's dimension (finiteness is checked
    by the geometry: a non-finite pose gives an invalid enclosure)."""
    if isinstance(pose, Pose):
        p, R = pose.position, pose.rotation
        d = robot.dim
        if (
            type(p) is np.ndarray
            and type(R) is np.ndarray
            and p.shape == (d,)
            and R.shape == (d, d)
            and p.dtype == np.float64
            and R.dtype == np.float64
        ):
            return pose
        p = np.asarray(p, dtype=float)
        R = np.asarray(R, dtype=float)
        if p.shape != (d,) or R.shape != (d, d):
            raise ValueError(
                f"pose: robot {robot.name!r} (dof {robot.dof}) needs a {d}-D position and "
                f"a {d}x{d} rotation"
            )
        return Pose(p, R)
    if isinstance(pose, str):
        from ..robot.geometry import parse_pose

        return _as_pose(robot, parse_pose(robot.dof, pose))
    return _as_pose(robot, Pose.from_params(robot.dof, list(pose)))


def _check_pose(pose: Pose, enc) -> None:
    """Clear errors for a pose whose geometry is undefined."""
    if enc.valid:
        return
    if not (np.all(np.isfinite(pose.position)) and np.all(np.isfinite(pose.rotation))):
        raise ValueError("pose: position and rotation must be finite")
    raise ValueError("pose: a platform attachment coincides with its base anchor (ρ = 0)")


def _as_robot(robot) -> Robot:
    return robot if isinstance(robot, Robot) else Robot.load(robot)


def limit_violations(robot: Robot, tau, u, tol: float = LIMIT_TOL) -> list[Violation]:
    """Every tension outside ``[τ_min, τ_max]`` and control outside its stroke."""
    out: list[Violation] = []
    if tau is not None:
        tau = np.asarray(tau, dtype=float)
        for i in np.flatnonzero(tau < robot.tau_min - tol):
            out.append(
                Violation(
                    int(i) + 1, "tau", "min", float(tau[i]), float(robot.tau_min[i]),
                    float(robot.tau_min[i] - tau[i]),
                )
            )  # fmt: skip
        for i in np.flatnonzero(tau > robot.tau_max + tol):
            out.append(
                Violation(
                    int(i) + 1, "tau", "max", float(tau[i]), float(robot.tau_max[i]),
                    float(tau[i] - robot.tau_max[i]),
                )
            )  # fmt: skip
    if u is not None:
        u = np.asarray(u, dtype=float)
        for i in np.flatnonzero(~np.isfinite(u)):
            out.append(Violation(int(i) + 1, "u", "max", None, float(robot.u_max[i]), np.inf))
        for i in np.flatnonzero(u < robot.u_min - tol):
            out.append(
                Violation(
                    int(i) + 1, "u", "min", float(u[i]), float(robot.u_min[i]),
                    float(robot.u_min[i] - u[i]),
                )
            )  # fmt: skip
        for i in np.flatnonzero(u > robot.u_max + tol):
            out.append(
                Violation(
                    int(i) + 1, "u", "max", float(u[i]), float(robot.u_max[i]),
                    float(u[i] - robot.u_max[i]),
                )
            )  # fmt: skip
    out.sort(key=lambda v: (v.wire, v.quantity))
    return out


def _controls(robot: Robot, rho, tau):
    """Eq. (5); NaN where the tension reaches ``k`` (no length can produce it)."""
    u = control_point(robot, rho, tau)
    return np.where(tau < robot.k, u, np.nan)


def _window(robot: Robot, u_last, window):
    """Control box: strokes ∩ ``u_last ± window / 2`` (window in cm, full width)."""
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


def _require_elastic(robot: Robot, method: str) -> None:
    try:
        robot.require_elastic(f"inverse kinematics {method}")
    except RobotFileError as exc:
        raise RobotFileError(
            f"robot {robot.name!r} has no elastic wire model ({exc}); method {method} needs "
            "k, K, V, L0 and the stroke u of every wire -- use method 'tension' for the "
            "tensions only"
        ) from None


def _overdetermined_note(robot: Robot, w: int) -> str:
    return (
        f"{w} equilibrium equations for {robot.m} tensions: the pose is over-determined; "
        "it is an equilibrium only at poses the robot can reach (forward kinematics), and "
        "such a solution cannot be certified by a square Krawczyk test"
    )


# -- tension first -----------------------------------------------------------------------------
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
            _check_pose(pose, enclose_pose(robot, pose.position, pose.rotation))
    ch = distribute_tensions(
        H, wg, robot.tau_min, robot.tau_max, mode=distribution, check_lp=check_lp
    )
    messages = list(ch.notes)
    elastic = is_elastic(robot)
    tau = ch.tau if np.all(np.isfinite(ch.tau)) else None
    u = None
    if elastic and tau is not None:
        u = _controls(robot, rho, tau)
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
        messages.append(_overdetermined_note(robot, H.shape[0]))
        if ch.equilibrium:
            messages.append(
                f"the pose is an equilibrium up to a residual of {ch.residual:.3g} "
                "(checked numerically, relative tolerance 1e-9)"
            )
    if not ch.equilibrium:
        status = "not-equilibrium"
    elif ch.margin < -LIMIT_TOL:
        status = "infeasible"
        messages.append(
            f"no admissible tension: the best distribution misses the limits by "
            f"{-ch.margin:.4g} N (the pose is outside the wrench-feasible workspace)"
        )
    elif ch.margin <= LIMIT_TOL:
        status = "boundary"
        messages.append(
            "the best tensions touch a limit (margin 0): the pose is on the boundary of the "
            "wrench-feasible workspace" + (" (all wires slack)" if not np.any(ch.tau) else "")
        )
    else:
        status = "limits-violated" if violations else "ok"
        if u is not None and violations:
            messages.append("tensions are admissible but some controls are outside the strokes")
    return IKResult(
        robot.name,
        robot.dof,
        "tension",
        pose,
        status,
        status == "ok",
        u,
        tau,
        rho,
        ch.margin if np.isfinite(ch.margin) else None,
        ch.residual if np.isfinite(ch.residual) else None,
        violations,
        _no_cert(),
        messages,
        details,
        time.perf_counter() - t0,
    )


# -- Algorithm 2 -------------------------------------------------------------------------------
def _fixed_wires(H, fixed_wire, count: int) -> list[int]:
    """``count`` 0-based wires to fix: the requested ones, completed by pivoted QR."""
    m = H.shape[1]
    if fixed_wire is None:
        given = [0]
    elif isinstance(fixed_wire, (int, np.integer)):
        given = [int(fixed_wire) - 1]
    else:
        given = [int(j) - 1 for j in fixed_wire]
    for j in given:
        if not 0 <= j < m:
            raise ValueError(f"fixed wire {j + 1}: the robot has wires 1..{m}")
    if len(set(given)) != len(given):
        raise ValueError("fixed wires must be distinct")
    if count <= 0:
        return []
    if len(given) > count:
        raise ValueError(
            f"{len(given)} fixed wires requested, but only {count} can be fixed "
            f"({m} wires, {H.shape[0]} equations)"
        )
    if len(given) < count:
        rest = [j for j in range(m) if j not in given]
        _, _, piv = scipy.linalg.qr(H[:, rest], pivoting=True, mode="economic")
        given += [rest[j] for j in piv[H.shape[0] :][: count - len(given)]]
    return sorted(given)


def _newton_u(robot, rho, H_S, c, S, u0, max_iter=30):
    """Classical Newton on ``H_S τ_S(u_S) + c = 0``; Jacobian ``H_S diag(τ')``.

    Returns ``(u, iterations, converged)``; a singular Jacobian or a wire length <= 0 along
    the way stops it (not converged).
    """
    k, K, V, L0 = robot.k[S], robot.K[S], robot.V[S], robot.L0[S]
    W = rho[S] + V
    u = np.array(u0, dtype=float)
    for it in range(1, max_iter + 1):
        L = W + K * u
        if not (L.min() > 0.0):
            return u, it, False
        tau = k * (L - L0) / L
        f = H_S @ tau + c
        J = H_S * (k * L0 * K / (L * L))
        try:
            step = np.linalg.solve(J, f)
        except np.linalg.LinAlgError:
            return u, it, False
        u = u - step
        if not np.isfinite(u).all():
            return u, it, False
        if (np.abs(step) <= 1e-13 * (1.0 + np.abs(u))).all():
            return u, it, True
    return u, max_iter, False


def ik_algorithm2(
    robot: Robot,
    pose: Pose,
    *,
    fixed_wire: int | Sequence[int] = 1,
    tau_fixed: float | Sequence[float] | None = None,
    u_fixed: float | Sequence[float] | None = None,
    solve: str = "tau",
    u_last=None,
    window: float | None = None,
    box_radius: float = 1e-4,
    certify: bool = True,
) -> IKResult:
    """Algorithm 2: fix wire(s), solve the square system, certify (module docstring).

    ``fixed_wire``: 1-based wire(s) whose control is fixed (``m - w`` are needed; missing ones
    are chosen by pivoted QR).  Their control comes from ``u_fixed`` if given, else from eq. 5
    with ``tau_fixed`` (default: the middle of the wire's tension range).  ``solve="tau"``
    solves in the tension coordinates (exact, one linear solve); ``"newton"`` runs Newton in
    ``u`` from ``u_last`` (or the middle of the strokes).  ``window`` (cm, full width) with
    ``u_last``: controls outside ``u_last ± window/2`` are reported.  ``box_radius`` (cm,
    relative to ``1 + |u|``): half-width of the box proven to hold exactly one solution; a
    second, 1e-10-wide box proven at the same time gives the tight enclosure.
    """
    t0 = time.perf_counter()
    if not is_elastic(robot):
        _require_elastic(robot, "alg2")
    if solve not in ("tau", "newton"):
        raise ValueError(f"solve {solve!r}: expected tau or newton")
    if not box_radius > 0:
        raise ValueError("box_radius must be positive")
    if u_last is not None:
        _, _, u_last = _window(robot, u_last, window)
    with np.errstate(all="ignore"):
        return _alg2(
            robot, pose, t0, fixed_wire, tau_fixed, u_fixed, solve, u_last, window,
            box_radius, certify,
        )  # fmt: skip


def _alg2(robot, pose, t0, fixed_wire, tau_fixed, u_fixed, solve, u_last, window, rad, certify):
    enc = enclose_pose(robot, pose.position, pose.rotation)
    _check_pose(pose, enc)
    rho, Ht, wg = enc.rho, enc.Ht, enc.wg
    m, w = Ht.shape
    messages: list[str] = []
    details: dict = {"solve": solve}

    def result(status, u, tau, violations, cert=None, f=None):
        res = margin = None
        if tau is not None:
            res = float(np.abs(tau @ Ht + wg if f is None else f).max())
            margin = float(np.minimum(tau - robot.tau_min, robot.tau_max - tau).min())
        return IKResult(
            robot.name, robot.dof, "alg2", pose, status, status == "ok", u, tau, rho, margin,
            res, violations, cert or _no_cert(), messages, details, time.perf_counter() - t0,
        )  # fmt: skip

    if m < w:  # over-determined: unique tensions if any, nothing square to certify
        ch = distribute_tensions(Ht.T, wg, robot.tau_min, robot.tau_max)
        messages += ch.notes + [_overdetermined_note(robot, w)]
        u = _controls(robot, rho, ch.tau)
        viol = limit_violations(robot, ch.tau, u)
        status = "not-equilibrium" if not ch.equilibrium else "uncertified"
        return result(status, u, ch.tau, viol)

    F, S = _split_wires(Ht, fixed_wire, m - w)
    details["fixed_wires"] = [int(j) + 1 for j in F]
    u = np.zeros(m)
    if F.size == 1 and (u_fixed is None or np.ndim(u_fixed) == 0) and np.ndim(tau_fixed) == 0:
        # one fixed wire (MARIONET, planar): scalar arithmetic
        j = int(F[0])
        k, K, L0, W = float(robot.k[j]), float(robot.K[j]), float(robot.L0[j]), float(enc.W[j])
        if u_fixed is not None:
            uj = float(u_fixed)
        else:
            tj = (
                0.5 * (float(robot.tau_min[j]) + float(robot.tau_max[j]))
                if tau_fixed is None
                else float(tau_fixed)
            )
            if not tj < k:
                raise ValueError("tau_fixed must be below the wire constant k")
            uj = k * L0 / (K * (k - tj)) - W / K
        if not math.isfinite(uj):
            raise ValueError("fixed controls must be finite")
        u[j] = uj
        Lj = W + K * uj
        c = wg + (k * (Lj - L0) / Lj) * Ht[j]
    elif F.size:
        if u_fixed is not None:
            uf = np.broadcast_to(np.asarray(u_fixed, dtype=float), F.shape)
        else:
            tf = 0.5 * (robot.tau_min[F] + robot.tau_max[F]) if tau_fixed is None else tau_fixed
            tf = np.broadcast_to(np.asarray(tf, dtype=float), F.shape)
            if np.any(tf >= robot.k[F]):
                raise ValueError("tau_fixed must be below the wire constant k")
            uf = control_point(robot, rho[F], tf, F)
        if not np.all(np.isfinite(uf)):
            raise ValueError("fixed controls must be finite")
        u[F] = uf
        LF = enc.W[F] + robot.K[F] * u[F]
        tauF = robot.k[F] * (LF - robot.L0[F]) / LF
        c = wg + tauF @ Ht[F]
    else:
        c = wg
    try:
        sq = SquareSystem(robot, enc, S)
    except np.linalg.LinAlgError:
        messages.append(
            "the wrench matrix of the free wires is singular at this pose: fix another wire"
        )
        return result("singular", None, None, [])
    if solve == "tau":
        tau_S = sq.G @ -c
        if not (tau_S < robot.k[S]).all():
            bad = [int(S[i]) + 1 for i in np.flatnonzero(~(tau_S < robot.k[S]))]
            messages.append(f"no control: wires {bad} would need a tension >= k")
            return result("no-solution", None, None, [])
        u_S = sq.controls(tau_S)
        details["iterations"] = 1
    else:
        u0 = u_last[S] if u_last is not None else 0.5 * (robot.u_min[S] + robot.u_max[S])
        u_S, its, conv = _newton_u(robot, rho, Ht[S].T, c, S, u0)
        details["iterations"] = its
        if not conv:
            messages.append(f"Newton did not converge in {its} iterations")
            tau_S = sq.G @ -c
            if not (tau_S < robot.k[S]).all():
                bad = [int(S[i]) + 1 for i in np.flatnonzero(~(tau_S < robot.k[S]))]
                messages.append(f"no control exists: wires {bad} would need a tension >= k")
            return result("no-solution", None, None, [])
    u[S] = u_S
    cert = None
    if certify:
        # two nested boxes in one call: the large one for uniqueness, the small one for a
        # tight enclosure
        au = 1.0 + np.abs(u_S)
        radii = np.stack([rad * au, 1e-10 * au])
        xlo, xhi, klo, khi, proven, tc, fc = sq.krawczyk(np.stack([u, u]), radii)
        tau = tc[0]
        res_f = fc[0]
        if proven[0] or proven[1]:
            b = 0 if proven[0] else 1
            e = 1 if proven[1] else 0
            cert = _certificate(u, F, S, xlo[b], xhi[b], klo[e], khi[e], xlo[e], xhi[e])
        else:
            messages.append("Krawczyk test failed: the solution is not certified")
    else:
        L = enc.W + robot.K * u
        tau = robot.k * (L - robot.L0) / L
        res_f = tau @ Ht + wg
    tol = LIMIT_TOL
    if not (
        (tau >= robot.tau_min - tol)
        & (tau <= robot.tau_max + tol)
        & (u >= robot.u_min - tol)
        & (u <= robot.u_max + tol)
    ).all():
        violations = limit_violations(robot, tau, u)
    else:
        violations = []
    if u_last is not None and window is not None:
        violations += _window_violations(u, u_last, window)
    if certify and cert is None:
        status = "uncertified"
    else:
        status = "limits-violated" if violations else "ok"
    return result(status, u, tau, violations, cert, res_f)


def _window_violations(u, u_last, window) -> list[Violation]:
    out = []
    half = 0.5 * window
    for i in range(u.size):
        if u[i] < u_last[i] - half - LIMIT_TOL:
            lim = u_last[i] - half
            out.append(Violation(i + 1, "u-window", "min", float(u[i]), lim, lim - u[i]))
        elif u[i] > u_last[i] + half + LIMIT_TOL:
            lim = u_last[i] + half
            out.append(Violation(i + 1, "u-window", "max", float(u[i]), lim, u[i] - lim))
    return out


_SPLIT_CACHE: dict = {}


def _split_wires(Ht, fixed_wire, count):
    """(fixed, free) 0-based index arrays; the common single-wire case is cached."""
    m = Ht.shape[0]
    if isinstance(fixed_wire, (int, np.integer)) and count == 1:
        key = (m, int(fixed_wire))
        hit = _SPLIT_CACHE.get(key)
        if hit is None:
            j = int(fixed_wire) - 1
            if not 0 <= j < m:
                raise ValueError(f"fixed wire {j + 1}: the robot has wires 1..{m}")
            hit = (np.array([j]), np.array([i for i in range(m) if i != j]))
            _SPLIT_CACHE[key] = hit
        return hit
    F = _fixed_wires(Ht.T, fixed_wire, count)
    return np.array(F, dtype=np.int64), np.array([j for j in range(m) if j not in F], np.int64)


def _certificate(u, F, S, xlo, xhi, klo, khi, slo=None, shi=None) -> Certificate:
    """Certificate from the unicity box ``[xlo, xhi]`` and a Krawczyk image ``[klo, khi]`` of
    a box ``[slo, shi]`` (default: the same box) inside it."""
    if slo is None:
        slo, shi = xlo, xhi
    blo, bhi = u.copy(), u.copy()
    blo[S], bhi[S] = xlo, xhi
    elo, ehi = u.copy(), u.copy()
    elo[S], ehi[S] = np.maximum(klo, slo), np.minimum(khi, shi)
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
    return Certificate("unique-in-box", stmt, (blo, bhi), (elo, ehi), fixed)


# -- Algorithm 1 -------------------------------------------------------------------------------
def ik_algorithm1(
    robot: Robot,
    pose: Pose,
    *,
    u_last=None,
    window: float | None = None,
    max_boxes: int = 20000,
    timeout: float | None = 10.0,
    eps: float = 1e-9,
    box_radius: float = 1e-6,
) -> IKResult:
    """Algorithm 1: first certified solution in the strokes, or in ``u_last ± window/2``.

    ``window`` (cm, full width) defaults to 0.1 (1 mm) when ``u_last`` is given.
    """
    t0 = time.perf_counter()
    if not is_elastic(robot):
        _require_elastic(robot, "alg1")
    if u_last is not None and window is None:
        window = 0.1
    ulo, uhi, u_last = _window(robot, u_last, window)
    with np.errstate(all="ignore"):
        enc = enclose_pose(robot, pose.position, pose.rotation)
    _check_pose(pose, enc)
    rho, H, wg = enc.rho, enc.H, enc.wg
    w, m = H.shape
    out = search_controls(
        robot, enc, ulo, uhi, max_boxes=max_boxes, timeout=timeout, eps=eps, box_radius=box_radius
    )
    details = {
        "domain": _box_list(ulo, uhi),
        "boxes": out.boxes,
        "rounds": out.rounds,
        "search_time": out.time,
        "parametric_wires": [j + 1 for j in out.params],
    }
    if out.verdict == "unknown":
        details["stopped_by"] = str(out.status)
    messages: list[str] = []
    where = "the strokes" if u_last is None else f"the {window:g} cm window around u_last"
    u = tau = margin = res = None
    cert = _no_cert()
    violations: list[Violation] = []
    if out.verdict == "certified":
        u = out.u
        tau, _ = tension_mr(robot, enc, u)
        margin = margin_of(tau, robot.tau_min, robot.tau_max)
        res = float(np.max(np.abs(H @ tau + wg)))
        F = np.array(out.params, dtype=np.int64)
        S = np.array([j for j in range(m) if j not in out.params], dtype=np.int64)
        cert = _certificate(u, F, S, out.box_lo[S], out.box_hi[S], out.enc_lo[S], out.enc_hi[S])
        violations = limit_violations(robot, tau, u)
        status = "limits-violated" if violations else "ok"
    elif out.verdict == "infeasible":
        status = "infeasible"
        messages.append(
            f"proved: no control vector in {where} holds the platform at this pose with "
            "tensions within their limits"
        )
    else:
        status = "uncertified"
        if m < w:
            messages.append(_overdetermined_note(robot, w))
        if out.undecided:
            lo, hi = out.undecided[0]
            tau = 0.5 * lo + 0.5 * hi
            u = _controls(robot, rho, tau)
            margin = margin_of(tau, robot.tau_min, robot.tau_max)
            res = float(np.max(np.abs(H @ tau + wg)))
            details["undecided_tension_boxes"] = [_box_list(a, b) for a, b in out.undecided]
            messages.append(
                f"{len(out.undecided)} undecided box(es) of width < eps: a solution may exist "
                "there (returned: the centre of the first one, not certified)"
            )
        else:
            messages.append(f"search stopped ({out.status}) before a certified solution")
    return IKResult(
        robot.name, robot.dof, "alg1", pose, status, status == "ok", u, tau, rho, margin, res,
        violations, cert, messages, details, time.perf_counter() - t0,
    )  # fmt: skip


# -- entry point -------------------------------------------------------------------------------
def inverse_kinematics(robot, pose, method: str = "tension", **options) -> IKResult:
    """Controls (and tensions) holding the platform at ``pose``.

    ``robot``: :class:`~certsolve.robot.Robot` (or anything :meth:`Robot.load` accepts);
    ``pose``: :class:`~certsolve.robot.Pose`, a parameter list (``x,y,z,yaw,pitch,roll`` in
    cm and degrees; planar ``x,y,theta``; point ``x,y``) or the same as a string.
    ``method``: ``"tension"`` (options ``distribution``, ``check_lp``), ``"alg1"`` (``u_last``,
    ``window``, ``max_boxes``, ``timeout``, ``eps``, ``box_radius``) or ``"alg2"``
    (``fixed_wire``, ``tau_fixed``, ``u_fixed``, ``solve``, ``u_last``, ``window``,
    ``box_radius``, ``certify``).  Robots without the elastic model support only
    ``"tension"`` (Algorithms 1 and 2 raise :class:`~certsolve.robot.RobotFileError`).
    """
    robot = _as_robot(robot)
    pose = _as_pose(robot, pose)
    if method == "tension":
        return ik_tension_first(robot, pose, **options)
    if method == "alg1":
        return ik_algorithm1(robot, pose, **options)
    if method == "alg2":
        return ik_algorithm2(robot, pose, **options)
    raise ValueError(f"method {method!r}: expected one of {', '.join(METHODS)}")
