"""Compositions of contractors (IBEX ``CtcCompo``, ``CtcFixPoint``), batched, and the
default pipelines.

Every part follows the protocol of :mod:`.batch` (``apply(batch)``, ``describe()``), and so
does every composition, so compositions nest:

* :class:`Sequence` -- the parts one after the other, each on what the previous one left
  (IBEX ``CtcCompo``).  Rows proven empty are dropped after each part; the composition of
  sound contractors is sound.
* :class:`FixPoint` -- the inner contractor, then every box that shrank at least as much
  as a bisection would (log-volume ``<= log 1/2`` over the variables a bisection may still
  split, :func:`.batch.progress_gain`; in the hull's fixpoint, since the round began, and
  where the hull alone narrowed the box only the variables it halved count) goes back to
  the buffer for another round instead of being split.  The iteration of IBEX's
  ``CtcFixPoint`` runs through the buffer: the box comes back in a later batch, so its
  next round is batched with the others.  It stops: a box goes round again only after
  halving its volume over variables wider than ``eps``, which can happen only finitely
  often.
* :class:`Inflate` -- where the linearisation is informative (``batch.regular``) but the
  box stalled, the certifier's inflated Krawczyk test (:meth:`.Certifier.inflate`); a proven
  solution is recorded and the part of the box outside its unicity box goes back to the
  buffer.
* :class:`~.shaving.Shave` -- CID on the variable the bisector chose and on more variables
  by smear order (ACID).

The solver's default pipeline (:func:`default_pipeline`) is::

    Sequence(
        FixPoint(Sequence(HC4, PartialNewton..., IntervalNewton(iterations=8))),
        FixPoint(PolytopeHull(share=HULL_SHARE), since_round=True,
                 significant=HULL_PROGRESS),
        Inflate(),
        FixPoint(Shave(HC4, slices=4, count="auto", learn_first=True)),
    )

(IBEX's ``DefaultSolver`` is ``CtcCompo(HC4, ACID, Newton)``: Newton loops inside its call,
ACID learns on the first boxes; ``docs/solver.md``, *Contraction strength beside
ibexsolve*.)

then the solver bisects what is left (:meth:`.Solver.process`).  Forward kinematics
composes its own (:class:`certsolve.kinematics.fk_solver.FKSolver`: no CID, one Newton step,
the hull once a round after the fixpoint for the general-19 system).
Adding a technique: a class with ``apply`` and ``describe``, and one line where the
pipeline is assembled (``docs/architecture.md``, *Adding a contractor*).
"""

from __future__ import annotations

from collections.abc import Iterator
from collections.abc import Sequence as Seq
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval.reductions import all_last
from .batch import BISECTION_GAIN, Batch, Contractor
from .certify import box_difference
from .contractors import HC4, IntervalNewton, PartialNewton
from .relaxation import HullShare, PolytopeHull
from .shaving import Shave, check_count

__all__ = ["FixPoint", "Inflate", "Sequence", "core", "default_pipeline", "find", "parts_of"]

#: Hansen's mixed Jacobian with one variable per group is one stacked program of ``n``
#: copies of ``f`` and ``J`` (:mod:`certsolve.expr.stacked`): ``n`` times the nodes of the
#: system's ``f, J`` program.  Its construction grows with that size times the DAG's depth
#: (Yamamura1-0040: 86,520 nodes, 0.4 s; -0080: 601,840, 4 s; -0400 and the 1,000-variable
#: files: minutes, and memory as ``n^3`` for a dense system).  Past this many nodes
#: ``newton_groups="variables"`` uses the plain interval Jacobian.
MIXED_NODES = 250_000

#: the polytope hull's learnt share in the solver's pipeline (:class:`.relaxation.HullShare`;
#: the defaults, as forward kinematics): useful when it halves a box's volume, over the last
#: ~32 boxes it contracted.  A stricter share (a 4x cut over ~16 boxes) saved 2 % of the CPU
#: on the 42 smallest of the 65 files both solvers complete and cost katsura-6 36 % more
#: boxes (22,079 -> 29,982, 2.2 -> 2.9 s); ``docs/solver.md``, *The hull where it pays, on
#: small files*.
HULL_SHARE = HullShare(ratio=0.5, window=32)

#: the polytope hull's fixpoint in the solver's pipeline: a box that HC4 and Newton left as
#: the round began and that only the hull narrowed goes round again when the variables the
#: hull narrowed to at most this share of their width -- as much as a bisection narrows
#: the one it splits -- make half its volume (:class:`FixPoint` ``since_round``,
#: ``significant``).  Counting every variable, a hull that narrowed a few of many variables
#: a little at every round looked like progress: on ExtendedFreud-0100 it narrowed the same
#: 3 of the 100 variables to 0.74 of their width round after round (together a halving of
#: the volume) and one box went round 903 times, where the search now takes 21 boxes;
#: BroydenBanded-016 58 -> 37 boxes (``docs/solver.md``, *What counts as progress in the
#: fixpoint*).  Where HC4 or Newton narrowed the box too, the round's volume counts, as
#: before: on Bratu and Trigo1 that progress pays.
HULL_PROGRESS = 0.5

#: Newton steps a box may take in one round of the solver's pipeline
#: (:class:`~.contractors.IntervalNewton` ``iterations``); forward kinematics keeps 1.
NEWTON_STEPS = 8


class Sequence:
    """The parts one after the other (IBEX ``CtcCompo``); empty rows dropped after each."""

    def __init__(self, *parts: Contractor):
        self.parts: tuple[Contractor, ...] = tuple(parts)

    def apply(self, batch: Batch) -> None:
        for part in self.parts:
            if batch.size == 0:
                return
            part.apply(batch)
            batch.drop_empty()

    def describe(self) -> str:
        return f"Sequence({', '.join(p.describe() for p in self.parts)})"

    def children(self) -> tuple[Contractor, ...]:
        return self.parts

    def replace(self, old: Contractor, new: Contractor) -> Sequence:
        """This composition with the part ``old`` (anywhere inside) replaced by ``new``."""
        return Sequence(*(_replaced(p, old, new) for p in self.parts))


class FixPoint:
    """The inner contractor; boxes that shrank at least as much as a bisection go back to
    the buffer for another round (module docstring).  ``gain``: the log-volume change at
    or below which a box goes round again (default ``log 1/2``).

    ``since_round``: the change is measured from the box as the round began
    (``batch.start_lo``, ``start_hi``), the parts before this one included, not from this
    part's input; and a box that reached this part as the round began (the parts before
    left it untouched) counts only the variables the inner contractor narrowed to at most
    ``significant`` of their width (:func:`.batch.progress_gain`).
    """

    def __init__(
        self,
        inner: Contractor,
        gain: float = BISECTION_GAIN,
        *,
        since_round: bool = False,
        significant: float = 1.0,
    ):
        if not gain < 0.0:
            raise ValueError("FixPoint gain must be negative (a log-volume ratio)")
        if not 0.0 < significant <= 1.0:
            raise ValueError("FixPoint significant must be in (0, 1] (a width ratio)")
        if significant < 1.0 and not since_round:
            raise ValueError("FixPoint significant applies to since_round fixpoints only")
        self.inner = inner
        self.gain = float(gain)
        self.since_round = since_round
        self.significant = float(significant)

    def apply(self, batch: Batch) -> None:
        lo0, hi0, ids0 = batch.lo, batch.hi, batch.ids
        self.inner.apply(batch)
        batch.drop_empty()
        if batch.size == 0:
            return
        at = np.searchsorted(ids0, batch.ids)  # rows keep their order: where each one was
        if at.size != ids0.size:
            lo0, hi0 = lo0[at], hi0[at]
        if not self.since_round:
            batch.send_back(batch.gain(lo0, hi0) <= self.gain)
            return
        slo, shi = batch.start_lo[batch.ids], batch.start_hi[batch.ids]
        progress = batch.gain(slo, shi)
        untouched = all_last((lo0 == slo) & (hi0 == shi))
        if self.significant < 1.0 and untouched.any():
            alone = batch.gain(lo0, hi0, self.significant)
            progress = np.where(untouched, alone, progress)
        batch.send_back(progress <= self.gain)

    def describe(self) -> str:
        if not self.since_round:
            return f"FixPoint({self.inner.describe()}, gain={self.gain!r})"
        return (
            f"FixPoint({self.inner.describe()}, gain={self.gain!r}, since_round=True, "
            f"significant={self.significant!r})"
        )

    def children(self) -> tuple[Contractor, ...]:
        return (self.inner,)

    def replace(self, old: Contractor, new: Contractor) -> FixPoint:
        inner = _replaced(self.inner, old, new)
        return FixPoint(
            inner, self.gain, since_round=self.since_round, significant=self.significant
        )


class Inflate:
    """Inflated Krawczyk proofs where Newton is informative but the box stalled.

    For each row with ``batch.regular`` (every row when no part linearised), the
    certifier looks for a float Newton point near the box and proves a unicity box ``U``
    around it (:meth:`.Certifier.inflate`).  The solution is recorded; when ``U`` overlaps
    the box with positive volume, the box minus ``U`` (:func:`.certify.box_difference`: at
    most ``2n`` boxes covering it) goes back to the buffer and the row leaves the round --
    ``U`` holds exactly one solution, recorded.  Otherwise the row stays (to be split).
    """

    def apply(self, batch: Batch) -> None:
        if batch.certifier is None:
            raise RuntimeError("Inflate needs the solver's certifier on the batch")
        lo, hi = batch.lo, batch.hi
        rows = batch.regular if batch.regular is not None else np.ones(batch.size, dtype=bool)
        try_inflate = np.flatnonzero(rows)
        if try_inflate.size == 0:
            return
        idx, Elo, Ehi, Ulo, Uhi = batch.certifier.inflate(lo[try_inflate], hi[try_inflate])
        if idx.size == 0:
            return
        assert batch.prove is not None
        batch.prove(Elo, Ehi, Ulo, Uhi)
        done = np.zeros(batch.size, dtype=bool)
        for k, r in enumerate(try_inflate[idx]):
            # progress only if U overlaps X with positive volume: otherwise the remainder
            # would be X itself; leave X to bisection instead
            ilo = np.maximum(lo[r], Ulo[k])
            ihi = np.minimum(hi[r], Uhi[k])
            if not np.all(ilo < ihi):
                continue
            hint = batch.row_hints(slice(r, r + 1))  # the pieces start from the box's
            for plo, phi in box_difference(lo[r], hi[r], Ulo[k], Uhi[k]):
                batch.push_back(plo[None], phi[None], hint)
            done[r] = True
        if np.any(done):
            batch.keep(~done)

    def describe(self) -> str:
        return "Inflate()"


def _replaced(part: Contractor, old: Contractor, new: Contractor) -> Contractor:
    if part is old:
        return new
    replace = getattr(part, "replace", None)
    return replace(old, new) if callable(replace) else part


def parts_of(contractor: Contractor) -> Iterator[Contractor]:
    """Every part of a composition, depth first, the compositions included."""
    yield contractor
    children = getattr(contractor, "children", None)
    for child in children() if callable(children) else ():
        yield from parts_of(child)


def find(contractor: Contractor, kind: type) -> Any:
    """The first part of ``contractor`` of type ``kind`` (depth first), or ``None``."""
    return next((p for p in parts_of(contractor) if isinstance(p, kind)), None)


def core(
    csys: CompiledSystem,
    *,
    hc4: HC4,
    subsystems: Seq[tuple[Any, Any]] = (),
    newton_groups: Any = "variables",
    newton_steps: int = 1,
) -> list[Contractor]:
    """The contractors of a round before any LP: HC4, partial Newton on each sub-system,
    interval Newton (Hansen's mixed Jacobian over ``newton_groups``: ``"variables"``, one
    variable per group, unless its stacked program would exceed :data:`MIXED_NODES`
    nodes, then the plain Jacobian; ``None``: the plain Jacobian; or a list of boolean
    masks)."""
    if isinstance(newton_groups, str):
        if newton_groups != "variables":
            raise ValueError("newton_groups: 'variables', None or a list of masks")
        small = csys.n * csys.fj.n_nodes <= MIXED_NODES
        newton_groups = list(np.eye(csys.n, dtype=bool)) if small else None
    partial = [PartialNewton(csys, e, v) for e, v in subsystems]
    return [hc4, *partial, IntervalNewton(csys, newton_groups, iterations=newton_steps)]


def default_pipeline(
    csys: CompiledSystem,
    *,
    hc4_passes: int = 4,
    subsystems: Seq[tuple[Any, Any]] = (),
    newton_groups: Any = "variables",
    relax: bool = True,
    cid_slices: int = 4,
    cid_vars: int | str | None = "auto",
    newton_steps: int = NEWTON_STEPS,
) -> Sequence:
    """The solver's pipeline from its options (see :meth:`.Solver.default`)."""
    hc4 = HC4(csys, max_passes=hc4_passes)
    parts = core(
        csys,
        hc4=hc4,
        subsystems=subsystems,
        newton_groups=newton_groups,
        newton_steps=newton_steps,
    )
    pipeline: list[Contractor] = [FixPoint(Sequence(*parts))]
    if relax:
        hull = PolytopeHull(csys, share=HULL_SHARE)
        pipeline.append(FixPoint(hull, since_round=True, significant=HULL_PROGRESS))
    pipeline.append(Inflate())
    if cid_slices:
        pipeline.append(FixPoint(Shave(hc4, cid_slices, count=cid_vars, n=csys.n)))
    else:
        check_count(cid_vars)  # refused even when CID is off, as before
    return Sequence(*pipeline)
