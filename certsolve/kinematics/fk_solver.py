"""The forward-kinematics solver: control vector ``u`` -> every equilibrium pose.

:class:`FKSolver` builds a formulation (:mod:`.fk_systems`) and compiles it once for a
robot, and solves it for any ``u`` (the control vector is the value of the compiled
system's parameters, given to each search), returning an
:class:`FKResult`: every pose in the search domain, each certified to be the only solution
in its box, plus undecided and pending boxes -- the solver's guarantees, read back as poses.
:func:`.fk.forward_kinematics` is the one-call form; :mod:`.seeding` builds on this module.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem
from ..inputs import InputError
from ..robot.elastic import tension
from ..robot.geometry import euler_zyx
from ..robot.model import Robot
from ..robot.schema import RobotSpec
from ..solver import SearchStatus, Solver, SolverLimits
from ..solver.certify import Certifier
from ..solver.contractors import HC4
from ..solver.pipeline import FixPoint, Inflate, Sequence, core
from ..solver.relaxation import PolytopeHull
from ..solver.result import SolveResult
from ..solver.starts import NewtonStarts
from .energy_minima import energy_minima
from .fk_formulation import FKFormulation
from .fk_position import ForceBalance, PositionNewton
from .fk_systems import build_formulation
from .stability import EnergyHessian, Stability, StabilityVerdict
from .stable_only import StableOnly

__all__ = ["FK_STARTS", "SEED_RADIUS", "FKPose", "FKResult", "FKSearch", "FKSolver", "with_tau_max"]

#: half-width (cm) of the seed boxes around the energy's local minima, in every chosen
#: point's coordinates (``seed_minima``)
SEED_RADIUS = 0.5
#: float Newton from random points of the pending boxes (``newton_starts``): drawn uniformly
#: in the boxes (the domain is the robot's, in cm), six phases, at 64 to 65,536 bisections
#: (45 to 46,080 on general-19's 19 variables; such a search at 60 N makes ~7,000 a CPU
#: second); full Newton steps, as measured in docs/fk-cost.md
FK_STARTS = NewtonStarts(near=None, phases=6)


@dataclass
class FKPose:
    """One certified equilibrium pose."""

    position: np.ndarray  # (d,) platform frame origin, world
    rotation: np.ndarray  # (d, d)
    platform_points: np.ndarray  # (m, d) world coordinates of every wire's B_i
    rho: np.ndarray  # (m,)
    tau: np.ndarray  # (m,)
    box: list  # existence box of the system's variables
    variables: list[str]
    certificate: str = "unique"
    verified: bool | None = None
    #: stable / unstable / undecided over ``box``, with an enclosure of the Hessian's
    #: smallest eigenvalue (:mod:`.stability`)
    stability: StabilityVerdict = field(default_factory=StabilityVerdict.unknown)
    #: a robot with tolerances: bounds of the pose over the box for every robot of the set
    #: (:class:`.fk_tolerance.PoseBounds`); None for an exact robot
    bounds: Any = None

    @property
    def euler_deg(self) -> np.ndarray:
        if self.rotation.shape == (3, 3):
            return np.degrees(euler_zyx(self.rotation))
        return np.degrees([np.arctan2(self.rotation[1, 0], self.rotation[0, 0])])

    def to_dict(self) -> dict:
        return {
            "position": self.position.tolist(),
            "rotation": self.rotation.tolist(),
            "euler": self.euler_deg.tolist(),
            "platform_points": self.platform_points.tolist(),
            "rho": self.rho.tolist(),
            "tau": self.tau.tolist(),
            "certificate": self.certificate,
            "verified": self.verified,
            "box": self.box,
            "variables": list(self.variables),
            **self.stability.to_dict(),
            **({} if self.bounds is None else self.bounds.to_dict()),
        }


@dataclass
class FKResult:
    robot: str
    formulation: str
    u: np.ndarray
    status: SearchStatus  # of the search (see :class:`~certsolve.solver.SearchStatus`)
    solutions: list[FKPose]
    solve: SolveResult  # the underlying solver result (undecided, pending, stats)
    seeding: dict | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def undecided(self):
        return self.solve.undecided

    @property
    def pending(self):
        return self.solve.pending

    @property
    def stats(self):
        return self.solve.stats

    def to_dict(self) -> dict:
        d = self.solve.to_dict()
        return {
            "robot": self.robot,
            "formulation": self.formulation,
            "u": self.u.tolist(),
            "status": str(self.status),
            "solutions": [s.to_dict() for s in self.solutions],
            "variables": d["variables"],
            "undecided": d["undecided"],
            "pending": d["pending"],
            **{k: d[k] for k in ("undecided_total", "undecided_dropped", "pending_total")},
            "pending_boxes": d["pending_boxes"],
            "stats": d["stats"],
            "seeding": self.seeding,
            "notes": list(self.notes),
        }


def with_tau_max(robot: Robot | RobotSpec, tau_max: float | None) -> Robot:
    """The robot with every wire's ``tau_max`` replaced (paper: 10, 20, 60 N ...).

    ``robot`` may be its file's model (:class:`~certsolve.robot.schema.RobotSpec`): the
    :class:`Robot` is then built once, with the new limits.
    """
    if tau_max is None:
        return robot if isinstance(robot, Robot) else Robot.from_spec(robot)
    spec = robot.spec if isinstance(robot, Robot) else robot
    data = spec.model_dump()
    for w in data["wires"]:
        w["tau"] = [min(w["tau"][0], float(tau_max)), float(tau_max)]
    return Robot.load(data)


@dataclass(kw_only=True)
class FKSearch:
    """The search for one control vector: ``u`` (checked), the search box ``domain`` of
    eq. (7), ``ok``: whether it is non-empty, and the ``solver`` assembled for it (on
    ``domain``, the compiled system with ``u`` as its parameter values)."""

    u: np.ndarray
    domain: np.ndarray
    ok: bool
    solver: Solver


class FKSolver:
    """Compile a formulation once, solve forward kinematics for many control vectors.

    The formulation (:mod:`.fk_systems`) is built and its system compiled once; each
    :meth:`solve` assembles a solver from the formulation's parts for its ``u``
    (:meth:`search`): nothing built or compiled here changes from one ``u`` to the next.

    ``stable_only``: search for the stable equilibria only (:mod:`.stable_only`: boxes
    whose interval Hessian of the energy is proven not positive definite are dropped, and
    so are the certified poses proven unstable); ``complete`` then means that no other
    stable equilibrium is in the domain.

    ``seed_minima`` (spatial robots, point formulations): each search first finds the
    local minima of the potential energy in floats (:mod:`.energy_minima`, a fraction of
    a second) and searches boxes of :data:`SEED_RADIUS` cm around them before the whole
    domain (:meth:`seeded_boxes`: the answer is the same, and as complete); the stable
    equilibria -- where a robot at rest is -- come first, in the
    first rounds, and a search stopped by a limit still reports them.

    ``position_newton`` (platform-frame formulations): a parametric interval Newton step
    on the force balance in the reference point, the wire lengths taken from the pose,
    over each box's orientations (:mod:`.fk_position`), before the full Newton step.  Off
    by default: fewer boxes, and more CPU but on T-16 at 60 N (docs/fk-cost.md, "The
    position determined by the orientation", medians of 3 interleaved): T-16 at 60 N,
    u = IK(P), 331,313 -> 257,034 boxes, 22.4 -> 22.2 CPU s; general-19 at 10 N 128,721 ->
    124,533, 11.3 -> 13.5 s; T-16 at 10 N 1,694 -> 1,570, 0.71 -> 0.76 s.

    ``newton_starts``: float Newton from random points of the pending boxes, the points it
    converges to proven as the search's own solutions (:mod:`certsolve.solver.starts`,
    :data:`FK_STARTS`: drawn uniformly in the boxes, six phases, from 64 to 65,536
    bisections on T-16, from 45 to 46,080 on general-19's 19 variables).  The poses,
    stable and unstable, come in the first seconds where the search alone reaches them
    late; the search still covers the domain, so a complete answer is the same.  Off for
    ``stable_only`` (the energy's minima seed the stable poses; a phase would prove
    unstable ones, which ``max_solutions`` would count) and for a robot set's search
    (:mod:`.fk_tolerance`).

    ``relax``: the polytope hull of the X-Taylor and affine relaxation
    (:class:`.PolytopeHull`, one direction) once a round, after the contraction fixpoint,
    on every box narrower than the formulation's hull widths
    (:meth:`.FKFormulation.hull_widths`: the orientation within ~0.2 of the longest edge,
    where it empties half the boxes or more) and on the wider ones as its learnt share plans
    (``PolytopeHull(always=...)``, :class:`.HullShare`: every box while it halves enough of
    them, one in 16 otherwise).  By default on for the general-19 system, off for the
    others (docs/fk-cost.md, "The polytope hull once a round"; CPU s, medians of 3
    interleaved):
    general-19 at 10 N, u = 0, 128,721 -> 17,535 boxes, 10.1 -> 3.6 s; at 60 N, u drawn
    in the strokes, 156,877 -> 35,511 boxes, 10.5 -> 5.7 s; T-16 at 60 N, u = IK(P),
    331,313 -> 318,751 boxes, 20.1 -> 19.3 s, but more CPU at 10 N (0.67 -> 0.81 s).
    """

    def __init__(
        self,
        robot: Robot,
        formulation: str = "auto",
        *,
        eps: float = 1e-8,
        batch_size: int = 2048,
        stable_only: bool = False,
        seed_minima: bool = True,
        position_newton: bool = False,
        relax: bool | None = None,
        newton_starts: bool = True,
        prepare_search: bool = True,
    ):
        # batch_size: boxes per numpy call.  The FK systems' batches are large enough for
        # numpy's per-call cost to matter: 2048 against 512 is 25-30 % less CPU with the
        # same boxes (general-19 u~S(2) and T-16 u=2 at 60 N, general-19 at 10 N); 4096 and
        # 8192 are slower again (cache).  Peak RSS of T-16 at 60 N: 160 MB (113 MB at 512).
        self.robot = robot
        self.form: FKFormulation = build_formulation(robot, formulation)
        #: the compiled system (its parameters: ``u = 0``; each search gets its own values)
        self.csys = CompiledSystem(self.form.system)
        self.eps = eps
        self.batch_size = batch_size
        #: search for stable equilibria only: boxes proven to hold none are dropped, after
        #: HC4 and the partial Newton, before the full Newton step
        self.stable_only = stable_only
        #: search around the energy's local minima first (spatial robots only)
        self.seed_minima = seed_minima and robot.dof == 6
        #: the position's Newton step over each box's orientations (:mod:`.fk_position`;
        #: platform-frame formulations only), before the full Newton step
        if position_newton and robot.toleranced:  # its interval path is not tested yet
            raise InputError("position_newton", "not available for a robot with tolerances")
        self.position_newton = position_newton
        #: the polytope hull once a round (default: the general-19 system only; on the
        #: smaller systems its LPs cost more than the boxes they save)
        self.relax = "general-19" in self.form.name if relax is None else bool(relax)
        #: the phases of float Newton from random points (:data:`FK_STARTS`)
        self.newton_starts = newton_starts and not stable_only
        # the parts' compiled programs (Newton's columns, the sub-systems', the energy's
        # Hessian for stable_only) are made now, once, and shared by every search's copy;
        # prepare_search=False: the formulation and its compiled system only (a tracker
        # never searches: building one, T-16 74 -> 65 ms, general-19 138 -> 129 ms CPU)
        if prepare_search:
            self.search(np.zeros(robot.m))

    @property
    def formulation(self) -> str:
        return self.form.name

    def search_box(self, u) -> np.ndarray:
        """The FK search domain ``(n, 2)`` for control ``u`` (eq. 7: wire lengths allowed by
        the tension limits; the system's own domain is left as it is)."""
        return self.form.search_domain(np.asarray(u, dtype=float).ravel())[0]

    def search(self, u, extra: tuple = ()) -> FKSearch:
        """The search for control ``u``: ``u`` checked, its search box, and the solver.

        The solver is assembled from the formulation's parts, without CID: HC4, partial
        Newton on the formulation's sub-systems, Newton with its mixed Jacobian, in a
        fixpoint, then (``relax``) the polytope hull once, then inflated proofs -- on the
        compiled system with ``u`` as its parameter values
        (:meth:`.CompiledSystem.with_parameters`; ``extra`` contractors go before the full
        Newton step), the formulation's bisector for the box and its bisection mask.
        """
        u = np.asarray(u, dtype=float).ravel()
        if u.shape != (self.robot.m,):
            raise ValueError(f"u: expected {self.robot.m} values (one per wire), got {u.size}")
        if not np.all(np.isfinite(u)):
            raise ValueError("u: values must be finite")
        form = self.form
        dom, ok = form.search_domain(u)
        csys = self.csys.with_parameters(form.parameters_for(u))
        newton = core(
            csys,
            hc4=HC4(csys),
            subsystems=form.subsystems(),
            newton_groups=form.newton_groups(),
        )
        if self.position_newton:
            newton.insert(-1, PositionNewton(self.forces, csys))
        if self.stable_only:
            newton.insert(-1, StableOnly(self.hessian, csys, self.robot, form.rho_columns()))
        newton[-1:-1] = list(extra)  # e.g. the set's Krawczyk (:mod:`.fk_tolerance`)
        rounds: list[Any] = [FixPoint(Sequence(*newton))]
        if self.relax:
            rounds.append(PolytopeHull(csys, directions=1, always=form.hull_widths()))
        solver = Solver(
            csys,
            Sequence(*rounds, Inflate()),
            Certifier(csys),
            form.bisector(dom),
            limits=SolverLimits(
                eps=self.eps, batch_size=self.batch_size, bisect_mask=form.bisect_mask()
            ),
            starts=FK_STARTS if self.newton_starts and not extra else None,
        )
        return FKSearch(u=u, domain=dom, ok=ok, solver=solver.on_domain(dom))

    def solve(
        self,
        u,
        *,
        timeout: float | None = None,
        max_boxes: int | None = None,
        max_solutions: int | None = None,
        progress=None,
        executor: Any = None,
        verify: bool = False,
        boxes: tuple[np.ndarray, np.ndarray] | None = None,
        cancel: Any = None,
        workers: int | None = None,
        checkpoint: Any = None,
    ) -> FKResult:
        """All equilibrium poses for control ``u`` (``boxes``: search only these boxes).

        Limits, ``executor``, ``progress``, ``cancel`` and ``checkpoint`` as
        :meth:`.Solver.solve` (the fingerprint covers ``u``: the system's parameters and
        domain).
        """
        search = self.search(u)
        u = search.u
        notes = []
        seeding = None
        if boxes is None and self.seed_minima and search.ok:
            boxes, seeding = self.seeded_boxes(u, search.domain)
        for i in (
            np.flatnonzero(u < self.robot.u_min).tolist()
            + np.flatnonzero(u > self.robot.u_max).tolist()
        ):
            notes.append(
                f"u{i + 1} = {u[i]:g} is outside the stroke "
                f"[{self.robot.u_min[i]:g}, {self.robot.u_max[i]:g}]"
            )
        if not search.ok:
            notes.append("no wire length satisfies the tension limits inside the domain")
            res = SolveResult(list(self.form.system.variables), SearchStatus.COMPLETE)
            return FKResult(self.robot.name, self.formulation, u, res.status, [], res, notes=notes)
        res = search.solver.solve(
            timeout=timeout,
            max_boxes=max_boxes,
            max_solutions=max_solutions,
            progress=progress,
            executor=executor,
            verify=verify,
            boxes=boxes,
            cancel=cancel,
            workers=workers,
            checkpoint=checkpoint,
        )
        sols = self.decode_all(res.solutions, u)
        if len(sols) < len(res.solutions):
            left = len(res.solutions) - len(sols)
            notes.append(f"stable only: {left} unstable pose(s) left out")
        if self.stable_only and res.status != SearchStatus.COMPLETE:
            # the status is the result's own (a command's deadline turns a cancelled
            # search into a timeout after this): not repeated here
            notes.append(
                "stable only: the search stopped before the rest of the domain was "
                "refuted: another stable pose is not excluded"
            )
        return FKResult(
            self.robot.name, self.formulation, u, res.status, sols, res, seeding, notes=notes
        )

    def seeded_boxes(self, u, domain: np.ndarray) -> tuple[Any, dict]:
        """The initial boxes of a search seeded by the energy's local minima -- the whole
        domain, then the seed boxes, last, so that they are on top of the search's stack --
        and what the seeding did (for the result).

        A pose certified in a seed box is certified again where the domain's boxes reach
        it: the second proof is recognised as the same solution, and boxes inside its
        unicity box are dropped (:meth:`.SolutionSet.prune`), so the seeds cost little more
        than their own boxes.  (The exact difference of the domain minus the seeds, as
        planar seeding does, costs more: its slabs split worse; general-19 at 10 N,
        u = 0: 153,022 boxes against 128,670.)
        """
        t0 = time.perf_counter()
        minima = energy_minima(self.robot, u)
        boxes = (self.form.pose_box(m.position, m.rotation, SEED_RADIUS, domain) for m in minima)
        seeds = [s for s in boxes if s is not None]
        n = domain.shape[0]
        slo = np.array([a for a, _ in seeds]).reshape(-1, n)
        shi = np.array([b for _, b in seeds]).reshape(-1, n)
        info = {
            "method": "energy minima",
            "minima": len(minima),
            "seed_boxes": len(seeds),
            "seed_radius": SEED_RADIUS,
            "time": time.perf_counter() - t0,
        }
        return (np.vstack([domain[:, 0], slo]), np.vstack([domain[:, 1], shi])), info

    @functools.cached_property
    def forces(self) -> ForceBalance:
        """The force balance with the wire lengths taken from the pose, and its Jacobian in
        the position (compiled on first use; :mod:`.fk_position`)."""
        return ForceBalance(self.form)

    @functools.cached_property
    def hessian(self) -> EnergyHessian:
        """The interval Hessian of the potential energy (compiled on first use)."""
        return EnergyHessian(self.form)

    def decode_all(self, solutions, u) -> list[FKPose]:
        """:meth:`decode` of the solver's solutions, with one batched stability verdict
        (``stable_only``: the poses proven unstable are left out)."""
        if not solutions:
            return []
        lo = np.array([s.lo for s in solutions])
        hi = np.array([s.hi for s in solutions])
        verdicts = self.hessian.verdicts(lo, hi, u)
        return [
            self.decode(s.lo, s.hi, u, s, verdict=v)
            for s, v in zip(solutions, verdicts, strict=True)
            if not (self.stable_only and v.stability == Stability.UNSTABLE)
        ]

    def decode(self, lo, hi, u, sol=None, point=None, verdict=None) -> FKPose:
        """Read a robot pose from a (tight) solution box of the system's variables.

        The pose is taken at ``point`` if given (e.g. a converged Newton point inside the
        box), else at the box midpoint.  ``verdict``: its stability over the box (computed
        here if not given: :class:`.EnergyHessian`).
        """
        if verdict is None:
            verdict = self.hessian.verdicts(np.asarray(lo)[None], np.asarray(hi)[None], u)[0]
        x = 0.5 * np.asarray(lo) + 0.5 * np.asarray(hi) if point is None else np.asarray(point)
        rho = x[-self.robot.m :].copy()
        pos, R, points = self.form.decode(x)
        tau = tension(self.robot, rho, u)
        box = [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]
        return FKPose(
            pos,
            R,
            points,
            rho,
            tau,
            box,
            list(self.form.system.variables),
            certificate=getattr(sol, "certificate", "unique"),
            verified=getattr(sol, "verified", None),
            stability=verdict,
        )
