"""Inverse kinematics of a robot known within tolerances: control intervals for every robot.

A robot file with ``tolerances`` (:mod:`certsolve.robot.tolerance`) describes a *set* of
robots.  At a pose ``P`` (the position and the float rotation matrix, as every IK
certificate reads it), each robot ``r`` of the set has its own statics (Merlet 2007,
eqs. 3-4)::

    H(P; A, B) τ = -w_g(mass, com),

``w`` equations in ``m >= w`` tensions, and its own controls from eq. 5.  No single control
vector holds the pose for every robot (each robot with the same ``u`` has its own
equilibrium: forward kinematics gives the set's pose box); the answer is a **control
interval per wire** holding every robot's control, for one tension *distribution* that
every robot follows:

``method="tension"``
    ``m - w`` wires (the last ones of a pivoted QR of the nominal ``H``: the others are the
    best-conditioned basis) are held at fixed tensions ``τ_F``, the same for every robot:
    first the nominal robot's max-margin tensions (:mod:`.ik_tension`, the ``tension``
    method's answer, so a set of one robot gives the nominal answer); when that does not
    prove every limit, with one fixed wire, the value of ``τ_F`` with the largest proven
    margin: a batch of 32 values across its tension range, then two finer batches around
    the best.
``method="alg2"``
    Algorithm 2's fixed wire(s) at one fixed *control* ``u_F`` (``u_fixed``, or eq. 5 on
    the nominal robot from ``tau_fixed``, default the middle of the range, as
    :func:`.ik_algorithm2`): the same control for every robot, whose tension ``τ_F``
    (eq. 6) is then an interval over the set.

The free wires' tensions of every robot are enclosed by :mod:`.ik_set_statics` (the
Krawczyk operator of the set's linear statics, in a mean-value form in the anchors and
attachments).

The controls follow from eq. 2 and eq. 1 solved for the length, each number once::

    L_i = L0_i / (1 - τ_i / k_i),     u_i = (L_i - ρ_i - V_i) / K_i,

in interval arithmetic over ``τ``, ``k``, ``L0``, ``V``, ``K`` and ``ρ`` (the control is
undefined where ``τ_i`` may reach ``k_i``).  **What is proven**: for every robot of the
set, the distribution has exactly one tension vector, inside the reported tension
bounds, and the control of each wire that gives it lies in its interval; ``ok`` means
every tension bound lies within ``[τ_min, τ_max]`` and every control interval within the
stroke.  A bound that fails is reported per wire (:class:`.Violation`) with the worst
case of the enclosure -- an upper bound of the set's worst case: the violation is certain
(for the nominal robot) only where ``details["set"]["nominal_tau"]`` violates it too.  The
result's ``u`` is the middle of the intervals: one control vector to send, which proves
nothing about the pose of a robot of the set.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg

from ..inputs import InputError
from ..interval import arith
from ..interval.core import Pair, midpoint
from ..interval.rounding import down
from ..robot.geometry import Pose
from ..robot.model import Robot
from .ik_alg2 import Alg2Options, fix_controls, fixed_wires
from .ik_enclose import enclose_pose, is_elastic
from .ik_inputs import check_pose, require_elastic, search_window
from .ik_result import (
    LIMIT_TOL,
    Certificate,
    IKResult,
    IKStatus,
    Violation,
    limit_violations,
    window_violations,
)
from .ik_set_statics import SetStatics, SetSystem, set_statics, solve_linear_set
from .ik_tension import distribute_tensions

__all__ = ["check_tolerant_ik", "tolerant_inverse_kinematics"]

#: values of a single fixed tension tried, across its range, when the nominal one fails
GRID = 32
#: rounds of that grid, each around the best value of the last
ROUNDS = 3


def _elastic(robot: Robot, idx: np.ndarray | slice = slice(None)) -> dict[str, Pair]:
    """The intervals of ``k``, ``K``, ``V``, ``L0`` of the wires ``idx`` over the set."""
    b = robot.bounds()
    out = {}
    for name in ("k", "K", "V", "L0"):
        lo, hi = getattr(b, name)
        out[name] = (np.asarray(lo, dtype=float)[idx], np.asarray(hi, dtype=float)[idx])
    return out


def _tension_of_control(robot: Robot, st: SetStatics, F: np.ndarray, uF: np.ndarray) -> Pair:
    """Eq. 6 over the set for the wires ``F`` at the controls ``uF``: ``L = ρ + V + K u``,
    ``τ = k (1 - L0 / L)``, as a batch of one ``(1, |F|)``."""
    e = _elastic(robot, F)
    Ku = arith.scale(e["K"][0], e["K"][1], uF)
    L = arith.add(st.rho[0][F], st.rho[1][F], e["V"][0], e["V"][1])
    L = arith.add(L[0], L[1], Ku[0], Ku[1])
    if not np.all(L[0] > 0.0):
        raise InputError("u_fixed", "a wire length of the set may reach 0 with this control")
    q = arith.div_nonzero(e["L0"][0], e["L0"][1], L[0], L[1])
    one = np.ones_like(q[0])
    s = arith.sub(one, one, q[0], q[1])
    tl, th = arith.mul(e["k"][0], e["k"][1], s[0], s[1])
    return tl[None], th[None]


def _controls(robot: Robot, tau: Pair, rho: Pair) -> Pair:
    """Controls over the set from tensions (eq. 2, eq. 1 for ``L``; module docstring), NaN
    where ``τ`` may reach ``k``."""
    e = _elastic(robot)
    q = arith.div_nonzero(tau[0], tau[1], e["k"][0], e["k"][1])
    one = np.ones_like(q[0])
    s = arith.sub(one, one, q[0], q[1])
    defined = s[0] > 0.0
    L = arith.div_nonzero(e["L0"][0], e["L0"][1], np.where(defined, s[0], 1.0), s[1])
    d = arith.sub(L[0], L[1], rho[0], rho[1])
    d = arith.sub(d[0], d[1], e["V"][0], e["V"][1])
    u = arith.div_nonzero(d[0], d[1], e["K"][0], e["K"][1])
    return np.where(defined, u[0], np.nan), np.where(defined, u[1], np.nan)


def _interval_violations(robot: Robot, lo, hi) -> list[Violation]:
    """The worst cases of ``limit_violations``: an upper limit against the upper bounds, a
    lower limit against the lower bounds (``lo``, ``hi``: ``(τ, u)`` pairs, ``u`` may be
    None)."""
    above = [v for v in limit_violations(robot, *hi) if v.bound == "max"]
    below = [v for v in limit_violations(robot, *lo) if v.bound == "min"]
    return sorted(above + below, key=lambda v: (v.wire, v.quantity))


def _margin(robot: Robot, tlo: np.ndarray, thi: np.ndarray) -> np.ndarray:
    """Proven smallest distance of the tensions to their limits, ``(C,)`` (N, rounded down)."""
    return np.min(
        np.minimum(down(tlo - robot.tau_min), down(robot.tau_max - thi)), axis=-1, initial=np.inf
    )


def check_tolerant_ik(
    robot: Robot, method: str, solve: str = "tau", pose: Pose | None = None
) -> None:
    """What the IK of a set does not take, refused naming the field
    (:class:`~certsolve.inputs.InputError`): Algorithm 1 (a search for one robot's
    controls), ``solve="newton"`` (the set's statics are linear in the tensions), a robot
    with fewer wires than equilibrium equations (a pose is an equilibrium of chosen robots
    only, not of a set), and with ``pose``, a wire whose length may be 0 for a robot of the
    set (:func:`set_statics`)."""
    if method not in ("tension", "alg2"):
        raise InputError(
            "method", f"{method} is not available for a robot with tolerances (use tension or alg2)"
        )
    if solve != "tau":
        raise InputError("solve", "a robot with tolerances is solved in the tensions (tau)")
    if robot.m < robot.wrench_dim:
        raise InputError(
            "robot.tolerances",
            f"{robot.wrench_dim} equilibrium equations for {robot.m} tensions: the pose is "
            "an equilibrium of chosen robots only, not of a set",
        )
    if pose is not None:
        set_statics(robot, pose)


def _tensions(robot: Robot, pose: Pose, st: SetStatics, F: np.ndarray, tauF: Pair):
    """For a batch of fixed tensions ``τ_F`` ``(C, |F|)`` (intervals): bounds ``(C, m)`` of
    every wire's tension over the set, the mask of the proven rows, and their proven margins
    (``-inf`` where not proven)."""
    m = st.H[0].shape[1]
    C = tauF[0].shape[0]
    system = SetSystem(robot, pose, st, F, tauF)
    xlo, xhi, proven = solve_linear_set(system, C)
    tlo, thi = np.empty((C, m)), np.empty((C, m))
    tlo[:, F], thi[:, F] = tauF
    tlo[:, system.S], thi[:, system.S] = xlo, xhi
    return tlo, thi, proven, np.where(proven, _margin(robot, tlo, thi), -np.inf)


def _best_fixed_tension(robot: Robot, pose: Pose, st: SetStatics, F: np.ndarray, first: tuple):
    """The fixed tension of the one fixed wire ``F`` with the largest proven margin: a batch
    of :data:`GRID` values across its range, then :data:`ROUNDS` - 1 finer batches around
    the best; ``first`` ``(margin, tlo, thi, proven)`` is the nominal one's.  Returns the
    best ``(margin, tlo, thi, proven)`` and the number of values tried."""
    j = int(F[0])
    best, count = first, 1
    a, b = float(robot.tau_min[j]), float(robot.tau_max[j])
    for _ in range(ROUNDS):
        grid = np.linspace(a, b, GRID)[:, None]
        glo, ghi, gok, gm = _tensions(robot, pose, st, F, (grid, grid))
        count += GRID
        k = int(np.argmax(gm))
        if gm[k] > best[0]:
            best = (float(gm[k]), glo[k], ghi[k], bool(gok[k]))
        step, t = (b - a) / (GRID - 1), float(best[1][j])
        a, b = max(t - step, float(robot.tau_min[j])), min(t + step, float(robot.tau_max[j]))
    return best, count


def _verdict(
    nominal: Robot,
    ok: bool,
    tau: tuple[np.ndarray, np.ndarray],
    u: tuple[np.ndarray | None, np.ndarray | None],
    tau_n: np.ndarray,
    messages: list[str],
) -> tuple[IKStatus, list[Violation]]:
    """The status and the worst-case violations of the set's bounds (``messages`` gets
    each tension violation with the nominal robot's value: certain where it violates too)."""
    if not ok:
        messages.append(
            "the set's statics could not be enclosed: the free wires' wrench matrix may be "
            "singular for a robot of the set"
        )
        return IKStatus.UNCERTIFIED, []
    (tlo, thi), (ulo, uhi) = tau, u
    violations = _interval_violations(nominal, (tlo, ulo), (thi, uhi))
    for v in violations:
        if v.quantity == "tau":
            nv = float(tau_n[v.wire - 1])
            certain = nv > v.limit + LIMIT_TOL if v.bound == "max" else nv < v.limit - LIMIT_TOL
            messages.append(
                f"wire {v.wire}: the set's worst case is at most {v.excess:.4g} N "
                f"{'above' if v.bound == 'max' else 'below'} the limit; the nominal robot has "
                f"{nv:.6g} N ({'violated' if certain else 'within'})"
            )
    if ulo is not None and not np.all(np.isfinite(ulo)):
        bad = [int(i) + 1 for i in np.flatnonzero(~np.isfinite(ulo))]
        messages.append(
            f"no control: the tension of wires {bad} may reach k for a robot of the set"
        )
        return IKStatus.NO_SOLUTION, violations
    return (IKStatus.LIMITS_VIOLATED if violations else IKStatus.OK), violations


def tolerant_inverse_kinematics(
    robot: Robot,
    pose: Pose,
    method: str = "tension",
    *,
    distribution: str = "auto",
    check_lp: bool = False,
    fixed_wire: int = 1,
    tau_fixed: float | None = None,
    u_fixed: float | None = None,
    solve: str = "tau",
    u_last: np.ndarray | None = None,
    window: float | None = None,
) -> IKResult:
    """Control intervals holding ``pose`` for every robot of ``robot``'s set, with the tension
    bounds of the distribution and what fails (module docstring).  ``method``: ``"tension"``
    (options ``distribution``, ``check_lp`` of the nominal distribution) or ``"alg2"``
    (``fixed_wire``, ``tau_fixed``, ``u_fixed``; ``u_last`` and ``window``: controls
    that may leave the window are reported).  ``alg1`` and ``solve="newton"`` are refused
    (:class:`~certsolve.inputs.InputError`): the set's statics are solved in the tensions."""
    t0 = time.perf_counter()
    check_tolerant_ik(robot, method, solve)
    nominal = robot.nominal()
    elastic = is_elastic(nominal)
    if method == "alg2" and not elastic:
        require_elastic(nominal, "alg2")
    enc = enclose_pose(nominal, pose.position, pose.rotation)
    check_pose(pose, enc)
    H0, wg0 = enc.H, enc.wg
    w, m = H0.shape
    st = set_statics(robot, pose)
    messages: list[str] = []
    details: dict = {}
    if method == "tension":
        ch = distribute_tensions(
            H0, wg0, nominal.tau_min, nominal.tau_max, mode=distribution, check_lp=check_lp
        )
        messages += ch.notes
        if ch.lp_check is not None:
            details["lp_check"] = ch.lp_check
        _, _, piv = scipy.linalg.qr(H0, pivoting=True)
        F = np.sort(piv[w:])
        tau_nom = np.where(np.isfinite(ch.tau), ch.tau, 0.5 * (nominal.tau_min + nominal.tau_max))
        cand = tau_nom[F][None]
        tauF: Pair = (cand, cand)
        fixed_u: dict[int, float] = {}
    else:
        if u_last is not None:
            _, _, u_last = search_window(nominal, u_last, window)
        F = np.array(fixed_wires(H0, fixed_wire, m - w), dtype=np.int64)
        opts = Alg2Options(fixed_wire=fixed_wire, tau_fixed=tau_fixed, u_fixed=u_fixed)
        u0, _ = fix_controls(nominal, enc, F, opts)
        uF = u0[F]
        fixed_u = {int(j) + 1: float(v) for j, v in zip(F, uF, strict=True)}
        tauF = _tension_of_control(robot, st, F, uF)
    S = np.setdiff1d(np.arange(m), F)
    tlo, thi, proven, margins = _tensions(robot, pose, st, F, tauF)
    C = 1
    if method == "tension" and F.size == 1 and not margins[0] >= 0.0:
        first = (float(margins[0]), tlo[0], thi[0], bool(proven[0]))
        (margin, tlo, thi, ok), C = _best_fixed_tension(robot, pose, st, F, first)
        j = int(F[0])
        if tlo[j] != first[1][j]:
            messages.append(
                f"the nominal robot's max-margin tension of wire {j + 1} does not hold the "
                f"limits for the whole set; fixed at {float(tlo[j]):.6g} N instead (the "
                f"largest proven margin of {C - 1} values across its range)"
            )
    else:
        tlo, thi, ok, margin = tlo[0], thi[0], bool(proven[0]), float(margins[0])
    # the nominal robot under the same distribution, for the certainty of a violation
    with np.errstate(all="ignore"):
        if method == "tension":
            tnF = tlo[F]
        else:
            L0n = enc.W[F] + nominal.K[F] * uF
            tnF = nominal.k[F] * (L0n - nominal.L0[F]) / L0n
        tau_n = np.empty(m)
        tau_n[F] = tnF
        tau_n[S] = np.linalg.solve(H0[:, S], -(wg0 + H0[:, F] @ tnF))
    ulo = uhi = None
    if elastic and ok:
        ulo, uhi = _controls(robot, (tlo, thi), st.rho)
        if method == "alg2":
            ulo[F] = uhi[F] = uF
    fixed_what = "tension" if method == "tension" else "control"
    fixed_vals = tlo[F] if method == "tension" else uF
    fixed_text = ", ".join(
        f"{'tau' if method == 'tension' else 'u'}_{int(j) + 1} = {float(v):.6g}"
        for j, v in zip(F, fixed_vals, strict=True)
    )
    details["set"] = {
        "fixed": fixed_what,
        "fixed_wires": [int(j) + 1 for j in F],
        "fixed_values": [float(v) for v in fixed_vals],
        "tau_lo": tlo,
        "tau_hi": thi,
        "u_lo": ulo,
        "u_hi": uhi,
        "margin_lo": margin,
        "nominal_tau": tau_n,
        "candidates": C,
    }
    status, violations = _verdict(nominal, ok, (tlo, thi), (ulo, uhi), tau_n, messages)
    if ok and ulo is not None and uhi is not None and u_last is not None and window is not None:
        violations += [v for v in window_violations(uhi, u_last, window) if v.bound == "max"]
        violations += [v for v in window_violations(ulo, u_last, window) if v.bound == "min"]
        if status == IKStatus.OK and violations:
            status = IKStatus.LIMITS_VIOLATED
    u = None
    if ulo is not None and uhi is not None and status != IKStatus.NO_SOLUTION:
        u = midpoint(ulo, uhi)
    cert = Certificate(
        kind="every-robot" if ok else "none",
        statement=(
            f"with {fixed_text} for every robot of the set, each robot has exactly one "
            "tension vector solving its statics, within details.set tau_lo..tau_hi, and its "
            "controls lie in 'enclosure'"
        )
        if ok
        else "floating-point result, not certified",
        enclosure=None if u is None or ulo is None or uhi is None else (ulo, uhi),
        fixed=fixed_u,
    )
    messages.append(
        "robot with tolerances: u is the middle of the control intervals (certificate."
        "enclosure); each robot of the set needs its own control within them, and u itself "
        "proves nothing about a robot's pose (forward kinematics with u gives the set's pose box)"
    )
    return IKResult(
        robot=robot.name,
        dof=robot.dof,
        method=method,
        pose=pose,
        status=status,
        feasible=status == IKStatus.OK,
        u=u,
        tau=midpoint(tlo, thi) if ok else None,
        rho=enc.rho,
        margin=margin if ok else None,
        residual=None,
        violations=violations,
        certificate=cert,
        messages=messages,
        details=details,
        time=time.perf_counter() - t0,
    )
