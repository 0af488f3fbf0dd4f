"""Certification of solutions: Krawczyk proofs, existence boxes, de-duplication.

A certified solution is a pair of boxes ``E ⊆ U``: ``K(U) ⊂ int U`` proves that ``U``
holds exactly one solution, and that solution lies in the tight existence box ``E``.

* :meth:`Certifier.inflate` -- for boxes where ``K(X) ⊂ int X`` failed (the solution sits
  near a face, or ``X`` is too wide for the Jacobian to contract), run float Newton from the
  midpoint to an approximate solution ``x*`` and try ``U = x* ± s·r`` for decreasing
  scales ``s``, where ``r`` is the radius that makes ``U`` cover ``X``.  The largest ``U`` that
  passes is kept, so the part of ``X`` left outside it (:func:`box_difference`) is thin.
  This is IBEX's "inflating Newton" turned around: shrink from large instead of growing
  from a point, because a large ``U`` leaves less of ``X`` to search.
* :meth:`Certifier.tighten` -- iterate ``E ← K(E) ∩ E``; every zero in ``E`` stays in
  ``K(E)``, so ``E`` keeps the solution and shrinks to a few ulps.
* :class:`SolutionSet` -- the solutions found so far.  A new pair ``(E', U')`` is the same
  solution as a known ``(E, U)`` when ``E' ⊆ U`` or ``E ⊆ U'`` (each ``U`` holds only one).
  Boxes inside a known ``U`` need no further search (:meth:`SolutionSet.prune`).
"""

from __future__ import annotations

import time

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval.core import is_subset
from ..interval.reductions import all_last, any_last, count_last
from .buffer import BoxStack
from .newton import batched_solve, krawczyk, linearize

__all__ = ["Certifier", "SolutionSet", "box_difference", "boxes_minus"]


def box_difference(lo, hi, ulo, uhi) -> list[tuple[np.ndarray, np.ndarray]]:
    """Closed boxes covering ``X \\ int(U)`` (at most ``2n`` pieces, none meeting ``int U``)."""
    pieces = []
    clo, chi = lo.copy(), hi.copy()
    for i in range(lo.shape[0]):
        if clo[i] < ulo[i]:
            plo, phi = clo.copy(), chi.copy()
            phi[i] = min(ulo[i], chi[i])
            pieces.append((plo, phi))
            clo[i] = ulo[i]
        if chi[i] > uhi[i]:
            plo, phi = clo.copy(), chi.copy()
            plo[i] = max(uhi[i], clo[i])
            pieces.append((plo, phi))
            chi[i] = uhi[i]
        if clo[i] > chi[i]:  # X and U disjoint along i: X itself is the remainder
            return [(lo.copy(), hi.copy())]
    return pieces


def boxes_minus(lo, hi, cut_lo, cut_hi) -> tuple[np.ndarray, np.ndarray]:
    """Boxes ``(B, n)`` covering ``X \\ ∪ int(U_j)``: :func:`box_difference` iterated over the
    boxes ``U_j`` (rows of ``cut_lo, cut_hi``) on every piece that meets their interior."""
    pieces = [(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))]
    for ulo, uhi in zip(cut_lo, cut_hi, strict=True):
        nxt = []
        for plo, phi in pieces:
            if np.all(np.maximum(plo, ulo) < np.minimum(phi, uhi)):
                nxt.extend(box_difference(plo, phi, ulo, uhi))
            else:
                nxt.append((plo, phi))
        pieces = nxt
    n = len(lo)
    return (
        np.array([a for a, _ in pieces]).reshape(-1, n),
        np.array([b for _, b in pieces]).reshape(-1, n),
    )


def _meeting(lo, hi, ulo, uhi) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(row, u)`` whose closed boxes meet, in row-major order: the first
    variable on every pair, each next one on the pairs still meeting.  A box misses most
    unicity boxes in its first variables, so this costs a few ``B × U`` comparisons where
    the dense test costs ``2n`` of them (FK, ~400 unicity boxes: 8 % of the search)."""
    meet = (lo[:, None, 0] <= uhi[None, :, 0]) & (hi[:, None, 0] >= ulo[None, :, 0])
    rows, us = np.nonzero(meet)
    for j in range(1, lo.shape[1]):
        if rows.size == 0:
            break
        ok = (lo[rows, j] <= uhi[us, j]) & (hi[rows, j] >= ulo[us, j])
        rows, us = rows[ok], us[ok]
    return rows, us


class SolutionSet:
    """Certified solutions ``(E, U, kind)``; ``kind`` is ``"ok"``, ``"boundary"``,
    ``"constraint"`` or ``"rejected"`` (proven, but outside the domain or violating a
    constraint: kept only to prune its unicity box)."""

    def __init__(self, n: int):
        self.n = n
        self.kind: list[str] = []
        # the existence boxes E and unicity boxes U, row i the i-th solution's, grown in place
        # (each new solution is compared with all: arrays rebuilt from lists at each
        # comparison took 12 of 16 s on 3^8 solutions)
        self._e = BoxStack(n)
        self._u = BoxStack(n)

    def entry(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Copies of solution ``i``'s ``(E_lo, E_hi, U_lo, U_hi)``."""
        (elo, ehi), (ulo, uhi) = self._e.view(), self._u.view()
        return elo[i].copy(), ehi[i].copy(), ulo[i].copy(), uhi[i].copy()

    def __len__(self) -> int:
        return len(self.kind)

    def count(self, kind: str = "ok") -> int:
        return sum(k == kind for k in self.kind)

    def find(self, elo, ehi, ulo, uhi) -> int:
        """Index of a known solution equal to ``(E, U)``, or -1."""
        if not self.kind:
            return -1
        (Ulo, Uhi), (Elo, Ehi) = self._u.view(), self._e.view()
        same = is_subset(elo, ehi, Ulo, Uhi).all(axis=1)
        same |= is_subset(Elo, Ehi, ulo, uhi).all(axis=1)
        idx = np.flatnonzero(same)
        return int(idx[0]) if idx.size else -1

    def add(self, elo, ehi, ulo, uhi, kind: str) -> bool:
        """Record a proven solution; returns False if it was already known.

        ``kind="alias"`` records only another unicity box of a known solution.
        """
        k = self.find(elo, ehi, ulo, uhi)
        if k >= 0:  # an alias of solution k: its existence box, this (larger) unicity box
            elo, ehi = self.entry(k)[:2]
        self._e.push(np.asarray(elo, dtype=float)[None], np.asarray(ehi, dtype=float)[None])
        self._u.push(np.asarray(ulo, dtype=float)[None], np.asarray(uhi, dtype=float)[None])
        known = k >= 0 or kind == "alias"
        self.kind.append("alias" if known else kind)
        return not known

    def prune(self, lo, hi):
        """Remove what known unicity boxes cover (nothing is left to find there).

        Returns ``(keep, pieces_lo, pieces_hi)``: boxes inside a unicity box are dropped
        (``keep`` false); a box that a unicity box covers in all but one direction is
        replaced by the (at most two) pieces of its difference, which are returned.
        """
        B, n = lo.shape
        none = np.empty((0, n))
        keep = np.ones(B, dtype=bool)
        if not len(self.kind) or B == 0:
            return keep, none, none
        # only pairs whose closed boxes meet can be "inside" or overlap: most boxes meet
        # no unicity box, so the tests below run on those pairs only (row-major order kept)
        Ulo, Uhi = self._u.view()
        rows, us = _meeting(lo, hi, Ulo, Uhi)
        if rows.size == 0:
            return keep, none, none
        blo, bhi, ulo, uhi = lo[rows], hi[rows], Ulo[us], Uhi[us]
        cover = (blo >= ulo) & (bhi <= uhi)
        keep[rows[all_last(cover)]] = False
        overlap = all_last((blo < uhi) & (bhi > ulo))
        uncovered = n - count_last(cover)  # directions where U does not cover the box
        clip = keep[rows] & overlap & (uncovered == 1)
        if not np.any(clip):
            return keep, none, none
        plo, phi = [], []
        rows, us = rows[clip], us[clip]
        done = set()
        for r, k in zip(rows.tolist(), us.tolist()):
            if r in done:
                continue
            done.add(r)
            for a, b in box_difference(lo[r], hi[r], Ulo[k], Uhi[k]):
                plo.append(a)
                phi.append(b)
            keep[r] = False
        return keep, np.array(plo).reshape(-1, n), np.array(phi).reshape(-1, n)

    def items(self, kind: str):
        for i, k in enumerate(self.kind):
            if k == kind:
                yield self.entry(i)


#: the most halvings of a damped Newton step (:meth:`Certifier.newton_point`): ``λ >= 2^-10``
HALVINGS = 10


class Certifier:
    """Krawczyk-based proofs and the classification of proven solutions."""

    def __init__(
        self,
        csys: CompiledSystem,
        newton_iterations: int = 8,
        scales: tuple[float, ...] = (1.0, 0.2, 0.04, 0.008, 1e-3, 1e-4, 1e-6),
        tighten_steps: int = 4,
        surplus: int = 0,
    ):
        self.csys = csys
        #: the last ``surplus`` constraints are the equations an over-determined system has
        #: beyond its square subsystem (:mod:`.nonsquare`): a proven solution of the
        #: subsystem whose enclosures of them hold 0 is ``subsystem``, not ``constraint``
        self.surplus = int(surplus)
        #: the search domain (solutions touching its boundary are ``boundary``); a search
        #: on another domain uses a copy with its own (:meth:`.Solver.on_domain`)
        self.domain = csys.system.domain
        self.newton_iterations = newton_iterations
        self.scales = scales
        self.tighten_steps = tighten_steps
        checked = [i for i, c in enumerate(csys.system.constraints) if not c.redundant]
        self._checked = np.array(checked, dtype=np.int64)
        cons = csys.system.constraints
        self._clo = np.array([cons[i].lo for i in checked], dtype=np.float64)
        self._chi = np.array([cons[i].hi for i in checked], dtype=np.float64)

    def describe(self) -> str:
        """The settings that shape the answer, as text (for the checkpoint fingerprint)."""
        return (
            f"{type(self).__name__}(newton_iterations={self.newton_iterations}, "
            f"scales={self.scales!r}, tighten_steps={self.tighten_steps}"
            + (f", surplus={self.surplus})" if self.surplus else ")")
        )

    # -- float Newton -----------------------------------------------------------------------
    def newton_point(
        self,
        x0: np.ndarray,
        lo=None,
        hi=None,
        *,
        iterations: int | None = None,
        damped: bool | np.ndarray = False,
        deadline: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Float Newton iterations from ``x0`` (B, n); returns points and a converged mask.

        With ``lo, hi``, iterates that leave the box widened by its width on every side
        are abandoned (the caller only uses points near the box).  ``iterations``: at most
        that many steps (default :attr:`newton_iterations`).  ``damped`` (one flag, or one
        per point): each step ``x + λ s`` takes the largest ``λ`` of ``1, 1/2, ...,
        2^-HALVINGS`` where ``|f|_2`` falls, and a point where none does is abandoned (a
        local minimum of ``|f|``): far from a solution the full step of a high-degree
        system overshoots, and a point that would wander off converges (IBEX's I5, 512
        points in ``[-10, 10]^10``: 3 converge in 30 full steps, 81 in 60 damped ones).
        Convergence is judged on the full step ``s``, which is taken once it is that small.
        No step starts past ``deadline`` (:func:`time.monotonic`).
        """
        x = x0.copy()
        conv = np.zeros(x.shape[0], dtype=bool)
        alive = np.ones(x.shape[0], dtype=bool)
        damp = np.broadcast_to(np.asarray(damped, dtype=bool), conv.shape)
        if lo is not None:
            w = hi - lo
            far_lo, far_hi = lo - w - 1e-9 * (1.0 + np.abs(lo)), hi + w + 1e-9 * (1.0 + np.abs(hi))
        for _ in range(self.newton_iterations if iterations is None else iterations):
            idx = np.flatnonzero(alive & ~conv)
            if idx.size == 0 or (deadline is not None and time.monotonic() > deadline):
                break
            f, J = self.csys.eval_fj_float(x[idx])
            step, ok = batched_solve(J, f)
            with np.errstate(all="ignore"):
                step = -np.where(ok[:, None], step, 0.0)
                xn = x[idx] + step
                small = all_last(np.abs(step) <= 1e-12 * (1.0 + np.abs(xn)))
                # a full step this small is taken: |f| is at its rounding there
                d = np.flatnonzero(damp[idx] & ~small)
                if d.size:
                    xn[d], fell = self._damped(x[idx[d]], step[d], f[d])
                    ok[d] &= fell
            good = ok & all_last(np.isfinite(xn))
            if lo is not None:
                good &= all_last((xn >= far_lo[idx]) & (xn <= far_hi[idx]))
            x[idx[good]] = xn[good]
            alive[idx[~good]] = False
            conv[idx[small & good]] = True
        return x, conv & alive

    def _damped(self, x: np.ndarray, step: np.ndarray, f: np.ndarray):
        """``x + λ step`` with the largest ``λ`` of ``1, 1/2, ..., 2^-HALVINGS`` where
        ``|f|_2`` falls below ``|f(x)|_2``, and whether one did (a row where none does is at
        a local minimum of ``|f|`` or a singular ``J``: :meth:`newton_point` abandons it).
        The full step first, then the others for the rows it did not serve, in one call."""
        norm = np.linalg.norm(f, axis=1)
        xn = x + step
        fell = np.linalg.norm(self.csys.eval_f_float(xn), axis=1) < norm  # NaN: not
        rows = np.flatnonzero(~fell)
        if rows.size == 0:
            return xn, fell
        lam = 0.5 ** np.arange(1, HALVINGS + 1)
        tries = x[rows][None] + lam[:, None, None] * step[rows][None]  # (HALVINGS, k, n)
        fn = self.csys.eval_f_float(tries.reshape(-1, x.shape[1]))
        falls = np.linalg.norm(fn, axis=1).reshape(HALVINGS, rows.size) < norm[rows]
        some = np.any(falls, axis=0)
        xn[rows[some]] = tries[np.argmax(falls, axis=0)[some], np.flatnonzero(some)]
        fell[rows[some]] = True
        return xn, fell

    # -- proofs -------------------------------------------------------------------------------
    def inflate(self, lo, hi):
        """Try to prove a solution near each box; returns ``(index, E_lo, E_hi, U_lo, U_hi)``.

        ``index`` lists the boxes (rows of ``lo``) for which a unicity box was proven.
        """
        B, n = lo.shape
        empty = (np.empty(0, dtype=np.int64),) + (np.empty((0, n)),) * 4
        if B == 0:
            return empty
        c = 0.5 * lo + 0.5 * hi
        x, conv = self.newton_point(c, lo, hi)
        w = hi - lo
        slack = 0.25 * w + 1e-9 * (1.0 + np.abs(x))  # degenerate boxes: rounding slack
        near = conv & all_last((x >= lo - slack) & (x <= hi + slack))
        todo = np.flatnonzero(near)
        if todo.size == 0:
            return empty
        xs = x[todo]
        r = np.maximum(np.maximum(xs - lo[todo], hi[todo] - xs), 0.0)
        # a box already shrunk to rounding level: prove on a slightly larger U
        r = np.maximum(r * (1.0 + 1e-9) + 1e-13 * (1.0 + np.abs(xs)), 1e-10 * (1.0 + np.abs(xs)))
        found_idx, found_U = [], []
        remaining = np.arange(todo.size)
        for s in self.scales:
            if remaining.size == 0:
                break
            ulo = xs[remaining] - s * r[remaining]
            uhi = xs[remaining] + s * r[remaining]
            lin = linearize(self.csys, ulo, uhi)
            _, _, proven = krawczyk(lin)
            if np.any(proven):
                found_idx.append(remaining[proven])
                found_U.append((ulo[proven], uhi[proven]))
                remaining = remaining[~proven]
        if not found_idx:
            return empty
        sel = np.concatenate(found_idx)
        Ulo = np.concatenate([u[0] for u in found_U])
        Uhi = np.concatenate([u[1] for u in found_U])
        # existence boxes: one Krawczyk step (tightened later, only for new solutions)
        lin = linearize(self.csys, Ulo, Uhi)
        klo, khi, _ = krawczyk(lin)
        Elo, Ehi = np.fmax(klo, Ulo), np.fmin(khi, Uhi)
        return todo[sel], Elo, Ehi, Ulo, Uhi

    def expand(self, elo, ehi, ulo, uhi, refine: int = 3):
        """Epsilon-inflation: grow each unicity box as far as Krawczyk still proves it unique.

        Candidates are ``mid(E) ± f·s`` (``s``: the domain widths, or ``1 + |mid E|`` along an
        unbounded variable), with ``f`` first on a grid from 0.3 down to 1e-9 (factor
        ``√10``), then refined by ``refine`` bisections of ``log f`` between the largest
        proven and the smallest failed candidate.  A candidate counts only if it contains
        ``E`` (hence the known solution) and passes Krawczyk: a proof that it holds no other
        solution, however close one may be.  A larger unicity box lets the search discard
        more of the neighbourhood of a known solution, where Newton cannot exclude the boxes
        that nearly touch it.
        """
        S = elo.shape[0]
        if S == 0:
            return ulo, uhi
        mid = 0.5 * elo + 0.5 * ehi
        dom = self.domain
        dw = dom[:, 1] - dom[:, 0]
        scale = np.where(np.isfinite(dw), dw, 1.0 + np.abs(mid))  # (S, n)
        urad = 0.5 * (uhi - ulo)

        def proven(f):  # f (S, F) -> candidates (S, F, n) and their proofs (S, F)
            rad = np.maximum(f[:, :, None] * scale[:, None, :], urad[:, None, :])
            clo, chi = mid[:, None, :] - rad, mid[:, None, :] + rad
            F = f.shape[1]
            lin = linearize(self.csys, clo.reshape(S * F, -1), chi.reshape(S * F, -1))
            ok = krawczyk(lin)[2].reshape(S, F)
            ok &= all_last((clo <= elo[:, None, :]) & (chi >= ehi[:, None, :]))
            return clo, chi, ok

        grid = 10.0 ** -np.arange(0.5, 9.5, 0.5)
        clo, chi, ok = proven(np.broadcast_to(grid, (S, grid.size)))
        first = np.argmax(ok, axis=1)  # grid decreasing: the first proof is the largest box
        found = ok[np.arange(S), first]
        good = np.where(found, grid[first], 0.0)
        bad = np.where(found & (first > 0), grid[np.maximum(first - 1, 0)], 0.0)
        best_lo = np.where(found[:, None], clo[np.arange(S), first], ulo)
        best_hi = np.where(found[:, None], chi[np.arange(S), first], uhi)
        for _ in range(refine):
            todo = bad > 0.0
            if not np.any(todo):
                break
            f = np.sqrt(np.where(todo, good * bad, 1.0))
            tlo, thi, tok = proven(f[:, None])
            win = todo & tok[:, 0]
            best_lo = np.where(win[:, None], tlo[:, 0], best_lo)
            best_hi = np.where(win[:, None], thi[:, 0], best_hi)
            good = np.where(win, f, good)
            bad = np.where(todo & ~tok[:, 0], f, bad)
        larger = np.all(best_hi - best_lo >= uhi - ulo, axis=1)
        return (
            np.where(larger[:, None], best_lo, ulo),
            np.where(larger[:, None], best_hi, uhi),
        )

    def tighten(self, lo, hi):
        """``E ← K(E) ∩ E`` a few times, starting from boxes proven to hold one zero each."""
        lo, hi = lo.copy(), hi.copy()
        for _ in range(self.tighten_steps):
            if lo.shape[0] == 0:
                break
            lin = linearize(self.csys, lo, hi)
            klo, khi, _ = krawczyk(lin)
            use = lin.ok[:, None]
            nlo = np.where(use, np.fmax(lo, klo), lo)
            nhi = np.where(use, np.fmin(hi, khi), hi)
            # the solution is in both; a numerically empty meet would be a bug: keep old box
            bad = any_last(nlo > nhi)
            lo = np.where(bad[:, None], lo, nlo)
            hi = np.where(bad[:, None], hi, nhi)
        return lo, hi

    def classify(self, elo, ehi) -> list[str]:
        """``ok`` / ``boundary`` / ``constraint`` / ``rejected`` for proven existence boxes;
        ``subsystem`` for an ``ok`` box where only the surplus equations of an
        over-determined system are undecided (their enclosures hold 0, not proven 0)."""
        B = elo.shape[0]
        dlo, dhi = self.domain[:, 0], self.domain[:, 1]
        inside = np.all((elo >= dlo) & (ehi <= dhi), axis=1)
        outside = np.any((ehi < dlo) | (elo > dhi), axis=1)
        kinds = np.where(inside, "ok", np.where(outside, "rejected", "boundary")).astype(object)
        if self._checked.size and B:
            glo, ghi = self.csys.eval_constraints(elo, ehi)
            glo, ghi = glo[:, self._checked], ghi[:, self._checked]
            held = (glo >= self._clo) & (ghi <= self._chi)
            viol = np.any((ghi < self._clo) | (glo > self._chi), axis=1)
            sat = np.all(held, axis=1)
            undecided = np.where(sat, kinds, "constraint")
            if self.surplus:  # the surplus equations are the last constraints checked
                own = np.all(held[:, : held.shape[1] - self.surplus], axis=1)
                undecided = np.where(~sat & own & (kinds == "ok"), "subsystem", undecided)
            kinds = np.where(viol, "rejected", undecided)
        return [str(k) for k in kinds]
