"""Linear relaxation of a box and its polytope hull (IBEX ``LinearizerXTaylor`` +
``CtcPolytopeHull``), batched and rigorous.

**Relaxation.**  For a box ``X = [l, h]``, a corner ``a`` of it and every ``x ∈ X``, the mean
value theorem gives ``f_i(x) ∈ f_i(a) + J_i(X)·(x - a)``, and ``x - a`` has a known sign in
every component.  At the lower corner (``d = x - l ∈ [0, w]``, ``w = h - l``) a zero of
``f_i`` therefore satisfies the two linear inequalities

    J̲_i·d <= -f̲_i(l),        -J̄_i·d <= f̄_i(l),

and at the upper corner (``x - h = d - w <= 0``)

    J̄_i·d <= -f̲_i(h) + J̄_i·w,   -J̲_i·d <= f̄_i(h) - J̲_i·w,

with ``[f̲, f̄]`` rigorous enclosures of ``f`` at the corners and ``[J̲, J̄]`` of the Jacobian
over ``X`` (Araya, Trombettoni, Neveu 2012: "X-Newton").  The right-hand sides are rounded up,
so every solution in ``X`` satisfies all ``4n`` inequalities exactly, in real arithmetic.

**Polytope hull.**  The smallest and largest ``d_j`` over ``{d ∈ [0, w] : G d <= ρ}`` are
linear programs; :func:`.lp.dual_active_set` solves them for a whole batch of boxes at once,
in floating point.  The rows come in opposite pairs (the two rows of ``J̲_i`` are ``±J̲_i``,
those of ``J̄_i`` and of an affine form likewise), slabs that its ratio test flips across as
it flips a variable across the box.  Its multipliers ``y >= 0`` are then turned into *proven* bounds
(Neumaier & Shcherbina 2004): for every feasible ``d``,

    ±d_j >= ±d_j + y·(G d - ρ) >= Σ_k min(0, g_k) w_k - y·ρ,   g = ±e_j + Gᵀ y,

evaluated with outward rounding, so an inaccurate multiplier only loosens a bound.  With
``c = 0`` the same inequality, if its right-hand side is positive, proves the box empty
(Farkas).  The contractor is sound whatever the LP solver returns.

**Where it pays** (:class:`HullShare`).  On a search where the hull rarely shrinks a box
much it costs a round more than it saves, on another it is most of the pruning; the
search learns which, as ACID learns its count: a running share of the boxes the hull
halved (or proved empty), every box contracted while the share is high, a sample of the
boxes while it is low (to notice when the hull becomes useful again); and only boxes the
round has left stalled, a box HC4 and Newton halved going back to the buffer anyway.
Skipping a sound contractor is sound: the learnt state changes the work, never the answer.

Only the ``directions`` variables with the largest smear (IBEX ``SmearSumRelative``) get
their two programs: every program can prove the box empty, and on ``examples/systems`` three
directions cost a third of all ``2n`` programs for 5-10% more boxes.  The relaxation needs
``f`` differentiable on ``X``: boxes where ``f`` is not defined everywhere or an enclosure is
not finite are left unchanged.

**Iterations.**  A program starts at a corner of the box and needs about one pivot per row
active at its optimum: with 12 variables (Dietmaier) 74 % of the programs were still running
after 15 iterations, the median one converged near 20, and a bound cut off half-way is a
weak one.  So the programs run up to ``max_iter = 40`` pivots, and a :class:`.lp.StallRule`
stops those whose bound has stopped moving (from the 20th pivot, less than 0.5 % of the
variable's width in 5 pivots: a 22-variable program can creep for 60), as does a batch
whose last few programs would cost a small search more than they save.  Against 15 pivots
(one worker): Dietmaier 263,840 -> 108,192 boxes, Katsura-14 4,532 -> 2,330, Trigo1-0012
13,439 -> 7,359 (2,154 since HC4 inverts sin and cos), Geneig-icse 6,527 -> 6,072; systems
whose programs converge within 15 pivots do not change.

**Warm starts.**  The programs of a box and those of its halves differ only by the
enclosures over a smaller box, so the parent's optimal active sets are nearly the
children's.  Each contracted box leaves them as its *hint* (:mod:`.buffer`), which its
halves inherit, and each program of a hinted box starts from the active set of the
parent's program in the same position (:func:`.lp.warm_start`): every row of the
relaxation has an opposite (slabs and bounds), so any basis is made dual feasible by taking
the opposite of a constraint whose multiplier is negative -- whatever the box's own
directions are now.  On FK's general-19 at 60 N (the sub-case of docs/fk-cost.md, "The
hull from its parent's active sets") a program took 8 pivots where it took 25, its bound
as tight or tighter (fewer programs stop at the iteration cap): 204,620 -> 195,153
boxes, ~14 % less CPU.  The start is only a start: the bounds are proven from the final
multipliers, as from a cold one.
"""

from __future__ import annotations

from dataclasses import KW_ONLY, dataclass, replace

import numpy as np

from ..expr.affine import affine_forms
from ..expr.compiled import CompiledSystem
from ..interval.linalg import gamma
from ..interval.reductions import all_last, any_last, to_front
from ..interval.rounding import down, up
from .batch import BISECTION_GAIN, Batch
from .bisectors import smear_scores
from .buffer import no_hints
from .lp import StallRule, dual_active_set, warm_start

__all__ = ["HullShare", "PolytopeHull", "affine_rows", "xtaylor_rows", "proven_lower_bounds"]

_TINY = 2.0**-1000
#: warm starts (:class:`PolytopeHull` ``warm``) up to this many variables: a start inverts
#: an ``n x n`` active matrix per program, and the buffer holds ``2n`` integers per
#: direction beside each box's ``2n`` bounds
WARM_MAX_VARIABLES = 100
#: up to this many node values a batch's corners are evaluated in the f + J program with
#: the boxes (one call), above it in f's own program (J at points would cost more)
_CORNERS_WITH_J = 4096
#: when the programs stop before optimality (see the module doc, *Iterations*)
_STALL = StallRule()


def xtaylor_rows(csys: CompiledSystem, lo, hi):
    """The ``4n`` relaxation rows ``G d <= ρ`` of every box (``d = x - lo``).

    Returns ``G`` ``(B, 4n, n)``, ``rho`` ``(B, 4n)`` (rounded up), ``w`` ``(B, n)`` (an upper
    bound of ``hi - lo``) and the ``(B,)`` mask of boxes where the relaxation is valid.
    """
    B = lo.shape[0]
    # every bound is rounded alone whatever the batch, so boxes evaluated side by side get
    # the floats they get alone: the corners ride along in one call (numpy's per-call cost
    # is the cost at small batches); in the f + J program while J at them costs little
    if B * csys.fj.n_nodes <= _CORNERS_WITH_J:
        both = csys.eval_fj(
            np.concatenate([lo, lo, hi]), np.concatenate([hi, lo, hi]), check_domain=True
        )
        flo, fhi = both[0][B:], both[1][B:]
        jlo, jhi, defined = both[2][:B], both[3][:B], both[4][:B]
    else:
        _, _, jlo, jhi, defined = csys.eval_fj(lo, hi, check_domain=True)
        flo, fhi = csys.eval_f_at(np.concatenate([lo, hi]))
    flo_l, fhi_l, flo_h, fhi_h = flo[:B], fhi[:B], flo[B:], fhi[B:]
    with np.errstate(all="ignore"):
        w = up(hi - lo)
        wl = np.maximum(down(hi - lo), 0.0)
        G = np.concatenate([jlo, -jhi, jhi, -jlo], axis=1)
        rho = np.concatenate(
            [
                -flo_l,
                fhi_l,
                up(-flo_h + _row_dot_bound(jhi, wl, w, upper=True)),
                up(fhi_h - _row_dot_bound(jlo, wl, w, upper=False)),
            ],
            axis=1,
        )
    ok = (
        defined
        & np.all(np.isfinite(G), axis=(1, 2))
        & all_last(np.isfinite(rho))
        & all_last(np.isfinite(w))
    )
    return G, rho, w, ok


def affine_rows(csys: CompiledSystem, lo, hi):
    """The ``2n`` rows ``G d <= ρ`` (``d = x - lo``) of the affine forms of ``f``.

    With ``f_i(x) ∈ c₀ + c·(x - m) ± e`` over the box (:func:`certsolve.expr.affine.
    affine_forms`) and ``x - m = d - s``, ``s = m - lo``, a zero of ``f_i`` satisfies

        c·d <= -c₀ + e + c·s,        -c·d <= c₀ + e - c·s,

    right-hand sides bounded above with the rounding of ``s``, of the products and of the
    sums (Higham, Thm 3.1).  Over a wide box the forms keep what X-Taylor's corner rows lose
    on quadratic terms (``x²``: an error of ``r²/2`` against ``2w²``).  Returns ``G``
    ``(B, 2n, n)`` and ``rho`` ``(B, 2n)``; the two rows of a form that is not finite (an
    overflow, a box reaching outside ``f_i``'s domain) are ``0 <= 0``.
    """
    F = affine_forms(csys.f, lo, hi, csys.param_lo, csys.param_hi)
    n = lo.shape[1]
    with np.errstate(all="ignore"):
        s = F.mid - lo  # the exact m - lo is within one rounding of it
        t = F.c * s[:, None, :]
        cs = np.sum(t, axis=2)
        err = gamma(n + 4) * np.sum(np.abs(t), axis=2) + (n + 4) * _TINY
        slack = F.e + err + gamma(6) * (np.abs(F.c0) + F.e + np.abs(cs))
        G = np.concatenate([F.c, -F.c], axis=1)
        rho = np.concatenate([up(cs - F.c0 + slack), up(F.c0 - cs + slack)], axis=1)
    bad = ~(np.isfinite(rho) & all_last(np.isfinite(G)))
    return np.where(bad[:, :, None], 0.0, G), np.where(bad, 0.0, rho)


def _row_dot_bound(J, wl, wh, upper: bool):
    """Rigorous upper (or lower) bound of ``J_i·W`` over ``W ∈ [wl, wh]``, per row ``i``."""
    n = J.shape[-1]
    a, b = J * wl[:, None, :], J * wh[:, None, :]
    t = np.maximum(a, b) if upper else np.minimum(a, b)
    err = gamma(n + 1) * np.sum(np.abs(t), axis=2) + n * _TINY
    s = np.sum(t, axis=2)
    return up(s + err) if upper else down(s - err)


def _sum_bound(t, axis):
    """``(sum, error bound)`` of a floating-point sum of rounded products along ``axis``."""
    k = t.shape[axis]
    if t.ndim > 2 and axis not in (-1, t.ndim - 1):  # same sums, faster (see to_front)
        t, axis = to_front(t, axis), 0
    return np.sum(t, axis=axis), gamma(k + 2) * np.sum(np.abs(t), axis=axis) + (k + 2) * _TINY


def _objective_rows(G, y, sign, j):
    """``g = c + Gᵀy`` (``c = sign·e_j``, 0 where ``j = -1``) of every program, and a bound of
    its rounding error, by batched ``matmul`` (``G`` ``(S, m, n)`` per set, ``y`` ``(S·K, m)``).

    Whatever the order of the additions (BLAS may block them) and with or without fused
    multiply-adds, a floating-point sum of ``m + 1`` products errs by at most
    ``γ_{m+1} Σ|terms|`` (Higham, Thm 3.1 and §3.1), plus the underflow unit per product
    (covered by ``_TINY``); ``Σ|terms|`` is itself computed (a dot product of nonnegative
    terms, plus the exact 1 of ``c``), at least ``1 - γ_{m+1}`` times its exact value, so
    ``γ_{2m+4}`` times it (``gamma`` rounded up generously) bounds the error.
    """
    S, m, n = G.shape
    L = y.shape[0]
    yv = y.reshape(S, L // S, m)
    g = np.matmul(yv, G).reshape(L, n)
    mag = np.matmul(np.abs(yv), np.abs(G)).reshape(L, n)
    has = j >= 0
    rows = np.flatnonzero(has)
    g[rows, j[has]] += sign[has]
    mag[rows, j[has]] += 1.0
    return g, up(gamma(2 * m + 4) * mag) + (m + 2) * _TINY


def proven_lower_bounds(G, rho, w, y, sign, j):
    """Proven lower bounds of ``sign·d_j`` over ``{d ∈ [0, w] : G d <= ρ}``, from ``y >= 0``.

    ``G`` ``(S, m, n)``, ``rho`` ``(S, m)`` and ``w`` ``(S, n)`` are ``S`` sets; ``y``
    ``(L, m)``, ``sign`` ``(L,)`` of ±1 and ``j`` ``(L,)`` variable indices are ``L = S·K``
    programs, ``K`` per set (program ``l`` uses set ``l // K``); ``j = -1`` means ``c = 0``: a
    positive bound then proves the set empty.  Rounding: each sum and dot product is enlarged
    by its a priori error bound (Higham, Thm 3.1) and every final operation is rounded
    outward.
    """
    S, m, _ = G.shape
    K = y.shape[0] // S
    g, gerr = _objective_rows(G, y, sign, j)
    part = np.minimum(down(g - gerr), 0.0) * np.repeat(w, K, axis=0)
    low, low_err = _sum_bound(part, axis=1)
    yrho, yrho_err = _sum_bound((y.reshape(S, K, m) * rho[:, None, :]).reshape(-1, m), axis=1)
    return down(down(low - low_err) - up(yrho + yrho_err))


@dataclass
class HullShare:
    """Whether the polytope hull pays in a search, learnt from what it does there.

    ``share`` is a running share of the boxes the hull contracted *usefully*: proven empty,
    or their volume over the variables a bisection may still split at most ``ratio`` times
    what it was (:func:`.batch.progress_gain`).  After a call that contracted ``m`` boxes,
    ``u`` of them usefully,

        share <- a^m share + (1 - a^m) u / m,        a = 1 - 1/window,

    an exponential mean over the last ~``window`` boxes contracted.  While ``share >=
    threshold`` the hull contracts every box; below, one box in ``sample`` (those whose
    position in the count of boxes offered is a multiple of ``sample``), whose outcomes keep
    the share current, so a hull that becomes useful deeper in the search comes back.  The
    plan is a function of the state and the batch size only: a search repeated with the
    same batches makes the same choices.

    Plain data, like :class:`.shaving.AdaptiveCount`: the solver keeps it in its search
    state, so a checkpoint saves it and a worker task starts from its search's.  It only
    chooses which boxes a sound contractor sees, never what is kept.

    The defaults: the share of boxes the hull halved was 3-25 % on the files where it did
    not pay for itself (Trigexp1-024, Prolog-icse, CountercurrentReactors2-6, Neveu1), 63-71
    % where it did (katsura-6, Brown-05, brown5a, kolev36), 36-47 % on both sides.  On
    those eight and Caprasse and Rose (CPU s, one process, min of 2 runs, against the hull
    on every box: 14.6 s), threshold 0.3 and sample 8 took 12.6 s, 0.45 and 16 11.8 s (0.55:
    12.0; window 64: 11.3 against 10.8 in a second sweep; sample 32: 10.7, within the
    noise); a hull that only samples (threshold > 1) 20.0 s (katsura-6 108,295 boxes).  Near
    the root the hull rarely halves a box (katsura-6: the share falls to 0.15 in the first
    rounds, then comes back above 0.9), hence the sample.
    """

    _: KW_ONLY
    window: int = 32
    threshold: float = 0.45
    ratio: float = 0.5
    sample: int = 16
    share: float = 1.0  #: the running share (1: contract every box until told otherwise)
    boxes: int = 0  #: boxes offered so far

    def __post_init__(self) -> None:
        if self.window < 1 or self.sample < 1 or not 0.0 < self.ratio < 1.0:
            raise ValueError("need window >= 1, sample >= 1 and 0 < ratio < 1")

    @property
    def gain(self) -> float:
        """The log-volume change at or below which a contraction is useful."""
        return float(np.log(self.ratio))

    def plan(self, boxes: int) -> np.ndarray:
        """Which of the next ``boxes`` boxes the hull contracts (a mask)."""
        if self.share >= self.threshold:
            return np.ones(boxes, dtype=bool)
        return (self.boxes + np.arange(boxes)) % self.sample == 0

    def done(self, useful: np.ndarray, boxes: int) -> None:
        """After :meth:`plan` ``(boxes)``: ``useful`` says, for each box contracted, whether
        the contraction was useful."""
        m = int(useful.size)
        if m:
            keep = (1.0 - 1.0 / self.window) ** m
            self.share = keep * self.share + (1.0 - keep) * float(np.mean(useful))
        self.boxes += int(boxes)

    def describe(self) -> str:
        """The settings (not the learnt state), for the checkpoint fingerprint."""
        return (
            f"HullShare(window={self.window}, threshold={self.threshold!r}, "
            f"ratio={self.ratio!r}, sample={self.sample})"
        )


class PolytopeHull:
    """Contract boxes to the proven hull of their linear relaxation: the X-Taylor rows
    (:func:`xtaylor_rows`) and, with ``affine``, the rows of the affine forms
    (:func:`affine_rows`).

    ``adaptive``: on the boxes a :class:`HullShare` plans, the search's (``batch.hull``,
    created by :meth:`hull_learner` from ``share``, its settings: default
    ``HullShare()``), among the *stalled* ones -- the rows the round has not yet shrunk as
    much as a bisection (:data:`.batch.BISECTION_GAIN`, from the boxes the round began
    with): a row HC4 and Newton have halved goes back to the buffer whatever the hull
    does (:class:`.pipeline.FixPoint`), and its next round contracts the smaller box.
    Without a learnt state, or with ``adaptive=False``, every box.

    ``always`` (per variable): every box narrower than these widths is contracted whatever
    the share plans, and the share plans and learns from the other boxes only (forward
    kinematics: :meth:`.FKFormulation.hull_widths`, where the hull's yield follows the
    box's width and a share averaging narrow and wide boxes sat at its threshold).
    """

    def __init__(
        self,
        csys: CompiledSystem,
        directions: int = 3,
        max_iter: int = 40,
        affine: bool = True,
        stall: StallRule | None = _STALL,
        adaptive: bool = True,
        share: HullShare | None = None,
        always: np.ndarray | None = None,
        warm: bool = True,
    ):
        self.csys = csys
        #: start each box's programs from its parent's last active sets (its hint)
        self.warm = bool(warm)
        self.adaptive = bool(adaptive)
        #: per variable, the widths under which a box is contracted whatever the share plans
        self.always = None if always is None else np.asarray(always, dtype=float)
        #: the settings of the learnt state a search starts from (:meth:`hull_learner`)
        self.share = HullShare() if share is None else replace(share)
        self.affine = bool(affine)
        self.directions = int(directions)
        self.max_iter = int(max_iter)
        #: programs still creeping after ``stall.start`` iterations stop (None: never)
        self.stall = stall

    @staticmethod
    def _pair(m: int, n: int, slabs: tuple[tuple[int, int, int], ...] = ()) -> np.ndarray:
        """The opposite constraint of every constraint (``g_pair = -g``), or -1: the bounds
        (``d_k <= w_k`` <-> ``-d_k <= 0``, after the ``m`` rows) and, for each ``(a, b, q)``
        of ``slabs``, rows ``a + i`` <-> ``b + i`` (``i < q``)."""
        pair = np.full(m + 2 * n, -1)
        pair[m : m + n] = m + n + np.arange(n)
        pair[m + n :] = m + np.arange(n)
        for a, b, q in slabs:
            pair[a : a + q] = b + np.arange(q)
            pair[b : b + q] = a + np.arange(q)
        return pair

    def hint_width(self, n: int) -> int:
        """The width of a box's hint: the active sets of its ``2·directions`` programs
        (``n`` constraints each)."""
        return 2 * min(self.directions, n) * n

    def contract(self, lo, hi):
        """Returns ``(lo, hi, empty)`` for a batch of boxes ``(B, n)``."""
        return self.contract_hinted(lo, hi)[:3]

    def contract_hinted(self, lo, hi, hints=None):
        """Returns ``(lo, hi, empty, hints)`` for a batch of boxes ``(B, n)`` and their
        hints (or ``None``): each program starts from its box's hint, where that is a basis
        (:func:`.lp.warm_start`; module doc, *Warm starts*), and the new hints are the
        programs' last active sets (``-1`` rows where no program ran)."""
        B, n = lo.shape
        lo, hi = lo.copy(), hi.copy()
        empty = np.zeros(B, dtype=bool)
        new_hints = no_hints(B, self.hint_width(n))
        if hints is not None and hints.shape[1] != new_hints.shape[1]:
            hints = None
        if B == 0:
            return lo, hi, empty, new_hints
        G, rho, w, ok = xtaylor_rows(self.csys, lo, hi)
        q = G.shape[1] // 4
        # the rows' slabs: J̲ at the lower corner <-> at the upper one, J̄ likewise
        slabs: tuple[tuple[int, int, int], ...] = ((0, 3 * q, q), (q, 2 * q, q))
        if self.affine:
            # the affine rows hold wherever they are finite: a box without valid X-Taylor
            # rows (f not differentiable everywhere on it) keeps its affine rows alone
            G = np.where(ok[:, None, None], G, 0.0)
            rho = np.where(ok[:, None], rho, 0.0)
            GA, rhoA = affine_rows(self.csys, lo, hi)
            G, rho = np.concatenate([G, GA], 1), np.concatenate([rho, rhoA], 1)
            slabs += ((4 * q, 5 * q, q),)  # c·d and -c·d of each affine form
            ok = all_last(np.isfinite(w)) & np.any(GA != 0.0, axis=(1, 2))
        idx = np.flatnonzero(ok)
        if idx.size == 0:
            return lo, hi, empty, new_hints
        G, rho, w = G[idx], rho[idx], w[idx]
        S, m = rho.shape
        # the programs: min d_j and max d_j for the top-smear variables of each box
        t = min(self.directions, n)
        jmag = np.maximum(np.abs(G[:, :n]), np.abs(G[:, n : 2 * n]))
        score = smear_scores(np.zeros_like(w), w, jmag, jmag)
        top = np.argsort(-score, axis=1)[:, :t]
        K = 2 * t
        j = np.concatenate([top, top], axis=1).ravel()
        sign = np.tile(np.repeat([1.0, -1.0], t), S)
        L = S * K
        # constraints: the rows, then d <= w (index m + k), then -d <= 0 (index m + n + k);
        # start at the corner d_j = 0 (min) or d_j = w_j (max), the other d_k = 0
        eye = np.eye(n)
        GA = np.concatenate(
            [G, np.broadcast_to(eye, (S, n, n)), np.broadcast_to(-eye, (S, n, n))], 1
        )
        betaA = np.concatenate([rho, w, np.zeros((S, n))], axis=1)
        c = np.zeros((L, n))
        c[np.arange(L), j] = sign
        W0 = np.tile(m + n + np.arange(n), (L, 1))
        upper = np.flatnonzero(sign < 0)
        W0[upper, j[upper]] = m + j[upper]
        lam0 = np.abs(c)
        box = np.repeat(np.arange(S), K)
        N0inv = np.swapaxes(GA[box[:, None], W0], 1, 2)  # a signed permutation
        pair = self._pair(m, n, slabs)
        if hints is not None:
            # each program starts from its hint's active set where that is a basis
            Wh = hints[idx].reshape(L, n).astype(np.intp)
            warm, W_w, lam_w, inv_w = warm_start(GA, c, Wh, pair)
            # in C order: the lanes' matrix products keep this layout, and their last bits
            # depend on it
            N0inv = np.ascontiguousarray(N0inv)
            W0[warm], lam0[warm], N0inv[warm] = W_w, lam_w, inv_w
        with np.errstate(all="ignore"):
            # a program whose objective passes the far side of the box (min d_j > w_j or
            # max d_j < 0) makes the box empty: the box's other programs stop
            wj = w[box, j]
            cutoff = np.where(sign > 0, wj, 0.0) + 1e-9 * wj
            lp = dual_active_set(
                GA, betaA, c, W0, lam0, N0inv, pair=pair, cutoff=cutoff,
                stall=self.stall, scale=wj,
                max_iter=self.max_iter,
            )  # fmt: skip
            bound = proven_lower_bounds(
                G, rho, w, lp.y[:, :m], sign, np.where(lp.infeasible, -1, j)
            )
        bound = np.where(np.isfinite(bound), bound, -np.inf)
        emp = np.zeros(S, dtype=bool)
        np.logical_or.at(emp, box, lp.infeasible & (bound > 0.0))
        dlo = np.zeros((S, n))
        dhi = w.copy()
        rows = ~lp.infeasible & (sign > 0)
        np.maximum.at(dlo, (box[rows], j[rows]), bound[rows])
        rows = ~lp.infeasible & (sign < 0)
        np.minimum.at(dhi, (box[rows], j[rows]), -bound[rows])
        with np.errstate(all="ignore"):
            base = lo[idx]
            nlo = np.fmax(base, down(base + dlo))
            nhi = np.fmin(hi[idx], up(base + dhi))
        emp |= any_last(nlo > nhi)
        lo[idx] = np.where(emp[:, None], lo[idx], nlo)
        hi[idx] = np.where(emp[:, None], hi[idx], nhi)
        empty[idx] = emp
        if n <= WARM_MAX_VARIABLES:  # (the hints' int16 holds the indices of 8n rows)
            active = np.where(lp.infeasible[:, None], -1, lp.active)
            new_hints[idx] = active.reshape(S, K * n)
        return lo, hi, empty, new_hints

    def hull_learner(self) -> HullShare | None:
        """A fresh learnt state for a search (``adaptive``: a copy of ``share``), else
        ``None``."""
        return replace(self.share) if self.adaptive else None

    def apply(self, batch: Batch) -> None:
        learnt: HullShare | None = batch.hull if self.adaptive else None
        if learnt is None:
            every = np.ones(batch.size, dtype=bool)
            lo, hi, empty, hints = self.contract_hinted(
                batch.lo, batch.hi, self._hints_of(batch, every)
            )
            batch.with_rows(every, lo, hi, empty)
            self._leave_hints(batch, every, hints)
            return
        if self.always is None:
            sure = np.zeros(batch.size, dtype=bool)
        else:
            sure = all_last(batch.hi - batch.lo < self.always)
        offered = np.flatnonzero(~sure)  # the boxes the share plans and learns from
        rows = sure.copy()
        rows[offered[learnt.plan(offered.size)]] = True
        if rows.any():  # the stalled rows (class docstring)
            at = batch.ids
            rows &= batch.gain(batch.start_lo[at], batch.start_hi[at]) > BISECTION_GAIN
        if not rows.any():
            learnt.done(np.zeros(0, dtype=bool), offered.size)
            return
        lo, hi = (batch.lo, batch.hi) if rows.all() else (batch.lo[rows], batch.hi[rows])
        clo, chi, cemp, hints = self.contract_hinted(lo, hi, self._hints_of(batch, rows))
        gain = batch.progress(lo, hi, clo, chi)
        learnt.done((cemp | (gain <= learnt.gain))[~sure[rows]], offered.size)
        batch.with_rows(rows, clo, chi, cemp)
        self._leave_hints(batch, rows, hints)

    def _warm(self, batch: Batch) -> bool:
        return self.warm and batch.lo.shape[1] <= WARM_MAX_VARIABLES

    def _hints_of(self, batch: Batch, rows) -> np.ndarray | None:
        return batch.row_hints(rows) if self._warm(batch) else None

    def _leave_hints(self, batch: Batch, rows, hints: np.ndarray) -> None:
        if self._warm(batch):
            batch.set_hints(rows, hints)

    def describe(self) -> str:
        return (
            f"PolytopeHull(directions={self.directions}, max_iter={self.max_iter}, "
            f"affine={self.affine}, stall={self.stall!r}, adaptive={self.adaptive}, "
            f"share={self.share.describe()}"
            + ("" if self.always is None else f", always={self.always.tolist()!r}")
            + ("" if self.warm else ", warm=False")
            + ")"
        )
