"""Real-time forward kinematics: follow the platform from a known pose (Merlet 2007, III-B).

Between two control periods the platform moves little, so the new pose is found by Newton's
method started at the previous one, and then *certified*: Krawczyk's test proves that the
system has exactly one solution in a small box around the Newton point (default: every
chosen platform point within ±1 mm, ``half_width = 0.1`` cm; the wire lengths within
``±half_width·√d``, which covers every pose of that box).  A certified step is therefore a
proof that the pose is the only equilibrium within a millimetre, not just a converged
iteration.  The wire-length part of the box is the rigorous range of ``|A_i - B_i|`` over
the box of points, so the certificate covers every pose whose chosen points lie in the
box.  If the proof fails at the requested half-width (a soft configuration), it is tried
at half and a quarter of it and the result reports the half-width actually proven.  If
Newton does not converge, or the proof fails (a singular or bifurcating configuration),
the step says so and the caller should fall back to the full search
(:func:`~.fk.forward_kinematics`).

:class:`Tracker` compiles the formulation once; a step costs a few float Newton
iterations and one batched Krawczyk test.  With ``stability=True`` (:func:`track`, the
CLI) a certified step also says whether the pose is stable (:mod:`.stability`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..expr import esum, sqr, sqrt
from ..expr.scalar import ScalarProgram
from ..inputs import InputError, checked
from ..interval.linalg import krawczyk_image, mr_from_bounds, mr_matmul
from ..robot.geometry import Pose
from ..robot.inputs import TrackOptions, as_pose, check_controls
from ..robot.model import Robot
from ..solver.newton import KrawczykPoint
from .fk_geometry import papers_system
from .fk_points import PointsFormulation
from .fk_solver import FKPose, FKSolver
from .stability import StabilityVerdict

#: why tracking refuses a robot with tolerances (one message for Python, CLI and jobs)
TOLERANCES_REFUSED = (
    "tracking follows the equilibrium branch of one robot, and a robot with tolerances is a "
    "set of robots: track the nominal robot (drop the tolerances) or run the set's forward "
    "kinematics (docs/tolerances.md)"
)

__all__ = ["TOLERANCES_REFUSED", "Tracker", "TrackResult", "track"]


@dataclass
class TrackResult:
    certified: bool
    pose: FKPose | None
    iterations: int
    residual: float
    half_width: float
    time: float
    message: str = ""

    def to_dict(self) -> dict:
        return {
            "certified": self.certified,
            "pose": None if self.pose is None else self.pose.to_dict(),
            "iterations": self.iterations,
            "residual": self.residual,
            "half_width": self.half_width,
            "time": self.time,
            "message": self.message,
        }


#: a held Jacobian is enclosed over the chosen points within ``±WIDEN·h`` of the step's
#: Newton point and the controls within ``±WIDEN·h`` of its ``u`` (cm): the next steps of
#: a path that moves less than ``(WIDEN - 1)·h`` reuse it
WIDEN = 2.0


@dataclass(kw_only=True)
class HeldJacobian:
    """A Krawczyk preconditioner ``Y`` and ``mag >= |I - Y J|`` for every Jacobian ``J`` of
    the system over the box ``[lo, hi]`` of its variables and the controls ``[ulo, uhi]``.

    Krawczyk's ``K(X) = c - Y f(c; u) + (I - Y J)(X - c)`` needs ``J`` to enclose the
    Jacobian over the hull of ``X`` and ``c`` for the ``u`` of ``f(c; u)``; an enclosure
    over a larger set is one over the smaller.  So for every box ``X`` and centre ``c``
    inside ``[lo, hi]`` and every ``u`` in ``[ulo, uhi]`` the test needs only a rigorous
    ``f(c; u)`` (:meth:`Tracker.step`: a path's next steps)."""

    lo: np.ndarray
    hi: np.ndarray
    ulo: np.ndarray
    uhi: np.ndarray
    Y: np.ndarray
    mag: np.ndarray

    def covers(self, lo: np.ndarray, hi: np.ndarray, u: np.ndarray) -> bool:
        """Whether ``[lo, hi]`` (with its centre inside it) and ``u`` are inside."""
        return bool(
            (self.lo <= lo).all() and (hi <= self.hi).all()
            and (self.ulo <= u).all() and (u <= self.uhi).all()
        )  # fmt: skip

    def prove(self, lo, hi, c, flo, fhi, steps: int = 3):
        """:meth:`Tracker._prove` with this ``Y`` and ``|I - Y J|`` (``[lo, hi]`` covered,
        ``c`` in it, ``[flo, fhi]`` encloses ``f(c; u)``): ``(proven, lo, hi)``."""
        fc, fr = mr_from_bounds(flo, fhi)
        with np.errstate(all="ignore"):
            bc, br = mr_matmul(self.Y, None, fc, fr)
        for _ in range(steps):
            klo, khi, ok = krawczyk_image(c, lo, hi, self.mag, bc, br)
            nlo, nhi = np.fmax(klo, lo), np.fmin(khi, hi)
            if ok:
                return True, nlo, nhi
            if (nlo > nhi).any() or (nhi - nlo > 0.9 * (hi - lo)).all():
                break
            lo, hi = nlo, nhi
        return False, lo, hi


class Tracker:
    """Newton + Krawczyk steps of forward kinematics near a known pose: the reusable form
    of :func:`track`, for control loops (``certsolve.Tracker(robot)``).

    The formulation is built and compiled once, here (~0.03-0.08 s CPU); then each
    :meth:`step` costs a few float Newton iterations and one Krawczyk test on generated
    straight-line code (about 0.16 ms for T-16 and 0.29 ms for general-19, see
    ``benchmarks/trajectory_bench.py``)::

        tracker = certsolve.Tracker(robot)
        pose = start
        for u in controls:
            res = tracker.step(u, pose, half_width=0.1)
            if not res.certified:
                break  # fall back to certsolve.forward_kinematics(robot, u)
            pose = res.pose

    A step holds its Jacobian enclosure (:class:`HeldJacobian`, over a box ``WIDEN``
    times the step's and the controls ``±WIDEN·half_width``): the next steps whose box
    and controls it covers need only ``f`` at their Newton point (T-16: 11 steps of 12 on
    ``trajectory_bench``'s path; general-19 at ``half_width = 0.1``: none, its
    ``|I - Y J|`` over the step's own box is above 1 until narrowed).  Where the held
    one does not cover a step, or does not prove it, the step encloses a new one; where
    that fails too, the step gets its own proof, as a tracker with nothing held.  So a
    step that a fresh tracker certifies at ``half_width`` is certified there too; the
    proven box may be a little narrower or wider (another ``Y``).

    Whole paths, with a proof that the platform stays on one equilibrium branch between
    the steps, are :func:`certsolve.track_trajectory`'s.
    """

    def __init__(
        self,
        robot: Robot,
        formulation: str = "auto",
        max_iterations: int = 12,
        *,
        stability: bool = False,
    ):
        # stability: give each certified step a verdict (:mod:`.stability`).  Off by default
        # in loops: it costs ~1.5 ms a step (T-16 0.36 -> 1.85 ms, general-19 0.47 -> 2.26
        # ms), four times a step's own cost; :func:`track` and the CLI turn it on
        self.stability = stability
        if robot.toleranced:
            raise InputError("robot.tolerances", TOLERANCES_REFUSED)
        if formulation == "auto":  # the paper's point system: cheapest per-box code
            formulation = papers_system(robot)
        self.fk = FKSolver(robot, formulation, prepare_search=False)  # no search here
        if not isinstance(self.fk.form, PointsFormulation):
            raise ValueError("tracking uses one of the paper's point formulations")
        #: the formulation (the paper's chosen points: ``Q``, ``L``, ``n_points``)
        self.form: PointsFormulation = self.fk.form
        self.robot = robot
        self.csys = self.fk.csys
        self.max_iterations = max_iterations
        names = self.fk.form.system.variables
        self._is_rho = np.array([v.startswith("rho") for v in names])
        self._lengths = self._length_program() if self._is_rho.any() else None
        #: the Jacobian enclosure held from an earlier step (None: none yet)
        self.held: HeldJacobian | None = None
        # a wider enclosure that fails to prove its step is not tried again for the next
        # 2, 4, ... 64 steps that need a new one (general-19 at h = 0.1: |I - Y J| over X
        # alone is already above 1, proven only after narrowing, so it always fails)
        self._wide_wait = 0
        self._wide_misses = 0
        self._jac, self._jac_flat = self._jacobian_program()
        # the per-box code a step calls is compiled now, not in the first step: f and J
        # over boxes, f and J in floats (Newton), the lengths over boxes
        sf, sfj = self.csys.scalar()
        sf.prepare(interval=True)
        sfj.prepare(floats=True)
        self._jac.prepare(interval=True)
        if self._lengths is not None:
            self._lengths.prepare(interval=True)

    def set_controls(self, u: np.ndarray | tuple[np.ndarray, np.ndarray]) -> None:
        """The compiled system's parameters: the controls ``u`` (floats), or their bounds
        ``(lo, hi)`` arrays for every ``u`` in a box."""
        names = self.csys.param_names
        if isinstance(u, tuple):
            lo, hi = (np.asarray(b, dtype=float).tolist() for b in u)
            self.csys.set_parameters(dict(zip(names, zip(lo, hi, strict=True), strict=True)))
        else:
            self.csys.set_parameters(dict(zip(names, np.asarray(u).tolist(), strict=True)))

    @property
    def rho_mask(self) -> np.ndarray:
        """Which of the system's variables are wire lengths ``rho_i``."""
        return self._is_rho

    def initial_point(self, pose: Pose | FKPose) -> np.ndarray:
        """The system's variables at a pose: chosen points and wire lengths."""
        f = self.form
        P = pose.position + f.Q @ pose.rotation.T
        x = P.ravel()
        if self._is_rho.any():
            B = f.L @ P
            d = self.robot.A - B
            rho = np.sqrt((d * d).sum(axis=1))  # np.linalg.norm's floats, without its wrapper
            x = np.concatenate([x, rho])
        return x

    def _length_program(self) -> ScalarProgram:
        """Generated code for ``|A_i - B_i|`` as functions of the chosen points."""
        from ..expr import var

        f, r = self.form, self.robot
        d, k = r.dim, f.n_points
        axes = "xyz"[:d]
        P = [[var(f"{a}{j + 1}") for a in axes] for j in range(k)]
        g = self.csys.graph
        nodes = []
        for i in range(r.m):
            B = [esum(float(f.L[i, j]) * P[j][c] for j in np.flatnonzero(f.L[i])) for c in range(d)]
            nodes.append(g.add_expr(sqrt(esum(sqr(B[c] - float(r.A[i, c])) for c in range(d)))))
        return ScalarProgram(g, nodes)

    def _jacobian_program(self) -> tuple[ScalarProgram, np.ndarray]:
        """Generated code for the Jacobian alone, and the flat ``(n, n)`` indices of its
        outputs: the compiled system's ``fj_box`` without ``f`` over the box, which the
        Krawczyk test never reads (general-19: 828 -> 642 nodes, T-16: 553 -> 397)."""
        c = self.csys
        outs = c.fj.global_ids[c.fj.outputs].tolist()[c.n :]
        return ScalarProgram(c.graph, outs), np.flatnonzero(c.jac_structure.ravel())

    def jacobian_box(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bounds ``(jlo, jhi)`` of the Jacobian over the box ``[lo, hi]`` for the current
        parameter values (``(n, n)``, zeros where the system's structure has none)."""
        c = self.csys
        dlo, dhi = self._jac.interval(
            lo.tolist(), hi.tolist(), c.param_lo.tolist(), c.param_hi.tolist()
        )
        n = c.n
        jlo = np.zeros(n * n)
        jhi = np.zeros(n * n)
        jlo[self._jac_flat] = dlo
        jhi[self._jac_flat] = dhi
        return jlo.reshape(n, n), jhi.reshape(n, n)

    def box(self, plo: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The box whose chosen points are ``[plo, phi]`` (their wire-length components
        ignored) and whose lengths are the rigorous range of ``|A_i - B_i|`` over it."""
        lo, hi = plo.copy(), phi.copy()
        if self._lengths is not None:
            rlo, rhi = self._lengths.interval(lo.tolist(), hi.tolist(), [], [])
            lo[self._is_rho] = rlo
            hi[self._is_rho] = rhi
        return lo, hi

    def _box(self, x: np.ndarray, h: float):
        """Points within ±h of the Newton point; lengths: the exact range over that box."""
        return self.box(x - h, x + h)

    def krawczyk(self, lo, hi, c, steps: int = 3, b=None, rounds: int = 2, f=None):
        """:meth:`_prove`, with the :class:`KrawczykPoint` of the last test (None if none)
        and the box ``(jlo, jhi)`` its Jacobian was enclosed over: its ``Y`` and
        ``|I - Y J|`` hold for every box inside that one and every parameter value inside
        the current ones (an enclosure of ``J`` over the larger set is one over the
        smaller).  ``b``: instead of ``f(c)`` over the current parameter values, a function
        of ``Y`` giving bounds ``bc ± br`` of ``Y f(c)`` for every parameter value of
        interest (tighter than ``Y`` times a box of ``f``).  ``rounds``: how many Jacobian
        enclosures at most (the second over the narrowed box, when the first stalls).
        ``f``: the bounds ``(flo, fhi)`` of ``f(c)``, if the caller has them.
        Returns ``(proven, lo, hi, kp, (jlo, jhi))``."""
        csys = self.csys
        if f is not None:
            flo, fhi = f
        elif b is None:
            flo, fhi = csys.f_point(c)
        else:  # K(X) needs Y f(c) only: the KrawczykPoint's own is replaced
            flo = fhi = np.zeros(csys.n)
        kp = None
        jbox = (lo, hi)
        for _ in range(rounds):
            jbox = (np.minimum(lo, c), np.maximum(hi, c))
            jlo, jhi = self.jacobian_box(*jbox)
            kp = KrawczykPoint(c, flo, fhi, jlo, jhi)
            if b is not None and kp.ok:
                kp.bc, kp.br = b(kp.Y)
            for _ in range(steps):
                klo, khi, ok = kp.image(lo, hi)
                if ok:
                    return True, np.fmax(klo, lo), np.fmin(khi, hi), kp, jbox
                nlo, nhi = np.fmax(klo, lo), np.fmin(khi, hi)
                if (nlo > nhi).any():  # no zero at all in X (cannot happen at a Newton point)
                    return False, lo, hi, kp, jbox
                if (nhi - nlo > 0.9 * (hi - lo)).all():
                    break  # no progress
                lo, hi = nlo, nhi
        return False, lo, hi, kp, jbox

    def _prove(self, lo, hi, c, steps: int = 3, f=None):
        """Exactly one zero in ``[lo, hi]``?  Krawczyk about the Newton point ``c``.

        ``K(X) = c - Y f(c) + (I - Y J)(X - c)`` with ``J`` enclosing the Jacobian over the
        hull of ``X`` and ``c``: ``K(X) ⊂ int X`` proves exactly one zero in ``X`` (the
        centre need not be the midpoint; the radius used is the distance from ``c`` to the
        farthest face).  Every zero in ``X`` lies in ``X' = K(X) ∩ X``, so a proof for
        ``X'`` is a proof for ``X``.  ``X'`` is re-tested with the same ``f(c)`` and the same
        ``J`` (an enclosure over ``X`` is one over ``X' ⊂ X``): only matrix work, no new
        evaluation.  If that stalls, ``J`` is evaluated once more over the narrowed box.
        """
        ok, lo, hi, _, _ = self.krawczyk(lo, hi, c, steps, f=f)
        return ok, lo, hi

    def _prove_held(self, lo, hi, x, u, h: float):
        """:meth:`_prove` of a step's box ``[lo, hi]`` about its Newton point ``x`` for the
        current controls ``u``: with the held Jacobian if it covers them; else with a new
        one over the wider box (held for the next steps if it proves this one); else alone.
        """
        flo, fhi = self.csys.f_point(x)
        held = self.held
        if held is not None and held.covers(lo, hi, u):
            ok, elo, ehi = held.prove(lo, hi, x, flo, fhi)
            if ok:
                return ok, elo, ehi
        if self._wide_wait > 0:
            self._wide_wait -= 1
            return self._prove(lo, hi, x, f=(flo, fhi))
        wlo, whi = self._box(x, WIDEN * h)
        du = WIDEN * h
        if (wlo <= lo).all() and (hi <= whi).all():
            self.set_controls((u - du, u + du))
            jlo, jhi = self.jacobian_box(wlo, whi)
            self.set_controls(u)
            kp = KrawczykPoint(x, flo, fhi, jlo, jhi)
            if kp.ok:
                held = HeldJacobian(lo=wlo, hi=whi, ulo=u - du, uhi=u + du, Y=kp.Y, mag=kp.mag)
                ok, elo, ehi = held.prove(lo, hi, x, flo, fhi)
                if ok:
                    self.held, self._wide_misses = held, 0
                    return ok, elo, ehi
        self._wide_misses = min(self._wide_misses + 1, 6)
        self._wide_wait = 2**self._wide_misses
        return self._prove(lo, hi, x, f=(flo, fhi))

    def newton(self, x: np.ndarray) -> tuple[np.ndarray, int, float, str]:
        """Float Newton from ``x`` for the current parameter values: ``(x, iterations,
        last step, message)``; the message is empty when it converged.

        It stops when a step is below ``1e-11 (1 + |x_0|)``, or once a step is below
        ``1e-6 (1 + |x_0|)`` after one at least ten times larger: Newton converging
        quadratically, the next step would be below ``1e-12``.  Nothing rests on that
        guess: the Krawczyk test that follows is the proof, and fails if the point is poor.
        """
        csys = self.csys
        res = prev = np.inf
        scale = 1.0 + float(np.abs(x).max())  # of the start: the steps are small beside it
        for it in range(1, self.max_iterations + 1):
            f, J = csys.fj_point_float(x)
            try:
                step = np.linalg.solve(J, f)
            except np.linalg.LinAlgError:
                return x, it, float("nan"), "singular Jacobian"
            x = x - step
            res = float(np.abs(step).max())
            if not math.isfinite(res):
                break
            if res <= 1e-11 * scale or (res <= 1e-6 * scale and res <= 0.1 * prev):
                return x, it, res, ""
            prev = res
        return x, self.max_iterations, res, "Newton did not converge"

    def _stability(self, elo, ehi, x, u) -> StabilityVerdict:
        """The verdict on the zero proven in ``E = [elo, ehi]``, over a box ``x ± 1e-8 (1 +
        |x|)`` proven to hold it (Krawczyk again): ``E`` itself, a millimetre wide, leaves
        the Hessian's enclosure too wide to decide.  ``E`` if that proof fails."""
        t = 1e-8 * (1.0 + np.abs(x))
        ok, lo, hi = self._prove(x - t, x + t, x, steps=1)
        if not ok:
            lo, hi = elo, ehi
        return self.fk.hessian.verdicts(lo[None], hi[None], u)[0]

    def step(self, u, near: Pose | FKPose, half_width: float = 0.1) -> TrackResult:
        """One step from ``near`` (a pose, an FK pose or pose parameters) for controls ``u``.

        Newton from ``near``'s point, then Krawczyk's test on the box of every chosen
        platform point within ``±half_width`` cm of the Newton point (then half and a
        quarter of it): ``certified`` means that box holds exactly one equilibrium for
        ``u``.  Tension limits are not checked here (:func:`certsolve.track_trajectory`
        checks them)."""
        t0 = time.perf_counter()
        if not isinstance(near, FKPose):
            near = as_pose(self.robot.dof, near, "near_pose")
        u = np.asarray(u, dtype=float)
        if u.shape != (self.robot.m,):
            raise ValueError(f"u: expected {self.robot.m} values, got {u.size}")
        if not half_width > 0:
            raise ValueError("half_width must be positive")
        unknown = StabilityVerdict.unknown()
        self.set_controls(u)
        x, it, res, msg = self.newton(self.initial_point(near))
        if msg:
            nan = float("nan") if msg == "singular Jacobian" else res
            return TrackResult(False, None, it, nan, half_width, time.perf_counter() - t0, msg)
        for h in (half_width, 0.5 * half_width, 0.25 * half_width):
            lo, hi = self._box(x, h)
            if h == half_width:
                ok, elo, ehi = self._prove_held(lo, hi, x, u, h)
            else:
                ok, elo, ehi = self._prove(lo, hi, x)
            if ok:
                # the Newton point is the best estimate of the zero proven to be in E
                inside = bool(((elo <= x) & (x <= ehi)).all())
                verdict = self._stability(elo, ehi, x, u) if self.stability else None
                pose = self.fk.decode(
                    elo, ehi, u, point=x if inside else None, verdict=verdict or unknown
                )
                msg = "" if h == half_width else f"proven only at half-width {h:g} cm"
                return TrackResult(True, pose, it, res, h, time.perf_counter() - t0, msg)
        # no equilibrium is proven near x: no verdict on it either
        pose = self.fk.decode(x, x, u, verdict=unknown)
        pose.certificate = "none"
        return TrackResult(
            False,
            pose,
            it,
            res,
            half_width,
            time.perf_counter() - t0,
            "Krawczyk test failed: the solution may not be unique in the box",
        )


def track(robot: Robot, u, near, half_width: float = 0.1, formulation: str = "auto") -> TrackResult:
    """One certified tracking step, with its stability verdict: the one-off form of
    :class:`Tracker` (it compiles the system at every call, ~0.05-0.15 s CPU: use
    ``Tracker(robot).step`` in loops, :func:`certsolve.track_trajectory` for paths).

    ``near``: a :class:`~certsolve.robot.Pose`, an :class:`FKPose` or pose parameters
    (``[x, y, theta]``, ``[x, y, z, yaw, pitch, roll]``; cm, degrees).  The inputs are
    checked as ``POST /v1/fk/track`` and ``certsolve fk --near`` check them
    (:class:`~certsolve.robot.inputs.TrackOptions`): a value they refuse raises
    :class:`~certsolve.inputs.InputError` naming it.
    """
    pose = near if isinstance(near, FKPose) else as_pose(robot.dof, near, "near_pose")
    values = Pose(pose.position, pose.rotation).params(robot.dof)
    opts = checked(TrackOptions, {"u": u, "near_pose": values, "half_width": half_width})
    check_controls(robot.m, opts.u)
    return Tracker(robot, formulation, stability=True).step(opts.u, pose, opts.half_width)
