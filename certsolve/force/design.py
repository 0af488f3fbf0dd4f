"""Certified design (Krut et al. 2004, section IV-B): parameter boxes proven to give the
required isotropic force over a whole workspace.

Given design parameters ``θ`` in a box ``Θ`` (:mod:`certsolve.robot.params`: anchors,
attachments and tension limits as affine functions of ``θ``), a workspace box ``W`` of
positions (fixed orientation) and a required force ``F > 0``, the search classifies boxes
``P ⊂ Θ``:

* **good**: for every ``θ ∈ P`` and every pose ``p ∈ W``, ``f_min(θ, p) ≥ F``.  Proof: ``W``
  is covered by pose boxes ``Q`` each proven *inside* for the robot box ``P`` (or for a box
  containing ``P``) by :func:`~.enclosure.slack_enclosures` with interval robot arrays
  (every slack ``g ≥ 0``, ``H`` of full rank, no anchor in ``Q``);
* **bad**: there is a pose box ``Q ⊂ W`` (the ``witness``) such that for every ``θ ∈ P`` and
  every ``p ∈ Q``, ``f_min(θ, p) < F`` (one slack ``g < 0`` over ``P × Q``).  So every
  robot of the box misses the requirement somewhere in the workspace, with a common
  witness region;
* **undecided**: ``P`` is narrower than ``eps`` (a fraction of each parameter range) and some
  pose box narrower than ``workspace_eps`` is neither proven inside nor outside for it;
The three are a box's verdict (:class:`~.design_step.DesignVerdict`).  A box without one is
**pending**: the search stopped first, and its status
(:class:`~certsolve.solver.search.SearchStatus`: ``timeout``, ``max_boxes``, ``cancelled``)
says why.  The good, bad, undecided and pending boxes tile ``Θ``: nothing is dropped.

**The search** works on pairs ``(P, Q)``, a batch of pairs per numpy call.  A pair proven
inside is done (``Q`` stays proven for every sub-box of ``P``); a pair proven outside makes
``P`` bad; an undecided pair is split along its widest axis relative to the stopping
widths: a pose axis splits ``Q`` (two new pairs with the same ``P``), a parameter axis
defers ``Q`` until every pair of ``P`` is processed, and then ``P`` is bisected and both
halves inherit only the deferred pose boxes.  The search is a step of the one search driver
(:class:`~.design_step.DesignStep` on :func:`~certsolve.solver.search.run_search`): limits,
cancellation, progress and checkpoints are the driver's.

**Margin.**  Every inside pair also gives a lower bound of the force:
``f_min ≥ F + min_k glo_k / ||c_k,f||_hi`` (the slacks are ``g = (d_k + c_k·w) -
F ||c_k,f||`` for facet normals ``c_k``, :mod:`.enclosure`).  The margin of a good box is a
proven lower bound of ``f_min - F`` over ``P × W``: the larger of the smallest such bound
over the pose boxes of its proof and the smallest over a fixed grid of pose boxes (8 per
axis; 4 in 3-D), which makes margins of boxes of different histories comparable.  The
**best** box is the good box with the largest margin; its centre is the robot
``--emit-robot`` writes (its arrays are checked to lie in the box's interval arrays, so the
proof covers it).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..robot.geometry import rotation_2d, rotation_zyx
from ..robot.model import Robot
from ..robot.params import AffineRobot
from ..robot.schema import RobotFileError
from ..solver.protocol import Saver, SearchStats
from ..solver.search import Limits, ProgressCallback, SearchStatus, run_search
from .certified import parse_box
from .design_spec import DesignSpec, DesignSpecError, load_design_spec
from .design_step import DesignProblem, DesignState, DesignStep, DesignVerdict
from .enclosure import slack_enclosures

__all__ = ["PARTS", "DesignResult", "DesignVerdict", "design"]

#: the parts a design splits the parameter box into: the verdicts, and the boxes left pending
PARTS: tuple[str, ...] = (*map(str, DesignVerdict), "pending")


@dataclass(kw_only=True)
class DesignResult:
    """Boxes of parameters and what is proven about them.

    Box arrays have shape ``(n, k, 2)`` (``k`` parameters, ``[lo, hi]``).  ``margin[i]`` is a
    proven lower bound of ``f_min - min_force`` over ``good[i]`` × the workspace;
    ``witness[i]`` ``(d, 2)`` a pose box where every robot of ``bad[i]`` has ``f_min <
    min_force``.  ``best`` is the index in ``good`` of the largest margin (None if no box is
    good) and ``best_robot`` the robot file at its centre.  ``status`` is the search's:
    ``complete`` means nothing is pending.  ``pairs``: (parameter box, pose box) pairs
    evaluated, every run of a resumed search included; ``stats``: the driver's counters
    (its ``boxes`` are the pairs taken from the queue, those dropped because their
    parameter box was already bad included).
    """

    robot: str
    dof: int
    names: list[str]
    paths: list[str]
    modes: list[str]
    ranges: np.ndarray  # (k, 2)
    workspace: np.ndarray  # (d, 2)
    orientation: list[float]  # fixed angles (degrees)
    min_force: float
    eps: float
    workspace_eps: float
    good: np.ndarray
    margin: np.ndarray  # (n_good,)
    bad: np.ndarray
    witness: np.ndarray  # (n_bad, d, 2)
    undecided: np.ndarray
    pending: np.ndarray
    best: int | None
    best_robot: dict | None
    status: SearchStatus
    pairs: int
    parameter_boxes: int  # parameter boxes examined
    time: float  # seconds of this run
    notes: list[str] = field(default_factory=list)
    resumed_from: int | None = None  # pairs evaluated before this run (from a checkpoint)
    stats: SearchStats = field(default_factory=SearchStats)

    def share(self, part: str) -> float:
        """Share of the parameter box's volume in ``part`` (one of :data:`PARTS`)."""
        boxes = getattr(self, str(part))
        if len(boxes) == 0:
            return 0.0
        w = self.ranges[:, 1] - self.ranges[:, 0]
        return float(np.sum(np.prod((boxes[..., 1] - boxes[..., 0]) / w, axis=1)))

    @property
    def complete(self) -> bool:
        return self.status == SearchStatus.COMPLETE

    @property
    def best_box(self) -> np.ndarray | None:
        return None if self.best is None else self.good[self.best]

    def to_dict(self, boxes: bool = True) -> dict:
        best = None
        if self.best is not None:
            b = self.good[self.best]
            best = {
                "box": b.tolist(),
                "centre": (0.5 * (b[:, 0] + b[:, 1])).tolist(),
                "margin": float(self.margin[self.best]),
                "min_force_bound": float(self.min_force + self.margin[self.best]),
                "parameters": dict(zip(self.names, (0.5 * (b[:, 0] + b[:, 1])).tolist())),
            }
        out = {
            "robot": self.robot,
            "dof": self.dof,
            "parameters": [
                {"name": n, "path": p, "mode": mo, "range": r.tolist()}
                for n, p, mo, r in zip(self.names, self.paths, self.modes, self.ranges)
            ],
            "workspace": self.workspace.tolist(),
            "orientation": list(self.orientation),
            "min_force": self.min_force,
            "eps": self.eps,
            "workspace_eps": self.workspace_eps,
            "status": str(self.status),
            "complete": self.complete,
            "counts": {c: int(len(getattr(self, c))) for c in PARTS},
            "shares": {c: self.share(c) for c in PARTS},
            "pairs": self.pairs,
            "resumed_from": self.resumed_from,
            "parameter_boxes": self.parameter_boxes,
            "time": self.time,
            "stats": self.stats.to_dict(),
            "best": best,
            "definitions": {
                "good": "for every parameter value in the box and every pose of the workspace, "
                "the maximum isotropic force is >= min_force (proof)",
                "bad": "for every parameter value in the box, the force is < min_force at "
                "every pose of the witness box (proof)",
                "margin": "proven lower bound of (isotropic force - min_force) over the box "
                "and the workspace",
            },
            "notes": list(self.notes),
        }
        if boxes:
            for c in PARTS:
                out[f"{c}_boxes"] = getattr(self, c).tolist()
            out["good_margins"] = self.margin.tolist()
            out["bad_witnesses"] = self.witness.tolist()
        return out


def _rotation(robot: Robot, orientation) -> tuple[np.ndarray | None, list[float]]:
    """Fixed rotation matrix from angles in degrees (identity by default)."""
    if robot.dof == 2:
        if orientation not in (None, [], 0, 0.0):
            raise DesignSpecError("orientation: a point platform (dof 2) has no orientation")
        return None, []
    n = 1 if robot.dof == 3 else 3
    ang = [0.0] * n if orientation is None else list(np.atleast_1d(orientation).astype(float))
    if len(ang) != n:
        raise DesignSpecError(f"orientation: expected {n} angle(s) in degrees")
    if not np.all(np.isfinite(ang)):
        raise DesignSpecError("orientation: angles must be finite")
    rad = np.radians(ang)
    R = rotation_2d(rad[0]) if n == 1 else rotation_zyx(*rad)
    return R, ang


def design(
    spec: DesignSpec | str | Path | Mapping[str, Any],
    *,
    progress: ProgressCallback | None = None,
    cancel: Any = None,
    timeout: float | None = None,
    max_boxes: int | None = None,
    batch: int = 1024,
    checkpoint: Saver | None = None,
) -> DesignResult:
    """Classify the parameter boxes of ``spec`` (module docstring).

    ``spec``: a :class:`~.design_spec.DesignSpec`, or what
    :func:`~.design_spec.load_design_spec` reads (a path, JSON text, a dict).  The rest are
    the search's options, those of the driver (:func:`~certsolve.solver.search.run_search`):
    ``progress`` is called after every batch of ``batch`` pairs with a
    :class:`~certsolve.solver.search.Progress` (``boxes``: pairs taken, ``pending``: pairs
    queued, ``solutions``: good boxes, ``undecided``; ``extra``: ``good``, ``bad``,
    ``undecided``, ``pairs`` evaluated and ``good_share``); returning ``False``, or
    ``cancel.is_set()``, stops the search (status ``cancelled``).  ``timeout`` (seconds) and
    ``max_boxes`` (pairs taken from the queue) stop it too, with the undecided parameter
    boxes pending.  ``checkpoint`` (:class:`~certsolve.solver.checkpoint.Checkpoint`): save
    the search as it goes and resume from a saved one of the same problem; the limits
    apply to each run.  Raises :class:`~.design_spec.DesignSpecError` (a ``ValueError``)
    naming the field for bad input.
    """
    t0 = time.perf_counter()
    ds = load_design_spec(spec)
    if timeout is not None and not timeout > 0:
        raise DesignSpecError("timeout must be positive (seconds)")
    if max_boxes is not None and max_boxes < 1:
        raise DesignSpecError("max_boxes must be at least 1")
    problem = _problem(ds)
    W = problem.W
    step = DesignStep(problem, batch)
    root = np.concatenate([[0.0], W[:, 0]]), np.concatenate([[0.0], W[:, 1]])
    run = run_search(
        step,
        root[0][None],
        root[1][None],
        limits=Limits(timeout=timeout, max_boxes=max_boxes),
        progress=progress,
        cancel=cancel,
        checkpoint=checkpoint,
    )
    res = _result(ds, problem, run.state, run.status, t0)
    res.resumed_from = run.state.restored_pairs
    res.stats = run.stats
    return res


def _problem(ds: DesignSpec) -> DesignProblem:
    """The spec checked against its robot and turned into arrays (errors name the field)."""
    try:
        affine = AffineRobot(ds.robot, ds.definitions())
    except RobotFileError as exc:
        raise DesignSpecError(f"robot: {exc}".replace("\n", "; ")) from None
    except ValueError as exc:
        raise DesignSpecError(str(exc).replace("\n", "; ")) from None
    rb = affine.robot
    try:
        W = parse_box(ds.workspace, rb.dim)
    except ValueError as exc:
        raise DesignSpecError(f"workspace: {exc}".replace("box: ", "")) from None
    R, _ = _rotation(rb, ds.orientation)
    if rb.m < rb.wrench_dim:
        raise DesignSpecError(
            f"robot {rb.name!r}: {rb.m} wires cannot resist a force in every direction"
        )
    theta = affine.box
    weps = ds.workspace_eps
    if weps is None:
        weps = float(np.max(W[:, 1] - W[:, 0])) / 16 or 1.0
    return DesignProblem(
        affine=affine,
        theta=theta,
        W=W,
        R=R,
        min_force=float(ds.min_force),
        pscale=ds.eps * (theta[:, 1] - theta[:, 0]),
        workspace_eps=float(weps),
        about=f"design\nrobot: {rb.spec.model_dump_json()}\n"
        f"spec: {ds.model_dump_json(exclude={'robot'})}",
    )


def _result(
    ds: DesignSpec, pb: DesignProblem, state: DesignState, status: SearchStatus, t0: float
) -> DesignResult:
    boxes, affine, W = state.boxes, pb.affine, pb.W
    k, d = len(pb.theta), W.shape[0]
    parts: dict[str, list[int]] = {c: [] for c in PARTS}
    for p in range(boxes.n):
        if p in boxes.verdict:
            parts[str(boxes.verdict[p])].append(p)
        elif not boxes.done[p]:  # the search stopped before this box was decided
            parts["bad" if boxes.bad[p] else "pending"].append(p)

    def arr(ids):
        if not ids:
            return np.zeros((0, k, 2))
        return np.stack([boxes.lo[ids], boxes.hi[ids]], axis=2)

    good = parts["good"]
    margin = boxes.margin[good] if good else np.zeros(0)
    if good:
        grid = _grid_margin(ds, affine, W, boxes.lo[good], boxes.hi[good])
        margin = np.maximum(margin, grid)
    best = int(np.argmax(margin)) if good else None
    notes = []
    best_robot = None
    if best is not None:
        p = good[best]
        centre = 0.5 * (boxes.lo[p] + boxes.hi[p])
        best_robot = affine.spec_at(centre)
        best_robot["name"] = f"{affine.robot.name}-design"
        inside = _arrays_inside(affine, best_robot, boxes.lo[p], boxes.hi[p])
        if not inside:  # cannot happen with outward rounding; never claim what is not proven
            notes.append("the emitted robot's arrays are not inside the proven box: not emitted")
            best_robot = None
    if ds.orientation is None and affine.robot.dof != 2:
        notes.append("orientation: identity (fixed)")
    witness = [boxes.witness[p] for p in parts["bad"]]
    return DesignResult(
        robot=affine.robot.name,
        dof=affine.robot.dof,
        names=affine.names,
        paths=[p.path for p in ds.parameters],
        modes=[p.mode for p in ds.parameters],
        ranges=affine.box,
        workspace=W,
        orientation=_rotation(affine.robot, ds.orientation)[1],
        min_force=float(ds.min_force),
        eps=float(ds.eps),
        workspace_eps=pb.workspace_eps,
        good=arr(good),
        margin=np.asarray(margin, dtype=float),
        bad=arr(parts["bad"]),
        witness=np.stack(witness) if witness else np.zeros((0, d, 2)),
        undecided=arr(parts["undecided"]),
        pending=arr(parts["pending"]),
        best=best,
        best_robot=best_robot,
        status=status,
        pairs=boxes.pairs,
        parameter_boxes=boxes.n,
        time=time.perf_counter() - t0,
        notes=notes,
    )


def _grid_margin(ds, affine: AffineRobot, W, plo, phi, chunk: int = 4096) -> np.ndarray:
    """Proven lower bounds of ``f_min - F`` over ``[plo, phi] × W`` from a fixed grid of pose
    boxes (8 per axis, 4 for 3-D workspaces): comparable margins for every good box.

    A cell contributes ``min_k glo_k / ||c_k,f||_hi`` when it is proven inside, ``-inf``
    otherwise (no bound); the box's margin is the smallest over its cells.
    """
    rb = affine.robot
    R, _ = _rotation(rb, ds.orientation)
    d = W.shape[0]
    n = 8 if d == 2 else 4
    edges = [np.linspace(W[i, 0], W[i, 1], n + 1) for i in range(d)]
    cells = np.stack(np.meshgrid(*[np.arange(n)] * d, indexing="ij"), -1).reshape(-1, d)
    clo = np.stack([edges[i][cells[:, i]] for i in range(d)], axis=1)
    chi = np.stack([edges[i][cells[:, i] + 1] for i in range(d)], axis=1)
    nb, nc = len(plo), len(cells)
    out = np.full(nb * nc, -np.inf)
    box_of = np.repeat(np.arange(nb), nc)
    cell_of = np.tile(np.arange(nc), nb)
    F = float(ds.min_force)
    for s in range(0, nb * nc, chunk):
        b, c = box_of[s : s + chunk], cell_of[s : s + chunk]
        glo, _, full_rank, wires_ok, nhi = slack_enclosures(
            rb, clo[c].T, chi[c].T, F, rotation=R, params=affine.bounds(plo[b], phi[b]),
            norms=True,
        )  # fmt: skip
        with np.errstate(divide="ignore", invalid="ignore"):
            low = np.min(np.where(glo >= 0.0, glo / nhi, -np.inf), axis=0)
        ok = full_rank & wires_ok & ~np.isnan(low)
        out[s : s + chunk] = np.where(ok, low, -np.inf)
    return out.reshape(nb, nc).min(axis=1)


def _arrays_inside(affine: AffineRobot, spec: dict, lo, hi) -> bool:
    """The float arrays of the robot file ``spec`` lie in the interval arrays of ``[lo, hi]``."""
    r = Robot.load(spec)
    b = affine.bounds(lo[None], hi[None])
    checks = [
        (r.A, b.A),
        (r.B, b.B),
        (r.tau_min, b.tau_min),
        (r.tau_max, b.tau_max),
    ]
    return all(np.all((iv[0][..., 0] <= a) & (a <= iv[1][..., 0])) for a, iv in checks)
