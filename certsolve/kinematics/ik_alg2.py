"""Algorithm 2 of Merlet (2007): fix wire(s), solve the square system, certify it.

Fix the control of ``m - w`` wires (default wire 1) from a mid-range tension (eq. 5), solve
the square system ``H_S τ_S(u_S) + c = 0`` in the other controls (Newton in the ``τ``
coordinates: one linear solve; or classical Newton in ``u`` with ``solve="newton"``), then
prove with the Krawczyk test (:meth:`.ik_enclose.SquareSystem.krawczyk`) that a small box
around the point holds exactly one solution.  Tension and stroke violations of the result
are reported.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from ..inputs import InputError
from ..robot.geometry import Pose
from ..robot.inputs import as_pose
from ..robot.model import Robot
from .ik_enclose import FreeWires, PoseEnclosure, SquareSystem, enclose_pose, free_wires, is_elastic
from .ik_inputs import check_pose, controls, overdetermined_note, require_elastic, search_window
from .ik_result import (
    LIMIT_TOL,
    IKResult,
    IKStatus,
    Violation,
    limit_violations,
    no_certificate,
    unique_in_box,
    window_violations,
)
from .ik_search import control_point
from .ik_tension import distribute_tensions

__all__ = ["Alg2Options", "Algorithm2", "fix_controls", "fixed_wires", "ik_algorithm2"]


@dataclass(kw_only=True, frozen=True)
class Alg2Options:
    """The options of :class:`Algorithm2` (documented there), checked."""

    fixed_wire: int | Sequence[int] = 1
    tau_fixed: float | Sequence[float] | None = None
    u_fixed: float | Sequence[float] | None = None
    solve: str = "tau"
    u_last: np.ndarray | None = None
    window: float | None = None
    box_radius: float = 1e-4
    certify: bool = True


def ik_algorithm2(robot: Robot, pose: Pose, **options: Any) -> IKResult:
    """Algorithm 2 at one pose (module docstring): the one-off form of :class:`Algorithm2`,
    whose options it takes and checks at every call.  ``pose`` is a
    :class:`~certsolve.robot.Pose`, taken as it is (:meth:`Algorithm2.solve` checks it)."""
    t0 = time.perf_counter()
    return Algorithm2(robot, **options)._solve(pose, t0)


class Algorithm2:
    """IK Algorithm 2 for one robot and one set of options, pose after pose (module
    docstring)::

        alg2 = Algorithm2(robot)  # or Algorithm2(robot, fixed_wire=3, tau_fixed=4.0)
        for pose in poses:
            res = alg2.solve(pose)

    ``fixed_wire``: 1-based wire(s) whose control is fixed (``m - w`` are needed; missing ones
    are chosen by pivoted QR).  Their control comes from ``u_fixed`` if given, else from eq. 5
    with ``tau_fixed`` (default: the middle of the wire's tension range).  ``solve="tau"``
    solves in the tension coordinates (exact, one linear solve); ``"newton"`` runs Newton in
    ``u`` from ``u_last`` (or the middle of the strokes).  ``window`` (cm, full width) with
    ``u_last``: controls outside ``u_last ± window/2`` are reported.  ``box_radius`` (cm,
    relative to ``1 + |u|``): half-width of the box proven to hold exactly one solution; a
    second, 1e-10-wide box proven at the same time gives the tight enclosure.

    The robot and the options are checked here, once (a ``ValueError`` names the option),
    and what depends only on them is worked out once (:class:`_Plan`: the fixed and free
    wires, the fixed wire's eq. 5 constant, the free wires' constants
    :class:`~.ik_enclose.FreeWires`, the limits); :meth:`solve` checks the pose
    (:func:`~certsolve.robot.inputs.as_pose`; a :class:`~certsolve.robot.Pose` of float64
    arrays is taken as it is, and refused at ``pose`` if it is not finite).  About 0.09 ms a
    pose on the MARIONET robots (``benchmarks/trajectory_bench.py``), where
    :func:`certsolve.inverse_kinematics` also validates its whole request at every call.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        fixed_wire: int | Sequence[int] = 1,
        tau_fixed: float | Sequence[float] | None = None,
        u_fixed: float | Sequence[float] | None = None,
        solve: str = "tau",
        u_last: ArrayLike | None = None,
        window: float | None = None,
        box_radius: float = 1e-4,
        certify: bool = True,
    ) -> None:
        if not is_elastic(robot):
            require_elastic(robot, "alg2")
        if solve not in ("tau", "newton"):
            raise ValueError(f"solve {solve!r}: expected tau or newton")
        if not box_radius > 0:
            raise ValueError("box_radius must be positive")
        if u_last is not None:
            _, _, u_last = search_window(robot, u_last, window)
        self.robot = robot
        self.options = Alg2Options(
            fixed_wire=fixed_wire,
            tau_fixed=tau_fixed,
            u_fixed=u_fixed,
            solve=solve,
            u_last=u_last,
            window=window,
            box_radius=box_radius,
            certify=certify,
        )
        d = robot.dim
        self._shapes = ((d,), (d, d))
        self._radii = np.array([[box_radius], [1e-10]])
        self._plan = _plan(robot, self.options)

    def solve(self, pose: Pose | ArrayLike | str) -> IKResult:
        """The controls holding the platform at ``pose`` (a :class:`~certsolve.robot.Pose`
        or pose parameters, cm and degrees), with this object's robot and options."""
        t0 = time.perf_counter()
        if not _plain_pose(pose, self._shapes):
            pose = as_pose(self.robot.dof, pose)
        # else: a Pose of float64 arrays of the right shapes; its finiteness is checked
        # only if its geometry is undefined (a NaN or an infinity makes it so), by as_pose
        return self._solve(pose, t0)  # type: ignore[arg-type]  # a Pose either way

    def _solve(self, pose: Pose, t0: float) -> IKResult:
        with np.errstate(all="ignore"):
            return _alg2(self, pose, t0)


_F8 = np.dtype(np.float64)
_ONE = np.array(1.0)  # 0-d: an array plus it is the same float as plus 1.0, faster
_all = np.logical_and.reduce  # of a 1-D array: .all() without the method's wrapper
_min = np.minimum.reduce
_max = np.maximum.reduce


def _plain_pose(pose: object, shapes: tuple[tuple[int, ...], tuple[int, ...]]) -> bool:
    """Whether ``pose`` is a :class:`Pose` whose arrays are float64 of the robot's shapes
    (what :func:`~certsolve.robot.inputs.as_pose` returns as it is when they are finite)."""
    if type(pose) is not Pose:
        return False
    p, R = pose.position, pose.rotation
    return (
        type(p) is np.ndarray
        and type(R) is np.ndarray
        and p.dtype == _F8
        and R.dtype == _F8
        and (p.shape, R.shape) == shapes
    )


@dataclass(kw_only=True, frozen=True)
class _OneFixed:
    """One fixed wire ``j`` (MARIONET, planar) in Python floats: its control is ``u`` if
    given, else ``a - W_j / K`` with ``a = k L0 / (K (k - τ_j))`` (eq. 5; ``W = ρ + V``)."""

    j: int
    k: float
    K: float
    L0: float
    a: float | None
    u: float | None

    def control(self, W: float) -> float:
        uj = self.u if self.u is not None else self.a - W / self.K  # type: ignore[operator]
        if not math.isfinite(uj):
            field = "u_fixed" if self.u is not None else "tau_fixed"
            raise InputError(field, "the fixed controls must be finite")
        return uj


@dataclass(kw_only=True, frozen=True)
class _Plan:
    """What Algorithm 2 does at every pose that depends only on the robot and the options:
    the fixed and free wires when they do not depend on the pose (``None`` otherwise), the
    free wires' constants and the fixed wire's, the bounds of the limits check."""

    split: tuple[np.ndarray, np.ndarray, FreeWires] | None  # (F, S, S's constants)
    one: _OneFixed | None
    lim_lo: np.ndarray
    lim_hi: np.ndarray


def _plan(robot: Robot, opts: Alg2Options) -> _Plan:
    m, w = robot.m, robot.wrench_dim
    lim_lo, lim_hi = _limits(robot)
    split = one = None
    fixed_wire = opts.fixed_wire
    if m == w + 1 and isinstance(fixed_wire, (int, np.integer)):
        j = int(fixed_wire) - 1
        if not 0 <= j < m:
            raise InputError("fixed_wire", f"wire {j + 1}: the robot has wires 1..{m}")
        F, S = robot.wire_splits[j]
        split = (F, S, free_wires(robot, S))
        if _scalar_options(opts):
            one = _one_fixed(robot, j, opts)
    return _Plan(split=split, one=one, lim_lo=lim_lo, lim_hi=lim_hi)


def _scalar_options(opts: Alg2Options) -> bool:
    """Whether ``u_fixed`` and ``tau_fixed`` are numbers (or not given)."""
    u_fixed, tau_fixed = opts.u_fixed, opts.tau_fixed
    return (u_fixed is None or np.ndim(u_fixed) == 0) and (
        tau_fixed is None or np.ndim(tau_fixed) == 0
    )


def _one_fixed(robot: Robot, j: int, opts: Alg2Options) -> _OneFixed:
    k, K, L0 = float(robot.k[j]), float(robot.K[j]), float(robot.L0[j])
    if opts.u_fixed is not None:
        uj = float(opts.u_fixed)  # type: ignore[arg-type]  # ndim 0: a number
        if not math.isfinite(uj):
            raise InputError("u_fixed", "the fixed controls must be finite")
        return _OneFixed(j=j, k=k, K=K, L0=L0, a=None, u=uj)
    tau_fixed = opts.tau_fixed
    tj = (
        0.5 * (float(robot.tau_min[j]) + float(robot.tau_max[j]))
        if tau_fixed is None
        else float(tau_fixed)  # type: ignore[arg-type]  # ndim 0, as u_fixed
    )
    if not tj < k:
        raise InputError("tau_fixed", "must be below the wire constant k")
    return _OneFixed(j=j, k=k, K=K, L0=L0, a=k * L0 / (K * (k - tj)), u=None)


def fixed_wires(H, fixed_wire, count: int) -> list[int]:
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
            raise InputError("fixed_wire", f"wire {j + 1}: the robot has wires 1..{m}")
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


def _split_wires(robot: Robot, Ht, fixed_wire, count):
    """(fixed, free) 0-based index arrays; one fixed wire reads :attr:`Robot.wire_splits`."""
    m = Ht.shape[0]
    if isinstance(fixed_wire, (int, np.integer)) and count == 1:
        j = int(fixed_wire) - 1
        if not 0 <= j < m:
            raise InputError("fixed_wire", f"wire {j + 1}: the robot has wires 1..{m}")
        return robot.wire_splits[j]
    F = fixed_wires(Ht.T, fixed_wire, count)
    return np.array(F, dtype=np.int64), np.array([j for j in range(m) if j not in F], np.int64)


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


def fix_controls(
    robot: Robot, enc: PoseEnclosure, F, opts: Alg2Options, one: _OneFixed | None = None
):
    """Controls ``u`` (fixed wires set, others 0) and ``c = w_g + H_F τ_F`` (eqs. 5, 6);
    ``one``: the fixed wire's constants when they were computed once (:func:`_plan`)."""
    m = robot.m
    Ht, wg = enc.Ht, enc.wg
    u = np.zeros(m)
    if one is None and F.size == 1 and _scalar_options(opts):
        one = _one_fixed(robot, int(F[0]), opts)
    if one is not None:  # one fixed wire (MARIONET, planar): scalar arithmetic
        j = one.j
        W = float(enc.W[j])
        uj = one.control(W)
        u[j] = uj
        Lj = W + one.K * uj
        return u, wg + (one.k * (Lj - one.L0) / Lj) * Ht[j]
    u_fixed, tau_fixed = opts.u_fixed, opts.tau_fixed
    if not F.size:
        return u, wg
    if u_fixed is not None:
        uf = np.broadcast_to(np.asarray(u_fixed, dtype=float), F.shape)
    else:
        tf = 0.5 * (robot.tau_min[F] + robot.tau_max[F]) if tau_fixed is None else tau_fixed
        tf = np.broadcast_to(np.asarray(tf, dtype=float), F.shape)
        if np.any(tf >= robot.k[F]):
            raise InputError("tau_fixed", "must be below the wire constant k")
        uf = control_point(robot, enc.rho[F], tf, F)
    if not np.all(np.isfinite(uf)):
        field = "u_fixed" if u_fixed is not None else "tau_fixed"
        raise InputError(field, "the fixed controls must be finite")
    u[F] = uf
    LF = enc.W[F] + robot.K[F] * u[F]
    tauF = robot.k[F] * (LF - robot.L0[F]) / LF
    return u, wg + tauF @ Ht[F]


def _limits(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """``(τ_min, u_min) - LIMIT_TOL`` and ``(τ_max, u_max) + LIMIT_TOL`` side by side: the
    bounds a result's ``(τ, u)`` is checked against, computed once per robot."""
    lim = robot.derived.get(__name__)
    if lim is None:
        tol = LIMIT_TOL
        lim = robot.derived[__name__] = (
            np.concatenate((robot.tau_min - tol, robot.u_min - tol)),
            np.concatenate((robot.tau_max + tol, robot.u_max + tol)),
        )
    return lim


def _tensions_beyond_k(robot: Robot, sq: SquareSystem, c, S) -> list[int]:
    """1-based wires whose tension in the square system's solution would reach ``k``."""
    tau_S = sq.G @ -c
    return [int(S[i]) + 1 for i in np.flatnonzero(~(tau_S < robot.k[S]))]


def _alg2(alg: Algorithm2, pose: Pose, t0: float) -> IKResult:
    robot, opts, plan = alg.robot, alg.options, alg._plan
    enc = enclose_pose(robot, pose.position, pose.rotation)
    if not enc.valid:
        as_pose(robot.dof, pose)  # InputError naming the pose if it is not finite
        check_pose(pose, enc)
    rho, Ht, wg = enc.rho, enc.Ht, enc.wg
    m, w = Ht.shape
    messages: list[str] = []
    details: dict = {"solve": opts.solve}

    def result(status, u, tau, violations, cert=None, f=None) -> IKResult:
        res = margin = None
        if tau is not None:
            res = float(_max(abs(tau @ Ht + wg if f is None else f)))
            margin = float(_min(np.minimum(tau - robot.tau_min, robot.tau_max - tau)))
        return IKResult(
            robot=robot.name,
            dof=robot.dof,
            method="alg2",
            pose=pose,
            status=status,
            feasible=status == IKStatus.OK,
            u=u,
            tau=tau,
            rho=rho,
            margin=margin,
            residual=res,
            violations=violations,
            messages=messages,
            details=details,
            certificate=no_certificate() if cert is None else cert,
            time=time.perf_counter() - t0,
        )

    if m < w:  # over-determined: unique tensions if any, nothing square to certify
        ch = distribute_tensions(Ht.T, wg, robot.tau_min, robot.tau_max)
        messages += ch.notes + [overdetermined_note(robot, w)]
        u = controls(robot, rho, ch.tau)
        viol = limit_violations(robot, ch.tau, u)
        status = IKStatus.NOT_EQUILIBRIUM if not ch.equilibrium else IKStatus.UNCERTIFIED
        return result(status, u, ch.tau, viol)

    if plan.split is not None:
        F, S, fw = plan.split
    else:
        F, S = _split_wires(robot, Ht, opts.fixed_wire, m - w)
        fw = free_wires(robot, S)
    details["fixed_wires"] = [int(j) + 1 for j in F]
    u, c = fix_controls(robot, enc, F, opts, plan.one)
    try:
        sq = SquareSystem(robot, enc, fw)
    except np.linalg.LinAlgError:
        messages.append(
            "the wrench matrix of the free wires is singular at this pose: fix another wire"
        )
        return result(IKStatus.SINGULAR, None, None, [])
    if opts.solve == "tau":
        tau_S = sq.G @ -c
        if not _all(tau_S < fw.kS):
            bad = _tensions_beyond_k(robot, sq, c, S)
            messages.append(f"no control: wires {bad} would need a tension >= k")
            return result(IKStatus.NO_SOLUTION, None, None, [])
        u_S = sq.controls(tau_S)
        details["iterations"] = 1
    else:
        u_last = opts.u_last
        u0 = u_last[S] if u_last is not None else 0.5 * (robot.u_min[S] + robot.u_max[S])
        u_S, its, conv = _newton_u(robot, rho, Ht[S].T, c, S, u0)
        details["iterations"] = its
        if not conv:
            messages.append(f"Newton did not converge in {its} iterations")
            bad = _tensions_beyond_k(robot, sq, c, S)
            if bad:
                messages.append(f"no control exists: wires {bad} would need a tension >= k")
            return result(IKStatus.NO_SOLUTION, None, None, [])
    sel = fw.sel
    u[sel] = u_S
    cert = None
    if opts.certify:
        # two nested boxes in one call: the large one for uniqueness, the small one for a
        # tight enclosure (u twice, not broadcast: BLAS takes another path for one row)
        radii = alg._radii * (np.abs(u_S) + _ONE)
        xlo, xhi, klo, khi, proven, tc, fc = sq.krawczyk(np.array([u, u]), radii)
        tau = tc[0]
        res_f = fc[0]
        if proven[0] or proven[1]:
            b = 0 if proven[0] else 1
            e = 1 if proven[1] else 0
            cert = unique_in_box(u, F, sel, xlo[b], xhi[b], klo[e], khi[e], xlo[e], xhi[e])
        else:
            messages.append("Krawczyk test failed: the solution is not certified")
    else:
        L = enc.W + robot.K * u
        tau = robot.k * (L - robot.L0) / L
        res_f = tau @ Ht + wg
    violations: list[Violation] = []
    tu = np.concatenate((tau, u))
    if not _all((plan.lim_lo <= tu) & (tu <= plan.lim_hi)):
        violations = limit_violations(robot, tau, u)
    if opts.u_last is not None and opts.window is not None:
        violations += window_violations(u, opts.u_last, opts.window)
    if opts.certify and cert is None:
        status = IKStatus.UNCERTIFIED
    else:
        status = IKStatus.LIMITS_VIOLATED if violations else IKStatus.OK
    return result(status, u, tau, violations, cert, res_f)
