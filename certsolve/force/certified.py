"""Certified isotropic-force workspace: a paving of a box of poses into proven parts.

Given ``f_req > 0`` and a box of positions (and, for rigid platforms, a fixed orientation
or ranges of angles), every box of the paving is

* **inside**: proven ``f_min ≥ f_req`` at every pose of the box (every interval ``g_k^±``
  of :mod:`.enclosure` has a non-negative lower bound, ``H`` is proven of full rank and no
  anchor is in the box);
* **outside**: proven ``f_min < f_req`` at every pose (one ``g_k^±`` has a negative upper
  bound over the whole box, no anchor in the box);
* **boundary**: undecided and narrower than ``eps`` (cm) in every position axis and
  ``eps_angle`` (degrees) in every angle axis;
* **pending**: not processed because the computation stopped early (timeout, progress
  callback returning ``False``, ``max_boxes``; the status says which).

Undecided boxes are bisected along their widest axis (relative to ``eps``/``eps_angle``);
boxes are processed in batches of ``batch`` with one set of numpy calls per batch
(:class:`PavingStep`, a step of the search driver :mod:`certsolve.solver.search`, so the
paving runs on local processes or a Dask cluster too).  A box's fate depends on that box
alone, so the paving is the same whatever the order or the executor.  Every decision
rests on outward-rounded interval arithmetic: no plain float enters a proof.

Measures (area for planar robots, volume for dof 6; with angle ranges the measure is the
product of position and angle widths, so shares stay meaningful) are sums of box volumes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..robot import Robot
from ..robot.params import RobotBounds
from ..solver.buffer import BoxStack
from ..solver.executors import resolve_executor
from ..solver.search import Limits, Progress, SearchStats, SearchStatus, Tally, run_search
from .enclosure import slack_enclosures
from .loads import force_rows

__all__ = ["CertifiedWorkspace", "PavingStep", "certified_workspace", "parse_box"]


@dataclass
class CertifiedWorkspace:
    robot: str
    dof: int
    min_force: float
    box: np.ndarray  # (d, 2) positions
    angles: np.ndarray  # (na, 2) degrees (empty for dof 2 / identity)
    angle_names: list[str]
    eps: float
    eps_angle: float
    inside: np.ndarray  # (n, nd, 2)
    outside: np.ndarray
    boundary: np.ndarray
    pending: np.ndarray
    status: SearchStatus  # complete, or what stopped the paving (then boxes are pending)
    boxes: int
    time: float
    notes: list[str] = field(default_factory=list)
    stats: SearchStats = field(default_factory=SearchStats)

    # -- measures -------------------------------------------------------------------------
    @staticmethod
    def _measure(b: np.ndarray) -> float:
        if b.size == 0:
            return 0.0
        w = b[..., 1] - b[..., 0]
        w = np.where(w > 0, w, 1.0)  # fixed angles do not count
        return float(np.sum(np.prod(w, axis=1)))

    @property
    def total_measure(self) -> float:
        allb = np.concatenate([self.box, self.angles]) if self.angles.size else self.box
        return self._measure(allb[None])

    @property
    def inside_measure(self) -> float:
        return self._measure(self.inside)

    @property
    def inside_share(self) -> float:
        t = self.total_measure
        return self.inside_measure / t if t > 0 else 0.0

    @property
    def unit(self) -> str:
        u = "cm^2" if self.dof != 6 else "cm^3"
        n_ang = int(np.sum(self.angles[:, 1] > self.angles[:, 0])) if self.angles.size else 0
        return u + ("*deg" if n_ang == 1 else f"*deg^{n_ang}" if n_ang else "")

    @property
    def complete(self) -> bool:
        return self.status == SearchStatus.COMPLETE

    def to_dict(self, boxes: bool = True) -> dict:
        total = self.total_measure
        out = {
            "robot": self.robot,
            "dof": self.dof,
            "min_force": self.min_force,
            "box": self.box.tolist(),
            "angles": {n: list(map(float, a)) for n, a in zip(self.angle_names, self.angles)},
            "eps": self.eps,
            "eps_angle": self.eps_angle,
            "status": str(self.status),
            "complete": self.complete,
            "boxes": self.boxes,
            "time": self.time,
            "stats": self.stats.to_dict(),
            "counts": {
                "inside": int(len(self.inside)),
                "outside": int(len(self.outside)),
                "boundary": int(len(self.boundary)),
                "pending": int(len(self.pending)),
            },
            "unit": self.unit,
            "total_measure": total,
            "inside_measure": self.inside_measure,
            "outside_measure": self._measure(self.outside),
            "boundary_measure": self._measure(self.boundary),
            "pending_measure": self._measure(self.pending),
            "inside_share": self.inside_share,
            "axes": ["x", "y", "z"][: self.box.shape[0]] + list(self.angle_names),
            "notes": list(self.notes),
        }
        if boxes:
            for k in ("inside", "outside", "boundary", "pending"):
                out[f"{k}_boxes"] = getattr(self, k).tolist()
        return out

    @classmethod
    def from_dict(cls, data: dict) -> CertifiedWorkspace:
        """The paving back from :meth:`to_dict` (with its boxes)."""
        box = np.asarray(data["box"], dtype=float).reshape(-1, 2)
        angles = data.get("angles") or {}
        ang = np.asarray(list(angles.values()), dtype=float).reshape(-1, 2)
        nd = len(box) + len(ang)

        def boxes(key: str) -> np.ndarray:
            if f"{key}_boxes" not in data:
                raise ValueError("the paving was saved without its boxes")
            return np.asarray(data[f"{key}_boxes"], dtype=float).reshape(-1, nd, 2)

        return cls(
            robot=data["robot"],
            dof=int(data["dof"]),
            min_force=float(data["min_force"]),
            box=box,
            angles=ang,
            angle_names=list(angles),
            eps=float(data["eps"]),
            eps_angle=float(data["eps_angle"]),
            inside=boxes("inside"),
            outside=boxes("outside"),
            boundary=boxes("boundary"),
            pending=boxes("pending"),
            status=SearchStatus(data["status"]),
            boxes=int(data["boxes"]),
            time=float(data["time"]),
            notes=list(data.get("notes", [])),
            stats=SearchStats(**data["stats"]) if "stats" in data else SearchStats(),
        )


def parse_box(box: ArrayLike, d: int) -> np.ndarray:
    """``[[xmin, xmax], ...]`` or ``[xmin, xmax, ymin, ymax, ...]`` -> ``(d, 2)`` array."""
    b = np.asarray(box, dtype=float)
    if b.shape == (2 * d,):
        b = b.reshape(d, 2)
    if b.shape != (d, 2):
        raise ValueError(
            f"box: expected {d} intervals (xmin,xmax,ymin,ymax{',zmin,zmax' * (d == 3)})"
        )
    if not np.all(np.isfinite(b)):
        raise ValueError("box: bounds must be finite")
    if np.any(b[:, 0] > b[:, 1]):
        raise ValueError("box: each interval needs min <= max")
    return b


def _parse_orientation(robot: Robot, orientation) -> tuple[np.ndarray, list[str]]:
    """Angle intervals (degrees): dof 3 ``θ``; dof 6 ``(yaw, pitch, roll)``; numbers or pairs."""
    if robot.dof == 2:
        if orientation is not None:
            raise ValueError("orientation: a point platform (dof 2) has no orientation")
        return np.zeros((0, 2)), []
    names = ["theta"] if robot.dof == 3 else ["yaw", "pitch", "roll"]
    if orientation is None:
        return np.zeros((len(names), 2)), names

    def number(x) -> bool:
        return isinstance(x, (int, float, np.integer, np.floating))

    if number(orientation):
        items = [orientation]
    elif robot.dof == 3 and len(orientation) == 2 and all(number(t) for t in orientation):
        items = [tuple(orientation)]  # one (lo, hi) range of theta
    else:
        items = list(orientation)
    if len(items) != len(names):
        raise ValueError(
            f"orientation: expected {len(names)} angle(s) ({', '.join(names)}, degrees)"
        )
    out = []
    for n, it in zip(names, items):
        a = np.atleast_1d(np.asarray(it, dtype=float))
        if a.size == 1:
            a = np.array([a[0], a[0]])
        if a.shape != (2,) or not np.all(np.isfinite(a)) or a[0] > a[1]:
            raise ValueError(f"orientation: {n} must be a number or a (lo, hi) pair of degrees")
        if a[1] - a[0] > 360:
            raise ValueError(f"orientation: {n} range wider than 360 degrees")
        out.append(a)
    return np.array(out), names


@dataclass
class PavingState:
    """The paving's state in a search: the buffer and the decided boxes."""

    stack: BoxStack
    inside: list = field(default_factory=list)  # (k, nd, 2) arrays
    outside: list = field(default_factory=list)
    boundary: list = field(default_factory=list)
    counts: dict = field(default_factory=lambda: {"inside": 0, "outside": 0, "boundary": 0})
    inside_measure: float = 0.0


class PavingStep:
    """The paving as a step of the search driver: prove a batch of boxes inside or
    outside, keep the narrow undecided ones as boundary, bisect the rest (see the module
    docstring).  Picklable: it holds the robot and the numbers of the request."""

    def __init__(
        self,
        robot: Robot,
        min_force: float,
        external: ArrayLike | None,
        d: int,
        use_rot: bool,
        scale: np.ndarray,
        total: float,
        batch: int,
        params: RobotBounds | None = None,
    ) -> None:
        self.robot = robot
        #: a robot with tolerances: its set's interval arrays (every robot must pass)
        self.params = params
        self.min_force = float(min_force)
        self.external = external
        self.d = d
        self.use_rot = use_rot
        self.scale = scale
        self.total = total
        self.batch_size = int(batch)

    def start(self, known: object = None) -> PavingState:
        return PavingState(BoxStack(self.scale.size))

    def fingerprint(self) -> str:
        """The robot and the request, as text (for checkpoints)."""
        ext = None if self.external is None else np.asarray(self.external).tolist()
        return (
            f"robot: {self.robot.spec.model_dump_json()}\nmin_force: {self.min_force!r}, "
            f"external: {ext}, d: {self.d}, rotation: {self.use_rot}, "
            f"eps: {self.scale.tolist()!r}"
        )

    def process(
        self, lo: np.ndarray, hi: np.ndarray, state: PavingState, *, deadline: float | None = None
    ) -> None:
        # ``deadline`` (:meth:`.Step.process`) is not used: no part of this round loops long
        d = self.d
        glo, ghi, full_rank, wires_ok = slack_enclosures(
            self.robot,
            lo[:, :d].T,
            hi[:, :d].T,
            self.min_force,
            self.external,
            alo=lo[:, d:].T if self.use_rot else None,
            ahi=hi[:, d:].T if self.use_rot else None,
            params=self.params,
        )
        ins = np.all(glo >= 0.0, axis=0) & full_rank & wires_ok
        out = np.any(ghi < 0.0, axis=0) & wires_ok & ~ins
        rel = (hi - lo) / self.scale
        small = np.all(rel <= 1.0, axis=1)
        bnd = ~ins & ~out & small
        split = ~ins & ~out & ~small
        for key, mask in (("inside", ins), ("outside", out), ("boundary", bnd)):
            if mask.any():
                getattr(state, key).append(np.stack([lo[mask], hi[mask]], axis=2))
                state.counts[key] += int(mask.sum())
        if ins.any():
            wd = hi[ins] - lo[ins]
            state.inside_measure += float(np.sum(np.prod(np.where(wd > 0, wd, 1.0), axis=1)))
        if split.any():
            slo, shi = lo[split], hi[split]
            axis = np.argmax(rel[split], axis=1)
            rows = np.arange(len(slo))
            mid = 0.5 * slo[rows, axis] + 0.5 * shi[rows, axis]
            left_hi = shi.copy()
            left_hi[rows, axis] = mid
            right_lo = slo.copy()
            right_lo[rows, axis] = mid
            state.stack.push(np.concatenate([slo, right_lo]), np.concatenate([left_hi, shi]))

    def tally(self, state: PavingState) -> Tally:
        share = state.inside_measure / self.total if self.total > 0 else 0.0
        return Tally(
            solutions=state.counts["inside"],
            undecided=state.counts["boundary"],
            extra={**state.counts, "inside_share": share},
        )

    def known(self, state: PavingState) -> None:
        return None  # boxes are decided independently of each other

    def found(self, state: PavingState) -> tuple[list, list, list, float]:
        return state.inside, state.outside, state.boundary, state.inside_measure

    def merge(self, state: PavingState, found: tuple[list, list, list, float]) -> None:
        inside, outside, boundary, measure = found
        for key, parts in (("inside", inside), ("outside", outside), ("boundary", boundary)):
            getattr(state, key).extend(parts)
            state.counts[key] += sum(len(p) for p in parts)
        state.inside_measure += measure


def set_bounds(robot: Robot) -> RobotBounds | None:
    """The interval arrays of a robot with tolerances (:meth:`.RobotBounds.of_tolerances`),
    None for an exact robot.  The force index reads the anchors, the attachments, the
    tension limits and the weight's wrench (the mass and the centre of mass: the slacks
    are taken at the corners of their box, :func:`.enclosure.slack_enclosures`); ``k``,
    ``K``, ``V``, ``L0`` do not enter it."""
    if not robot.toleranced:
        return None
    return RobotBounds.of_tolerances(robot)


def certified_workspace(
    robot: Robot,
    min_force: float,
    box: ArrayLike,
    eps: float,
    progress: Callable[[Progress], bool | None] | None = None,
    timeout: float | None = None,
    orientation: float | Sequence[float | tuple[float, float]] | None = None,
    eps_angle: float = 1.0,
    external: ArrayLike | None = None,
    max_boxes: int | None = None,
    batch: int = 1024,
    *,
    executor: Any = None,
    cancel: Any = None,
    max_solutions: int | None = None,
    checkpoint: Any = None,
) -> CertifiedWorkspace:
    """Pave ``box`` (positions, cm) into boxes proven inside/outside ``{f_min ≥ min_force}``.

    ``orientation``: dof 3: ``θ`` or ``(θlo, θhi)``; dof 6: ``(yaw, pitch, roll)``, each a
    number or a ``(lo, hi)`` range (degrees); default: identity.  ``progress`` is called
    after every batch (or worker task) with a :class:`~certsolve.solver.Progress` whose
    ``solutions`` count inside boxes, ``undecided`` boundary boxes, and ``extra`` holds
    ``inside``, ``outside``, ``boundary`` and ``inside_share``; returning ``False`` (or
    ``cancel.is_set()``) stops the paving (status ``"cancelled"``, the rest is
    ``pending``).  ``max_solutions`` stops it after that many inside boxes.  ``executor``
    as :meth:`certsolve.solver.Solver.solve`: the paving is the same on every executor.
    ``checkpoint`` (:class:`~certsolve.solver.checkpoint.Checkpoint`): save the paving as
    it goes and resume it from the last save.
    """
    if not (np.isfinite(min_force) and min_force > 0):
        raise ValueError("min_force must be a positive number (N)")
    if not (np.isfinite(eps) and eps > 0):
        raise ValueError("eps must be a positive number (cm)")
    if not (np.isfinite(eps_angle) and eps_angle > 0):
        raise ValueError("eps_angle must be a positive number (degrees)")
    if timeout is not None and not timeout > 0:
        raise ValueError("timeout must be positive (seconds)")
    w = robot.wrench_dim
    if robot.m < w:
        raise ValueError(
            f"{robot.name}: {robot.m} wires cannot resist a force in every direction of a "
            f"dof-{robot.dof} platform (at least {w} are needed; the isotropic force is never "
            "positive): nothing to certify"
        )
    if external is not None:
        external = np.asarray(external, dtype=float).reshape(-1)
        if external.shape != (w,) or not np.all(np.isfinite(external)):
            raise ValueError(f"external wrench: expected {w} finite components")
    d = robot.dim
    pbox = parse_box(box, d)
    angles, names = _parse_orientation(robot, orientation)
    use_rot = robot.dof != 2 and (orientation is not None)
    full = np.concatenate([pbox, angles]) if angles.size else pbox
    nd = full.shape[0]
    scale = np.concatenate([np.full(d, float(eps)), np.full(len(angles), float(eps_angle))])
    total = CertifiedWorkspace._measure(full[None])
    step = PavingStep(
        robot, min_force, external, d, use_rot, scale, total, batch, params=set_bounds(robot)
    )
    run = run_search(
        step,
        full[None, :, 0].copy(),
        full[None, :, 1].copy(),
        limits=Limits(timeout=timeout, max_boxes=max_boxes, max_solutions=max_solutions),
        executor=resolve_executor(executor),
        progress=progress,
        cancel=cancel,
        checkpoint=checkpoint,
    )
    state = run.state

    def cat(key):
        parts = getattr(state, key)
        return np.concatenate(parts) if parts else np.zeros((0, nd, 2))

    plo, phi = state.stack.snapshot()
    notes = []
    if robot.dof != 2 and not use_rot:
        notes.append("orientation: identity (fixed)")
    return CertifiedWorkspace(
        robot=robot.name,
        dof=robot.dof,
        min_force=float(min_force),
        box=pbox,
        angles=angles,
        angle_names=names,
        eps=float(eps),
        eps_angle=float(eps_angle),
        inside=cat("inside"),
        outside=cat("outside"),
        boundary=cat("boundary"),
        pending=np.stack([plo, phi], axis=2) if len(plo) else np.zeros((0, nd, 2)),
        status=run.status,
        boxes=run.stats.boxes,
        time=run.stats.time,
        notes=notes + [f"force rows: {force_rows(robot)}"],
        stats=run.stats,
    )
