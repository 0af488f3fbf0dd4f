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
* **pending**: not decided because the search stopped (timeout, ``max_boxes``, the
  progress callback returned ``False``).

The union of the four classes is ``Θ``: nothing is dropped.

**The search** works on pairs ``(P, Q)``, a batch of pairs per numpy call.  A pair proven
inside is done (``Q`` stays proven for every sub-box of ``P``); a pair proven outside makes
``P`` bad; an undecided pair is split along its widest axis relative to the stopping
widths: a pose axis splits ``Q`` (two new pairs with the same ``P``), a parameter axis
defers ``Q`` until every pair of ``P`` is processed, and then ``P`` is bisected and both
halves inherit only the deferred pose boxes.

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
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from ..robot.geometry import rotation_2d, rotation_zyx
from ..robot.model import Robot
from ..robot.params import AffineRobot
from ..robot.schema import RobotFileError
from ..solver.bisectors import split as bisect
from ..solver.checkpoint import Checkpoint
from .certified import parse_box
from .design_spec import DesignSpec, DesignSpecError, load_design_spec
from .enclosure import slack_enclosures

__all__ = ["BoxClass", "DesignProgress", "DesignResult", "design"]


class BoxClass(StrEnum):
    """The class of a parameter box (module docstring)."""

    GOOD = "good"
    BAD = "bad"
    UNDECIDED = "undecided"
    PENDING = "pending"


class DesignStatus(StrEnum):
    """How a design search ended: ``complete`` (every parameter box classified), or what
    stopped it (``timeout``, ``max_boxes``; ``stopped``: the progress callback)."""

    COMPLETE = "complete"
    TIMEOUT = "timeout"
    MAX_BOXES = "max_boxes"
    STOPPED = "stopped"


@dataclass(kw_only=True)
class DesignProgress:
    """Passed to the ``progress`` callback after every batch."""

    pairs: int  # (parameter box, pose box) pairs evaluated so far
    queued: int  # pairs waiting
    good: int
    bad: int
    undecided: int
    elapsed: float  # seconds
    good_share: float  # share of the parameter box already proven good


@dataclass(kw_only=True)
class DesignResult:
    """Boxes of parameters and what is proven about them.

    Box arrays have shape ``(n, k, 2)`` (``k`` parameters, ``[lo, hi]``).  ``margin[i]`` is a
    proven lower bound of ``f_min - min_force`` over ``good[i]`` × the workspace;
    ``witness[i]`` ``(d, 2)`` a pose box where every robot of ``bad[i]`` has ``f_min <
    min_force``.  ``best`` is the index in ``good`` of the largest margin (None if no box is
    good) and ``best_robot`` the robot file at its centre.
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
    status: DesignStatus
    pairs: int  # (parameter box, pose box) pairs evaluated (every run of a resumed search)
    parameter_boxes: int  # parameter boxes examined
    time: float  # seconds of this run
    notes: list[str] = field(default_factory=list)
    resumed_from: int | None = None  # pairs evaluated before this run (from a checkpoint)

    def share(self, cls: BoxClass | str) -> float:
        """Share of the parameter box's volume in the class ``cls``."""
        boxes = getattr(self, str(cls))
        if len(boxes) == 0:
            return 0.0
        w = self.ranges[:, 1] - self.ranges[:, 0]
        return float(np.sum(np.prod((boxes[..., 1] - boxes[..., 0]) / w, axis=1)))

    @property
    def complete(self) -> bool:
        return self.status == DesignStatus.COMPLETE

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
            "counts": {str(c): int(len(getattr(self, str(c)))) for c in BoxClass},
            "shares": {str(c): self.share(c) for c in BoxClass},
            "pairs": self.pairs,
            "resumed_from": self.resumed_from,
            "parameter_boxes": self.parameter_boxes,
            "time": self.time,
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
            for c in BoxClass:
                out[f"{c}_boxes"] = getattr(self, str(c)).tolist()
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


class _Boxes:
    """Parameter boxes of the search and their bookkeeping (arrays grown by doubling)."""

    def __init__(self, k: int):
        self.n = 0
        self.lo = np.zeros((16, k))
        self.hi = np.zeros((16, k))
        self.open = np.zeros(16, dtype=np.int64)  # pairs of the box still queued
        self.bad = np.zeros(16, dtype=bool)
        self.done = np.zeros(16, dtype=bool)  # classified or split
        self.margin = np.zeros(16)
        self.cls: dict[int, BoxClass] = {}  # final class (split boxes have none)
        self.witness: dict[int, np.ndarray] = {}
        self.deferred: dict[int, list[np.ndarray]] = {}  # pose boxes waiting for a split

    def add(self, lo, hi, margin: float, open_pairs: int) -> int:
        if self.n == len(self.open):
            for name in ("lo", "hi", "open", "bad", "done", "margin"):
                a = getattr(self, name)
                setattr(self, name, np.concatenate([a, np.zeros_like(a)]))
        i = self.n
        self.lo[i], self.hi[i] = lo, hi
        self.open[i], self.bad[i], self.done[i], self.margin[i] = open_pairs, False, False, margin
        self.n += 1
        return i

    def ready(self) -> np.ndarray:
        """Boxes whose pairs are all processed and that are not classified yet."""
        n = self.n
        return np.flatnonzero((self.open[:n] == 0) & ~self.done[:n])


def design(
    robot=None,
    parameters=None,
    workspace=None,
    min_force: float | None = None,
    *,
    spec=None,
    orientation=None,
    eps: float | None = None,
    workspace_eps: float | None = None,
    progress: Callable[[DesignProgress], bool | None] | None = None,
    timeout: float | None = None,
    max_boxes: int | None = None,
    batch: int = 1024,
    checkpoint: Checkpoint | None = None,
) -> DesignResult:
    """Classify the parameter boxes (module docstring).

    Either ``spec`` (a path, JSON text, dict or :class:`~.design_spec.DesignSpec`) or the
    fields ``robot`` (a path or robot object), ``parameters`` (a list of dicts
    ``{"name", "path", "mode", "range"[, "centre"]}``), ``workspace`` (``[xmin, xmax, ymin,
    ymax[, zmin, zmax]]``) and ``min_force`` (N); keyword arguments override the spec's
    ``orientation``, ``eps`` (fraction of each parameter range) and ``workspace_eps`` (cm;
    default 1/16 of the largest workspace side).  ``progress`` is called after every batch
    with a :class:`DesignProgress`; returning ``False`` stops the search.  ``max_boxes``
    limits the evaluated pairs.  Raises :class:`~.design_spec.DesignSpecError` (a
    ``ValueError``) naming the field for bad input.

    ``checkpoint`` (:class:`~certsolve.solver.checkpoint.Checkpoint`): save the search (its
    parameter boxes and queued pairs) every ``checkpoint.interval`` seconds and when it
    stops, and resume from a saved one of the same problem; ``timeout`` and ``max_boxes``
    apply to each run.
    """
    t0 = time.perf_counter()
    if spec is None:
        spec = {"robot": robot, "parameters": parameters, "workspace": workspace}
        spec["min_force"] = min_force
    ds: DesignSpec = load_design_spec(spec)
    overrides = {"orientation": orientation, "eps": eps, "workspace_eps": workspace_eps}
    data = ds.model_dump()
    data.update({k: v for k, v in overrides.items() if v is not None})
    ds = load_design_spec(data)
    if timeout is not None and not timeout > 0:
        raise DesignSpecError("timeout must be positive (seconds)")
    if max_boxes is not None and max_boxes < 1:
        raise DesignSpecError("max_boxes must be at least 1")
    try:
        affine = AffineRobot(ds.robot, ds.definitions())
    except RobotFileError as exc:
        raise DesignSpecError(f"robot: {exc}".replace("\n", "; ")) from None
    except ValueError as exc:
        raise DesignSpecError(str(exc).replace("\n", "; ")) from None
    rb = affine.robot
    d = rb.dim
    try:
        W = parse_box(ds.workspace, d)
    except ValueError as exc:
        raise DesignSpecError(f"workspace: {exc}".replace("box: ", "")) from None
    R, angles = _rotation(rb, ds.orientation)
    if rb.m < rb.wrench_dim:
        raise DesignSpecError(
            f"robot {rb.name!r}: {rb.m} wires cannot resist a force in every direction"
        )
    F = float(ds.min_force)
    k = len(ds.parameters)
    theta = affine.box
    pscale = ds.eps * (theta[:, 1] - theta[:, 0])
    weps = ds.workspace_eps
    if weps is None:
        weps = float(np.max(W[:, 1] - W[:, 0])) / 16 or 1.0

    boxes = _Boxes(k)
    root = boxes.add(theta[:, 0], theta[:, 1], np.inf, 1)
    q_pid = np.array([root])
    q_lo = W[None, :, 0].copy()
    q_hi = W[None, :, 1].copy()
    pairs = 0
    status = DesignStatus.COMPLETE
    resumed_from = None
    if checkpoint is not None:
        about = (
            f"design\nrobot: {rb.spec.model_dump_json()}\n"
            f"spec: {ds.model_dump_json(exclude={'robot'})}\nbatch: {int(batch)}"
        )
        saved = checkpoint.begin_records(about)
        if saved is not None:
            boxes, q_pid, q_lo, q_hi, pairs = _restore(saved, k)
            resumed_from = checkpoint.resumed_from = pairs
    pairs0 = pairs  # limits apply to each run

    def finalize(pid: int):
        """All pairs of ``pid`` are done: classify it, or split it and queue its halves."""
        nonlocal q_pid, q_lo, q_hi
        boxes.done[pid] = True
        deferred = boxes.deferred.pop(pid, [])
        if boxes.bad[pid]:
            boxes.cls[pid] = BoxClass.BAD
            return
        if not deferred:
            boxes.cls[pid] = BoxClass.GOOD
            return
        rel = (boxes.hi[pid] - boxes.lo[pid]) / pscale
        if rel.max() <= 1.0:
            boxes.cls[pid] = BoxClass.UNDECIDED
            return
        halves = bisect(boxes.lo[pid][None], boxes.hi[pid][None], np.argmax(rel)[None], 0.5)
        dq = np.stack(deferred)  # (n, d, 2)
        for lo, hi in halves:
            child = boxes.add(lo[0], hi[0], boxes.margin[pid], len(dq))
            q_pid = np.concatenate([q_pid, np.full(len(dq), child)])
            q_lo = np.concatenate([q_lo, dq[:, :, 0]])
            q_hi = np.concatenate([q_hi, dq[:, :, 1]])

    while len(q_pid):
        if timeout is not None and time.perf_counter() - t0 > timeout:
            status = DesignStatus.TIMEOUT
            break
        if max_boxes is not None and pairs - pairs0 >= max_boxes:
            status = DesignStatus.MAX_BOXES
            break
        pid, lo, hi = q_pid[:batch], q_lo[:batch], q_hi[:batch]
        q_pid, q_lo, q_hi = q_pid[batch:], q_lo[batch:], q_hi[batch:]
        live = ~boxes.bad[pid]
        np.subtract.at(boxes.open, pid[~live], 1)
        pid, lo, hi = pid[live], lo[live], hi[live]
        n = len(pid)
        if n:
            pairs += n
            prm = affine.bounds(boxes.lo[pid], boxes.hi[pid])
            glo, ghi, full_rank, wires_ok, nhi = slack_enclosures(
                rb, lo.T, hi.T, F, rotation=R, params=prm, norms=True
            )
            ins = np.all(glo >= 0.0, axis=0) & full_rank & wires_ok
            out = np.any(ghi < 0.0, axis=0) & wires_ok & ~ins
            with np.errstate(divide="ignore", invalid="ignore"):
                low = np.min(np.where(nhi > 0, glo / nhi, np.inf), axis=0)
            np.minimum.at(boxes.margin, pid[ins], np.where(np.isnan(low), 0.0, low)[ins])
            for i in np.flatnonzero(out):
                p = int(pid[i])
                if not boxes.bad[p]:
                    boxes.bad[p] = True
                    boxes.witness[p] = np.stack([lo[i], hi[i]], axis=1)
            und = ~ins & ~out
            rel_pose = np.max((hi - lo) / weps, axis=1)
            rel_par = np.max((boxes.hi[pid] - boxes.lo[pid]) / pscale, axis=1)
            split = und & (rel_pose > 1.0) & (rel_pose >= rel_par)
            defer = und & ~split
            for i in np.flatnonzero(defer):
                boxes.deferred.setdefault(int(pid[i]), []).append(np.stack([lo[i], hi[i]], axis=1))
            np.subtract.at(boxes.open, pid, 1)
            if split.any():
                slo, shi, sp = lo[split], hi[split], pid[split]
                (l_lo, l_hi), (r_lo, r_hi) = bisect(slo, shi, np.argmax(shi - slo, axis=1), 0.5)
                q_pid = np.concatenate([q_pid, sp, sp])
                q_lo = np.concatenate([q_lo, l_lo, r_lo])
                q_hi = np.concatenate([q_hi, l_hi, r_hi])
                np.add.at(boxes.open, sp, 2)
        for p in boxes.ready():
            finalize(int(p))
        if checkpoint is not None and checkpoint.due():
            checkpoint.save_records("design", _records(boxes, q_pid, q_lo, q_hi, pairs))
        if progress is not None:
            info = _progress(boxes, theta, pairs, len(q_pid), t0)
            if progress(info) is False:
                status = DesignStatus.STOPPED if len(q_pid) else status
                break

    if checkpoint is not None:
        checkpoint.save_records("design", _records(boxes, q_pid, q_lo, q_hi, pairs))
    res = _result(ds, affine, W, angles, weps, boxes, status, pairs, t0)
    res.resumed_from = resumed_from
    return res


def _records(boxes: _Boxes, q_pid, q_lo, q_hi, pairs: int) -> dict:
    """The search's state as arrays (for a checkpoint; dicts flattened in their order)."""
    n = boxes.n
    dpid = [p for p, parts in boxes.deferred.items() for _ in parts]
    dbox = [b for parts in boxes.deferred.values() for b in parts]
    d = q_lo.shape[1]
    return {
        **{name: getattr(boxes, name)[:n] for name in ("lo", "hi", "open", "bad", "done")},
        "margin": boxes.margin[:n],
        "cls_id": np.array(list(boxes.cls), dtype=np.int64),
        "cls": [str(c) for c in boxes.cls.values()],
        "witness_id": np.array(list(boxes.witness), dtype=np.int64),
        "witness": np.array(list(boxes.witness.values())).reshape(-1, d, 2),
        "deferred_id": np.array(dpid, dtype=np.int64),
        "deferred": np.array(dbox).reshape(-1, d, 2),
        "q_pid": q_pid,
        "q_lo": q_lo,
        "q_hi": q_hi,
        "pairs": int(pairs),
    }


def _restore(saved: dict, k: int):
    """``(boxes, q_pid, q_lo, q_hi, pairs)`` from :func:`_records`."""
    boxes = _Boxes(k)
    for name in ("lo", "hi", "open", "bad", "done", "margin"):
        setattr(boxes, name, np.array(saved[name]))
    boxes.n = len(boxes.open)
    boxes.cls = {
        int(p): BoxClass(c) for p, c in zip(saved["cls_id"].tolist(), saved["cls"], strict=True)
    }
    boxes.witness = {int(p): w for p, w in zip(saved["witness_id"].tolist(), saved["witness"])}
    boxes.deferred = {}
    for p, b in zip(saved["deferred_id"].tolist(), saved["deferred"], strict=True):
        boxes.deferred.setdefault(int(p), []).append(b)
    q = (np.array(saved["q_pid"]), np.array(saved["q_lo"]), np.array(saved["q_hi"]))
    return (boxes, *q, int(saved["pairs"]))


def _progress(boxes: _Boxes, theta, pairs, queued, t0) -> DesignProgress:
    counts = {c: 0 for c in BoxClass}
    good_share = 0.0
    w = theta[:, 1] - theta[:, 0]
    for p, c in boxes.cls.items():
        counts[c] += 1
        if c is BoxClass.GOOD:
            good_share += float(np.prod((boxes.hi[p] - boxes.lo[p]) / w))
    return DesignProgress(
        pairs=pairs,
        queued=queued,
        good=counts[BoxClass.GOOD],
        bad=counts[BoxClass.BAD],
        undecided=counts[BoxClass.UNDECIDED],
        elapsed=time.perf_counter() - t0,
        good_share=good_share,
    )


def _result(ds, affine: AffineRobot, W, angles, weps, boxes: _Boxes, status, pairs, t0):
    k = len(ds.parameters)
    d = W.shape[0]
    cls: dict[BoxClass, list[int]] = {c: [] for c in BoxClass}
    for p in range(boxes.n):
        if p in boxes.cls:
            cls[boxes.cls[p]].append(p)
        elif not boxes.done[p]:  # the search stopped before this box was decided
            cls[BoxClass.BAD if boxes.bad[p] else BoxClass.PENDING].append(p)

    def arr(ids):
        if not ids:
            return np.zeros((0, k, 2))
        return np.stack([boxes.lo[ids], boxes.hi[ids]], axis=2)

    good = cls[BoxClass.GOOD]
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
    witness = [boxes.witness[p] for p in cls[BoxClass.BAD]]
    return DesignResult(
        robot=affine.robot.name,
        dof=affine.robot.dof,
        names=affine.names,
        paths=[p.path for p in ds.parameters],
        modes=[p.mode for p in ds.parameters],
        ranges=affine.box,
        workspace=W,
        orientation=angles,
        min_force=float(ds.min_force),
        eps=float(ds.eps),
        workspace_eps=float(weps),
        good=arr(good),
        margin=np.asarray(margin, dtype=float),
        bad=arr(cls[BoxClass.BAD]),
        witness=np.stack(witness) if witness else np.zeros((0, d, 2)),
        undecided=arr(cls[BoxClass.UNDECIDED]),
        pending=arr(cls[BoxClass.PENDING]),
        best=best,
        best_robot=best_robot,
        status=status,
        pairs=pairs,
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
