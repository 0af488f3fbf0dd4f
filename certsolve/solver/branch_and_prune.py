"""The branch-and-prune solver: contract, certify, bisect -- a batch of boxes at a time.

One *round* takes up to ``batch_size`` boxes from the buffer and, for all of them at once:

1. drops boxes inside the unicity box of a known solution;
2. contracts with :class:`~.contractors.HC4` (boxes proven empty are dropped), then with
   partial Newton on the given sub-systems, if any;
3. linearises and runs :class:`~.contractors.IntervalNewton`: the Krawczyk test on the box
   (``K(X) ⊂ int X`` -> exactly one solution, certified) and a Hansen–Sengupta sweep (with
   Hansen's mixed Jacobian by default); then contracts with the polytope hull of the
   X-Taylor linear relaxation (:class:`~.relaxation.PolytopeHull`);
4. for boxes where Newton is informative but stalled, tries :meth:`.Certifier.inflate`;
   the part of the box outside a proven unicity box goes back to the buffer;
5. sends boxes that shrank at least as much as a bisection would (log-volume) back for
   another round, reports boxes narrower than ``eps`` as *undecided*, and bisects the rest
   (:class:`~.bisectors.SmearSumRelative`), after a CID contraction
   (:class:`~.shaving.CID`) on the chosen variable.

Limits (time, boxes, a progress callback returning ``False``) stop the search between
rounds; the boxes still in the buffer are then reported as *pending* and the status is
``incomplete``.  Nothing is dropped without a proof that it holds no solution.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..expr.compiled import CompiledSystem
from ..expr.system import System
from ..interval.core import splittable_width
from .bisectors import SmearSumRelative, split
from .buffer import BoxStack
from .certify import Certifier, SolutionSet, box_difference
from .contractors import HC4, IntervalNewton, PartialNewton, log_volume_ratio
from .relaxation import PolytopeHull
from .result import Solution, SolveResult, Stats, Undecided
from .shaving import CID
from .summary import MAX_LISTED, summarize

__all__ = ["Solver", "Progress", "solve"]

_LOG_HALF = float(np.log(0.5))


@dataclass
class Progress:
    """What a progress callback receives after each round."""

    boxes: int
    pending: int
    solutions: int
    undecided: int
    elapsed: float


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
        boxes processed per round (per numpy call).
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
    subsystems:
        square sub-systems ``(equations, variables)`` also contracted by partial Newton.
    max_undecided, max_pending:
        caps on the undecided and pending hulls listed in the result (:mod:`.summary`).
    relax:
        contract with the polytope hull of the X-Taylor linear relaxation
        (:class:`~.relaxation.PolytopeHull`) after Newton.  Measured on
        ``examples/systems``: 2-40x fewer boxes; forward kinematics turns it off (its
        wide orientation boxes give weak relaxations at a high cost).
    """

    def __init__(
        self,
        system: System | CompiledSystem,
        *,
        eps: float = 1e-8,
        batch_size: int = 256,
        hc4_passes: int = 4,
        bisector=None,
        certifier: Certifier | None = None,
        bisect_mask=None,
        subsystems=(),
        newton_groups="variables",
        cid_slices: int = 4,
        max_undecided: int = MAX_LISTED,
        max_pending: int = MAX_LISTED,
        relax: bool = True,
    ):
        if not eps > 0:
            raise ValueError("eps must be positive")
        if not (int(max_undecided) >= 0 and int(max_pending) >= 1):
            raise ValueError("max_undecided must be >= 0 and max_pending >= 1")
        self.max_undecided = int(max_undecided)
        self.max_pending = int(max_pending)
        self.csys = system if isinstance(system, CompiledSystem) else CompiledSystem(system)
        self.system = self.csys.system
        self.n = self.csys.n
        self.eps = float(eps)
        self.batch_size = int(batch_size)
        self.hc4 = HC4(self.csys, max_passes=hc4_passes)
        if isinstance(newton_groups, str):
            if newton_groups != "variables":
                raise ValueError("newton_groups: 'variables', None or a list of masks")
            newton_groups = list(np.eye(self.n, dtype=bool))
        self.newton = IntervalNewton(self.csys, newton_groups)
        self.bisector = bisector or SmearSumRelative()
        self.certifier = certifier or Certifier(self.csys)
        #: square sub-systems ``(equations, variables)`` contracted by partial Newton
        self.partial = [PartialNewton(self.csys, e, v) for e, v in subsystems]
        #: CID on the variable chosen for bisection, before splitting (None: off); a box
        #: it shrinks as much as a bisection goes round again instead of being split
        self.cid = CID(self.hc4.contract, cid_slices) if cid_slices else None
        self.cid_gain = _LOG_HALF
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
        workers: int = 1,
        verify: bool = False,
        max_solutions: int | None = None,
    ) -> SolveResult:
        """Run the search over the whole domain (see the module docstring).

        ``max_solutions`` stops the search once that many solutions are certified (the
        status is then ``incomplete`` unless nothing was left to explore).
        """
        if workers > 1:
            from .parallel import solve_parallel

            result = solve_parallel(
                self, workers=workers, timeout=timeout, max_boxes=max_boxes, progress=progress
            )
        else:
            state = SearchState.start(self.system.domain, self.n)
            self.run(
                state,
                timeout=timeout,
                max_boxes=max_boxes,
                progress=progress,
                max_solutions=max_solutions,
            )
            result = self.result(state)
        if verify:
            from .verify import verify_solutions

            verify_solutions(self.csys, result.solutions)
        return result

    # -- the loop ----------------------------------------------------------------------------
    def run(
        self,
        state: SearchState,
        *,
        timeout: float | None = None,
        max_boxes: int | None = None,
        max_rounds: int | None = None,
        progress: Callable[[Progress], bool | None] | None = None,
        max_solutions: int | None = None,
    ) -> None:
        """Process rounds until the buffer is empty or a limit is hit (updates ``state``)."""
        t0 = time.perf_counter()
        stats = state.stats
        rounds = 0
        with np.errstate(all="ignore"):
            while len(state.stack):
                if timeout is not None and time.perf_counter() - t0 >= timeout:
                    stats.stopped_by = "timeout"
                    break
                if max_boxes is not None and stats.boxes >= max_boxes:
                    stats.stopped_by = "max_boxes"
                    break
                if max_rounds is not None and rounds >= max_rounds:
                    break
                if max_solutions is not None and state.solutions.count("ok") >= max_solutions:
                    stats.stopped_by = "max_solutions"
                    break
                self.round(state)
                rounds += 1
                stats.max_pending = max(stats.max_pending, len(state.stack))
                if progress is not None:
                    p = Progress(
                        stats.boxes,
                        len(state.stack),
                        state.solutions.count("ok"),
                        len(state.undecided),
                        stats.time + time.perf_counter() - t0,
                    )
                    if progress(p) is False:
                        stats.stopped_by = "cancelled"
                        break
        stats.time += time.perf_counter() - t0

    def round(self, state: SearchState) -> None:
        """One batched contract / certify / bisect step."""
        stats = state.stats
        lo, hi = state.stack.pop(self.batch_size)
        stats.boxes += lo.shape[0]
        stats.rounds += 1
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

        # 3. fixpoint: boxes that shrank at least as much as a bisection go round again
        shrunk = log_volume_ratio(lo0, hi0, lo1, hi1) <= _LOG_HALF
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
        small = np.all(wid <= self.eps, axis=1)
        for k in np.flatnonzero(small):
            state.undecided.append(Undecided(lo2[k].copy(), hi2[k].copy(), "eps"))
        big = ~small
        if np.any(big):
            lo3, hi3 = lo2[big], hi2[big]
            var = self.bisector.choose(
                lo3, hi3, jlo[todo][big], jhi[todo][big], self.eps, self.bisect_mask
            )
            if self.cid is not None:
                clo, chi, cemp = self.cid.contract(lo3, hi3, var)
                gain = log_volume_ratio(lo3, hi3, clo, chi)
                again = ~cemp & (gain <= self.cid_gain)
                if np.any(again):
                    state.stack.push(clo[again], chi[again])
                keep = ~cemp & ~again
                lo3, hi3, var = clo[keep], chi[keep], var[keep]
            (alo, ahi), (blo, bhi) = split(lo3, hi3, var, self.bisector.ratio)
            stats.bisections += lo3.shape[0]
            state.stack.push(np.concatenate([alo, blo]), np.concatenate([ahi, bhi]))

    def _record(self, state: SearchState, elo, ehi, ulo, uhi, tight: bool = True) -> None:
        """Record proven solutions; existence boxes are tightened only for new ones."""
        state.stats.certified += elo.shape[0]
        new = np.array(
            [state.solutions.find(elo[k], ehi[k], ulo[k], uhi[k]) < 0 for k in range(len(elo))],
            dtype=bool,
        )
        for k in np.flatnonzero(~new):  # known solution: keep its unicity box for pruning
            state.solutions.add(elo[k], ehi[k], ulo[k], uhi[k], "alias")
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
    def result(self, state: SearchState) -> SolveResult:
        """The result of a search (undecided and pending boxes summarised, :mod:`.summary`)."""
        sols = [Solution(e0, e1, u0, u1) for e0, e1, u0, u1 in state.solutions.items("ok")]
        sols.sort(key=lambda s: tuple(s.midpoint))
        und = [(u.lo, u.hi, u.reason) for u in state.undecided]
        dlo, dhi = self.system.domain[:, 0], self.system.domain[:, 1]
        for e0, e1, _, _ in state.solutions.items("boundary"):
            und.append((np.maximum(e0, dlo), np.minimum(e1, dhi), "boundary"))
        for e0, e1, _, _ in state.solutions.items("constraint"):
            und.append((e0, e1, "constraint"))
        plo, phi = state.stack.snapshot()
        summ = summarize(
            und, plo, phi, max_undecided=self.max_undecided, max_pending=self.max_pending
        )
        complete = summ.pending_total == 0 and summ.undecided_dropped == 0
        return SolveResult(
            variables=list(self.system.variables),
            status="complete" if complete else "incomplete",
            solutions=sols,
            undecided=[Undecided(a, b, r, k) for a, b, r, k in summ.undecided],
            pending_lo=summ.pending_lo,
            pending_hi=summ.pending_hi,
            stats=state.stats,
            eps=self.eps,
            undecided_total=summ.undecided_total,
            undecided_dropped=summ.undecided_dropped,
            pending_boxes=summ.pending_boxes,
            pending_total=summ.pending_total,
        )


@dataclass
class SearchState:
    """Everything a search carries between rounds (and between worker tasks)."""

    stack: BoxStack
    solutions: SolutionSet
    undecided: list
    stats: Stats

    @classmethod
    def start(cls, domain: np.ndarray, n: int) -> SearchState:
        st = BoxStack(n)
        st.push(domain[:, 0][None].copy(), domain[:, 1][None].copy())
        return cls(st, SolutionSet(n), [], Stats())


def solve(
    system: System,
    *,
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    workers: int = 1,
    verify: bool = False,
    progress: Callable[[Progress], bool | None] | None = None,
    max_solutions: int | None = None,
    **options,
) -> SolveResult:
    """Find every solution of ``system`` in its domain (see :class:`Solver`)."""
    solver = Solver(system, eps=eps, **options)
    return solver.solve(
        timeout=timeout,
        max_boxes=max_boxes,
        workers=workers,
        verify=verify,
        progress=progress,
        max_solutions=max_solutions,
    )
