"""The forward-kinematics solver: control vector ``u`` -> every equilibrium pose.

:class:`FKSolver` compiles a formulation (:mod:`.fk_systems`) once for a robot and solves
it for any ``u`` (the control vector is a parameter of the compiled system), returning an
:class:`FKResult`: every pose in the search domain, each certified to be the only solution
in its box, plus undecided and pending boxes -- the solver's guarantees, read back as poses.
:func:`.fk.forward_kinematics` is the one-call form; :mod:`.seeding` builds on this module.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem
from ..robot.elastic import tension
from ..robot.geometry import euler_zyx
from ..robot.model import Robot
from ..solver import SearchStatus, Solver, SolverLimits
from ..solver.bisectors import Prioritized, SmearSumRelative
from ..solver.certify import Certifier
from ..solver.contractors import HC4
from ..solver.pipeline import FixPoint, Inflate, Sequence, core
from ..solver.result import SolveResult
from .fk_systems import (
    FKFormulation,
    build_formulation,
    pose_from_angles,
    rotation_from_points,
    search_domain,
)
from .stability import EnergyHessian, Stability, StabilityVerdict
from .stable_only import StableOnly

__all__ = ["FKPose", "FKResult", "FKSolver", "with_tau_max"]

#: the largest share of the position's width over the orientation's at which the frame
#: bisector still splits the orientation (:class:`.Prioritized` ``alpha``, see ``_prepare``)
ALPHA_MAX = 0.5
#: the same for general-19, whose orientation is split on E_2 and E_3 only (E_4 auxiliary):
#: each split of them gains more, and the position is worth splitting later (at 60 N, 0.35
#: against 0.5: u~S(2) 174,968 -> 164,109 boxes, u~S(3) 226,492 -> 201,974,
#: random-general-0 3.85M -> 3.21M; T-16 keeps 0.5: 0.35 costs it 17 % more boxes)
ALPHA_MAX_GENERAL = 0.35


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


def with_tau_max(robot: Robot, tau_max: float | None) -> Robot:
    """The same robot with every wire's ``tau_max`` replaced (paper: 10, 20, 60 N ...)."""
    if tau_max is None:
        return robot
    data = robot.spec.model_dump()
    for w in data["wires"]:
        w["tau"] = [min(w["tau"][0], float(tau_max)), float(tau_max)]
    return Robot.load(data)


def _newton_groups(names) -> list[np.ndarray]:
    """Variable groups for Hansen's mixed Jacobian: edge vectors, reference point, wire lengths.

    Group ``k``'s columns are enclosed with the later groups at the box midpoint, so the
    pose columns see each wire's weight ``w_i = τ_i / ρ_i`` at the midpoint length: the
    tension, whose range over a box (~1.6 N per mm of length at 60 N) is the widest factor
    of the equilibrium equations, becomes a point in 12 of the 19 columns.  Measured against
    the order wire lengths first (their ``A_i - B_i`` factor a point instead): general-19 at
    60 N u~S(2) 164,109 -> 156,910 boxes, u~S(3) 201,974 -> 190,602, random-general-0
    3.21M -> 2.83M, at 10 N 130,749 -> 128,672; T-16 u=2 at 60 N 284,674 -> 271,875,
    almost-planar-13 39,406 -> 38,882, T-16 at 10 N 1,577 -> 1,692.
    """
    rho = np.array([v.startswith("rho") for v in names])
    edge = np.array([v.startswith("e") for v in names])
    groups = [edge, ~rho & ~edge, rho]
    return [g for g in groups if g.any()]


class FKSolver:
    """Compile a formulation once, solve forward kinematics for many control vectors.

    ``stable_only``: search for the stable equilibria only (:mod:`.stable_only`: boxes
    whose interval Hessian of the energy is proven not positive definite are dropped, and
    so are the certified poses proven unstable); ``complete`` then means that no other
    stable equilibrium is in the domain.
    """

    def __init__(
        self,
        robot: Robot,
        formulation: str = "auto",
        *,
        eps: float = 1e-8,
        batch_size: int = 2048,
        stable_only: bool = False,
    ):
        # batch_size: boxes per numpy call.  The FK systems' batches are large enough for
        # numpy's per-call cost to matter: 2048 against 512 is 25-30 % less CPU with the
        # same boxes (general-19 u~S(2) and T-16 u=2 at 60 N, general-19 at 10 N); 4096 and
        # 8192 are slower again (cache).  Peak RSS of T-16 at 60 N: 160 MB (113 MB at 512).
        self.robot = robot
        self.form: FKFormulation = build_formulation(robot, formulation)
        # auxiliary variables, never split: the wire lengths (fixed by the pose through the
        # length equations) and, in general-19's frame, the fourth edge vector (fixed by the
        # other two through the fourth-point equalities; splitting only E_2, E_3 and P_1:
        # general-19 at 60 N u~S(2) 332,650 -> 174,968 boxes, u~S(3) 304,304 -> 226,492,
        # at 10 N 156,523 -> 130,749; random-general-0 at 60 N 3.92M -> 3.85M)
        mask = [not v.startswith("rho") for v in self.form.system.variables]
        for j in self.form.info.get("determined", []):
            mask[j] = False
        sub = self.form.info.get("translation")
        subsystems = [(sub["equations"], sub["variables"])] if sub else []
        # smear: the FK systems' figures (docs/fk-cost.md) were measured with it
        bisector = SmearSumRelative()
        if self.form.kind == "frame":
            # orientation (edge vectors) first; the reference point only while it is wide
            names = self.form.system.variables
            bisector = Prioritized(
                [v.startswith("e") for v in names],
                [not v.startswith(("e", "rho")) for v in names],
                alpha=0.25,
            )
        # the solver's pipeline without its relaxation (fewer boxes, more CPU: see
        # Solver.default's ``relax``) and without CID: HC4, partial Newton on the
        # translation, Newton with the mixed Jacobian, in a fixpoint; inflated proofs
        csys = CompiledSystem(self.form.system)
        newton = core(
            csys,
            hc4=HC4(csys),
            subsystems=subsystems,
            newton_groups=_newton_groups(self.form.system.variables),
        )
        #: search for stable equilibria only: boxes proven to hold none are dropped, after
        #: HC4 and the partial Newton, before the full Newton step
        self.stable_only = stable_only
        if stable_only:
            rho = [j for j, v in enumerate(self.form.system.variables) if v.startswith("rho")]
            newton.insert(-1, StableOnly(self.hessian, csys, robot, rho))
        self.solver = Solver(
            csys,
            Sequence(FixPoint(Sequence(*newton)), Inflate()),
            Certifier(csys),
            bisector,
            limits=SolverLimits(eps=eps, batch_size=batch_size, bisect_mask=mask),
        )
        self.csys = self.solver.csys

    @property
    def formulation(self) -> str:
        return self.form.name

    def search_box(self, u) -> np.ndarray:
        """The FK search domain ``(n, 2)`` for control ``u`` (eq. 7: wire lengths allowed by
        the tension limits; the system's own domain is left as it is)."""
        return search_domain(self.form, np.asarray(u, dtype=float).ravel())[0]

    def _prepare(self, u) -> tuple[np.ndarray, np.ndarray, bool]:
        """Checked ``u``, set as the system's parameters; the search domain for it and
        whether it is non-empty."""
        u = np.asarray(u, dtype=float).ravel()
        if u.shape != (self.robot.m,):
            raise ValueError(f"u: expected {self.robot.m} values (one per wire), got {u.size}")
        if not np.all(np.isfinite(u)):
            raise ValueError("u: values must be finite")
        self.csys.set_parameters(self.form.parameters_for(u))
        dom, ok = search_domain(self.form, u)
        bis = self.solver.bisector
        if isinstance(bis, Prioritized) and self.robot.dim == 3:
            # narrow wire-length ranges (low tension limits) pin the platform position once
            # its orientation is known: split the orientation first; wide ranges leave
            # the position free, so it is split sooner (measured: T-16 at 10 N / 60 N; a
            # planar platform has a single rotation and keeps the default), though never
            # before it is twice as wide as the orientation (ALPHA_MAX): at 60 N a split of
            # the orientation leaves ~0.27 of a surviving box after contraction, one of the
            # position ~0.65 (random-general-0; 0.5 instead of 0.75: general-19 u~S(2) and
            # T-16 u=2 at 60 N, 8 % and 1 % fewer boxes; docs/fk-cost.md)
            rho = np.array([v.startswith("rho") for v in self.form.system.variables])
            width = float(np.mean(dom[rho, 1] - dom[rho, 0])) if rho.any() else 0.0
            cap = ALPHA_MAX_GENERAL if self.form.info.get("determined") else ALPHA_MAX
            bis.alpha = float(np.clip(width / 25.0, 0.25, cap))
        return u, dom, ok

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
        u, dom, ok = self._prepare(u)
        notes = []
        for i in (
            np.flatnonzero(u < self.robot.u_min).tolist()
            + np.flatnonzero(u > self.robot.u_max).tolist()
        ):
            notes.append(
                f"u{i + 1} = {u[i]:g} is outside the stroke "
                f"[{self.robot.u_min[i]:g}, {self.robot.u_max[i]:g}]"
            )
        if not ok:
            notes.append("no wire length satisfies the tension limits inside the domain")
            res = SolveResult(list(self.form.system.variables), SearchStatus.COMPLETE)
            return FKResult(self.robot.name, self.formulation, u, res.status, [], res, notes=notes)
        res = self.solver.solve(
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
            domain=dom,
        )
        sols = self.decode_all(res.solutions, u)
        if len(sols) < len(res.solutions):
            left = len(res.solutions) - len(sols)
            notes.append(f"stable only: {left} unstable pose(s) left out")
        return FKResult(self.robot.name, self.formulation, u, res.status, sols, res, notes=notes)

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
        f = self.form
        r = self.robot
        m = r.m
        rho = x[-m:].copy()
        if f.kind in ("points", "frame"):
            P = f.points_from(x)
            points = f.L @ P
            pos, R = rotation_from_points(f, P)
        else:
            pos, R = pose_from_angles(f, x)
            points = pos + r.B @ R.T
        tau = tension(r, rho, u)
        box = [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]
        return FKPose(
            pos,
            R,
            points,
            rho,
            tau,
            box,
            list(f.system.variables),
            certificate=getattr(sol, "certificate", "unique"),
            verified=getattr(sol, "verified", None),
            stability=verdict,
        )
