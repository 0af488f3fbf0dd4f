"""The branch-and-prune solver: contract, certify, bisect -- a batch of boxes at a time.

:class:`Solver` is the *step* of the search driver (:mod:`.search`): the driver owns the
limits, progress and the executor.  The solver is assembled from parts, as in IBEX:

* the **system** the results name (and the compiled system the parts search, the
  certifier's: the same, or the equivalent one of lower degree,
  :func:`~certsolve.expr.polynomial.reduce_degree`);
* the **contractor**: a composition of contractors over the round's batch record
  (:mod:`.batch`, :mod:`.pipeline`: ``Sequence``, ``FixPoint``, ``Shave`` ...);
* the **certifier** (:class:`~.certify.Certifier`): it classifies, tightens and expands
  the solutions the parts prove, and the pipeline's ``Inflate`` uses its proofs;
* the **bisector** (:mod:`.bisectors`): the variable each remaining box is split along;
* the **dive** (:mod:`.dive`): which half of a split box the next round takes (the half
  holding the float Newton point of its midpoint, by default);
* the **buffer** (:class:`~.buffer.BoxStack` by default): what holds the pending boxes;
* the **limits** (:class:`SolverLimits`): ``eps``, the variables a bisection may split,
  the batch size and how many undecided / pending hulls a result lists.

:meth:`Solver.default` builds today's pipeline from the classic options.  A round
(:meth:`Solver.process`) on up to ``batch_size`` boxes:

1. drops boxes inside the unicity box of a known solution;
2. passes the rest through the contractor, one :class:`~.batch.Batch`; by default
   (:func:`.pipeline.default_pipeline`): HC4, partial Newton on given sub-systems,
   interval Newton (the Krawczyk test, ``K(X) ⊂ int X`` -> exactly one solution,
   certified, and a Hansen–Sengupta sweep with Hansen's mixed Jacobian) and the polytope
   hull of the X-Taylor and affine linear relaxation, in a fixpoint that sends boxes which
   shrank as much as a bisection back for another round; the inflated Krawczyk test on
   boxes where Newton is informative but stalled; CID on the variable chosen for bisection
   and, as learnt (ACID), on others, in the same fixpoint;
3. reports boxes narrower than ``eps`` (in the variables a bisection may split) as
   *undecided* and bisects the rest along the bisector's choice
   (:class:`~.bisectors.SmearCurvatureMix` by default: smear, or curvature for a third of
   the boxes).

Limits (time, boxes, solutions, cancellation) stop the search between batches; the boxes
still in the buffer are then reported as *pending* and the status names the limit.
Nothing is dropped without a proof that it holds no solution.  The step and its state
pickle, so batches can run on worker processes or a Dask cluster (:mod:`.executors`).
"""

from __future__ import annotations

import copy
import pickle
import time
from collections.abc import Callable
from collections.abc import Sequence as Seq
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem, CompileTimeout
from ..expr.graph import check_deadline
from ..expr.minibex import load_system
from ..expr.node import to_string
from ..expr.polynomial import reduce_degree as lower_degree
from ..expr.system import System
from ..lazy import surely_valid
from .batch import Batch, Contractor
from .batching import BatchSizer
from .bisectors import SmearCurvatureMix, domain_scale, split
from .buffer import BoxStack, no_hints
from .certify import Certifier, SolutionSet
from .checkpoint import Checkpoint
from .dive import NewtonSide
from .executors import resolve_executor
from .nonsquare import ManifoldPaver, overdetermined
from .options_schema import SOLVE_OPTIONS_SCHEMA
from .pipeline import default_pipeline, parts_of
from .relaxation import HullShare
from .result import Certificate, Solution, SolveResult, Stats, Undecided
from .search import Limits, Progress, SearchRun, SearchStatus, Tally, run_search
from .shaving import AdaptiveCount
from .starts import NewtonStarts
from .summary import MAX_LISTED

#: the solver's multistart Newton (:mod:`.starts`), in :meth:`Solver.default` unless
#: ``starts=None``: 512 points a draw (fewer past 16 variables), half of them damped, 100
#: steps, eight phases, up to 8 draws a phase while a quarter of the points prove new
#: solutions (docs/solver.md, *Damped starts*)
STARTS = NewtonStarts(count=512, iterations=100, damped=0.5, phases=8, again=0.25, draws=8)

__all__ = ["SearchState", "Solver", "SolverLimits", "solve"]


@dataclass(kw_only=True, frozen=True, eq=False)
class SolverLimits:
    """How finely a solver splits, how much it lists, how many boxes a round takes.

    ``eps``: boxes whose every component a bisection may split is narrower than ``eps``
    are not bisected further; if still undecided they are reported as such.
    ``bisect_mask``: the variables a bisection may split (None: all); the others are
    auxiliary (FK wire lengths): their shrinking is no progress either
    (:func:`.batch.progress_gain`).  ``batch_size``: boxes per round (per numpy call);
    default 1024: a batch costs ~8 ms of numpy calls plus its boxes, so on
    ``examples/systems`` 1024 takes 1.3-1.5x less CPU than 256 for the same boxes
    (katsura-6 51,246 boxes: 6.6 -> 3.9-4.7 s; katsura-5 0.95 -> 0.69 s); box counts were
    equal on every file.  ``batch_start``: the first rounds' size (:class:`~.batching.
    BatchSizer`: it grows to ``batch_size`` while the per-box time falls); ``None`` (the
    default): ``batch_size`` from the first round.  Either way a round under a time limit is
    cut to the boxes the time left fits at twice the last round's per-box time, so a search
    without a time limit groups its boxes as with a fixed size.  ``max_undecided``,
    ``max_pending``: caps on the undecided and pending hulls listed in the result
    (:mod:`.summary`).
    """

    eps: float = 1e-8
    bisect_mask: np.ndarray | None = None
    batch_size: int = 1024
    batch_start: int | None = None
    max_undecided: int = MAX_LISTED
    max_pending: int = MAX_LISTED

    def __post_init__(self) -> None:
        if not self.eps > 0:
            raise ValueError("eps must be positive")
        if not (int(self.max_undecided) >= 0 and int(self.max_pending) >= 1):
            raise ValueError("max_undecided must be >= 0 and max_pending >= 1")
        if not int(self.batch_size) >= 1:
            raise ValueError("batch_size must be >= 1")
        if self.batch_start is not None and not int(self.batch_start) >= 1:
            raise ValueError("batch_start must be >= 1 (or None)")
        mask = None if self.bisect_mask is None else np.asarray(self.bisect_mask, dtype=bool)
        for name, value in (
            ("eps", float(self.eps)),
            ("batch_size", int(self.batch_size)),
            ("batch_start", None if self.batch_start is None else int(self.batch_start)),
            ("max_undecided", int(self.max_undecided)),
            ("max_pending", int(self.max_pending)),
            ("bisect_mask", mask),
        ):
            object.__setattr__(self, name, value)


class Solver:
    """All solutions of a square system in its domain, each certified unique.

    Parameters (the parts; :meth:`default` builds them from the classic options)
    ----------
    system:
        the :class:`~certsolve.expr.system.System` the results and checkpoints name (or a
        :class:`~certsolve.expr.compiled.CompiledSystem`: its system).
    contractor:
        the pipeline (:mod:`.pipeline`): every part follows the :mod:`.batch` protocol.
    certifier:
        the :class:`~.certify.Certifier` on the compiled system the parts search (that
        system is :attr:`csys`; ``verify`` re-proves certificates on it).
    bisector:
        ``choose(lo, hi, jlo, jhi, eps, mask, scale=...)``, ``ratio`` and optionally
        ``at_zero`` (:func:`.bisectors.split`).
    buffer:
        ``buffer(n)`` makes the search's box buffer (default :class:`~.buffer.BoxStack`).
    limits:
        :class:`SolverLimits` (eps, the variables a bisection may split, batch size,
        listing caps).
    dive:
        ``upper_first(csys, lo, hi, var, at)``: which half of a split box the next round
        takes (:mod:`.dive`; default :class:`~.dive.NewtonSide`, the half holding the float
        Newton point of the box's midpoint).
    """

    def __init__(
        self,
        system: System | CompiledSystem,
        contractor: Contractor,
        certifier: Certifier,
        bisector: Any,
        buffer: Callable[[int], BoxStack] = BoxStack,
        limits: SolverLimits | None = None,
        dive: Any = None,
        starts: NewtonStarts | None = None,
    ):
        self.system = system.system if isinstance(system, CompiledSystem) else system
        #: the compiled system searched (the certifier's); :attr:`system` is the one given
        #: (they differ when ``reduce_degree`` replaced equations)
        self.csys = certifier.csys
        self.contractor = contractor
        self.certifier = certifier
        self.bisector = bisector
        self.buffer = buffer
        self.limits = limits or SolverLimits()
        self.dive = dive or NewtonSide()
        #: certified solutions early, from float Newton at random points (:mod:`.starts`)
        self.starts = starts
        #: the box searched by :meth:`solve` (the system's; see :meth:`on_domain`)
        self.domain = self.system.domain
        self.n = self.csys.n
        mask = self.limits.bisect_mask
        if mask is not None and mask.shape != (self.n,):
            raise ValueError(f"bisect_mask must have {self.n} entries")
        #: the part whose learnt state the search keeps (:attr:`SearchState.acid`), if any
        self._learner: Any = next(
            (p for p in parts_of(contractor) if callable(getattr(p, "learner", None))), None
        )
        #: the part whose learnt state is :attr:`SearchState.hull`, if any
        self._hull_learner: Any = next(
            (p for p in parts_of(contractor) if callable(getattr(p, "hull_learner", None))),
            None,
        )

    @classmethod
    def default(
        cls,
        system: System | CompiledSystem,
        *,
        eps: float = 1e-8,
        batch_size: int = 1024,
        batch_start: int | None = None,
        hc4_passes: int = 4,
        bisector: Any = None,
        split_at_zero: bool = True,
        dive: Any = None,
        certifier: Certifier | None = None,
        bisect_mask: Any = None,
        subsystems: Seq[tuple[Any, Any]] = (),
        newton_groups: Any = "variables",
        cid_slices: int = 4,
        cid_vars: int | str | None = "auto",
        max_undecided: int = MAX_LISTED,
        max_pending: int = MAX_LISTED,
        relax: bool = True,
        reduce_degree: bool = True,
        starts: NewtonStarts | None = STARTS,
        deadline: float | None = None,
    ) -> Solver:
        """The solver with the default pipeline (:func:`.pipeline.default_pipeline`).

        ``batch_start``: the first rounds' size, grown to ``batch_size`` while that pays
        (:class:`SolverLimits`, :class:`~.batching.BatchSizer`); ``None`` (default):
        ``batch_size`` from the first round.  Starting small was measured not to bring the
        first solutions earlier on IBEX's files where certsolve is behind (Trigo1-0017,
        Brent-10, CountercurrentReactors2-12, Redeco9 at 6,000 boxes: docs/solver.md).

        ``hc4_passes``, ``bisector``, ``dive``, ``certifier``: swappable parts (defaults: 4
        HC4 passes, :class:`~.bisectors.SmearCurvatureMix`, :class:`~.dive.NewtonSide`,
        Krawczyk).  ``split_at_zero``: the default bisector splits the variables that
        multiply others (:attr:`~certsolve.expr.compiled.CompiledSystem.coupled`) at 0 while
        0 is well inside their interval (:func:`.bisectors.split`), a *sign split*; on by
        default (``docs/solver.md``, *The split point* and *Going round again on the faces*:
        it finds the first solutions of Eco10, Redeco10 and CountercurrentReactors2-12 to
        -28 within 10 s, where the midpoint finds none; Katsura's solutions with zero
        coordinates then lie on bisection faces, katsura-6 2.3 -> 2.5 CPU s).  ``False``:
        the ratio's point everywhere.  ``newton_groups``:
        ``"variables"`` (default): Hansen–Sengupta with Hansen's mixed Jacobian, one
        variable per group; ``None``: the plain interval Jacobian; or a list of boolean
        masks (:class:`~.contractors.IntervalNewton`).  ``cid_slices``: slices of the CID
        contraction before a bisection; 0 turns it off (mixed Jacobian + CID need 2-3x fewer
        boxes on Katsura and the 6R system).  ``cid_vars``: how many variables CID
        contracts, the chosen one first (:class:`~.shaving.Shave`: a number, ``None`` for
        all, ``"auto"`` (default) for the count learnt as IBEX's ACID does).
        ``subsystems``: square sub-systems ``(equations, variables)`` also contracted by
        partial Newton.

        ``relax``: contract with the polytope hull of the X-Taylor and affine-form linear
        relaxation (:class:`~.relaxation.PolytopeHull`) after Newton.  Measured on
        ``examples/systems``: 2-40x fewer boxes.  Forward kinematics leaves it out: a box's
        LPs cost ~10x the rest of its work there, which general-19 repays (at 10 N 128,672
        -> 12,196 boxes, 13.2 -> 9.3 CPU s; at 60 N u~S(2) 156,910 -> 15,413, 12.8 -> 10.4
        s) but T-16 does not (60 N u=2: 271,875 -> 92,523 boxes, 18.5 -> 45.4 s; random-T-0
        6.1 -> 11.3 s), nor general-19's open case (random-general-0 at 60 N, 60 pivots:
        294k boxes in 300 s, against all 2.83M in ~230 s without).

        ``reduce_degree``: solve the equivalent system of
        :func:`~certsolve.expr.polynomial.reduce_degree`: exact linear combinations of
        polynomial equations that cancel their leading monomials replace equations (same
        solutions, each as unique).  Results and checkpoints name the given system;
        ``verify`` re-proves the certificates on the searched one.  Only with a
        :class:`~certsolve.expr.system.System` and no ``subsystems``.  Among IBEX's files it
        changes Dietmaier (two linear equations: 459,140 -> 271,252 boxes, 137 -> 83 CPU s
        on one worker) and ExtendedFreud-0010 (97 -> 67 boxes); no forward-kinematics
        system.

        ``starts``: certified solutions early (:class:`~.starts.NewtonStarts`, default
        :data:`STARTS`): once the search has made 64 bisections (fewer past 16 variables), and
        at 4, 16 ... 4^7 times that, float Newton from random points of the pending boxes
        (half of them damped), each point it converges to
        proven by the certifier's inflated Krawczyk test; ``None``: the search alone.  On
        IBEX's files neither solver completes in 10 s it raised certsolve's certified
        solutions at the limit from 460 to 2,352 (``docs/solver.md``, *Certified solutions
        early: Newton from random points*).

        ``deadline`` (a :func:`time.monotonic` value): building past it (degree reduction,
        compile, the pipeline's programs) raises :class:`~certsolve.expr.compiled.
        CompileTimeout`; :func:`solve` reports it as a search stopped by its time limit.
        """
        limits = SolverLimits(
            eps=eps,
            bisect_mask=bisect_mask,
            batch_size=batch_size,
            batch_start=batch_start,
            max_undecided=max_undecided,
            max_pending=max_pending,
        )
        surplus = 0
        if isinstance(system, CompiledSystem):
            csys = system
        elif len(system.equations) > system.n:  # over-determined: a square subsystem
            square, surplus = overdetermined(system)
            csys = CompiledSystem(square, deadline=deadline)
        elif len(system.equations) < system.n:
            raise ValueError(
                f"{len(system.equations)} equations for {system.n} variables: an "
                "under-determined system is paved by solver.nonsquare.ManifoldPaver "
                "(solve() and certsolve solve choose it)"
            )
        else:
            solved = lower_degree(system) if reduce_degree and not subsystems else system
            check_deadline(deadline, "reducing the degree")
            csys = CompiledSystem(solved, deadline=deadline)
        contractor = default_pipeline(
            csys,
            hc4_passes=hc4_passes,
            subsystems=subsystems,
            newton_groups=newton_groups,
            relax=relax,
            cid_slices=cid_slices,
            cid_vars=cid_vars,
        )
        check_deadline(deadline, "building the contractors")
        return cls(
            system,
            contractor,
            certifier or Certifier(csys, surplus=surplus),
            bisector or SmearCurvatureMix(at_zero=csys.coupled if split_at_zero else False),
            limits=limits,
            dive=dive,
            starts=starts,
        )

    @property
    def eps(self) -> float:
        return self.limits.eps

    @property
    def batch_size(self) -> int:
        return self.limits.batch_size

    def sizer(self) -> BatchSizer:
        """A new batch size for one search: from ``batch_start`` (or ``batch_size``), cut to
        the time left (:class:`~.batching.BatchSizer`)."""
        start = self.limits.batch_start
        return BatchSizer(cap=self.batch_size, start=self.batch_size if start is None else start)

    @property
    def bisect_mask(self) -> np.ndarray | None:
        """The variables a bisection may split (None: all)."""
        return self.limits.bisect_mask

    @property
    def max_undecided(self) -> int:
        return self.limits.max_undecided

    @property
    def max_pending(self) -> int:
        return self.limits.max_pending

    # -- public entry point ------------------------------------------------------------------
    def solve(
        self,
        *,
        timeout: float | None = None,
        max_boxes: int | None = None,
        progress: Callable[[Progress], bool | None] | None = None,
        executor: Any = None,
        verify: bool = False,
        max_solutions: int | None = None,
        cancel: Any = None,
        boxes: tuple[np.ndarray, np.ndarray] | None = None,
        workers: int | None = None,
        checkpoint: Checkpoint | None = None,
        domain: np.ndarray | None = None,
    ) -> SolveResult:
        """Run the search over the whole domain, or over ``boxes`` ``(lo, hi)`` if given.

        ``domain`` ``(n, 2)`` replaces the system's domain for this search only (solutions
        touching its boundary are reported as ``boundary``; :meth:`on_domain`).

        ``executor``: where batches run (``None``: here; a number of local processes,
        ``"auto"``, a ``distributed.Client`` ... see :func:`.executors.resolve_executor`);
        ``workers`` is the older name of an integer ``executor``.  ``max_solutions`` stops
        the search once that many solutions are certified; ``progress`` returning ``False``
        or ``cancel.is_set()`` cancels it.  The status is ``complete`` when nothing is
        pending, else the limit that stopped the search (:class:`.SearchStatus`).
        ``checkpoint`` (:class:`.checkpoint.Checkpoint`): save the search as it goes and
        resume it from the last save (limits apply to each run).
        """
        if domain is not None:
            return self.on_domain(domain).solve(
                timeout=timeout,
                max_boxes=max_boxes,
                progress=progress,
                executor=executor,
                verify=verify,
                max_solutions=max_solutions,
                cancel=cancel,
                boxes=boxes,
                workers=workers,
                checkpoint=checkpoint,
            )
        if boxes is None:
            dom = self.domain
            boxes = (dom[:, 0][None].copy(), dom[:, 1][None].copy())
        run = run_search(
            self,
            *boxes,
            limits=Limits(timeout=timeout, max_boxes=max_boxes, max_solutions=max_solutions),
            executor=resolve_executor(executor, workers=workers),
            progress=progress,
            cancel=cancel,
            checkpoint=checkpoint,
            sizer=self.sizer(),
        )
        result = self.result(run)
        if verify:
            from .verify import verify_solutions

            verify_solutions(self.csys, result.solutions)  # the system the search proved
        return result

    def on_domain(self, domain) -> Solver:
        """This solver searching ``domain`` ``(n, 2)`` instead of the system's.

        A shallow copy (the compiled system and the contractors are shared, nothing of this
        solver or its system changes); it is also the step that travels to the workers.
        """
        dom = np.asarray(domain, dtype=np.float64)
        if dom.shape != (self.n, 2):
            raise ValueError(f"domain must have shape ({self.n}, 2), got {dom.shape}")
        step = copy.copy(self)
        step.domain = dom
        step.certifier = copy.copy(self.certifier)
        step.certifier.domain = dom
        return step

    # -- the step of the search driver ------------------------------------------------------
    def fingerprint(self) -> str:
        """The problem and the settings that shape the answer, as text (for checkpoints,
        :mod:`.checkpoint`): equations, constraints, domain, parameter values, the limits
        and each part's own description (the contractor's composition, the bisector, the
        certifier, the buffer)."""
        sysm, c = self.system, self.csys
        mask = None if self.bisect_mask is None else self.bisect_mask.tolist()
        parts = [
            "variables: " + ",".join(sysm.variables),
            "domain: " + repr(self.domain.tolist()),
            *(f"eq: {to_string(e)}" for e in sysm.equations),
            *(
                f"constraint: {to_string(k.expr)} in [{k.lo!r}, {k.hi!r}] {k.redundant}"
                for k in sysm.constraints
            ),
            f"parameters: {c.param_names} {c.param_lo.tolist()!r} {c.param_hi.tolist()!r}",
            f"eps: {self.eps!r}, mask: {mask}",
            f"contractor: {self.contractor.describe()}",
            f"bisector: {type(self.bisector).__name__} {_settings(self.bisector)}",
            f"certifier: {self.certifier.describe()}",
            f"starts: {self.starts!r}",
            f"buffer: {getattr(self.buffer, '__qualname__', repr(self.buffer))}",
        ]
        if c.system is not sysm:
            parts += [f"solved as: {to_string(e)}" for e in c.system.equations]
        return "\n".join(parts)

    def start(self, known: bytes | None = None) -> SearchState:
        """An empty search state, with the solutions and the learnt states (the CID count,
        the polytope hull's share) in ``known`` (see :meth:`known`)."""
        if known is None:
            learner, hull = self._learner, self._hull_learner
            sols = SolutionSet(self.n)
            acid = None if learner is None else learner.learner()
            share = None if hull is None else hull.hull_learner()
        else:
            sols, acid, share = pickle.loads(known)
        return SearchState(
            self.buffer(self.n),
            sols,
            [],
            Stats(),
            mark=len(sols),
            acid=acid,
            hull=share,
            starts=known is None,
        )

    def tally(self, state: SearchState) -> Tally:
        sols = sum(state.solutions.count(kind) for kind in _PROVEN)
        return Tally(solutions=sols, undecided=len(state.undecided))

    def known(self, state: SearchState) -> bytes:
        """The solution set and the learnt states, pickled (for tasks: unpickling is
        ~100x faster than adding the solutions one by one, and the copy is the task's
        own; a task goes on with the CID count and hull share its search has learnt)."""
        known = (state.solutions, state.acid, state.hull)
        return pickle.dumps(known, protocol=pickle.HIGHEST_PROTOCOL)

    def found(self, state: SearchState):
        """Solutions recorded since :meth:`start`, undecided boxes, counters and the learnt
        states (the CID count, the hull's share)."""
        sols = state.solutions
        new = range(state.mark, len(sols))
        entries = [(*sols.entry(i), sols.kind[i]) for i in new]
        st = state.stats
        counters = (st.bisections, st.certified, st.duplicates, st.started)
        return entries, state.undecided, counters, copy.copy(state.acid), copy.copy(state.hull)

    def merge(self, state: SearchState, found) -> None:
        """Add a task's findings; a solution two tasks proved is recorded once.  The learnt
        states are the task's (the latest a task brings home; a checkpoint's on restore)."""
        before = state.stats.bisections
        entries, undecided, (bisections, certified, duplicates, *started), *rest = found
        # absent from checkpoints written before they were kept
        acid, hull = (*rest, None, None)[:2]
        for e0, e1, u0, u1, kind in entries:
            if kind == "alias":
                state.solutions.add(e0, e1, u0, u1, "alias")
            elif not state.solutions.add(e0, e1, u0, u1, kind):
                state.stats.duplicates += 1
        state.undecided.extend(undecided)
        state.stats.bisections += bisections
        state.stats.certified += certified
        state.stats.duplicates += duplicates
        state.stats.started += sum(started)  # absent from checkpoints written before it
        if acid is not None and state.acid is not None:
            state.acid = copy.copy(acid)
        if hull is not None and state.hull is not None:
            state.hull = copy.copy(hull)
        if before > 0:  # a task's work (a restore starts from 0 and replays no phase)
            self._phase_if_due(state, before)

    def listed(self, state: SearchState, start: int) -> tuple[list[Solution], int]:
        """The solutions recorded from position ``start`` of the solution set on (for
        :attr:`.search.Progress.found`: streamed as they are proven), and the end."""
        sols = state.solutions
        end = len(sols)
        new = [
            Solution(*sols.entry(i), _PROVEN[sols.kind[i]])
            for i in range(start, end)
            if sols.kind[i] in _PROVEN
        ]
        return new, end

    def process(
        self,
        lo: np.ndarray,
        hi: np.ndarray,
        state: SearchState,
        *,
        deadline: float | None = None,
        hints: np.ndarray | None = None,
    ) -> None:
        """One round on the boxes ``lo, hi``: prune by known solutions, contract (the
        pipeline), then report the boxes narrower than ``eps`` and bisect the others.
        ``deadline``: the parts may stop contracting past it (:attr:`.Batch.deadline`).
        ``hints``: the boxes' hints from the buffer (:mod:`.buffer`), if any."""
        bisections = state.stats.bisections
        keep, plo, phi = state.solutions.prune(lo, hi)
        if hints is not None:  # the pieces of a pruned box start without
            hints = np.concatenate([hints[keep], no_hints(plo.shape[0], hints.shape[1])])

        def prove(elo, ehi, ulo, uhi) -> None:
            self._record(state, elo, ehi, ulo, uhi, tight=False)

        batch = Batch(
            np.concatenate([lo[keep], plo]),
            np.concatenate([hi[keep], phi]),
            csys=self.csys,
            eps=self.eps,
            mask=self.bisect_mask,
            faces=self.faces,
            scale=self.scale,
            choose=self._choose,
            certifier=self.certifier,
            stack=state.stack,
            prove=prove,
            acid=state.acid,
            hull=state.hull,
            deadline=deadline,
            hints=hints,
        )
        self.contractor.apply(batch)
        batch.drop_empty()
        if batch.size:
            self._split(batch, state)
        batch.flush()  # what the parts sent back goes on top: the next round takes it
        self._phase_if_due(state, bisections, deadline)

    def _phase_if_due(self, state: SearchState, before: int, deadline: float | None = None) -> None:
        """The phase of :class:`~.starts.NewtonStarts` the bisections since ``before``
        reached, if any, else the next draw of the last phase if its last draw paid, on the
        search's own state (a worker task's runs none)."""
        if self.starts is None or not state.starts:
            return
        phase = self.starts.due(before, state.stats.bisections, self.csys.n)
        if phase is not None:
            self._newton_starts(state, phase, 0, deadline)
        elif state.redraw is not None:
            self._newton_starts(state, *state.redraw, deadline)

    def _newton_starts(
        self, state: SearchState, phase: int, draw: int = 0, deadline: float | None = None
    ) -> None:
        """A draw of a phase of :class:`~.starts.NewtonStarts`: float Newton from random
        points of the pending boxes (of the domain when the workers hold them all), and the
        points it converged to proven (inflated Krawczyk) and recorded as any solution the
        search proves.  If it proved ``again`` of its size as new solutions, the next round
        runs the next draw (``state.redraw``), up to ``draws``: one draw at a time, so the
        search checks its limits, cancellation and progress between draws (on 3^8
        solutions, eight draws in a row took 6-9 s).  Past ``deadline``
        (:func:`time.monotonic`) Newton stops iterating."""
        starts = self.starts
        assert starts is not None
        state.redraw = None
        lo, hi = state.stack.view()
        if lo.shape[0] == 0:  # all handed out to workers: start anywhere in the domain
            lo, hi = self.domain[:, 0][None], self.domain[:, 1][None]
        x = starts.points(self.certifier, self.domain, lo, hi, phase, draw, deadline=deadline)
        w = 1e-9 * (1.0 + np.abs(x))
        xlo, xhi = x - w, x + w
        # a point in a known solution's unicity box is that solution: not proven again
        keep, _, _ = state.solutions.prune(xlo, xhi)
        if not np.any(keep):
            return
        idx, elo, ehi, ulo, uhi = self.certifier.inflate(xlo[keep], xhi[keep])
        if idx.size:
            new = self._record(state, elo, ehi, ulo, uhi, tight=False)
            state.stats.started += new
            if new >= starts.again * starts.size(self.csys.n) and draw + 1 < starts.draws:
                state.redraw = (phase, draw + 1)

    def _split(self, batch: Batch, state: SearchState) -> None:
        """Report the rows narrower than ``eps`` as undecided, push the halves of the
        others."""
        var = batch.choice()
        small = var < 0
        for i in np.flatnonzero(small):
            state.undecided.append(Undecided(batch.lo[i].copy(), batch.hi[i].copy(), "eps"))
        big = ~small
        if np.any(big):
            lo3, hi3 = batch.lo[big], batch.hi[big]
            faces = self.faces
            at_zero = False if faces is None else faces
            (alo, ahi), (blo, bhi) = split(lo3, hi3, var[big], self.bisector.ratio, at_zero=at_zero)
            state.stats.bisections += lo3.shape[0]
            hints = batch.row_hints(big)  # each half starts from its parent's
            # the halves the dive chose go on top: the next round takes them (.dive); when
            # the next round takes the whole stack anyway, the order is moot
            rows = np.arange(lo3.shape[0])
            if len(state.stack) + 2 * rows.size + batch.backlog <= self.batch_size:
                up = np.zeros(rows.size, dtype=bool)
            else:
                up = self.dive.upper_first(self.csys, lo3, hi3, var[big], ahi[rows, var[big]])
            first = up[:, None]
            state.stack.push(
                np.concatenate([np.where(first, alo, blo), np.where(first, blo, alo)]),
                np.concatenate([np.where(first, ahi, bhi), np.where(first, bhi, ahi)]),
                None if hints is None else np.concatenate([hints, hints]),
            )

    def _choose(self, lo, hi, jlo, jhi) -> np.ndarray:
        """The bisector's variable for each box (``jlo, jhi``: its Jacobian enclosure)."""
        return self.bisector.choose(lo, hi, jlo, jhi, self.eps, self.bisect_mask, scale=self.scale)

    @property
    def faces(self) -> np.ndarray | None:
        """``(n,)`` the variables the bisector splits at 0 (its ``at_zero``, where the
        domain holds 0 inside), None if none: the fixpoints count them only where not far
        narrower than the box's widest (:func:`.batch.progress_gain`)."""
        at_zero = getattr(self.bisector, "at_zero", False)
        faces = (
            np.asarray(at_zero, dtype=bool) & (self.domain[:, 0] < 0.0) & (self.domain[:, 1] > 0.0)
        )
        return faces if faces.any() else None

    @property
    def scale(self) -> np.ndarray:
        """The domain's widths: a box on which the Jacobian tells the bisector nothing is
        split along its variable widest relative to them (:func:`~.bisectors.domain_scale`)."""
        return domain_scale(self.domain)

    def _record(self, state: SearchState, elo, ehi, ulo, uhi, tight: bool = True) -> int:
        """Record proven solutions; existence boxes are tightened only for new ones.
        Returns how many new ones are reported as solutions (not ``boundary``,
        ``constraint`` or ``rejected``)."""
        state.stats.certified += elo.shape[0]
        new = np.array(
            [state.solutions.find(elo[k], ehi[k], ulo[k], uhi[k]) < 0 for k in range(len(elo))],
            dtype=bool,
        )
        for j in np.flatnonzero(~new):  # known solution: keep its unicity box for pruning
            state.solutions.add(elo[j], ehi[j], ulo[j], uhi[j], "alias")
            state.stats.duplicates += 1
        if not np.any(new):
            return 0
        elo, ehi, ulo, uhi = elo[new], ehi[new], ulo[new], uhi[new]
        if not tight:
            elo, ehi = self.certifier.tighten(elo, ehi)
        ulo, uhi = self.certifier.expand(elo, ehi, ulo, uhi)
        kinds = self.certifier.classify(elo, ehi)
        added = 0
        for k, kind in enumerate(kinds):
            if state.solutions.add(elo[k], ehi[k], ulo[k], uhi[k], kind):
                added += kind in _PROVEN
            else:
                state.stats.duplicates += 1
        return added

    # -- results -----------------------------------------------------------------------------
    def result(self, run: SearchRun) -> SolveResult:
        """The :class:`SolveResult` of a finished search (undecided and pending boxes summarised,
        :mod:`.summary`)."""
        state = run.state
        sols = [
            Solution(e0, e1, u0, u1, certificate)
            for kind, certificate in _PROVEN.items()
            for e0, e1, u0, u1 in state.solutions.items(kind)
        ]
        sols.sort(key=lambda s: tuple(s.midpoint))
        und = [(u.lo, u.hi, u.reason) for u in state.undecided]
        dlo, dhi = self.domain[:, 0], self.domain[:, 1]
        for e0, e1, _, _ in state.solutions.items("boundary"):
            und.append((np.maximum(e0, dlo), np.minimum(e1, dhi), "boundary"))
        for e0, e1, _, _ in state.solutions.items("constraint"):
            und.append((e0, e1, "constraint"))
        return SolveResult.of_search(
            run,
            variables=self.system.variables,
            solutions=sols,
            undecided=und,
            stats=state.stats,
            eps=self.eps,
            max_undecided=self.max_undecided,
            max_pending=self.max_pending,
        )


#: the options of :func:`solve` the paving of an under-determined system takes (the others
#: shape the square solver's pipeline)
_PAVER_OPTIONS = ("batch_size", "hc4_passes", "max_undecided", "max_pending")

#: seconds a build is always given, however short the time limit: a short limit still
#: builds a small system and runs its first round (a checkpointed search moves on; the
#: command line's backstop is 0.01 s), while a build longer than both stops at the limit
MIN_BUILD_SECONDS = 1.0

#: the kinds of the solution set reported as solutions, and their certificates
_PROVEN = {"ok": Certificate.UNIQUE, "subsystem": Certificate.SQUARE_SUBSYSTEM}


def _settings(obj) -> str:
    """The plain settings of a part (numbers, strings, arrays), sorted by name."""
    items = []
    for k, v in sorted(vars(obj).items()):
        if isinstance(v, np.ndarray):
            v = v.tolist()
        if isinstance(v, (bool, int, float, str, list, tuple, type(None))):
            items.append(f"{k}={v!r}")
    return ", ".join(items)


@dataclass
class SearchState:
    """The solver's state in a search (the driver's buffer and the records of a step)."""

    stack: BoxStack
    solutions: SolutionSet
    undecided: list
    stats: Stats  # the step's counters: bisections, certified, duplicates
    mark: int = 0  # solutions[:mark] were known when the state started
    acid: AdaptiveCount | None = None  # the learnt CID count (:class:`.shaving.Shave`)
    hull: HullShare | None = None  # the hull's learnt share (:class:`.relaxation.PolytopeHull`)
    starts: bool = False  # runs the phases of :class:`.starts.NewtonStarts` (not a task's)
    #: the phase and draw the next round runs, after a draw that paid (not in checkpoints:
    #: a restored search replays no phase)
    redraw: tuple[int, int] | None = None


def solve(
    system: System | str | PathLike,
    *,
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    executor: Any = None,
    verify: bool = False,
    progress: Callable[[Progress], bool | None] | None = None,
    max_solutions: int | None = None,
    cancel: Any = None,
    workers: int | None = None,
    checkpoint: Checkpoint | None = None,
    **options,
) -> SolveResult:
    """Find every solution of ``system`` in its domain (see :meth:`Solver.default` for the
    ``options`` and :meth:`Solver.solve`).  ``system``: a :class:`System`, a Minibex file's path, or
    Minibex text (:func:`~certsolve.expr.minibex.load_system`).  An over-determined
    system is solved through a square subsystem, an under-determined one paved
    (:mod:`.nonsquare`: in this process, without checkpoints; of the ``options`` only
    those of :class:`~.nonsquare.ManifoldPaver` apply).  The options are checked
    as the ``solve`` job and ``certsolve solve`` check them (:class:`~.options.
    SolveOptions`): a value they refuse raises :class:`~certsolve.inputs.InputError`
    naming it."""
    if not isinstance(system, System):
        system = load_system(system)
    given = {
        "eps": eps,
        "timeout": timeout,
        "max_boxes": max_boxes,
        "max_solutions": max_solutions,
        "verify": verify,
    }
    if not surely_valid(SOLVE_OPTIONS_SCHEMA, given):  # the model, with pydantic, only then
        from ..inputs import checked
        from .options import SolveOptions

        checked(SolveOptions, given)
    if len(system.equations) < system.n:  # under-determined: pave the solution set
        from ..inputs import InputError

        if not system.equations:
            raise InputError("system", "no equations (inequalities alone are not solved)")
        if verify:
            raise InputError("verify", "an under-determined system has no unique solutions")
        if checkpoint is not None:
            raise InputError("checkpoint", "not available for an under-determined system")
        paving = {k: options[k] for k in _PAVER_OPTIONS if k in options}
        paver = ManifoldPaver(system, eps=eps, **paving)
        return paver.solve(
            timeout=timeout,
            max_boxes=max_boxes,
            max_solutions=max_solutions,
            progress=progress,
            cancel=cancel,
        )
    started, cpu0 = time.monotonic(), time.process_time()
    deadline = None if timeout is None else started + max(timeout, MIN_BUILD_SECONDS)
    try:
        solver = Solver.default(system, eps=eps, deadline=deadline, **options)
    except CompileTimeout:  # the limit passed before the first box: all of it pending
        return SolveResult.unexplored(
            variables=system.variables,
            domain=system.domain,
            status=SearchStatus.TIMEOUT,
            eps=eps,
            time=time.monotonic() - started,
            cpu=time.process_time() - cpu0,
        )
    # the search then has its own ``timeout``, as before, and always runs a first round (the
    # command line's deadline counts the build and the search together)
    return solver.solve(
        timeout=timeout,
        max_boxes=max_boxes,
        executor=executor,
        verify=verify,
        progress=progress,
        max_solutions=max_solutions,
        cancel=cancel,
        workers=workers,
        checkpoint=checkpoint,
    )
