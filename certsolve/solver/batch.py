"""The batch record of one round, and the protocol every contractor follows over it.

A round of the solver (:meth:`.branch_and_prune.Solver.process`) passes one :class:`Batch`
through its contractor, a composition of parts (:mod:`.pipeline`).  The record holds

* the bounds ``lo, hi`` ``(k, n)`` of the boxes still in the round and the ``empty`` mask
  (``empty[r]``: box ``r`` is proven to hold no solution);
* the shared linearisation, when a part computed one: the interval Jacobian
  (:meth:`share_jacobian`, :meth:`jacobian`: ``(jlo, jhi)`` ``(k, n, n)``) and the rows
  where Newton is informative (``regular``);
  Newton computes it once per round and the later parts (inflation, CID's smear order,
  the bisector) reuse it.  A Jacobian over a box encloses the Jacobian over every box
  inside it, so it stays valid for a row however much later parts contract it;
* the variable the bisector splits in each box (:meth:`choice`), chosen once per round;
* what a part may do besides contracting: prove a solution (:meth:`prove`), send a box
  back to the buffer for another round (:meth:`send_back`, :meth:`push_back`), and the
  search's learnt states (``acid``, see :class:`.shaving.AdaptiveCount`; ``hull``, see
  :class:`.relaxation.HullShare`);
* each box's *hints* (``hints``, :mod:`.buffer`): what a part left for the box's next
  contraction (the polytope hull's LP active sets).  They travel with the box: a box sent
  back keeps its row, the halves of a bisection inherit it.

**Order.** What a part sends back waits on the batch and reaches the buffer when the round
ends (:meth:`flush`), *after* the halves of the round's bisections: the buffer pops its last
boxes first, so a box that contracted as much as a bisection (Newton converging on a
solution) is in the next round, where pushed at once it sank under the round's halves and
waited for their whole subtree -- a search stopped by its limit then had few or no proven
solutions (Butcher8-a at 30 s: 0).  Every box is still processed exactly once per push,
so a complete search explores the same boxes, in another order.

**Protocol.** A contractor is an object with ``apply(batch)`` and ``describe()``:
``apply`` replaces ``batch.lo`` / ``batch.hi`` by boxes that still hold every solution of
the old ones, sets ``batch.empty`` on rows it proves empty, and may take rows out of the
round (:meth:`keep`) once it has accounted for them -- proven (:meth:`prove`), or pushed
back (:meth:`send_back`).  A row's contracted box is a subset of its box: nothing of a
solution is dropped.  ``describe()`` is the part and its settings as text, for the
checkpoint fingerprint.  The compositions (:mod:`.pipeline`) drop the empty rows after each
part, so a part sees only live rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import KW_ONLY, dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..interval.core import splittable_width
from ..interval.reductions import all_last
from .buffer import no_hints, stacked_hints

if TYPE_CHECKING:
    from ..expr.compiled import CompiledSystem
    from .buffer import BoxStack
    from .certify import Certifier
    from .newton import Linearization

__all__ = [
    "BISECTION_GAIN",
    "NARROW_SHARE",
    "Batch",
    "Contractor",
    "log_volume_ratio",
    "progress_gain",
]

#: the progress gain of a bisection, ``log 1/2``: a contraction that shrank a box at least
#: this much was worth as much as a split (the fixpoint's and Newton's repeat rule)
BISECTION_GAIN = float(np.log(0.5))

#: :func:`progress_gain` counts a variable the bisector splits at 0 only where it is at
#: least this share of the box's widest counted variable
NARROW_SHARE = 0.01

Choose = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
Prove = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]


def log_volume_ratio(lo0, hi0, lo1, hi1, significant: float = 1.0) -> np.ndarray:
    """``Σ_i log(w1_i / w0_i)`` per box (0 for degenerate components): < 0 means it shrank.
    Only the components that shrank to ``significant`` of their width or less count."""
    with np.errstate(all="ignore"):  # unbounded boxes: infinite widths are fine here
        w0 = hi0 - lo0
        w1 = np.maximum(hi1 - lo1, 0.0)
        r = np.where(w0 > 0.0, w1 / w0, 1.0)
        if significant < 1.0:
            r = np.where(r <= significant, r, 1.0)
        return np.sum(np.log(np.maximum(r, 1e-300)), axis=1)


def progress_gain(
    lo0,
    hi0,
    lo1,
    hi1,
    eps: float,
    mask: np.ndarray | None,
    significant: float = 1.0,
    *,
    faces: np.ndarray | None = None,
    scale: np.ndarray | None = None,
) -> np.ndarray:
    """Log-volume change from ``lo0, hi0`` to ``lo1, hi1`` over the variables a bisection
    may still split: those of ``mask`` (None: all), wider than ``eps`` in ``lo0, hi0``;
    of them, only those that shrank to ``significant`` of their width or less.  Of the
    variables of ``faces`` (``(n,)``, those the bisector splits at 0; None: none), only
    those at least :data:`NARROW_SHARE` as wide as the box's widest counted variable, in
    units of ``scale`` (the domain's widths; None: 1).

    A variable narrower than ``eps`` is never split, so its shrinking is no progress
    towards a decision: counted, a component converging to an exact zero (``[-1e-200,
    1e-200]``, then ``[-1e-250, 1e-250]`` ...) looked like a halving of the volume at every
    round, and one box went round again ~180 times (katsura-5, batches of 1024).

    The sign split (:func:`.bisectors.split`) puts solutions with zero coordinates on the
    faces of its halves, and HC4 narrows those coordinates onto the face linearly, by about
    half a round, while the others stay wide: ``x1`` in ``[0, 5e-3]`` and ``x5`` in ``[0,
    1e-2]`` halving round after round, ``x0`` staying ``[0.19, 0.38]``.  Counted, that sent
    the boxes round again where a bisection lets Newton converge (katsura-6: 83 rounds
    where the midpoint split takes 42; 50 now, ``docs/solver.md``, *Going round again on
    the faces*).  Elsewhere the narrow variables' shrinking pays, and counts (Trigo1,
    Discrete-Integralf2: their searches lean on it).
    """
    width = hi0 - lo0
    count = width > eps
    if mask is not None:
        count &= mask
    if faces is not None:
        rel = width if scale is None else width / scale
        widest = np.max(np.where(count, rel, 0.0), axis=1, initial=0.0, keepdims=True)
        count &= ~faces | (rel >= NARROW_SHARE * widest)
    lo0, hi0 = np.where(count, lo0, 0.0), np.where(count, hi0, 0.0)
    return log_volume_ratio(lo0, hi0, lo1, hi1, significant)


class Contractor(Protocol):
    """A part of the solver's pipeline (module docstring)."""

    def apply(self, batch: Batch) -> None:
        """Contract the boxes of ``batch`` in place (bounds, empty mask, rows)."""

    def describe(self) -> str:
        """The part and the settings that shape the answer, as text."""
        ...


@dataclass(eq=False)
class Batch:
    """The boxes of one round and what the parts share about them (module docstring).

    Per-row arrays (``lo``, ``hi``, ``empty``, ``ids``, ``regular``, the Jacobian and the
    bisector's choice) always have the same rows; :meth:`keep` selects rows in all of them.
    The Jacobian ``(k, n, n)`` is selected lazily: :meth:`keep` narrows an index into the
    arrays Newton computed, and :meth:`jacobian` gathers the rows asked for when a part
    asks (one copy a round, where every selection copied it).
    """

    lo: np.ndarray  # (k, n)
    hi: np.ndarray
    _: KW_ONLY
    csys: CompiledSystem  # the system searched
    eps: float  # boxes narrower than eps in every splittable variable are not split
    mask: np.ndarray | None = None  # variables the bisector may split (None: all)
    faces: np.ndarray | None = None  # (n,) the variables split at 0 (:func:`progress_gain`)
    scale: np.ndarray | None = None  # the domain's widths (:func:`progress_gain`)
    choose: Choose | None = None  # the bisector: (lo, hi, jlo, jhi) -> variable per box
    certifier: Certifier | None = None
    stack: BoxStack | None = None  # the buffer: boxes sent back reach it at :meth:`flush`
    prove: Prove | None = None  # record proven solutions (existence, unicity boxes)
    acid: Any = None  # the search's learnt state (:class:`.shaving.AdaptiveCount`), if any
    hull: Any = None  # the search's learnt state (:class:`.relaxation.HullShare`), if any
    #: a :func:`time.monotonic` value (the search's limit) past which a part whose work on
    #: the batch is long (ACID's loop over variables) stops early: contracting less is sound
    deadline: float | None = None
    empty: np.ndarray = field(init=False)
    ids: np.ndarray = field(init=False)  # each row's position in the round's first batch
    #: the boxes as the round received them (row ``ids[r]`` is row ``r``'s), and the
    #: linearisation a part shared (Newton's :class:`~.newton.Linearization`, whose
    #: Jacobian :meth:`jacobian` reads), kept for the round: the large arrays of a round
    #: then live until its end, as they did when the round was one function -- freed as
    #: soon as replaced, glibc returned the top of the heap to the system between the
    #: kernels and the FK rounds of 2048 boxes took 2-3x the page faults (marionet-t at
    #: 60 N, 60k boxes: +0.3-0.9 s of system time on 4.4 s)
    start_lo: np.ndarray = field(init=False, repr=False)
    start_hi: np.ndarray = field(init=False, repr=False)
    linearization: Linearization | None = None
    regular: np.ndarray | None = None  # Newton informative (preconditioned pivots free of 0)
    _jac: tuple[np.ndarray, np.ndarray] | None = field(default=None, init=False, repr=False)
    _jac_at: np.ndarray | None = field(default=None, init=False, repr=False)  # rows of _jac
    _var: np.ndarray | None = field(default=None, init=False, repr=False)
    #: each row's hints (:mod:`.buffer`), or ``None``: no part has left any
    hints: np.ndarray | None = None
    _back: list[tuple[np.ndarray, np.ndarray, np.ndarray | None]] = field(
        default_factory=list, init=False
    )

    def __post_init__(self) -> None:
        self.empty = np.zeros(self.lo.shape[0], dtype=bool)
        self.ids = np.arange(self.lo.shape[0])
        self.start_lo, self.start_hi = self.lo, self.hi

    @property
    def size(self) -> int:
        """Rows in the round."""
        return int(self.lo.shape[0])

    def keep(self, rows: np.ndarray) -> None:
        """Keep only ``rows`` (a boolean mask) in every per-row array."""
        self.lo, self.hi = self.lo[rows], self.hi[rows]
        self.empty, self.ids = self.empty[rows], self.ids[rows]
        if self._jac is not None:
            at = np.arange(self._jac[0].shape[0]) if self._jac_at is None else self._jac_at
            self._jac_at = at[rows]
        if self.regular is not None:
            self.regular = self.regular[rows]
        if self._var is not None:
            self._var = self._var[rows]
        if self.hints is not None:
            self.hints = self.hints[rows]

    def drop_empty(self) -> None:
        """Take the rows proven empty out of the round."""
        if np.any(self.empty):
            self.keep(~self.empty)

    def send_back(self, rows: np.ndarray) -> None:
        """Send the boxes of ``rows`` (a boolean mask) back to the buffer for another round
        (at :meth:`flush`) and take them out of this one."""
        if not np.any(rows):
            return
        hints = None if self.hints is None else self.hints[rows]
        self.push_back(self.lo[rows], self.hi[rows], hints)
        self.keep(~rows)

    def push_back(self, lo: np.ndarray, hi: np.ndarray, hints: np.ndarray | None = None) -> None:
        """Boxes ``(k, n)`` (and their hints) for the buffer, pushed at :meth:`flush`
        (module docstring)."""
        if self.stack is None:
            raise RuntimeError("this batch has no buffer to send boxes back to")
        if lo.shape[0]:
            self._back.append((lo, hi, hints))

    @property
    def backlog(self) -> int:
        """Boxes sent back in this round, not yet on the buffer."""
        return sum(a.shape[0] for a, _, _ in self._back)

    def flush(self) -> None:
        """Push what the parts sent back onto the buffer (call once, when the round ends:
        after the halves of its bisections, so these boxes come next)."""
        if self._back:
            assert self.stack is not None
            lo = np.concatenate([a for a, _, _ in self._back])
            hi = np.concatenate([b for _, b, _ in self._back])
            hints = stacked_hints([(a.shape[0], h) for a, _, h in self._back])
            self._back = []
            self.stack.push(lo, hi, hints)

    def set_hints(self, rows: np.ndarray, hints: np.ndarray) -> None:
        """Write ``hints`` ``(k, width)`` into ``rows`` (indices or a mask); the other rows
        keep theirs (``-1`` rows if the batch had none, or of another width)."""
        if self.hints is None or self.hints.shape[1] != hints.shape[1]:
            self.hints = no_hints(self.size, hints.shape[1])
        self.hints[rows] = hints

    def row_hints(self, rows: np.ndarray | slice) -> np.ndarray | None:
        """The hints of ``rows`` (indices or a mask), or ``None`` if the batch has none."""
        return None if self.hints is None else self.hints[rows]

    def gain(self, lo0: np.ndarray, hi0: np.ndarray, significant: float = 1.0) -> np.ndarray:
        """:func:`progress_gain` of every row from ``lo0, hi0`` (same rows) to its box now."""
        return self.progress(lo0, hi0, self.lo, self.hi, significant)

    def progress(self, lo0, hi0, lo1, hi1, significant: float = 1.0) -> np.ndarray:
        """:func:`progress_gain` from ``lo0, hi0`` to ``lo1, hi1`` with this search's
        ``eps``, mask, sign-split variables and domain widths."""
        return progress_gain(
            lo0, hi0, lo1, hi1, self.eps, self.mask, significant, faces=self.faces, scale=self.scale
        )

    def share_jacobian(self, jlo: np.ndarray, jhi: np.ndarray) -> None:
        """Make ``jlo, jhi`` ``(k, n, n)``, enclosures of the Jacobian over each row's box
        (or a box containing it), the round's shared Jacobian."""
        self._jac, self._jac_at = (jlo, jhi), None

    def jacobian(self, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The shared Jacobian enclosure of every row (or of ``rows``, a mask or indices):
        Newton's, or evaluated here on the boxes now."""
        if self._jac is None:
            _, _, jlo, jhi = self.csys.eval_fj(self.lo, self.hi)
            self.share_jacobian(jlo, jhi)
        assert self._jac is not None
        jlo, jhi = self._jac
        at = self._jac_at
        if rows is not None:
            at = np.arange(self.size)[rows] if at is None else at[rows]
        if at is None:
            return jlo, jhi
        if rows is None:  # every row: gathered once, then kept as the shared one
            self.share_jacobian(jlo[at], jhi[at])
            return self._jac
        return jlo[at], jhi[at]

    def splittable(self) -> np.ndarray:
        """Rows wider than ``eps`` in some variable the bisector may split."""
        wid = splittable_width(self.lo, self.hi)  # 0 where no float is left inside
        if self.mask is not None:
            wid = wid[:, self.mask]
        return ~all_last(wid <= self.eps)

    def choice(self) -> np.ndarray:
        """The variable the bisector splits in each row (-1: narrower than ``eps``), chosen
        once per round on the boxes as they are at the first call (then kept per row)."""
        if self._var is None:
            big = self.splittable()
            var = np.full(self.size, -1, dtype=np.int64)
            if np.any(big):
                if self.choose is None:
                    raise RuntimeError("this batch has no bisector to choose variables")
                if big.all():
                    jlo, jhi = self.jacobian()
                    var[:] = self.choose(self.lo, self.hi, jlo, jhi)
                else:
                    jlo, jhi = self.jacobian(big)
                    var[big] = self.choose(self.lo[big], self.hi[big], jlo, jhi)
            self._var = var
        return self._var

    def with_rows(self, rows: np.ndarray, lo, hi, empty) -> None:
        """Write contracted ``lo, hi`` and ``empty`` back into ``rows`` (indices or a mask
        covering every row: then the arrays replace the old ones)."""
        if rows.dtype == bool and rows.all():
            self.lo, self.hi = lo, hi
            self.empty = self.empty | empty
            return
        self.lo, self.hi = self.lo.copy(), self.hi.copy()
        self.lo[rows], self.hi[rows] = lo, hi
        self.empty[rows] |= empty
