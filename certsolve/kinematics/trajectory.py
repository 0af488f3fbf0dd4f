"""Follow a control path with a certificate at every step and between the steps.

A path is a list of control vectors ``u_0 .. u_{N-1}``; the platform starts near a known
pose.  For each step ``k`` float Newton (started from the secant prediction
``2 x_{k-1} - x_{k-2}``) gives a point ``x_k``, and two proofs are made
(:class:`~.tracking.Tracker` holds the compiled system and the Krawczyk test):

* **the step** (*certified*): Krawczyk's test proves that the box ``E_k`` (inside the
  points' ``±half_width`` box around ``x_k``) holds exactly one equilibrium for ``u_k``;
* **the link** (*joined*): for a run of steps ``k0 .. k1`` (a *chunk*), with ``X`` the
  hull of their boxes and the parameters ``U`` the hull of ``u_k0 .. u_k1``, Krawczyk's
  ``K(X) ⊂ int X`` with ``J`` enclosed over ``X × U`` proves that for every ``u`` in
  ``U`` -- every point of the polyline ``u_k0 -> ... -> u_k1`` among them -- ``X`` holds
  exactly one equilibrium ``x(u)``, and that every Jacobian over ``X × U`` is
  nonsingular, so ``x(u)`` is continuous along the polyline (implicit function theorem).
  The step proofs tie the chunks together: ``E_k`` lies in the ``X`` of both chunks that
  share step ``k``, and its one equilibrium is therefore the ``x(u_k)`` of both.  The
  path from ``u_0`` to ``u_k`` thus moves the platform continuously along one branch: no
  silent jump to another equilibrium.

``Y f(c; u)`` over the polyline is bounded in mean value form in ``u``, with ``∂f/∂u``
generated from the same equations (:meth:`TrajectoryFollower._b_along`): ``Y`` times one
box of ``f`` over ``U`` is several times too wide (the wrapping effect).

Cost: the chunk's ``Y ≈ mid J(X, U)^-1`` and ``|I - Y J(X, U)|`` hold for every step box
inside the box ``J`` was enclosed over (``X``, or ``X`` narrowed by the chunk's first
test) and every ``u`` in ``U``, so a step's proof needs only a rigorous ``f(x_k; u_k)``:
the step proofs of a chunk are one batched :func:`~certsolve.interval.linalg.
krawczyk_image`, and one Jacobian enclosure serves the whole chunk.  A chunk whose proof
fails is split in halves, down to one link; a link that fails is cut at its middle
control (Newton there, a step proof, two links), at most ``max_halvings`` times deep.  A
step whose proof fails with the chunk's ``Y`` gets a proof of its own (the Tracker's, at
``half_width``, then a half and a quarter of it).

The path is **lost** at the first step that is not certified, for one of the
:class:`LostReason` s: Newton fails or meets a singular Jacobian, a wire's tension is not
proven inside its bounds (over ``E_k``, eq. 6 in interval arithmetic), the step's proof
fails, or its link does (a fold: two equilibria meet near there).  Nothing after it is
reported.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..expr import var
from ..expr.graph import Graph
from ..expr.node import Expr
from ..expr.scalar import ScalarProgram
from ..inputs import InputError, checked
from ..interval import arith
from ..interval.linalg import krawczyk_image, mr_from_bounds, mr_matmul, mr_to_bounds
from ..robot.geometry import Pose
from ..robot.inputs import TrajectoryOptions, as_pose, check_trajectory
from ..robot.model import Robot
from .fk_solver import FKPose, with_tau_max
from .stability import StabilityVerdict
from .tracking import Tracker
from .trajectory_result import (
    LostReason,
    TrajectoryResult,
    TrajectoryStatus,
    TrajectoryStep,
    tension_enclosure,
)

__all__ = [
    "LostReason",
    "TrajectoryFollower",
    "TrajectoryResult",
    "TrajectoryStatus",
    "TrajectoryStep",
    "follower_for",
    "tension_enclosure",
    "track_trajectory",
]

#: condition number of ``J(x)`` above which a failed step is called singular
SINGULAR_COND = 1e10


@dataclass(kw_only=True)
class _Point:
    """A Newton point of the path: its controls, point, proven box (None: not proven)."""

    u: np.ndarray
    x: np.ndarray
    elo: np.ndarray | None = None
    ehi: np.ndarray | None = None
    h: float = 0.0


def _params_as_variables(e: Expr) -> Expr:
    """``e`` with every ``param(name)`` leaf a ``var(name)`` (iteratively, shared nodes
    once)."""
    memo: dict[int, Expr] = {}
    stack: list[tuple[Expr, bool]] = [(e, False)]
    while stack:
        x, ready = stack.pop()
        if id(x) in memo:
            continue
        if x.op == "param":
            memo[id(x)] = var(x.param)
        elif not x.args:
            memo[id(x)] = x
        elif ready:
            memo[id(x)] = Expr(x.op, tuple(memo[id(a)] for a in x.args), x.param)
        else:
            stack.append((x, True))
            stack.extend((a, False) for a in x.args if id(a) not in memo)
    return memo[id(e)]


class _Lost(Exception):
    def __init__(self, index: int, why: LostReason, text: str, point: _Point | None = None):
        super().__init__(text)
        self.index, self.why, self.text, self.point = index, why, text, point


class TrajectoryFollower:
    """Follow control paths on one robot (the :class:`Tracker` compiled once, and the
    generated code of ``∂f/∂u``).

    ``chunk``: steps per chunk to start with.  A proven chunk doubles the size, up to a cap
    that starts at ``max_chunk``; a failed one halves it and sets the cap one below its
    size, and each proven chunk raises the cap by one again.  ``max_halvings``: how deep a
    link may be cut.  :meth:`follow` sets the compiled system's parameters and its
    counters as it goes: one follower per thread.
    """

    def __init__(
        self,
        robot: Robot,
        formulation: str = "auto",
        *,
        chunk: int = 16,
        max_chunk: int = 64,
        max_halvings: int = 3,
    ):
        self.tracker = Tracker(robot, formulation)
        self.robot = robot
        self.chunk = chunk
        self.max_chunk = max_chunk
        self.max_halvings = max_halvings
        tr = self.tracker
        self._rho = tr.rho_mask
        self._names = tr.csys.param_names
        self._fu, self._fu_flat = self._u_jacobian()

    # -- parameters ------------------------------------------------------------------------
    def _set_u(self, u: np.ndarray) -> None:
        self.tracker.set_controls(u)

    def _set_hull(self, us: np.ndarray) -> None:
        self.tracker.set_controls((us.min(axis=0), us.max(axis=0)))

    # -- the parts -------------------------------------------------------------------------
    def _newton(self, index: int, u: np.ndarray, guesses) -> _Point:
        """Newton for ``u`` from the first guess that converges (params set to ``u``)."""
        self._set_u(u)
        msg = ""
        for g in guesses:
            x, _, _, msg = self.tracker.newton(g)
            if not msg:
                return _Point(u=u, x=x)
        if msg == "singular Jacobian":
            raise _Lost(index, LostReason.SINGULAR, "the Jacobian is singular")
        raise _Lost(index, LostReason.NEWTON, "Newton did not converge")

    def _own_proof(self, index: int, p: _Point, h: float) -> None:
        """The step's own Krawczyk proof (params set to ``p.u``), at ``h``, ``h/2``, ``h/4``."""
        tr = self.tracker
        self._set_u(p.u)
        for hh in (h, 0.5 * h, 0.25 * h):
            ok, elo, ehi, _, _ = tr.krawczyk(*tr.box(p.x - hh, p.x + hh), p.x)
            if ok:
                p.elo, p.ehi, p.h = elo, ehi, hh
                self.own_proofs += 1
                return
        _, J = tr.csys.fj_point_float(p.x)
        cond = float(np.linalg.cond(J))
        if not cond < SINGULAR_COND:
            raise _Lost(
                index,
                LostReason.SINGULAR,
                f"the Jacobian is nearly singular (condition number {cond:.3g}): "
                "a fold or a bifurcation of the equilibria",
                p,
            )
        raise _Lost(
            index,
            LostReason.CERTIFICATE,
            f"Krawczyk test failed at half-width {0.25 * h:g} cm: the "
            "equilibrium may not be unique near the Newton point",
            p,
        )

    def _chunk_proof(self, pts: list[_Point], fs: list, h: float) -> bool:
        """The chunk's proof (module docstring), and its steps' proofs with its ``Y``.

        ``fs``: rigorous ``f(x_k; u_k)`` of each point (``None`` for the first, proven
        already).  True if the chunk's link is proven; then each step is proven with the
        chunk's ``Y`` where that works (``elo``/``ehi`` set), the others are left to
        their own proof.
        """
        tr = self.tracker
        xs = np.array([p.x for p in pts])
        box_lo, box_hi = tr.box(xs.min(axis=0) - h, xs.max(axis=0) + h)
        us = np.array([p.u for p in pts])
        mid = len(pts) // 2  # >= 1: its f(x; u) is in fs
        c = pts[mid].x
        bounds = self._b_along(c, us, pts[mid].u, fs[mid])
        self._set_hull(us)
        ok, _, _, kp, (box_lo, box_hi) = tr.krawczyk(box_lo, box_hi, c, b=bounds)
        if not ok or kp is None:
            return False
        # from here [box_lo, box_hi] is where the chunk's J was enclosed (X, or the box
        # narrowed by the first test): the steps' boxes are taken inside it
        todo = [i for i, f in enumerate(fs) if f is not None and pts[i].elo is None]
        if todo:
            c_k = xs[todo]
            flo = np.array([fs[i][0] for i in todo])
            fhi = np.array([fs[i][1] for i in todo])
            fc, fr = mr_from_bounds(flo, fhi)
            with np.errstate(all="ignore"):
                bc, br = mr_matmul(kp.Y, None, fc.T, fr.T)
            lo = np.empty_like(c_k)
            hi = np.empty_like(c_k)
            for j, i in enumerate(todo):
                lo[j], hi[j] = tr.box(pts[i].x - h, pts[i].x + h)
            lo, hi = np.fmax(lo, box_lo), np.fmin(hi, box_hi)  # inside where J holds
            # |I - Y J| bounds the Jacobians over the hull of a box and its centre only if
            # that centre is inside too (a step whose point is not is proven alone)
            inside = np.all((box_lo <= c_k) & (c_k <= box_hi), axis=1)
            done = np.zeros(len(todo), dtype=bool)
            for _ in range(3):  # a box whose test fails is re-tested narrowed (Tracker._prove)
                klo, khi, proven = krawczyk_image(c_k, lo, hi, kp.mag, bc.T, br.T)
                nlo, nhi = np.fmax(klo, lo), np.fmin(khi, hi)
                for j in np.flatnonzero(proven & inside & ~done).tolist():
                    pts[todo[j]].elo, pts[todo[j]].ehi, pts[todo[j]].h = nlo[j], nhi[j], h
                done |= proven & inside
                if done.all():
                    break
                keep = ~np.any(nlo > nhi, axis=1)  # empty: no zero (cannot be at a Newton point)
                lo, hi = np.where(keep[:, None], nlo, lo), np.where(keep[:, None], nhi, hi)
        return True

    def _b_along(self, c: np.ndarray, us: np.ndarray, anchor: np.ndarray, f_anchor):
        """A function of ``Y`` bounding ``Y f(c; u)`` for every ``u`` on the polyline ``us``
        (``f_anchor``: the bounds of ``f(c; anchor)``, the point's own, computed already).

        Mean value form in ``u`` about ``anchor`` (a vertex): for ``u`` on the link
        ``u_k -> u_{k+1}``, ``u - anchor ∈ d_k = (u_k - anchor) + [0, 1] (u_{k+1} - u_k)``
        and ``f(c; u) ∈ f(c; anchor) + F_u(c; U) d_k`` with ``F_u`` the Jacobian in ``u``
        enclosed over the hull ``U`` of the polyline (each ``f_i`` takes its mean value on
        the segment from ``anchor`` to ``u``, inside ``U``).  Then
        ``Y f ∈ Y f(c; anchor) + (Y F_u) d_k``: ``(Y F_u) d_k`` is about the motion of the
        solution along the link (``Y F_u ≈ -dx/du``), where ``Y`` times one box of ``f``
        over ``U`` would be several times wider (the wrapping effect).  All products in
        midpoint-radius form (:func:`~certsolve.interval.linalg.mr_matmul`), the sums
        rounded outward; the bound is the hull over the links.
        """
        csys = self.tracker.csys
        n, m = csys.n, self.robot.m
        ulo, uhi = us.min(axis=0), us.max(axis=0)
        xl = c.tolist()
        dlo, dhi = self._fu.interval(xl + ulo.tolist(), xl + uhi.tolist(), [], [])
        fulo = np.zeros(n * m)
        fuhi = np.zeros(n * m)
        fulo[self._fu_flat] = dlo
        fuhi[self._fu_flat] = dhi
        fu_c, fu_r = mr_from_bounds(fulo.reshape(n, m), fuhi.reshape(n, m))
        fc, fr = mr_from_bounds(*f_anchor)
        e = arith.sub(us[:-1], us[:-1], anchor, anchor)
        step = arith.sub(us[1:], us[1:], us[:-1], us[:-1])
        d = arith.add(*e, np.minimum(step[0], 0.0), np.maximum(step[1], 0.0))
        d_c, d_r = mr_from_bounds(*d)

        def bounds(Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            with np.errstate(all="ignore"):
                ac, ar = mr_matmul(Y, None, fc[:, None], fr[:, None])
                mc, mr = mr_matmul(Y, None, fu_c, fu_r)
                qc, qr = mr_matmul(mc, mr, d_c.T, d_r.T)
            lo, hi = arith.add(*mr_to_bounds(ac, ar), *mr_to_bounds(qc, qr))
            return mr_from_bounds(lo.min(axis=1), hi.max(axis=1))

        return bounds

    def _u_jacobian(self) -> tuple[ScalarProgram, np.ndarray]:
        """Generated code for ``∂f/∂u`` (``u`` as variables after the system's own): the
        program and the flat ``(n, m)`` indices of its outputs (the others are zero)."""
        system = self.tracker.fk.form.system
        names = list(system.variables) + list(self._names)
        g = Graph(names)
        n = len(system.variables)
        nodes, flat = [], []
        for i, eq in enumerate(system.equations):
            root = g.add_expr(_params_as_variables(eq))
            for j in range(len(self._names)):
                dn = g.derivative(root, n + j)
                if dn is not None:
                    nodes.append(dn)
                    flat.append(i * len(self._names) + j)
        return ScalarProgram(g, nodes), np.array(flat, dtype=int)

    def _f_at(self, p: _Point):
        """Rigorous ``f(x; u)`` at the point (params set to ``p.u`` by :meth:`_newton`)."""
        return self.tracker.csys.f_point(p.x)

    def _link(self, index: int, a: _Point, b: _Point, h: float, depth: int) -> int:
        """Prove the link ``a -> b`` alone, cutting it at its middle control if needed;
        returns how deep it was cut.  ``b`` gets its step proof on the way."""
        fb = self._f_at_u(b)
        if self._chunk_proof([a, b], [None, fb], h):
            return depth
        if depth >= self.max_halvings:
            raise _Lost(
                index,
                LostReason.LINK,
                f"the link from step {index - 1} could not be proven "
                f"(cut {depth} times): two equilibria may meet near there (a fold), "
                "the path may jump branch",
                b,
            )
        self.halvings += 1
        um = 0.5 * a.u + 0.5 * b.u
        m = self._newton(index, um, [0.5 * a.x + 0.5 * b.x, a.x, b.x])
        self._own_proof(index, m, h)
        d1 = self._link(index, a, m, h, depth + 1)
        d2 = self._link(index, m, b, h, depth + 1)
        return max(d1, d2)

    def _f_at_u(self, p: _Point):
        self._set_u(p.u)
        return self._f_at(p)

    # -- the path --------------------------------------------------------------------------
    def follow(self, controls, start: Pose | FKPose, half_width: float = 0.1) -> TrajectoryResult:
        """Follow ``controls`` (``(N, m)``) from ``start`` (module docstring)."""
        t0 = time.perf_counter()
        us = np.asarray(controls, dtype=float)
        if us.ndim != 2 or us.shape[1] != self.robot.m or us.shape[0] == 0:
            raise ValueError(f"controls: expected rows of {self.robot.m} values")
        if not half_width > 0:
            raise ValueError("half_width must be positive")
        self.chunks = self.chunk_failures = self.halvings = self.own_proofs = 0
        h = float(half_width)
        tr = self.tracker
        pts: list[_Point] = []
        joined: list[bool | None] = []
        depths: list[int] = []
        lost: _Lost | None = None
        try:
            first = self._newton(0, us[0], [tr.initial_point(start)])
            self._own_proof(0, first, h)
            bad = self._tension_failure(0, [first])
            if bad is not None:
                raise bad
            pts.append(first)
            joined.append(None)
            depths.append(0)
            size, cap = self.chunk, self.max_chunk  # cap: below the last size that failed
            pending: list[_Point] = []  # solved ahead, not yet proven
            fs: list = []  # their rigorous f(x; u)
            ahead: _Lost | None = None  # where Newton failed ahead
            k = 1
            while k < len(us):
                while len(pending) < size and k + len(pending) < len(us) and ahead is None:
                    j = k + len(pending)
                    chain = [*pts[-2:], *pending][-2:]
                    guesses = [chain[-1].x]
                    if len(chain) == 2:  # the secant prediction first
                        guesses.insert(0, 2 * chain[-1].x - chain[-2].x)
                    try:
                        p = self._newton(j, us[j], guesses)
                    except _Lost as e:
                        ahead = e
                        break
                    pending.append(p)
                    fs.append(self._f_at(p))
                if not pending:
                    assert ahead is not None
                    raise ahead
                chunk = pending[:size]
                if self._chunk_proof([pts[-1], *chunk], [None, *fs[: len(chunk)]], h):
                    self.chunks += 1
                    depth = [0] * len(chunk)
                    cap = min(cap + 1, self.max_chunk)  # probe upwards again, slowly
                    size = min(2 * size, cap)
                elif len(chunk) > 1:  # split: retry with the first half
                    self.chunk_failures += 1
                    cap = max(1, len(chunk) - 1)
                    size = max(1, len(chunk) // 2)
                    continue
                else:  # one link: cut it
                    depth = [self._link(k, pts[-1], chunk[0], h, 0)]
                    size = 1
                good, err = len(chunk), None
                try:
                    for j, p in enumerate(chunk):
                        if p.elo is None:
                            self._own_proof(k + j, p, h)
                except _Lost as e:
                    good, err = e.index - k, e
                bad = self._tension_failure(k, chunk[:good])
                if bad is not None:
                    good, err = bad.index - k, bad
                pts.extend(chunk[:good])
                joined.extend([True] * good)
                depths.extend(depth[:good])
                if err is not None:
                    raise err
                k += len(chunk)
                del pending[: len(chunk)], fs[: len(chunk)]
        except _Lost as e:
            lost = e
        steps = [self._step(i, p, joined[i], depths[i], certified=True) for i, p in enumerate(pts)]
        status, lost_at, reason, why = TrajectoryStatus.COMPLETE, None, "", None
        if lost is not None:
            status, lost_at, reason, why = TrajectoryStatus.LOST, lost.index, lost.text, lost.why
            at = lost.point
            steps.append(
                TrajectoryStep(
                    index=lost.index,
                    u=us[lost.index],
                    certified=False,
                    joined=False if lost.why is LostReason.LINK else None,
                    pose=None if at is None else self._decode(at, proven=at.elo is not None),
                )
            )
        return TrajectoryResult(
            robot=self.robot.name,
            formulation=tr.form.name,
            half_width=h,
            status=status,
            lost_at=lost_at,
            reason=reason,
            lost_reason=why,
            steps=steps,
            chunks=self.chunks,
            chunk_failures=self.chunk_failures,
            halvings=self.halvings,
            own_proofs=self.own_proofs,
            time=time.perf_counter() - t0,
        )

    def _tension_failure(self, index: int, pts: list[_Point]) -> _Lost | None:
        """None if every wire's tension, over each step's proven box (steps ``index,
        index + 1, ...``), is inside its bounds; else the first step and wire that may
        leave them."""
        r = self.robot
        elo = np.array([p.elo for p in pts])
        ehi = np.array([p.ehi for p in pts])
        us = np.array([p.u for p in pts])
        tlo, thi = tension_enclosure(r, elo[:, self._rho], ehi[:, self._rho], us)
        low, high = tlo < r.tau_min, thi > r.tau_max
        bad = np.flatnonzero(np.any(low | high, axis=1))
        if bad.size == 0:
            return None
        j = int(bad[0])
        i = int(np.flatnonzero(low[j] | high[j])[0])
        if low[j, i]:
            word, bound, sure = "minimum", r.tau_min[i], thi[j, i] < r.tau_min[i]
        else:
            word, bound, sure = "maximum", r.tau_max[i], tlo[j, i] > r.tau_max[i]
        return _Lost(
            index + j,
            LostReason.TENSION,
            f"wire {i + 1} {'leaves' if sure else 'may leave'} its tension "
            f"bounds: tension in [{tlo[j, i]:.6g}, {thi[j, i]:.6g}] N, {word} {bound:g} N",
            pts[j],
        )

    def _decode(self, p: _Point, *, proven: bool) -> FKPose:
        lo, hi = (p.elo, p.ehi) if proven else (p.x, p.x)
        pose = self.tracker.fk.decode(lo, hi, p.u, point=p.x, verdict=StabilityVerdict.unknown())
        if not proven:
            pose.certificate = "none"
        return pose

    def _step(self, i: int, p: _Point, joined, depth: int, *, certified: bool) -> TrajectoryStep:
        return TrajectoryStep(
            index=i,
            u=p.u,
            certified=certified,
            joined=joined,
            pose=self._decode(p, proven=True),
            halvings=depth,
        )


def track_trajectory(
    robot: Robot,
    controls,
    start,
    *,
    half_width: float = 0.1,
    formulation: str = "auto",
    tau_max: float | None = None,
) -> TrajectoryResult:
    """Follow the equilibrium branch from ``start`` along ``controls`` (one control
    vector per row), each step certified and joined to the previous one (module
    docstring); the one-off form of :class:`TrajectoryFollower`.

    ``start``: a :class:`~certsolve.robot.Pose`, an :class:`FKPose` or pose parameters
    (``[x, y, theta]``, ``[x, y, z, yaw, pitch, roll]``; cm, degrees) near the equilibrium
    at the first row.
    The inputs are checked as the ``trajectory`` job and ``certsolve track`` check them
    (:class:`~certsolve.robot.inputs.TrajectoryOptions`): a value they refuse raises
    :class:`~certsolve.inputs.InputError` naming it (``controls.3``: the fourth row).
    """
    if isinstance(start, FKPose):
        start = Pose(start.position, start.rotation)
    pose = as_pose(robot.dof, start, "start")
    values = pose.params(robot.dof)
    opts = checked(
        TrajectoryOptions,
        {
            "controls": controls,
            "start": values,
            "half_width": half_width,
            "formulation": formulation,
            "tau_max": tau_max,
        },
    )
    check_trajectory(robot.m, opts.controls)
    return follower_for(robot, opts).follow(np.array(opts.controls), pose, opts.half_width)


def follower_for(robot: Robot, opts: TrajectoryOptions) -> TrajectoryFollower:
    """The follower of checked options: ``tau_max`` applied, a formulation the tracker
    cannot use refused as :class:`~certsolve.inputs.InputError` at ``formulation``."""
    try:
        return TrajectoryFollower(with_tau_max(robot, opts.tau_max), opts.formulation)
    except ValueError as exc:
        raise InputError("formulation", str(exc)) from None
