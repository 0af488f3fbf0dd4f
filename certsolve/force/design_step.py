"""The certified design's search as a step of the search driver (:mod:`certsolve.solver.search`).

The driver's boxes are **pairs** ``(P, Q)``: a parameter box ``P`` (a row of the table
:class:`ParameterBoxes`) and a pose box ``Q ⊂ W``.  A pair travels as one row
``[p, Q_lo]`` / ``[p, Q_hi]`` of width ``1 + d``: ``p`` is the index of ``P`` in the table
(a float, exact below ``2^53``).  :meth:`DesignStep.process` takes a batch of pairs in one
set of numpy calls (:func:`~.enclosure.slack_enclosures` with interval robot arrays over
the ``P`` of each pair):

* inside (every slack ``g ≥ 0``, ``H`` of full rank, no anchor in ``Q``): the pair is done,
  and ``P``'s margin is lowered to its bound ``min_k glo_k / ||c_k,f||_hi``;
* outside (one slack ``g < 0`` over ``P × Q``): ``P`` is bad, ``Q`` its witness; the pairs
  of ``P`` still queued are dropped when they come (``P`` is decided);
* undecided: split along the widest axis relative to the stopping widths.  A pose axis
  splits ``Q`` (two pairs pushed back with the same ``P``); a parameter axis defers ``Q``.

A parameter box whose pairs are all processed is **finalized** in the same batch: bad; good
when nothing was deferred; undecided when narrower than ``eps``; else bisected, and each
half gets one pair per deferred pose box (what was proven inside for ``P`` holds for its
halves).  So every pair taken from the buffer is accounted for -- done, deciding ``P``,
deferred, or pushed back as smaller pairs -- which is the driver's guarantee.

**Order.**  The buffer is first in, first out (:class:`PairQueue`): the pairs of a parameter
box are processed before those of its halves, as the design's own loop did, so the boxes,
verdicts, witnesses and counters are those of that loop.  A box's fate depends on the
other pairs of its parameter box, so the step runs on the serial executor: its ``found``
and ``merge`` carry the whole table, for checkpoints (a snapshot is the table and the
queued pairs; restoring it goes on exactly where the search was).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from ..robot.params import AffineRobot
from ..solver.bisectors import split as bisect
from ..solver.protocol import Tally
from .enclosure import slack_enclosures

__all__ = ["DesignProblem", "DesignState", "DesignStep", "DesignVerdict", "PairQueue"]


class DesignVerdict(StrEnum):
    """What is proven about a parameter box (:mod:`.design`): ``good``, ``bad`` or
    ``undecided`` (narrower than ``eps``).  A box with no verdict when the search stopped
    is *pending*; the search's status (:class:`~certsolve.solver.search.SearchStatus`)
    says why it stopped."""

    GOOD = "good"
    BAD = "bad"
    UNDECIDED = "undecided"


class PairQueue:
    """A first-in first-out buffer of rows, with the driver's buffer interface
    (``push``, ``pop``, ``pop_hinted``, ``snapshot``, ``hints``, ``len``;
    :class:`~certsolve.solver.buffer.BoxStack` is the last-in first-out one).  Rows live in
    ``[head, tail)`` of two arrays that grow by doubling; the used part moves to the front
    when the free room is at the front."""

    def __init__(self, n: int, capacity: int = 1024):
        self.n = n
        self._lo = np.empty((capacity, n))
        self._hi = np.empty((capacity, n))
        self._head = 0
        self._tail = 0

    def __len__(self) -> int:
        return self._tail - self._head

    def push(self, lo: np.ndarray, hi: np.ndarray, hints: np.ndarray | None = None) -> None:
        """Queue rows (``hints``: not kept -- no part of the design's step leaves any)."""
        k = lo.shape[0]
        if k == 0:
            return
        size = len(self)
        if self._tail + k > self._lo.shape[0]:
            cap = max(self._lo.shape[0], 2 * (size + k))
            for name in ("_lo", "_hi"):
                new = np.empty((cap, self.n))
                new[:size] = getattr(self, name)[self._head : self._tail]
                setattr(self, name, new)
            self._head, self._tail = 0, size
        self._lo[self._tail : self._tail + k] = lo
        self._hi[self._tail : self._tail + k] = hi
        self._tail += k

    def pop(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` oldest rows (fewer if the queue is shorter)."""
        end = min(self._head + k, self._tail)
        lo = self._lo[self._head : end].copy()
        hi = self._hi[self._head : end].copy()
        self._head = end
        if self._head == self._tail:
            self._head = self._tail = 0
        return lo, hi

    def pop_hinted(self, k: int) -> tuple[np.ndarray, np.ndarray, None]:
        """:meth:`pop`, and no hints."""
        return (*self.pop(k), None)

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the queued rows, oldest first (pushing them rebuilds the queue)."""
        return self._lo[self._head : self._tail].copy(), self._hi[self._head : self._tail].copy()

    def hints(self) -> None:
        """No hints are kept."""
        return None


_COLUMNS = ("lo", "hi", "open", "bad", "done", "margin")


class ParameterBoxes:
    """The parameter boxes of a search and their bookkeeping (columns grown by doubling).

    ``open[p]``: pairs of ``p`` queued; ``bad[p]``: proven bad (a witness is known);
    ``done[p]``: finalized (a verdict, or bisected); ``margin[p]``: the smallest bound of
    the inside pairs of ``p`` and of its ancestors; ``verdict``: the final verdicts (a
    bisected box has none); ``deferred``: pose boxes waiting for ``p`` to be bisected.
    """

    def __init__(self, k: int):
        self.n = 0
        self.lo = np.zeros((16, k))
        self.hi = np.zeros((16, k))
        self.open = np.zeros(16, dtype=np.int64)
        self.bad = np.zeros(16, dtype=bool)
        self.done = np.zeros(16, dtype=bool)
        self.margin = np.zeros(16)
        self.verdict: dict[int, DesignVerdict] = {}
        self.witness: dict[int, np.ndarray] = {}
        self.deferred: dict[int, list[np.ndarray]] = {}
        self.pairs = 0  # pairs evaluated (those of a box already bad are dropped, not counted)

    def add(self, lo: np.ndarray, hi: np.ndarray, margin: float, open_pairs: int) -> int:
        if self.n == len(self.open):
            for name in _COLUMNS:
                a = getattr(self, name)
                setattr(self, name, np.concatenate([a, np.zeros_like(a)]))
        i = self.n
        self.lo[i], self.hi[i] = lo, hi
        self.open[i], self.bad[i], self.done[i], self.margin[i] = open_pairs, False, False, margin
        self.n += 1
        return i

    def ready(self) -> np.ndarray:
        """Boxes whose pairs are all processed and that are not finalized yet."""
        n = self.n
        return np.flatnonzero((self.open[:n] == 0) & ~self.done[:n])

    def counts(self) -> dict[DesignVerdict, int]:
        out = dict.fromkeys(DesignVerdict, 0)
        for v in self.verdict.values():
            out[v] += 1
        return out

    def volume(self, ids: list[int], width: np.ndarray) -> float:
        """Share of the parameter box (of widths ``width``) covered by the boxes ``ids``."""
        if not ids:
            return 0.0
        return float(np.sum(np.prod((self.hi[ids] - self.lo[ids]) / width, axis=1)))

    # -- checkpoint records --------------------------------------------------------------------
    def records(self, d: int) -> dict[str, Any]:
        """The table as arrays (dicts flattened in their order)."""
        n = self.n
        dpid = [p for p, parts in self.deferred.items() for _ in parts]
        dbox = [b for parts in self.deferred.values() for b in parts]
        return {
            **{name: getattr(self, name)[:n] for name in _COLUMNS},
            "verdict_id": np.array(list(self.verdict), dtype=np.int64),
            "verdict": [str(v) for v in self.verdict.values()],
            "witness_id": np.array(list(self.witness), dtype=np.int64),
            "witness": np.array(list(self.witness.values())).reshape(-1, d, 2),
            "deferred_id": np.array(dpid, dtype=np.int64),
            "deferred": np.array(dbox).reshape(-1, d, 2),
            "pairs": int(self.pairs),
        }

    @classmethod
    def from_records(cls, saved: dict[str, Any], k: int) -> ParameterBoxes:
        """The inverse of :meth:`records`."""
        t = cls(k)
        for name in _COLUMNS:
            setattr(t, name, np.array(saved[name]))
        t.n = len(t.open)
        ids = saved["verdict_id"].tolist()
        t.verdict = {int(p): DesignVerdict(v) for p, v in zip(ids, saved["verdict"], strict=True)}
        t.witness = {int(p): w for p, w in zip(saved["witness_id"].tolist(), saved["witness"])}
        for p, b in zip(saved["deferred_id"].tolist(), saved["deferred"], strict=True):
            t.deferred.setdefault(int(p), []).append(b)
        t.pairs = int(saved["pairs"])
        return t


@dataclass(kw_only=True)
class DesignProblem:
    """What the search needs, checked and built once (:func:`.design.design`).

    ``theta`` ``(k, 2)``: the parameter box; ``W`` ``(d, 2)``: the workspace; ``R``: the
    fixed rotation (None for a point platform); ``min_force``: ``F``; ``pscale`` ``(k,)``:
    the parameter widths below which a box is not split (``eps`` × each range);
    ``workspace_eps``: the pose width (cm); ``about``: the problem as text (fingerprint).
    """

    affine: AffineRobot
    theta: np.ndarray
    W: np.ndarray
    R: np.ndarray | None
    min_force: float
    pscale: np.ndarray
    workspace_eps: float
    about: str


@dataclass
class DesignState:
    """The search's state: the queued pairs and the parameter boxes."""

    stack: PairQueue
    boxes: ParameterBoxes
    restored_pairs: int | None = None  # pairs evaluated before a restore (checkpoint)
    good_share: float = 0.0  # of the parameter box, proven good so far
    counts: dict[DesignVerdict, int] = field(
        default_factory=lambda: dict.fromkeys(DesignVerdict, 0)
    )


class DesignStep:
    """The design search as a step of the driver (module docstring)."""

    def __init__(self, problem: DesignProblem, batch: int = 1024):
        self.problem = problem
        self.batch_size = int(batch)

    def fingerprint(self) -> str:
        """The robot, the spec and the batch size, as text (for checkpoints)."""
        return f"{self.problem.about}\nbatch: {self.batch_size}"

    def start(self, known: Any = None) -> DesignState:
        """The queue empty and the table holding the root box ``theta`` (one pair awaited:
        the caller pushes ``(0, W)``)."""
        pb = self.problem
        boxes = ParameterBoxes(len(pb.theta))
        boxes.add(pb.theta[:, 0], pb.theta[:, 1], np.inf, 1)
        return DesignState(PairQueue(1 + len(pb.W)), boxes)

    def process(
        self, lo: np.ndarray, hi: np.ndarray, state: DesignState, *, deadline: float | None = None
    ) -> None:
        # ``deadline`` (:meth:`.Step.process`) is not used: no part of this round loops long
        pb, t = self.problem, state.boxes
        pid = lo[:, 0].astype(np.int64)
        live = ~t.bad[pid]
        np.subtract.at(t.open, pid[~live], 1)  # P is bad already: the pair is not needed
        pid, qlo, qhi = pid[live], lo[live, 1:], hi[live, 1:]
        if len(pid):
            t.pairs += len(pid)
            prm = pb.affine.bounds(t.lo[pid], t.hi[pid])
            glo, ghi, full_rank, wires_ok, nhi = slack_enclosures(
                pb.affine.robot, qlo.T, qhi.T, pb.min_force, rotation=pb.R, params=prm, norms=True
            )
            ins = np.all(glo >= 0.0, axis=0) & full_rank & wires_ok
            out = np.any(ghi < 0.0, axis=0) & wires_ok & ~ins
            with np.errstate(divide="ignore", invalid="ignore"):
                low = np.min(np.where(nhi > 0, glo / nhi, np.inf), axis=0)
            np.minimum.at(t.margin, pid[ins], np.where(np.isnan(low), 0.0, low)[ins])
            for i in np.flatnonzero(out):
                p = int(pid[i])
                if not t.bad[p]:
                    t.bad[p] = True
                    t.witness[p] = np.stack([qlo[i], qhi[i]], axis=1)
            und = ~ins & ~out
            rel_pose = np.max((qhi - qlo) / pb.workspace_eps, axis=1)
            rel_par = np.max((t.hi[pid] - t.lo[pid]) / pb.pscale, axis=1)
            split = und & (rel_pose > 1.0) & (rel_pose >= rel_par)
            for i in np.flatnonzero(und & ~split):
                t.deferred.setdefault(int(pid[i]), []).append(np.stack([qlo[i], qhi[i]], axis=1))
            np.subtract.at(t.open, pid, 1)
            if split.any():
                slo, shi, sp = qlo[split], qhi[split], pid[split]
                (l_lo, l_hi), (r_lo, r_hi) = bisect(slo, shi, np.argmax(shi - slo, axis=1), 0.5)
                col = np.concatenate([sp, sp]).astype(float)[:, None]
                state.stack.push(
                    np.hstack([col, np.concatenate([l_lo, r_lo])]),
                    np.hstack([col, np.concatenate([l_hi, r_hi])]),
                )
                np.add.at(t.open, sp, 2)
        for p in t.ready():
            self._finalize(int(p), state)

    def _finalize(self, p: int, state: DesignState) -> None:
        """All pairs of ``p`` are processed: its verdict, or its halves with their pairs."""
        t = state.boxes
        t.done[p] = True
        deferred = t.deferred.pop(p, [])
        if t.bad[p]:
            self._decide(p, DesignVerdict.BAD, state)
            return
        if not deferred:
            self._decide(p, DesignVerdict.GOOD, state)
            return
        rel = (t.hi[p] - t.lo[p]) / self.problem.pscale
        if rel.max() <= 1.0:
            self._decide(p, DesignVerdict.UNDECIDED, state)
            return
        halves = bisect(t.lo[p][None], t.hi[p][None], np.array([np.argmax(rel)]), 0.5)
        dq = np.stack(deferred)  # (n, d, 2)
        for lo, hi in halves:
            child = t.add(lo[0], hi[0], t.margin[p], len(dq))
            col = np.full((len(dq), 1), float(child))
            state.stack.push(np.hstack([col, dq[:, :, 0]]), np.hstack([col, dq[:, :, 1]]))

    def _decide(self, p: int, verdict: DesignVerdict, state: DesignState) -> None:
        state.boxes.verdict[p] = verdict
        state.counts[verdict] += 1
        if verdict is DesignVerdict.GOOD:
            state.good_share += state.boxes.volume([p], self._widths())

    def _widths(self) -> np.ndarray:
        theta = self.problem.theta
        return theta[:, 1] - theta[:, 0]

    def tally(self, state: DesignState) -> Tally:
        """Good boxes count as the solutions, undecided ones as undecided; ``extra`` has
        the three verdict counts, the pairs evaluated and the share proven good."""
        c = state.counts
        return Tally(
            solutions=c[DesignVerdict.GOOD],
            undecided=c[DesignVerdict.UNDECIDED],
            extra={
                **{str(v): n for v, n in c.items()},
                "pairs": state.boxes.pairs,
                "good_share": state.good_share,
            },
        )

    def known(self, state: DesignState) -> None:
        return None

    def found(self, state: DesignState) -> dict[str, Any]:
        """The whole table (the step runs serially; see the module docstring)."""
        return state.boxes.records(len(self.problem.W))

    def merge(self, state: DesignState, found: dict[str, Any]) -> None:
        """Restore the table of :meth:`found` into a state fresh from :meth:`start`."""
        t = ParameterBoxes.from_records(found, len(self.problem.theta))
        state.boxes = t
        state.restored_pairs = t.pairs
        state.counts = t.counts()
        good = [p for p, v in t.verdict.items() if v is DesignVerdict.GOOD]
        state.good_share = t.volume(good, self._widths())
