"""The branch-and-prune solver: contract, certify, bisect -- a batch of boxes at a time.

:class:`Solver` is the *step* of the search driver (:mod:`.search`): the driver owns the
buffer, the limits, progress and the executor.  The system searched is the given one, or
the equivalent one of lower degree (:func:`~certsolve.expr.polynomial.reduce_degree`).
:meth:`Solver.process` takes a batch of up to
``batch_size`` boxes and, for all of them at once:

1. drops boxes inside the unicity box of a known solution;
2. contracts with :class:`~.contractors.HC4` (boxes proven empty are dropped), then with
   partial Newton on the given sub-systems, if any;
3. linearises and runs :class:`~.contractors.IntervalNewton`: the Krawczyk test on the box
   (``K(X) ⊂ int X`` -> exactly one solution, certified) and a Hansen–Sengupta sweep (with
   Hansen's mixed Jacobian by default); then contracts with the polytope hull of the
   X-Taylor linear relaxation (:class:`~.relaxation.PolytopeHull`);
4. for boxes where Newton is informative but stalled, tries :meth:`.Certifier.inflate`;
   the part of the box outside a proven unicity box goes back to the buffer;
5. sends boxes that shrank at least as much as a bisection would (log-volume of the
   variables the bisector may split: auxiliary ones follow the others) back for another
   round, reports boxes narrower than ``eps`` as *undecided*, and bisects the rest
   (:class:`~.bisectors.SmearCurvatureMix`: smear, or curvature for a third of the boxes),
   after CID contractions
   (:class:`~.shaving.CID`) on the chosen variable and, with ``cid_vars``, on the other
   variables in decreasing smear order (IBEX's ACID applies CID to the first variables of
   that order).

Limits (time, boxes, solutions, cancellation) stop the search between batches; the boxes
still in the buffer are then reported as *pending* and the status names the limit.
Nothing is dropped without a proof that it holds no solution.  The step and its state
pickle, so batches can run on worker processes or a Dask cluster (:mod:`.executors`).
"""

from __future__ import annotations

import copy
import pickle
from collections.abc import Callable
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem
from ..expr.minibex import load_system
from ..expr.node import to_string
from ..expr.polynomial import reduce_degree as lower_degree
from ..expr.system import System
from ..inputs import checked
from ..interval.core import splittable_width
from ..interval.reductions import all_last, any_last
from .bisectors import SmearCurvatureMix, domain_scale, smear_scores, split
from .buffer import BoxStack
from .certify import Certifier, SolutionSet, box_difference
from .checkpoint import Checkpoint
from .contractors import HC4, IntervalNewton, PartialNewton, log_volume_ratio
from .executors import resolve_executor
from .options import SolveOptions
from .relaxation import PolytopeHull
from .result import Solution, SolveResult, Stats, Undecided
from .search import Limits, Progress, SearchRun, SearchStatus, Tally, run_search
from .shaving import CID, AdaptiveCount
from .summary import MAX_LISTED, summarize

__all__ = ["Solver", "SearchState", "solve"]

_LOG_HALF = float(np.log(0.5))


class Solver:
    """All solutions of a square system in its domain, each certified unique.

    Parameters
    ----------
    system:
        the :class:`~certsolve.expr.system.System` to solve.
    eps:
        boxes whose every component is narrower than ``eps`` are not bisected further;
        if still undecided they are reported as such.
    batch_size:
        boxes processed per round (per numpy call).  Default 1024: a batch costs ~8 ms of
        numpy calls plus its boxes, so on ``examples/systems`` 1024 takes 1.3-1.5x less CPU
        than 256 for the same boxes (katsura-6 51,246 boxes: 6.6 -> 3.9-4.7 s; katsura-5
        0.95 -> 0.69 s); box counts were equal on every file.
    hc4_passes, bisector, certifier:
        swappable parts (defaults: 4 HC4 passes, smear-sum-relative bisection, Krawczyk).
    newton_groups:
        ``"variables"`` (default): Hansen–Sengupta with Hansen's mixed Jacobian, one
        variable per group; ``None``: the plain interval Jacobian; or a list of boolean
        masks (see :class:`~.contractors.IntervalNewton`).
    cid_slices:
        slices of the CID contraction (HC4 on each slice, hull) applied to the variable
        chosen for bisection; 0 turns it off.  Measured on ``examples/systems``: mixed
        Jacobian + CID need 2-3x fewer boxes on Katsura and the 6R system.
    cid_vars:
        how many variables CID contracts before a bisection: the chosen one, then the others
        by decreasing smear score (variables that may be split and have a positive score);
        ``None``: all of them; ``"auto"`` (default): the count learnt during the search
        (:class:`~.shaving.AdaptiveCount`, IBEX's ACID rule; the learnt state is the
        search's, :attr:`SearchState.acid`).  Measured against 1 (batches of 1024, one
        process, CPU s, with the affine relaxation): on IBEX's benchmarks up to 8x fewer
        boxes and half the time or less on the hard files (Brent-10 141,814 -> 17,998
        boxes, 22.1 -> 11.8 s; transistor 216,437 -> 60,385 boxes, 27.3 -> 13.2 s;
        Discrete-Integral-6 118,067 -> 18,463 boxes, 7.8 -> 2.2 s), but 1.07-1.25x the
        time on medium systems (katsura-6 22,121 -> 21,680 boxes, 2.09 -> 2.27 s; eco-7
        0.81 -> 1.12 s, 0.91 -> 1.0 s since the extra variables of small batches are
        shaved side by side; Eco9 2.8 -> 3.3 s); searches of fewer than ~950 boxes never
        learn, so cost the same.
        ``None`` against 1: 2-9x fewer boxes, 1.3-2x the CPU time on ``examples/systems``.
    subsystems:
        square sub-systems ``(equations, variables)`` also contracted by partial Newton.
    max_undecided, max_pending:
        caps on the undecided and pending hulls listed in the result (:mod:`.summary`).
    reduce_degree:
        solve the equivalent system of :func:`~certsolve.expr.polynomial.reduce_degree`:
        exact linear combinations of polynomial equations that cancel their leading
        monomials replace equations (same solutions, each as unique).  Results and
        checkpoints name the given system; ``verify`` re-proves the certificates on the
        searched one.  Only with a :class:`~certsolve.expr.system.System` and no
        ``subsystems``.  Among IBEX's files it changes Dietmaier (two linear equations:
        459,140 -> 271,252 boxes, 137 -> 83 CPU s on one worker) and ExtendedFreud-0010
        (97 -> 67 boxes); no forward-kinematics system.
    relax:
        contract with the polytope hull of the X-Taylor and affine-form linear relaxation
        (:class:`~.relaxation.PolytopeHull`) after Newton.  Measured on
        ``examples/systems``: 2-40x fewer boxes.  Forward kinematics turns it off: a box's
        LPs cost ~10x the rest of its work there, which general-19 repays (at 10 N 128,672
        -> 12,196 boxes, 13.2 -> 9.3 CPU s; at 60 N u~S(2) 156,910 -> 15,413, 12.8 -> 10.4 s)
        but T-16 does not (60 N u=2: 271,875 -> 92,523 boxes, 18.5 -> 45.4 s; random-T-0
        6.1 -> 11.3 s), nor general-19's open case (random-general-0 at 60 N, 60 pivots:
        294k boxes in 300 s, against all 2.83M in ~230 s without).
    """

    def __init__(
        self,
        system: System | CompiledSystem,
        *,
        eps: float = 1e-8,
        batch_size: int = 1024,
        hc4_passes: int = 4,
        bisector=None,
        certifier: Certifier | None = None,
        bisect_mask=None,
        subsystems=(),
        newton_groups="variables",
        cid_slices: int = 4,
        cid_vars: int | str | None = "auto",
        max_undecided: int = MAX_LISTED,
        max_pending: int = MAX_LISTED,
        relax: bool = True,
        reduce_degree: bool = True,
    ):
        if not eps > 0:
            raise ValueError("eps must be positive")
        if not (int(max_undecided) >= 0 and int(max_pending) >= 1):
            raise ValueError("max_undecided must be >= 0 and max_pending >= 1")
        self.max_undecided = int(max_undecided)
        self.max_pending = int(max_pending)
        if isinstance(system, CompiledSystem):
            self.csys, self.system = system, system.system
        else:
            solved = lower_degree(system) if reduce_degree and not subsystems else system
            #: the system searched; :attr:`system` is the one given (they differ when
            #: ``reduce_degree`` replaced equations)
            self.csys = CompiledSystem(solved)
            self.system = system
        #: the box searched by :meth:`solve` (the system's; see :meth:`on_domain`)
        self.domain = self.system.domain
        self.n = self.csys.n
        self.eps = float(eps)
        self.batch_size = int(batch_size)
        self.hc4 = HC4(self.csys, max_passes=hc4_passes)
        if isinstance(newton_groups, str):
            if newton_groups != "variables":
                raise ValueError("newton_groups: 'variables', None or a list of masks")
            newton_groups = list(np.eye(self.n, dtype=bool))
        self.newton = IntervalNewton(self.csys, newton_groups)
        self.bisector = bisector or SmearCurvatureMix()
        self.certifier = certifier or Certifier(self.csys)
        #: square sub-systems ``(equations, variables)`` contracted by partial Newton
        self.partial = [PartialNewton(self.csys, e, v) for e, v in subsystems]
        #: CID on the variable chosen for bisection, before splitting (None: off); a box
        #: it shrinks as much as a bisection goes round again instead of being split
        self.cid = CID(self.hc4.contract, cid_slices) if cid_slices else None
        self.cid_gain = _LOG_HALF
        #: learn the count of variables to shave (``cid_vars="auto"``; the learnt state is
        #: the search's: :attr:`SearchState.acid`)
        self.auto_cid = cid_vars == "auto" and self.cid is not None
        if cid_vars not in (None, "auto") and not int(cid_vars) >= 1:
            raise ValueError("cid_vars must be >= 1, None (all variables) or 'auto'")
        #: variables CID contracts before a bisection (chosen first, then by smear score)
        self.cid_vars = self.n if cid_vars in (None, "auto") else min(int(cid_vars), self.n)
        #: a batch that plans at most this many (box, extra variable) CID calls shaves them
        #: side by side in one call (:meth:`_stacked_cid`), else one variable after the
        #: other.  Measured against always one after the other (CPU s, one worker, median
        #: of 5 runs interleaved): Brent-8 5.56 -> 3.90, Brent-10 13.5 -> 10.2, eco-7 1.15
        #: -> 0.98, transistor 15.3 -> 15.1, Caprasse 0.61 -> 0.59; Discrete-Integral-6
        #: 2.36 -> 2.46, katsura-6 2.49 -> 2.55; the others within 2 %.  Side by side on
        #: every batch (no limit) loses on the large ones (Katsura-14, Brent-8, 1 run).
        self.stacked_cid_pairs = 512
        #: polytope hull of the linear relaxation, after Newton (None: off)
        self.relax = PolytopeHull(self.csys) if relax else None
        #: variables the bisector may split (None: all); the others are auxiliary
        self.bisect_mask = None if bisect_mask is None else np.asarray(bisect_mask, dtype=bool)
        if self.bisect_mask is not None and self.bisect_mask.shape != (self.n,):
            raise ValueError(f"bisect_mask must have {self.n} entries")

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
        :mod:`.checkpoint`): equations, constraints, domain, parameter values, ``eps`` and
        the contractors' and bisector's settings."""
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
            f"eps: {self.eps!r}, hc4: {self.hc4.max_passes}, relax: {self.relax is not None}, "
            f"cid: {None if self.cid is None else self.cid.slices} x "
            f"{'auto' if self.auto_cid else self.cid_vars}, "
            f"mask: {mask}",
            f"newton: {[g.tolist() for g in self.newton.groups or []]}",
            f"partial: {[(p.S.tolist(), p.V.tolist()) for p in self.partial]}",
            f"bisector: {type(self.bisector).__name__} {_settings(self.bisector)}",
        ]
        if c.system is not sysm:
            parts += [f"solved as: {to_string(e)}" for e in c.system.equations]
        return "\n".join(parts)

    def start(self, known: bytes | None = None) -> SearchState:
        """An empty search state, with the solutions and the learnt CID count in ``known``
        (see :meth:`known`)."""
        if known is None:
            sols, acid = SolutionSet(self.n), AdaptiveCount(self.n) if self.auto_cid else None
        else:
            sols, acid = pickle.loads(known)
        return SearchState(BoxStack(self.n), sols, [], Stats(), mark=len(sols), acid=acid)

    def tally(self, state: SearchState) -> Tally:
        return Tally(solutions=state.solutions.count("ok"), undecided=len(state.undecided))

    def known(self, state: SearchState) -> bytes:
        """The solution set and the learnt CID count, pickled (for tasks: unpickling is
        ~100x faster than adding the solutions one by one, and the copy is the task's
        own; a task goes on with the count its search has learnt)."""
        return pickle.dumps((state.solutions, state.acid), protocol=pickle.HIGHEST_PROTOCOL)

    def found(self, state: SearchState):
        """Solutions recorded since :meth:`start`, undecided boxes, counters and the learnt
        CID count."""
        sols = state.solutions
        new = range(state.mark, len(sols))
        entries = [
            (sols.E_lo[i], sols.E_hi[i], sols.U_lo[i], sols.U_hi[i], sols.kind[i]) for i in new
        ]
        st = state.stats
        counters = (st.bisections, st.certified, st.duplicates)
        return entries, state.undecided, counters, copy.copy(state.acid)

    def merge(self, state: SearchState, found) -> None:
        """Add a task's findings; a solution two tasks proved is recorded once.  The learnt
        CID count is the task's (the latest a task brings home; a checkpoint's on restore)."""
        entries, undecided, (bisections, certified, duplicates), *rest = found
        acid = rest[0] if rest else None  # absent from checkpoints written before it was kept
        for e0, e1, u0, u1, kind in entries:
            if kind == "alias":
                state.solutions.add(e0, e1, u0, u1, "alias")
            elif not state.solutions.add(e0, e1, u0, u1, kind):
                state.stats.duplicates += 1
        state.undecided.extend(undecided)
        state.stats.bisections += bisections
        state.stats.certified += certified
        state.stats.duplicates += duplicates
        if acid is not None and state.acid is not None:
            state.acid = copy.copy(acid)

    def process(self, lo: np.ndarray, hi: np.ndarray, state: SearchState) -> None:
        """One batched contract / certify / bisect step on the boxes ``lo, hi``."""
        stats = state.stats
        keep, plo, phi = state.solutions.prune(lo, hi)
        lo0, hi0 = np.concatenate([lo[keep], plo]), np.concatenate([hi[keep], phi])

        # 1. HC4
        lo, hi, empty = self.hc4.contract(lo0, hi0)
        lo, hi, lo0, hi0 = lo[~empty], hi[~empty], lo0[~empty], hi0[~empty]
        if lo.shape[0] == 0:
            return
        for pn in self.partial:
            lo, hi, empty = pn.contract(lo, hi)
            lo, hi, lo0, hi0 = lo[~empty], hi[~empty], lo0[~empty], hi0[~empty]
            if lo.shape[0] == 0:
                return

        # 2. Newton + Krawczyk on the HC4-contracted boxes
        step = self.newton.contract(lo, hi)
        if np.any(step.proven):
            p = step.proven
            elo = np.fmax(step.klo[p], step.lo[p])
            ehi = np.fmin(step.khi[p], step.hi[p])
            self._record(state, elo, ehi, lo[p], hi[p], tight=False)
        rest = ~step.proven & ~step.empty
        regular = step.regular[rest]
        lo1, hi1 = step.lo[rest], step.hi[rest]
        lo0, hi0 = lo0[rest], hi0[rest]
        jlo, jhi = step.lin.jlo[rest], step.lin.jhi[rest]
        if lo1.shape[0] == 0:
            return
        if self.relax is not None:
            lo1, hi1, empty = self.relax.contract(lo1, hi1)
            keep = ~empty
            lo1, hi1, lo0, hi0 = lo1[keep], hi1[keep], lo0[keep], hi0[keep]
            jlo, jhi, regular = jlo[keep], jhi[keep], regular[keep]
            if lo1.shape[0] == 0:
                return

        # 3. fixpoint: boxes that shrank at least as much as a bisection go round again.  Only
        # the variables the bisector may split count: auxiliary ones (FK wire lengths) narrow
        # whenever the others move, and another round for them alone gains little (measured:
        # general-19 at 60 N, 406,749 -> 357,470 boxes; random-general-0: see docs/fk-cost.md)
        shrunk = self._gain(lo0, hi0, lo1, hi1) <= _LOG_HALF
        if np.any(shrunk):
            state.stack.push(lo1[shrunk], hi1[shrunk])
        stalled = ~shrunk

        # 4. inflated Krawczyk where Newton is informative but stalled
        try_inflate = np.flatnonzero(stalled & regular)
        done = np.zeros(lo1.shape[0], dtype=bool)
        if try_inflate.size:
            idx, Elo, Ehi, Ulo, Uhi = self.certifier.inflate(lo1[try_inflate], hi1[try_inflate])
            if idx.size:
                rows = try_inflate[idx]
                self._record(state, Elo, Ehi, Ulo, Uhi, tight=False)
                for k, r in enumerate(rows):
                    # progress only if U overlaps X with positive volume: otherwise the
                    # remainder would be X itself; leave X to bisection instead
                    ilo = np.maximum(lo1[r], Ulo[k])
                    ihi = np.minimum(hi1[r], Uhi[k])
                    if not np.all(ilo < ihi):
                        continue
                    for plo, phi in box_difference(lo1[r], hi1[r], Ulo[k], Uhi[k]):
                        state.stack.push(plo[None], phi[None])
                    done[r] = True

        # 5. undecided or bisect
        todo = stalled & ~done
        lo2, hi2 = lo1[todo], hi1[todo]
        if lo2.shape[0] == 0:
            return
        wid = splittable_width(lo2, hi2)  # 0 where no float is left inside
        if self.bisect_mask is not None:
            wid = wid[:, self.bisect_mask]
        small = all_last(wid <= self.eps)
        for i in np.flatnonzero(small):
            state.undecided.append(Undecided(lo2[i].copy(), hi2[i].copy(), "eps"))
        big = ~small
        if np.any(big):
            lo3, hi3 = lo2[big], hi2[big]
            jlo3, jhi3 = jlo[todo][big], jhi[todo][big]
            var = self.bisector.choose(
                lo3, hi3, jlo3, jhi3, self.eps, self.bisect_mask, scale=self.scale
            )
            if self.cid is not None:
                clo, chi, cemp = self._cid(lo3, hi3, jlo3, jhi3, var, state.acid)
                gain = self._gain(lo3, hi3, clo, chi)
                again = ~cemp & (gain <= self.cid_gain)
                if np.any(again):
                    state.stack.push(clo[again], chi[again])
                keep = ~cemp & ~again
                lo3, hi3, var = clo[keep], chi[keep], var[keep]
            (alo, ahi), (blo, bhi) = split(lo3, hi3, var, self.bisector.ratio)
            stats.bisections += lo3.shape[0]
            state.stack.push(np.concatenate([alo, blo]), np.concatenate([ahi, bhi]))

    @property
    def scale(self) -> np.ndarray:
        """The domain's widths: a box on which the Jacobian tells the bisector nothing is
        split along its variable widest relative to them (:func:`~.bisectors.domain_scale`)."""
        return domain_scale(self.domain)

    def _gain(self, lo0, hi0, lo1, hi1) -> np.ndarray:
        """Log-volume change from ``lo0, hi0`` to ``lo1, hi1`` over the variables the
        bisector may still split: those of the mask, wider than ``eps`` in ``lo0, hi0``.

        A variable narrower than ``eps`` is never split, so its shrinking is no progress
        towards a decision: counted, a component converging to an exact zero (``[-1e-200,
        1e-200]``, then ``[-1e-250, 1e-250]`` ...) looked like a halving of the volume at
        every round, and one box went round again ~180 times (katsura-5, batches of 1024).
        """
        count = (hi0 - lo0) > self.eps
        if self.bisect_mask is not None:
            count &= self.bisect_mask
        lo0, hi0 = np.where(count, lo0, 0.0), np.where(count, hi0, 0.0)
        return log_volume_ratio(lo0, hi0, lo1, hi1)

    def _cid(self, lo, hi, jlo, jhi, var, acid: AdaptiveCount | None = None):
        """CID on ``var`` then on up to ``cid_vars - 1`` other variables of each box (or the
        count ``acid`` has learnt, more for its learning boxes; this call updates it), by
        decreasing smear score over the box (``J`` is its enclosure from Newton).

        Each round is one batched CID call on the boxes that still have a variable to
        contract; every call is sound (:class:`~.shaving.CID`), so is the sequence.  A
        small batch shaves its extra variables side by side instead
        (:meth:`_stacked_cid`, :attr:`stacked_cid_pairs`).  A box proven empty stays
        empty.  Returns ``(lo, hi, empty)``.
        """
        assert self.cid is not None  # called only with CID on
        clo, chi, cemp = self.cid.contract(lo, hi, var)
        B = lo.shape[0]
        if acid is None:
            limit, learns = np.full(B, self.cid_vars), np.zeros(B, dtype=bool)
        else:
            limit, learns = acid.plan(B)
        needed = np.ones(B, dtype=np.int64)  # recorded for the learning boxes only
        extra = int(np.max(limit, initial=1)) - 1
        if extra > 0:
            rows = np.arange(B)
            score = smear_scores(lo, hi, jlo, jhi, self.eps, self.bisect_mask)
            score[rows, var] = -1.0
            order = np.argsort(-score, axis=1, kind="stable")[:, :extra]
            useful = np.take_along_axis(score, order, axis=1) > 0.0
            useful &= np.arange(order.shape[1]) < (limit - 1)[:, None]
            if np.count_nonzero(useful) <= self.stacked_cid_pairs:
                self._stacked_cid(clo, chi, cemp, order, useful, learns, needed, acid)
            else:
                for k in range(order.shape[1]):
                    act = np.flatnonzero(useful[:, k] & ~cemp)
                    if act.size == 0:
                        break  # scores are sorted: no box has a k-th (or later) variable
                    nlo, nhi, emp = self.cid.contract(clo[act], chi[act], order[act, k])
                    if acid is not None:
                        shrank = _learnt(acid, learns[act], clo[act], chi[act], nlo, nhi, emp)
                        needed[act[shrank]] = k + 2  # the chosen variable, then k + 1 others
                    clo[act], chi[act] = nlo, nhi
                    cemp[act] |= emp
        if acid is not None:
            acid.done(needed[learns], B)
        return clo, chi, cemp

    def _stacked_cid(self, clo, chi, cemp, order, useful, learns, needed, acid) -> None:
        """The extra variables of :meth:`_cid` side by side: one CID call on a copy of each
        box per variable, the results intersected (in place).

        Each copy's CID keeps every solution of the box, so their intersection does too, and
        an empty one (or an empty intersection) proves the box empty.  The sequence shaves
        each variable of an already shaved box, so it contracts more per box; side by side
        costs one call instead of one per variable, which wins when the batch is small (a
        numpy call costs nearly the same for 50 rows as for 500).  ACID learns from each
        variable's gain over the same starting box.
        """
        assert self.cid is not None
        box, k = np.nonzero(useful & ~cemp[:, None])
        if box.size == 0:
            return
        nlo, nhi, emp = self.cid.contract(clo[box], chi[box], order[box, k])
        if acid is not None:
            shrank = _learnt(acid, learns[box], clo[box], chi[box], nlo, nhi, emp)
            np.maximum.at(needed, box[shrank], k[shrank] + 2)
        np.maximum.at(clo, box, nlo)
        np.minimum.at(chi, box, nhi)
        np.logical_or.at(cemp, box, emp)
        cemp |= any_last(clo > chi)

    def _record(self, state: SearchState, elo, ehi, ulo, uhi, tight: bool = True) -> None:
        """Record proven solutions; existence boxes are tightened only for new ones."""
        state.stats.certified += elo.shape[0]
        new = np.array(
            [state.solutions.find(elo[k], ehi[k], ulo[k], uhi[k]) < 0 for k in range(len(elo))],
            dtype=bool,
        )
        for j in np.flatnonzero(~new):  # known solution: keep its unicity box for pruning
            state.solutions.add(elo[j], ehi[j], ulo[j], uhi[j], "alias")
            state.stats.duplicates += 1
        if not np.any(new):
            return
        elo, ehi, ulo, uhi = elo[new], ehi[new], ulo[new], uhi[new]
        if not tight:
            elo, ehi = self.certifier.tighten(elo, ehi)
        ulo, uhi = self.certifier.expand(elo, ehi, ulo, uhi)
        kinds = self.certifier.classify(elo, ehi)
        for k, kind in enumerate(kinds):
            if not state.solutions.add(elo[k], ehi[k], ulo[k], uhi[k], kind):
                state.stats.duplicates += 1

    # -- results -----------------------------------------------------------------------------
    def result(self, run: SearchRun) -> SolveResult:
        """The :class:`SolveResult` of a finished search (undecided and pending boxes summarised,
        :mod:`.summary`)."""
        state = run.state
        sols = [Solution(e0, e1, u0, u1) for e0, e1, u0, u1 in state.solutions.items("ok")]
        sols.sort(key=lambda s: tuple(s.midpoint))
        und = [(u.lo, u.hi, u.reason) for u in state.undecided]
        dlo, dhi = self.domain[:, 0], self.domain[:, 1]
        for e0, e1, _, _ in state.solutions.items("boundary"):
            und.append((np.maximum(e0, dlo), np.minimum(e1, dhi), "boundary"))
        for e0, e1, _, _ in state.solutions.items("constraint"):
            und.append((e0, e1, "constraint"))
        plo, phi = state.stack.snapshot()
        summ = summarize(
            und, plo, phi, max_undecided=self.max_undecided, max_pending=self.max_pending
        )
        status = run.status
        if status == SearchStatus.COMPLETE and summ.undecided_dropped:
            status = SearchStatus.TRUNCATED  # nothing pending, but not every box is listed
        return SolveResult(
            variables=list(self.system.variables),
            status=status,
            solutions=sols,
            undecided=[Undecided(a, b, r, k) for a, b, r, k in summ.undecided],
            pending_lo=summ.pending_lo,
            pending_hi=summ.pending_hi,
            stats=Stats.of(run.stats, state.stats, run.status),
            eps=self.eps,
            undecided_total=summ.undecided_total,
            undecided_dropped=summ.undecided_dropped,
            pending_boxes=summ.pending_boxes,
            pending_total=summ.pending_total,
        )


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
    acid: AdaptiveCount | None = None  # the learnt CID count (``cid_vars="auto"``)


def _learnt(acid: AdaptiveCount, learns, lo, hi, nlo, nhi, empty) -> np.ndarray:
    """The learning boxes a CID call contracted enough to count for ACID: proven empty, or
    their log-volume dropped below ``acid.threshold``."""
    return learns & (empty | (log_volume_ratio(lo, hi, nlo, nhi) < acid.threshold))


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
    """Find every solution of ``system`` in its domain (see :class:`Solver` and
    :meth:`Solver.solve`).  ``system``: a :class:`System`, a Minibex file's path, or
    Minibex text (:func:`~certsolve.expr.minibex.load_system`).  The options are checked
    as the ``solve`` job and ``certsolve solve`` check them (:class:`~.options.
    SolveOptions`): a value they refuse raises :class:`~certsolve.inputs.InputError`
    naming it."""
    if not isinstance(system, System):
        system = load_system(system)
    checked(
        SolveOptions,
        {
            "eps": eps,
            "timeout": timeout,
            "max_boxes": max_boxes,
            "max_solutions": max_solutions,
            "verify": verify,
        },
    )
    solver = Solver(system, eps=eps, **options)
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
