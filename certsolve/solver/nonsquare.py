"""Systems with more or fewer equations than variables (``m != n``), as ibexsolve takes them.

**Over-determined** (``m > n``): :func:`overdetermined` chooses a square subsystem of ``n``
equations by a rank-revealing choice at the domain's midpoint -- greedy column pivoting
(:func:`pivots`, the pivots of a QR factorisation with column pivoting) on the transposed
float Jacobian ``J(x_mid)^T`` -- and makes the other ``m - n`` equations constraints
``0 <= g(x) <= 0`` of the square system.  The solver then searches the square system as
usual: HC4 contracts with every equation and refutes a box where the enclosure of any
equation excludes 0; Krawczyk proves a unique solution of the subsystem; the certifier
(:class:`~.certify.Certifier` with ``surplus``) reports it as a solution with the
certificate ``square-subsystem-certified`` when the other equations' enclosures over its
box contain 0 -- they are satisfied within their enclosure, *not proven* (an equation is
proven only when its enclosure is exactly ``[0, 0]``), -- and drops it when one excludes 0.
The choice is made once per search, at the midpoint; a box where the subsystem is singular
is split until ``eps`` and reported undecided, as any singular box.

**Under-determined** (``m < n``): the solution set is a manifold of dimension ``n - m``
(where the Jacobian has rank ``m``); :class:`ManifoldPaver` paves it, as ibexsolve's
manifold mode does (IBEX ``Solver`` with ``CovSolverData``: its "solution" boxes are
proven by a parametric Newton test).  For a box ``X``, the ``m`` variables ``v`` are the
pivots of the float Jacobian at the midpoint (:func:`pivots`: the best-conditioned
``m x m`` block), the others are *parameters* ``p``.  With ``c`` the midpoint of ``X_v``,
``Y`` an approximate inverse of the midpoint of ``J_v``, the parametric Krawczyk operator

    ``K = c - Y f(c, X_p) + (I - Y J_v(X)) (X_v - c)``

contains, for every ``p ∈ X_p``, every zero of ``f(., p)`` in ``X_v`` (the mean-value
argument of :mod:`certsolve.interval.linalg` with ``f(c, X_p)`` enclosing ``f(c, p)``);
``K ⊂ int X_v`` proves that for *every* ``p ∈ X_p`` exactly one ``v ∈ X_v`` solves the
system: the box is reported as a solution with certificate ``parametric`` and its
parameters named.  ``X_v ∩ K`` contracts a box (empty: no solution in it).  Other boxes are
contracted by HC4 and split along their widest variable (relative to the domain) until
``eps``: narrower ones are undecided; ``max_boxes`` bounds the paving (the rest is pending).
The result is a :class:`~.result.SolveResult`: nothing of the solution set is dropped
without a proof -- it lies in the solution, undecided and pending boxes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..expr.compiled import CompiledSystem
from ..expr.system import Constraint, System
from ..interval.linalg import krawczyk_mr, mr_from_bounds
from .batch import Batch
from .batching import BatchSizer
from .bisectors import domain_scale, split
from .buffer import BoxStack
from .contractors import HC4
from .newton import batched_solve
from .result import Certificate, Solution, SolveResult, Stats, Undecided
from .search import Limits, SearchRun, Tally, run_search
from .summary import MAX_LISTED

__all__ = ["ManifoldPaver", "PavingState", "overdetermined", "pivots"]


def pivots(A: np.ndarray, k: int) -> np.ndarray:
    """``(B, k)`` columns of each ``A`` ``(B, r, c)`` chosen greedily: the column with the
    largest norm orthogonal to those already chosen (modified Gram-Schmidt with column
    pivoting: the pivots of QR with column pivoting), batched.  Non-finite entries count
    as 0."""
    R = np.where(np.isfinite(A), A, 0.0).astype(np.float64, copy=True)
    B, _, c = R.shape
    chosen = np.zeros((B, k), dtype=np.int64)
    free = np.ones((B, c), dtype=bool)
    rows = np.arange(B)
    for j in range(k):
        norms = np.where(free, np.einsum("brc,brc->bc", R, R), -1.0)
        best = np.argmax(norms, axis=1)
        chosen[:, j] = best
        free[rows, best] = False
        q = R[rows, :, best]  # (B, r)
        qn = np.sqrt(np.einsum("br,br->b", q, q))
        q = np.where(qn[:, None] > 0.0, q / np.where(qn > 0.0, qn, 1.0)[:, None], 0.0)
        R -= q[:, :, None] * np.einsum("br,brc->bc", q, R)[:, None, :]
    return chosen


def _midpoint(domain: np.ndarray) -> np.ndarray:
    """A finite point of the domain: its midpoint, 0 clipped into an unbounded side."""
    lo, hi = domain[:, 0], domain[:, 1]
    with np.errstate(all="ignore"):
        mid = 0.5 * lo + 0.5 * hi
    return np.where(np.isfinite(mid), mid, np.clip(0.0, lo, hi))


def _cycled(system: System, equations: list, size: int) -> System:
    """A square system of ``size`` equations: ``equations`` repeated (every zero of the
    given equations is a zero of it); only its first rows are read."""
    eqs = [equations[i % len(equations)] for i in range(size)]
    return System(list(system.variables), system.domain, eqs, [], parameters=system.parameters)


def _jacobian_at(system: System, x: np.ndarray) -> np.ndarray:
    """Float Jacobian ``(m, n)`` of the ``m`` equations at the point ``x`` (square systems
    of ``n`` of them at a time: a compiled system is square)."""
    n, eqs = system.n, list(system.equations)
    rows = []
    for start in range(0, len(eqs), n):
        part = CompiledSystem(_cycled(system, eqs[start : start + n], n))
        _, J = part.eval_fj_float(x[None])
        rows.append(J[0, : min(n, len(eqs) - start)])
    return np.concatenate(rows)


def overdetermined(system: System) -> tuple[System, int]:
    """The square system an over-determined ``system`` is searched as, and its surplus
    (module docstring): ``n`` equations chosen at the domain's midpoint, the other
    ``m - n`` as equality constraints, last."""
    n, m = system.n, len(system.equations)
    if m <= n:
        raise ValueError(f"not over-determined: {m} equations for {n} variables")
    J = _jacobian_at(system, _midpoint(system.domain))
    chosen = sorted(pivots(J.T[None], n)[0].tolist())
    rest = [i for i in range(m) if i not in set(chosen)]
    square = System(
        list(system.variables),
        system.domain,
        [system.equations[i] for i in chosen],
        [*system.constraints, *(Constraint(system.equations[i], 0.0, 0.0) for i in rest)],
        name=system.name,
        parameters=system.parameters,
    )
    return square, len(rest)


@dataclass(kw_only=True)
class PavingState:
    """The paver's state in a search: the buffer and what it recorded."""

    stack: BoxStack
    inside: list[Solution] = field(default_factory=list)  # proven parametric boxes
    undecided: list[Undecided] = field(default_factory=list)
    stats: Stats = field(default_factory=Stats)
    mark: int = 0  # inside[:mark] came with the state


class ManifoldPaver:
    """The step that paves the solution set of an under-determined system (module
    docstring); :meth:`solve` runs it with the search driver.

    ``eps``: boxes narrower than it in every variable are undecided; ``batch_size``: boxes
    per round; ``max_undecided`` / ``max_pending``: hulls listed in the result.
    """

    def __init__(
        self,
        system: System,
        *,
        eps: float = 1e-8,
        batch_size: int = 1024,
        hc4_passes: int = 4,
        max_undecided: int = MAX_LISTED,
        max_pending: int = MAX_LISTED,
    ):
        m, n = len(system.equations), system.n
        if m == 0:
            raise ValueError(f"no equations for {n} variables (inequalities alone are not solved)")
        if not m < n:
            raise ValueError(f"not under-determined: {m} equations for {n} variables")
        if not eps > 0:
            raise ValueError("eps must be positive")
        self.system = system
        self.m = m
        self.eps = float(eps)
        self.batch_size = int(batch_size)
        self.max_undecided = max_undecided
        self.max_pending = max_pending
        #: the equations cycled to a square system (rows ``:m`` are the system's)
        self.csys = CompiledSystem(_cycled(system, list(system.equations), n))
        self.hc4 = HC4(self.csys, max_passes=hc4_passes)
        self.scale = domain_scale(system.domain)

    # -- the step of the search driver ------------------------------------------------------
    def start(self, known: Any = None) -> PavingState:
        return PavingState(stack=BoxStack(self.system.n))

    def tally(self, state: PavingState) -> Tally:
        return Tally(solutions=len(state.inside), undecided=len(state.undecided))

    def known(self, state: PavingState) -> None:
        return None  # boxes are independent: a task needs nothing of the others

    def found(self, state: PavingState):
        return state.inside[state.mark :], state.undecided

    def merge(self, state: PavingState, found) -> None:
        inside, undecided = found
        state.inside.extend(inside)
        state.undecided.extend(undecided)

    def listed(self, state: PavingState, start: int) -> tuple[list[Solution], int]:
        return state.inside[start:], len(state.inside)

    def process(
        self, lo: np.ndarray, hi: np.ndarray, state: PavingState, *, deadline: float | None = None
    ) -> None:
        """One round: HC4, the parametric Krawczyk test and contraction, then split."""
        # ``deadline`` (:meth:`.Step.process`) is not used: a round is bounded by its size,
        # which :meth:`solve`'s sizer fits to the time left
        batch = Batch(lo, hi, csys=self.csys, eps=self.eps)
        self.hc4.apply(batch)
        batch.drop_empty()
        if batch.size == 0:
            return
        lo, hi = batch.lo, batch.hi
        live, proven, lo, hi, params = self._krawczyk(lo, hi)
        for r in np.flatnonzero(proven):
            names = [self.system.variables[j] for j in np.flatnonzero(params[r])]
            state.inside.append(
                Solution(lo[r], hi[r], lo[r], hi[r], Certificate.PARAMETRIC, parameters=names)
            )
        rest = live & ~proven
        lo, hi = lo[rest], hi[rest]
        if lo.shape[0] == 0:
            return
        wid = (hi - lo) / self.scale
        var = np.argmax(np.where(hi - lo > self.eps, wid, -1.0), axis=1)
        small = np.all(hi - lo <= self.eps, axis=1)
        for r in np.flatnonzero(small):
            state.undecided.append(Undecided(lo[r].copy(), hi[r].copy(), "eps"))
        big = ~small
        if np.any(big):
            (alo, ahi), (blo, bhi) = split(lo[big], hi[big], var[big], 0.5)
            state.stats.bisections += int(np.count_nonzero(big))
            state.stack.push(np.concatenate([alo, blo]), np.concatenate([ahi, bhi]))

    def _krawczyk(self, lo, hi):
        """The parametric Krawczyk test on every box: ``(live, proven, lo, hi, params)``
        -- boxes not refuted, boxes proven (their ``lo, hi`` replaced by the proven box),
        the others contracted by ``X_v ∩ K``, and the parameter mask ``(B, n)`` of each.

        The test runs on ``X_p × V`` with ``V = v* ± s r`` (``s`` = 1, 2, 4): ``v*`` the
        float Newton point for the midpoint's parameters, ``r`` the radius that makes ``V``
        cover ``X_v``.  A proof therefore covers the whole box -- every zero in ``X``
        lies in the proven box -- even where the solution set is steep in ``X`` (a box
        narrow in ``v`` and wide in ``p``); ``V`` must lie in the domain."""
        B, n, m = lo.shape[0], self.system.n, self.m
        rows = np.arange(B)[:, None]
        with np.errstate(all="ignore"):
            mid = 0.5 * lo + 0.5 * hi
        _, Jm = self.csys.eval_fj_float(mid)
        var = pivots(Jm[:, :m, :], m)  # (B, m): the variables solved for
        params = np.ones((B, n), dtype=bool)
        params[rows, var] = False
        vlo, vhi = lo[rows, var], hi[rows, var]
        dlo, dhi = self.system.domain[var, 0], self.system.domain[var, 1]
        star = self._newton(mid, var)
        proven = np.zeros(B, dtype=bool)
        plo, phi = lo.copy(), hi.copy()
        r = np.maximum(vhi - star, star - vlo)
        with np.errstate(all="ignore"):
            for scale in (1.0, 2.0, 4.0):
                Vlo, Vhi = star - scale * r, star + scale * r
                ok = self._test(lo, hi, var, params, star, Vlo, Vhi)[2]
                inside = (Vlo >= dlo) & (Vhi <= dhi) & (Vlo <= vlo) & (Vhi >= vhi)
                ok &= ~proven & np.all(inside, axis=1)
                plo[rows, var] = np.where(ok[:, None], Vlo, plo[rows, var])
                phi[rows, var] = np.where(ok[:, None], Vhi, phi[rows, var])
                proven |= ok
        # the others: X_v ∩ K(X), with the midpoint as centre
        klo, khi, _ = self._test(lo, hi, var, params, mid[rows, var], vlo, vhi)
        usable = np.all(np.isfinite(klo) & np.isfinite(khi), axis=1)
        nlo = np.where(usable[:, None], np.fmax(vlo, klo), vlo)
        nhi = np.where(usable[:, None], np.fmin(vhi, khi), vhi)
        live = proven | ~np.any(nlo > nhi, axis=1)
        keep = (~proven & live)[:, None]
        plo[rows, var] = np.where(keep, nlo, plo[rows, var])
        phi[rows, var] = np.where(keep, nhi, phi[rows, var])
        return live, proven, plo, phi, params

    def _test(self, lo, hi, var, params, c, Vlo, Vhi):
        """Parametric Krawczyk on ``X_p × V`` with centre ``c ∈ V``: ``(klo, khi, proven)``."""
        rows = np.arange(lo.shape[0])[:, None]
        m = self.m
        blo, bhi = lo.copy(), hi.copy()
        blo[rows, var], bhi[rows, var] = Vlo, Vhi
        clo, chi = blo.copy(), bhi.copy()
        clo[rows, var], chi[rows, var] = c, c
        flo, fhi = self.csys.eval_f(clo, chi)  # f(c, X_p)
        _, _, jlo, jhi = self.csys.eval_fj(blo, bhi)
        fc, fr = mr_from_bounds(flo[:, :m], fhi[:, :m])
        pick = var[:, None, :]
        Jc, Jr = mr_from_bounds(
            np.take_along_axis(jlo[:, :m, :], pick, axis=2),
            np.take_along_axis(jhi[:, :m, :], pick, axis=2),
        )
        return krawczyk_mr(c, Vlo, Vhi, fc, fr, Jc, Jr)

    def _newton(self, x: np.ndarray, var: np.ndarray, steps: int = 6) -> np.ndarray:
        """Float Newton on the variables ``var`` from ``x``, parameters fixed: ``(B, m)``
        (where a step fails, the last iterate; only a centre, any point is sound)."""
        rows = np.arange(x.shape[0])[:, None]
        x = x.copy()
        m = self.m
        with np.errstate(all="ignore"):
            for _ in range(steps):
                f, J = self.csys.eval_fj_float(x)
                Jv = np.take_along_axis(J[:, :m, :], var[:, None, :], axis=2)
                step, ok = batched_solve(Jv, f[:, :m])
                ok &= np.all(np.isfinite(step), axis=1)
                v = x[rows, var] - np.where(ok[:, None], step, 0.0)
                x[rows, var] = v
        return x[rows, var]

    # -- the search --------------------------------------------------------------------------
    def solve(
        self,
        *,
        timeout: float | None = None,
        max_boxes: int | None = None,
        max_solutions: int | None = None,
        progress: Any = None,
        cancel: Any = None,
    ) -> SolveResult:
        """Pave the domain (module docstring); the limits stop the paving, the boxes left
        are pending.  Rounds start at 16 boxes and grow to ``batch_size`` while that pays,
        cut to the time left (:class:`~.batching.BatchSizer`, as the solver's): one round of
        1,023 boxes of ``DiscreteBoundary-0200`` (200 variables, 141 equations) took 17 s,
        and a 10 s limit ran 19 s."""
        dom = self.system.domain
        run = run_search(
            self,
            dom[:, 0][None].copy(),
            dom[:, 1][None].copy(),
            limits=Limits(timeout=timeout, max_boxes=max_boxes, max_solutions=max_solutions),
            progress=progress,
            cancel=cancel,
            sizer=BatchSizer(cap=self.batch_size),
        )
        return self.result(run)

    def result(self, run: SearchRun) -> SolveResult:
        state = run.state
        return SolveResult.of_search(
            run,
            variables=self.system.variables,
            solutions=list(state.inside),
            undecided=[(u.lo, u.hi, u.reason) for u in state.undecided],
            stats=state.stats,
            eps=self.eps,
            max_undecided=self.max_undecided,
            max_pending=self.max_pending,
        )
