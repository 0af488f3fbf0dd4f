"""Algorithm 1 of Merlet (2007): the under-constrained IK system by branch and prune.

Unknowns: the controls ``u`` (``m`` of them) in the box ``U`` = strokes (or a window around
the last ``u``) ∩ the range allowed by the tension limits (eq. 5).  Equations: ``f(u) = H
τ(u) + w_g = 0`` (``w`` of them, ``w < m`` for MARIONET).  The search stops at the first
*certified* solution.

**Design.**  Each ``τ_i`` depends on ``u_i`` alone and increases with it (eq. 6), so a box of
``u`` is a box of ``τ`` and back; in ``τ`` the equations are *linear*.  The search therefore
runs on boxes of tensions ``T`` (the image of ``U`` intersected with ``[τ_min, τ_max]``,
enclosed outward), a batch of boxes per numpy call:

1. **contract** with the preconditioned linear system ``M τ + b = 0`` (``M = P H``, ``b = P
   w_g``, ``P`` chosen by a pivoted QR of ``H`` so that ``M ≈ [I | N]``; ``M``, ``b`` enclosed
   rigorously): interval Gauss–Seidel on every (row, variable) pair, repeated until it stalls,
   plus a check that each full row can still vanish.  An empty box is *proven* to hold no
   solution.  For a one-dimensional solution set (MARIONET) this contraction is nearly the
   hull of the segment of the solution line inside the box.
2. **certify**: the ``m - w`` *parametric* wires (the columns QR left out of the basis) are
   fixed at the controls of the midpoint tensions of the box, ``u_P``; the other controls
   follow from the square linear system in ``τ`` (one solve, the limit of Newton's method in
   the ``τ`` coordinates) and eq. 5.  A small box around that point (radius ``box_radius``,
   default 1e-6 cm) goes through the Krawczyk test on the *square* system in ``u_S`` with
   ``u_P`` fixed (:meth:`.ik_enclose.SquareSystem.krawczyk`): ``K(X) ⊂ int X`` proves that
   exactly one solution exists in ``X``, so ``(u_P, u_S*)`` is an exact solution of the
   under-constrained system.  It counts only if the proven enclosure lies in the
   strokes/window and its tensions provably within the limits.
3. **bisect** boxes that were neither discarded nor certified (widest side relative to the
   domain), until a solution is certified, the buffer is empty (proof that no solution exists
   in ``U``), or a limit is hit.

The loop is the search driver's (:mod:`certsolve.solver.search`, :class:`ControlSearch` is
the step) with ``max_solutions = 1``; boxes narrower than ``eps`` are all reported undecided.

With more than ``w`` equations (``m < w``: the almost-planar robot) nothing square remains
to certify: the search can still *prove* that no control vector in ``U`` balances the pose
(every box contracted to empty), or it narrows down to undecided boxes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import scipy.linalg

from ..interval import arith
from ..interval.linalg import UNDERFLOW, U, gamma, mr_matmul
from ..robot.model import Robot
from ..solver.buffer import BoxStack
from ..solver.search import Limits, SearchStatus, Tally, run_search
from .ik_enclose import (
    SAFE,
    PoseEnclosure,
    SquareSystem,
    tension_mr,
    tension_range,
)

__all__ = [
    "Verdict",
    "ControlSearch",
    "SearchOutcome",
    "control_point",
    "preconditioner",
    "search_controls",
]


def control_point(
    robot: Robot,
    rho: np.ndarray | float,
    tau: np.ndarray | float,
    idx: np.ndarray | slice | int = slice(None),
) -> np.ndarray:
    """Eq. (5) in floating point for the wires ``idx`` (no error bound: a candidate only)."""
    k, K, V, L0 = robot.k[idx], robot.K[idx], robot.V[idx], robot.L0[idx]
    return k * L0 / (K * (k - tau)) - (rho + V) / K


@dataclass
class Preconditioner:
    P: np.ndarray  # (w, w)
    basis: np.ndarray  # (r,) columns solved for
    params: np.ndarray  # (m - r,) columns fixed when certifying
    rank: int
    Mc: np.ndarray  # (w, m) enclosure of P H
    Mr: np.ndarray
    bc: np.ndarray  # (w,) enclosure of P w_g
    br: np.ndarray
    usable: np.ndarray  # (w, m) M_ij bounded away from 0 and not negligible


def preconditioner(enc: PoseEnclosure) -> Preconditioner:
    """``P`` with ``P H[:, basis] ≈ [I; 0]`` from a pivoted QR of ``H`` (see module docstring)."""
    H = enc.H
    w, m = H.shape
    _, Rq, piv = scipy.linalg.qr(H, pivoting=True, mode="economic")
    diag = np.abs(np.diag(Rq))
    rank = int(np.sum(diag > diag[0] * 1e-12)) if diag.size and diag[0] > 0 else 0
    basis = np.sort(piv[:rank])
    params = np.sort(piv[rank:])
    Q, R1 = np.linalg.qr(H[:, basis], mode="complete")
    P = np.zeros((w, w))
    P[:rank] = np.linalg.solve(R1[:rank, :rank], Q[:, :rank].T)
    P[rank:] = Q[:, rank:].T
    Mc, Mr = mr_matmul(P, None, H, enc.H_err)
    bc, br = mr_matmul(P, None, enc.wg, enc.wg_err)
    big = np.max(np.abs(Mc), axis=1, keepdims=True)
    usable = (np.abs(Mc) > 2.0 * Mr) & (np.abs(Mc) > 1e-10 * big)
    return Preconditioner(P, basis, params, rank, Mc, Mr, bc, br, usable)


def contract(
    pc: Preconditioner, lo: np.ndarray, hi: np.ndarray, sweeps: int = 8
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interval Gauss–Seidel (Jacobi order) on ``M τ + b = 0`` for a batch ``(B, m)``.

    Returns ``(lo, hi, empty)``; sound: every solution in a box stays in its contraction.
    """
    Mc, Mr, bc, br = pc.Mc, pc.Mr, pc.bc, pc.br
    m = Mc.shape[1]
    mask = 1.0 - np.eye(m)
    aMc = np.abs(Mc)
    Dlo = np.nextafter(Mc - Mr, -np.inf)[None]
    Dhi = np.nextafter(Mc + Mr, np.inf)[None]
    use = pc.usable[None]
    gm = gamma(m)
    gm1 = gamma(m + 1)
    empty = np.zeros(lo.shape[0], dtype=bool)
    for _ in range(sweeps):
        Tc = 0.5 * lo + 0.5 * hi
        Tr = np.maximum(hi - Tc, Tc - lo) * (1.0 + 4.0 * U)
        aTc = np.abs(Tc)
        Pc = Mc[None] * Tc[:, None, :]  # (B, w, m)
        aPc = np.abs(Pc)
        Pr = aMc[None] * Tr[:, None, :] + Mr[None] * (aTc + Tr)[:, None, :] + U * aPc
        # full rows must contain 0
        Fc = Pc.sum(axis=2) + bc
        Fr = (Pr.sum(axis=2) + br + gm1 * (aPc.sum(axis=2) + np.abs(bc))) * SAFE + UNDERFLOW
        empty |= np.any(np.abs(Fc) > Fr, axis=1)
        # rows without variable j
        Sc = Pc @ mask  # (B, w, m)
        Sr = (Pr @ mask + gm * (aPc @ mask)) * SAFE
        Nc = -(bc[None, :, None] + Sc)
        Nr = (br[None, :, None] + Sr + 2.0 * U * np.abs(Nc)) * SAFE + UNDERFLOW
        Nlo = np.nextafter(Nc - Nr, -np.inf)
        Nhi = np.nextafter(Nc + Nr, np.inf)
        qlo, qhi = arith.div(Nlo, Nhi, Dlo, Dhi)
        qlo = np.where(use, qlo, -np.inf)
        qhi = np.where(use, qhi, np.inf)
        nlo = np.maximum(lo, qlo.max(axis=1))
        nhi = np.minimum(hi, qhi.min(axis=1))
        empty |= np.any(~(nlo <= nhi), axis=1)
        w0 = hi - lo
        w1 = nhi - nlo
        lo, hi = nlo, nhi
        if not np.any(w1 < 0.9 * w0):
            break
    return lo, hi, empty


class Verdict(StrEnum):
    """What Algorithm 1 established (:attr:`SearchOutcome.verdict`)."""

    CERTIFIED = "certified"  # a solution, proven
    INFEASIBLE = "infeasible"  # proven: no solution in the box
    UNDECIDED = "undecided"  # searched completely; only boxes narrower than eps remain
    UNKNOWN = "unknown"  # a limit stopped the search first


@dataclass(kw_only=True)
class SearchOutcome:
    """Algorithm 1's answer.  ``status`` is the search's (:class:`SearchStatus`: it ends
    with ``max_solutions`` once a point is certified); :attr:`verdict` reads it."""

    status: SearchStatus
    u: np.ndarray | None = None  # (m,) the certified point (parametric wires exact)
    params: list[int] = field(default_factory=list)  # 0-based indices of fixed wires
    box_lo: np.ndarray | None = None  # unicity box (parametric wires degenerate)
    box_hi: np.ndarray | None = None
    enc_lo: np.ndarray | None = None  # tight enclosure of the solution
    enc_hi: np.ndarray | None = None
    undecided: list = field(default_factory=list)  # tension boxes (lo, hi)
    boxes: int = 0
    rounds: int = 0
    time: float = 0.0

    @property
    def verdict(self) -> Verdict:
        """``certified``; ``infeasible`` (proven: no solution in the box); ``undecided``
        (searched completely, only boxes narrower than eps remain); or ``unknown`` (a
        limit stopped the search first)."""
        if self.u is not None:
            return Verdict.CERTIFIED
        if self.status != SearchStatus.COMPLETE:
            return Verdict.UNKNOWN
        return Verdict.UNDECIDED if self.undecided else Verdict.INFEASIBLE

    def certified_point(
        self,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(u, box_lo, box_hi, enc_lo, enc_hi)``: the certified point, its unicity box and
        its enclosure (verdict ``certified`` only)."""
        u, blo, bhi, elo, ehi = self.u, self.box_lo, self.box_hi, self.enc_lo, self.enc_hi
        if u is None or blo is None or bhi is None or elo is None or ehi is None:
            raise ValueError("no certified point in this search outcome")
        return u, blo, bhi, elo, ehi


def _certify(robot, enc, pc, sq, lo, hi, ulo, uhi, box_radius):
    """Try to certify one solution per tension box; data of the first success or None."""
    B, m = lo.shape
    S, Pw = pc.basis, pc.params
    rho = enc.rho
    u = np.zeros((B, m))
    if Pw.size:
        tmid = 0.5 * lo[:, Pw] + 0.5 * hi[:, Pw]
        u[:, Pw] = np.clip(control_point(robot, rho[Pw], tmid, Pw), ulo[Pw], uhi[Pw])
        tP, _ = tension_mr(robot, enc, u)
        rhs = -(enc.wg[None] + tP[:, Pw] @ enc.Ht[Pw])
    else:
        rhs = np.broadcast_to(-enc.wg, (B, enc.Ht.shape[1]))
    tS = rhs @ sq.G.T
    uS = control_point(robot, rho[S], tS, S)
    ok = np.all(np.isfinite(uS) & (tS < robot.k[S]), axis=1)
    if not np.any(ok):
        return None
    u, uS = u[ok], uS[ok]
    u[:, S] = uS
    xlo, xhi, klo, khi, proven, _, _ = sq.krawczyk(u, box_radius * (1.0 + np.abs(uS)))
    if not np.any(proven):
        return None
    elo = np.maximum(klo, xlo)
    ehi = np.minimum(khi, xhi)
    E_lo = u.copy()
    E_hi = u.copy()
    E_lo[:, S] = elo
    E_hi[:, S] = ehi
    # the solution must be in the strokes / window and its tensions within the limits
    inside = np.all((E_lo >= ulo) & (E_hi <= uhi), axis=1)
    tlo, thi = tension_range(robot, enc, E_lo, E_hi)
    inside &= np.all((tlo >= robot.tau_min) & (thi <= robot.tau_max), axis=1)
    good = np.flatnonzero(proven & inside)
    if good.size == 0:
        return None
    k = int(good[0])
    X_lo, X_hi = u[k].copy(), u[k].copy()
    X_lo[S], X_hi[S] = xlo[k], xhi[k]
    return u[k], X_lo, X_hi, E_lo[k], E_hi[k]


@dataclass
class ControlState:
    stack: BoxStack
    undecided: list = field(default_factory=list)
    found: tuple | None = None  # (u, X_lo, X_hi, E_lo, E_hi) of the certified point


class ControlSearch:
    """Algorithm 1 as a step of the search driver: contract, certify, bisect tension boxes."""

    def __init__(
        self,
        robot: Robot,
        enc: PoseEnclosure,
        pc: Preconditioner,
        sq: SquareSystem | None,
        ulo: np.ndarray,
        uhi: np.ndarray,
        eps: float,
        box_radius: float,
        dom_w: np.ndarray,
        batch_size: int,
    ) -> None:
        self.robot, self.enc, self.pc, self.sq = robot, enc, pc, sq
        self.ulo, self.uhi = ulo, uhi
        self.eps, self.box_radius, self.dom_w = eps, box_radius, dom_w
        self.batch_size = int(batch_size)

    def start(self, known: object = None) -> ControlState:
        return ControlState(BoxStack(self.ulo.size))

    def tally(self, state: ControlState) -> Tally:
        return Tally(solutions=int(state.found is not None), undecided=len(state.undecided))

    def known(self, state: ControlState) -> None:
        return None

    def found(self, state: ControlState) -> tuple[tuple | None, list]:
        return state.found, state.undecided

    def merge(self, state: ControlState, found: tuple[tuple | None, list]) -> None:
        point, undecided = found
        if state.found is None:
            state.found = point
        state.undecided.extend(undecided)

    def process(
        self, lo: np.ndarray, hi: np.ndarray, state: ControlState, *, deadline: float | None = None
    ) -> None:
        # ``deadline`` (:meth:`.Step.process`) is not used: no part of this round loops long
        lo, hi, empty = contract(self.pc, lo, hi)
        lo, hi = lo[~empty], hi[~empty]
        if lo.shape[0] == 0:
            return
        if self.sq is not None:
            found = _certify(
                self.robot, self.enc, self.pc, self.sq, lo, hi, self.ulo, self.uhi, self.box_radius
            )
            if found is not None:
                state.found = found  # the search stops here (max_solutions = 1)
                return
        width = hi - lo
        small = np.all(width <= self.eps * (1.0 + np.abs(lo)), axis=1)
        for k in np.flatnonzero(small):
            state.undecided.append((lo[k].copy(), hi[k].copy()))
        big = ~small
        if np.any(big):
            lo, hi = lo[big], hi[big]
            j = np.argmax((hi - lo) / self.dom_w, axis=1)
            rows = np.arange(lo.shape[0])
            mid = 0.5 * lo[rows, j] + 0.5 * hi[rows, j]
            alo, ahi = lo.copy(), hi.copy()
            ahi[rows, j] = mid
            blo, bhi = lo.copy(), hi.copy()
            blo[rows, j] = mid
            state.stack.push(np.concatenate([blo, alo]), np.concatenate([bhi, ahi]))


def search_controls(
    robot: Robot,
    enc: PoseEnclosure,
    ulo: np.ndarray,
    uhi: np.ndarray,
    *,
    max_boxes: int = 20000,
    timeout: float | None = 10.0,
    eps: float = 1e-9,
    box_radius: float = 1e-6,
    batch_size: int = 64,
) -> SearchOutcome:
    """Algorithm 1 over the control box ``[ulo, uhi]`` (see the module docstring)."""
    with np.errstate(all="ignore"):
        return _search(robot, enc, ulo, uhi, max_boxes, timeout, eps, box_radius, batch_size)


def _search(robot, enc, ulo, uhi, max_boxes, timeout, eps, box_radius, batch_size):
    t0 = time.perf_counter()
    ulo = np.asarray(ulo, dtype=float)
    uhi = np.asarray(uhi, dtype=float)
    # tension domain: image of the control box, within the tension limits (outward)
    tlo, thi = tension_range(robot, enc, ulo, uhi)
    tlo = np.maximum(tlo, robot.tau_min)
    thi = np.minimum(thi, robot.tau_max)
    if np.any(~(tlo <= thi)) or np.any(ulo > uhi):  # proven: nothing to search
        return SearchOutcome(status=SearchStatus.COMPLETE, time=time.perf_counter() - t0)
    pc = preconditioner(enc)
    sq = None
    if pc.rank == enc.Ht.shape[1] and pc.basis.size == pc.rank:
        try:
            sq = SquareSystem(robot, enc, pc.basis)
        except np.linalg.LinAlgError:
            sq = None
    dom_w = np.maximum(thi - tlo, 1e-300)
    step = ControlSearch(robot, enc, pc, sq, ulo, uhi, eps, box_radius, dom_w, batch_size)
    run = run_search(
        step,
        tlo[None],
        thi[None],
        limits=Limits(timeout=timeout, max_boxes=max_boxes, max_solutions=1),
    )
    state = run.state
    out = SearchOutcome(
        status=run.status,
        params=[int(i) for i in pc.params],
        undecided=state.undecided,
        boxes=run.stats.boxes,
        rounds=run.stats.batches,
        time=time.perf_counter() - t0,
    )
    if state.found is not None:
        out.u, out.box_lo, out.box_hi, out.enc_lo, out.enc_hi = state.found
    return out
