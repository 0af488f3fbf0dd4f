"""A batched dual active-set method for many tiny linear programs at once.

Every program of the batch reads

    minimise  c·x   subject to   g_t·x <= β_t   (t = 1..M),

with ``n`` variables and ``M >= n`` constraints (the box bounds among them).  The method
keeps an *active set* ``W`` of ``n`` constraints whose normals span ``R^n``, the vertex
``x = N_W^{-1} β_W`` and the multipliers ``λ = -N_W^{-T} c``.  It starts dual feasible
(``λ >= 0``) and, like the dual simplex method, repeatedly brings the most violated
constraint ``t*`` into ``W``; the constraint leaving ``W`` is chosen by the ratio test
``min λ_k / α_k`` over ``α = N_W^{-T} g_{t*} > 0``, which keeps ``λ >= 0``.  When no
``α_k`` is positive the program is infeasible, and ``(1 at t*, -α on W)`` is a Farkas
certificate.  ``N_W^{-1}`` follows by a rank-one update (its pivot is ``α_k > 0``).

Box bounds come in pairs (``-d_k <= 0``, ``d_k <= w_k``), and so do the relaxation's rows
(slabs ``-β' <= g·d <= β``): with ``pair`` the ratio test is the *bound-flipping*
(long-step) one of the dual simplex method: a constraint whose multiplier reaches zero swaps
for its opposite, and the step goes on, while the dual objective still increases.  One
iteration then moves a vertex across a whole slab where the plain test needs one pivot per
side; on katsura-6 flipping the bounds alone took the median program from ~11 iterations to
~7 (and the plain test cycles on some programs); flipping the rows' slabs too, more of FK's
general-19 programs converge within the 40-pivot cap (its search 42,620 -> 18,656 boxes).
A pair is also priced once: one matmul column gives ``g·x`` for both of its constraints.
With ``cutoff`` the programs of a set stop as soon as one of them proves it empty (a Farkas
ray, or a dual objective past the cutoff). A :class:`StallRule` (with ``stall``) stops the
programs whose objective has stopped moving: the dual objective only grows, and the last
iterations of a program that creeps (degenerate pivots, or 22 variables where the optimum is
~60 pivots away) buy little bound for their cost.

Nothing here needs to be exact: the caller turns the multipliers into *rigorous* bounds
(any ``y >= 0`` gives a valid bound, Neumaier & Shcherbina 2004), so rounding, cycling or
the iteration cap can only weaken a bound, never make it wrong.  Programs sharing a
constraint set (one box, several objectives) share one ``(M, n)`` matrix: the violations of
all of them come from one batched ``matmul`` per iteration.  The programs of the sets still
in work sit side by side in lanes (:class:`_Lanes`) and every step runs on all of them, no
gather and scatter of the running ones: a program that finished has its multipliers recorded
and its lane pivots on garbage that nothing reads, until a quarter of the sets have finished
and the lanes are compacted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..interval.reductions import all_last, any_last, count_last, max_last

__all__ = ["LPBatch", "StallRule", "dual_active_set", "warm_start"]


@dataclass(frozen=True, kw_only=True)
class StallRule:
    """When programs stop before optimality (their multipliers as they are: valid, only
    less tight).

    From iteration ``start`` on, every ``window`` iterations, a program whose objective
    ``c·x`` grew by less than ``fraction · scale`` since the previous check stops.  After
    ``few_after`` iterations the whole batch stops once fewer than ``few`` programs run: an
    iteration costs ~25 numpy calls whatever its size, so a long tail of a few programs
    costs a small search (Brown-10: ~5 boxes a round) more than its bounds save.
    """

    start: int = 20
    window: int = 5
    fraction: float = 0.005
    few: int = 64
    few_after: int = 15


@dataclass(kw_only=True)
class LPBatch:
    """Multipliers of a batch of programs (``L`` programs, ``M`` constraints each)."""

    y: np.ndarray  # (L, M) multipliers >= 0: approximately optimal, or a Farkas ray
    infeasible: np.ndarray  # (L,) y is a Farkas certificate (the objective is not used)
    iterations: int  # iterations of the longest-running program
    #: (L, n) each program's last active set: where a program on nearby data starts
    #: (:func:`warm_start`)
    active: np.ndarray


def dual_active_set(
    G: np.ndarray,
    beta: np.ndarray,
    c: np.ndarray,
    W0: np.ndarray,
    lam0: np.ndarray,
    Ninv0: np.ndarray | None = None,
    *,
    pair: np.ndarray | None = None,
    cutoff: np.ndarray | None = None,
    stall: StallRule | None = None,
    scale: np.ndarray | None = None,
    max_iter: int = 15,
    tol: float = 1e-9,
) -> LPBatch:
    """Solve ``S·K`` programs: ``K`` objectives for each of ``S`` constraint sets.

    ``G`` ``(S, M, n)`` and ``beta`` ``(S, M)`` are the constraint sets; program
    ``l = s·K + k`` uses set ``s``, objective ``c[l]`` ``(n,)`` and starts from the active set
    ``W0[l]`` (``n`` constraint indices) with multipliers ``lam0[l] >= 0`` such that
    ``c + Σ_k lam0_k g_{W0_k} = 0`` (dual feasible); ``Ninv0`` is the inverse of the starting
    active matrix (computed if not given).

    ``pair`` ``(M,)``: the opposite constraint of each one (``g_{pair[t]} = -g_t`` in every
    set, ``pair[pair[t]] = t``) or -1; given, the ratio test flips bounds (see the module
    doc) and one matmul column prices both constraints of a pair.  ``cutoff`` ``(L,)``: a
    program whose dual objective ``c·x`` (a lower bound of its minimum) exceeds its cutoff
    proves its set empty for the caller; the set's other programs then stop, their
    multipliers as they are (valid, only less tight).  ``stall`` with ``scale`` ``(L,)``
    (each program's yardstick, the width of the variable it bounds): programs that creep
    stop (:class:`StallRule`); without them, programs run to optimality or ``max_iter``.
    """
    L, n = c.shape
    S, M, _ = G.shape
    K = L // S
    price = _Pricing.of(G, beta, pair)
    Gf = G.reshape(S * M, n)
    bf = beta.reshape(S * M)
    gap = None
    if pair is not None:
        gap = np.where(pair >= 0, beta + beta[:, np.maximum(pair, 0)], np.inf).reshape(S * M)
        gap = np.where(gap >= 0.0, gap, np.inf)  # an empty slab: no flip past it
    with np.errstate(all="ignore"):
        lanes = _Lanes.start(Gf, bf, c, W0, lam0, Ninv0, cutoff, scale, price)
    out = _Results(L, n, M)
    proven = np.zeros(S, dtype=bool)  # a program of the set proved it empty: all stop
    checked = None  # the objectives at the last stall check
    iterations = 0
    with np.errstate(all="ignore"):
        out.finish(lanes, ~all_last(np.isfinite(lanes.Ns.reshape(L, n * n))))
        while iterations < max_iter:
            iterations += 1
            if cutoff is not None or stall is not None:
                obj = np.einsum("li,li->l", lanes.c, lanes.x)
            if cutoff is not None:
                proven[lanes.set_of[(obj > lanes.cutoff) & lanes.running]] = True
            stop = proven[lanes.set_of]
            if stall is not None and scale is not None and iterations >= stall.start:
                if (iterations - stall.start) % stall.window == 0:
                    if checked is not None:
                        stop |= ~(obj - checked > stall.fraction * lanes.scale)
                    checked = obj
            out.finish(lanes, stop & lanes.running)
            live = int(np.count_nonzero(lanes.running))
            if live == 0:
                break
            if stall is not None and iterations > stall.few_after and live < stall.few:
                break
            if lanes.sets > 1 and 4 * live <= 3 * lanes.size:  # drop the finished sets
                keep = any_last(lanes.running.reshape(-1, K))
                if 4 * np.count_nonzero(keep) <= 3 * lanes.sets:
                    lanes = lanes.only(keep)
                    if checked is not None:
                        checked = checked[np.repeat(keep, K)]
            # normalised violations; the most violated constraint enters
            V = price.violations(lanes)
            V[lanes.ar[:, None], price.rank[lanes.W]] = -np.inf
            t = np.argmax(V, axis=1)
            vmax = V[lanes.ar, t]
            t = price.order[t]
            out.finish(lanes, (vmax <= tol * (1.0 + max_last(np.abs(lanes.x)))) & lanes.running)
            if not lanes.running.any():
                break
            delta = vmax * price.norms[lanes.set_of, t]  # g_t·x - β_t > 0
            _pivot(lanes, out, t, delta, Gf, bf, gap, pair, proven)
    out.finish(lanes, lanes.running)
    return out.result(iterations)


def warm_start(
    G: np.ndarray,
    c: np.ndarray,
    W: np.ndarray,
    pair: np.ndarray | None = None,
    tol: float = 1e-9,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Starts for :func:`dual_active_set` from earlier active sets ``W`` ``(L, n)`` (a
    program's on nearby data, e.g. the parent box's; ``-1``: none).

    Each ``W_l`` is kept where it is a basis of program ``l``'s constraints (``n``
    distinct indices, ``N_W`` invertible) and dual feasible for its objective: the
    multipliers ``λ = -N_W^{-T} c`` are ``>= -tol·max|λ|`` (those slightly below zero are
    set to zero: the method only needs them approximately, as every multiplier it returns
    is made rigorous by the caller).  With ``pair`` (as :func:`dual_active_set`'s), a
    constraint whose multiplier is negative is first swapped for its opposite, so a basis
    of paired constraints is always dual feasible.  Returns the programs so started (their
    indices) and, for each, its active set (swapped), ``λ`` ``(n,)`` and ``N_W^{-1}``
    ``(n, n)``: the caller writes them over its own starts.
    """
    L, n = c.shape
    S, M, _ = G.shape
    ok = all_last((W >= 0) & (W < M))
    if n > 1:
        ok &= all_last(np.diff(np.sort(W, axis=1), axis=1) != 0)
    idx = np.flatnonzero(ok)
    W = W[idx]
    N = G[(idx // (L // S))[:, None], W]
    with np.errstate(all="ignore"):
        try:
            Ni = np.linalg.inv(N)
        except np.linalg.LinAlgError:  # an exactly singular one among them: leave those out
            det = np.linalg.det(N)
            regular = np.isfinite(det) & (det != 0.0)
            Ni = np.full_like(N, np.nan)
            Ni[regular] = np.linalg.inv(N[regular])
        # λ_k = -Σ_i (N^{-1})_{ik} c_i
        lam = -np.einsum("lik,li->lk", Ni, c[idx])
        if pair is not None:
            # a constraint with a negative multiplier swaps for its opposite (g -> -g):
            # its multiplier and its column of N^{-1} change sign, c + Σ λ g = 0 holds
            flip = (lam < 0.0) & (pair[W] >= 0)
            W = np.where(flip, pair[W], W)
            sgn = np.where(flip, -1.0, 1.0)
            lam *= sgn
            Ni *= sgn[:, None, :]
        good = all_last(np.isfinite(lam)) & np.all(np.isfinite(Ni), axis=(1, 2))
        good &= all_last(lam >= -tol * (1.0 + max_last(np.abs(lam)))[:, None])
    return idx[good], W[good], np.maximum(lam[good], 0.0), Ni[good]


@dataclass(kw_only=True)
class _Pricing:
    """The normalised violations ``(g_t·x - β_t) / |g_t|`` of every constraint, one matmul
    column for both constraints of an opposite pair (``g_{pair} = -g_t``: the twin's
    violation is ``-(g_t·x)/|g_t| - β_pair/|g_t|``).

    The matmul's columns are the lower constraint of every pair, then the unpaired ones;
    the twins follow in the violations: ``order`` maps a column of the violations to its
    constraint, ``rank`` a constraint to its column.
    """

    norms: np.ndarray  # (S, M) |g_t|
    GT: np.ndarray  # (S, n, F) the priced normals, normalised, transposed
    beta_first: np.ndarray  # (S, F) their normalised right-hand sides
    beta_twin: np.ndarray  # (S, T) the twins' (T pairs: the first T columns)
    order: np.ndarray  # (M,) column of the violations -> constraint
    rank: np.ndarray  # (M,) constraint -> column

    @classmethod
    def of(cls, G: np.ndarray, beta: np.ndarray, pair: np.ndarray | None) -> _Pricing:
        S, M, _ = G.shape
        t = np.arange(M)
        pairs = np.full(M, -1) if pair is None else np.asarray(pair)
        paired = pairs >= 0
        if np.any(pairs[pairs[paired]] != t[paired]):
            raise ValueError("pair: pair[pair[t]] must be t")
        lower = np.flatnonzero(paired & (t < pairs))
        first = np.concatenate([lower, np.flatnonzero(~paired)])
        order = np.concatenate([first, pairs[lower]])
        rank = np.empty(M, dtype=np.intp)
        rank[order] = t
        norms = np.sqrt(np.einsum("smn,smn->sm", G, G))
        inv_norm = 1.0 / np.where(norms > 0.0, norms, 1.0)
        beta_n = beta * inv_norm
        GT = np.ascontiguousarray(np.swapaxes(G[:, first] * inv_norm[:, first, None], 1, 2))
        return cls(
            norms=norms, GT=GT, beta_first=beta_n[:, first], beta_twin=beta_n[:, pairs[lower]],
            order=order, rank=rank,
        )  # fmt: skip

    def violations(self, lanes: _Lanes) -> np.ndarray:
        """``(lanes, M)`` violations of every lane's vertex, in the columns' order."""
        S, n, F = lanes.GT.shape
        T = lanes.beta_twin.shape[1]
        K = lanes.size // S
        P = np.matmul(lanes.x.reshape(S, K, n), lanes.GT)
        V = np.empty((S, K, F + T))
        np.subtract(P, lanes.beta_first[:, None, :], out=V[:, :, :F])
        np.negative(P[:, :, :T], out=V[:, :, F:])
        V[:, :, F:] -= lanes.beta_twin[:, None, :]
        return V.reshape(lanes.size, F + T)


@dataclass(kw_only=True)
class _Lanes:
    """The programs in work, a whole number of sets (``K`` programs each), side by side.

    A program that finished (its multipliers recorded, :class:`_Results`) keeps its lane
    until its whole set has finished and the lanes are compacted: its lane goes on pivoting
    on garbage that nothing reads, where masking it out would cost every iteration numpy
    calls.  The inverse of the active matrix is kept with its columns' signs apart: ``Ns ·
    diag(sig)`` is ``N_W^{-1}``, so a bound flip (its row of ``N_W`` changes sign) flips one
    sign, not a column of ``Ns`` (exact: the same floats up to sign).
    """

    prog: np.ndarray  # (R,) each lane's program
    set_of: np.ndarray  # (R,) each lane's constraint set
    x: np.ndarray  # (R, n) vertex
    Ns: np.ndarray  # (R, n, n) N_W^{-1} up to its columns' signs
    sig: np.ndarray  # (R, n) the signs
    lam: np.ndarray  # (R, n) multipliers of W
    W: np.ndarray  # (R, n) active constraints
    running: np.ndarray  # (R,) not finished
    c: np.ndarray  # (R, n) objectives
    cutoff: np.ndarray  # (R,) (inf: none)
    scale: np.ndarray  # (R,) the stall rule's yardsticks
    ar: np.ndarray  # (R,) 0, 1, ..., R - 1
    base: np.ndarray  # (R,) each lane's first row in the flattened constraint sets
    GT: np.ndarray  # per set in work: the priced normals (see _Pricing)
    beta_first: np.ndarray
    beta_twin: np.ndarray
    M: int
    _scratch: np.ndarray | None = None

    def scratch(self) -> np.ndarray:
        """An ``(R, n, n)`` array to write into (one allocation per compaction, not one an
        iteration: past a few MB each allocation is fresh pages from the system)."""
        if self._scratch is None:
            self._scratch = np.empty_like(self.Ns)
        return self._scratch

    @classmethod
    def start(cls, Gf, bf, c, W0, lam0, Ninv0, cutoff, scale, price: _Pricing) -> _Lanes:
        L, n = c.shape
        S, M = price.norms.shape
        set_of = np.repeat(np.arange(S), L // S)
        W = W0.copy()
        at = (set_of * M)[:, None] + W
        Ns = np.linalg.inv(Gf[at]) if Ninv0 is None else Ninv0.astype(float)
        return cls(
            prog=np.arange(L), set_of=set_of, x=np.matmul(Ns, bf[at][:, :, None])[:, :, 0], Ns=Ns,
            sig=np.ones((L, n)), lam=lam0.astype(float), W=W, running=np.ones(L, dtype=bool),
            c=c, cutoff=np.full(L, np.inf) if cutoff is None else cutoff,
            scale=np.ones(L) if scale is None else scale, ar=np.arange(L), base=set_of * M,
            GT=price.GT, beta_first=price.beta_first, beta_twin=price.beta_twin, M=M,
        )  # fmt: skip

    @property
    def size(self) -> int:
        return int(self.prog.size)

    @property
    def sets(self) -> int:
        return int(self.GT.shape[0])

    def only(self, keep: np.ndarray) -> _Lanes:
        """The lanes of the sets ``keep`` (a mask over the sets in work)."""
        rows = np.repeat(keep, self.size // self.sets)
        return _Lanes(
            prog=self.prog[rows], set_of=self.set_of[rows], x=self.x[rows], Ns=self.Ns[rows],
            sig=self.sig[rows], lam=self.lam[rows], W=self.W[rows], running=self.running[rows],
            c=self.c[rows], cutoff=self.cutoff[rows], scale=self.scale[rows],
            ar=self.ar[: np.count_nonzero(rows)], base=self.base[rows], GT=self.GT[keep],
            beta_first=self.beta_first[keep], beta_twin=self.beta_twin[keep], M=self.M,
        )  # fmt: skip


class _Results:
    """Each program's multipliers, recorded when it finishes."""

    def __init__(self, L: int, n: int, M: int):
        self.W = np.zeros((L, n), dtype=np.intp)
        self.lam = np.zeros((L, n))
        self.y = np.zeros((L, M))
        self.infeasible = np.zeros(L, dtype=bool)

    def finish(self, lanes: _Lanes, mask: np.ndarray) -> None:
        """The lanes of ``mask`` finish with their active set and multipliers as they are."""
        f = np.flatnonzero(mask)
        if f.size:
            p = lanes.prog[f]
            self.W[p] = lanes.W[f]
            self.lam[p] = lanes.lam[f]
            lanes.running[f] = False

    def farkas(self, lanes: _Lanes, mask: np.ndarray, t: np.ndarray, alpha: np.ndarray) -> None:
        """The lanes of ``mask`` proved their program infeasible: ``(1 at t, -α on W)``."""
        f = np.flatnonzero(mask)
        rows = np.arange(f.size)
        fy = np.zeros((f.size, self.y.shape[1]))
        fy[rows, t[f]] = 1.0
        np.add.at(fy, (rows[:, None], lanes.W[f]), -alpha[f])
        p = lanes.prog[f]
        self.y[p] = np.maximum(fy, 0.0)
        self.infeasible[p] = True
        lanes.running[f] = False

    def result(self, iterations: int) -> LPBatch:
        feasible = np.flatnonzero(~self.infeasible)
        y = self.y
        np.add.at(y, (feasible[:, None], self.W[feasible]), np.maximum(self.lam[feasible], 0.0))
        return LPBatch(
            y=np.where(np.isfinite(y), y, 0.0),
            infeasible=self.infeasible,
            iterations=iterations,
            active=self.W,
        )


def _pivot(lanes: _Lanes, out: _Results, t, delta, Gf, bf, gap, pair, proven) -> None:
    """One dual step on every lane: ``t`` enters, the ratio test picks what leaves."""
    ar = lanes.ar
    base = lanes.base
    # g_t = Σ_k α_k g_{W_k}; numpy's matmul, not einsum: the same sums, 2-30x faster here
    alpha = np.matmul(Gf[base + t][:, None, :], lanes.Ns)[:, 0, :]
    alpha *= lanes.sig
    pos = alpha > 1e-12 * max_last(np.abs(alpha))[:, None]
    ratio = np.where(pos, lanes.lam / alpha, np.inf)
    farkas = lanes.running & ~any_last(pos)
    if gap is None:
        k = np.argmin(ratio, axis=1)
        flip = None
    else:
        k, flip = _long_step(ratio, pos, alpha, lanes.W, gap, base, delta)
    if farkas.any():  # every α_k <= 0: infeasible
        out.farkas(lanes, farkas, t, alpha)
        proven[lanes.set_of[farkas]] = True
    lam = lanes.lam
    if flip is not None and flip.any():
        # the flipped bounds change sides: their row of N, α and λ change sign
        lanes.W = np.where(flip, pair[lanes.W], lanes.W)
        sgn = np.where(flip, -1.0, 1.0)
        lanes.sig *= sgn
        alpha *= sgn
        lam = lam * sgn
    ak = alpha[ar, k]
    s = lam[ar, k] / ak
    lam = np.maximum(lam - s[:, None] * alpha, 0.0)
    lam[ar, k] = s
    lanes.lam = lam
    lanes.W[ar, k] = t
    # N' = N + e_k (g_t - g_k)ᵀ  =>  N'^{-1} = N^{-1} - N^{-1} e_k (α - e_k)ᵀ / α_k
    col = lanes.Ns[ar, :, k] * lanes.sig[ar, k][:, None]
    alpha[ar, k] -= 1.0
    r = alpha / ak[:, None]
    r *= lanes.sig
    outer = lanes.scratch()
    np.multiply(col[:, :, None], r[:, None, :], out=outer)
    lanes.Ns -= outer
    bW = bf[base[:, None] + lanes.W] * lanes.sig
    lanes.x = np.matmul(lanes.Ns, bW[:, :, None])[:, :, 0]
    out.finish(lanes, ~all_last(np.isfinite(lanes.x)) & lanes.running)


def _long_step(ratio, pos, alpha, Wr, gap, base, delta):
    """The bound-flipping ("long-step") ratio test of the dual simplex method.

    The breakpoints ``λ_k / α_k`` (``α_k > 0``) are passed in increasing order while the
    dual objective still increases: passing a bound ``k`` that has an opposite bound
    ``pair[W_k]`` (``g_{pair} = -g_{W_k}``) swaps it for that bound and lowers the slope
    ``δ = g_t·x - β_t`` by ``α_k (β_k + β_pair)`` (``gap`` holds ``β_k + β_pair`` of every
    constraint of every set, flat, ``inf`` without a pair); a constraint without a pair stops
    the step.  Returns the leaving position ``k`` and the ``(R, n)`` mask of bounds to flip
    (the breakpoints below ``k``'s; ``k`` itself is never flipped).
    """
    R = ratio.shape[0]
    rows = np.arange(R)
    cost = np.where(pos, alpha * gap[base[:, None] + Wr], np.inf)
    order = np.argsort(ratio, axis=1)
    # costs in breakpoint order, summed in order (cumsum adds sequentially along any axis);
    # many rows: down the short axis laid out first (whole rows at a time)
    if R > 64:
        cum = np.take_along_axis(cost, order, axis=1).T.copy()
        np.cumsum(cum, axis=0, out=cum)
        first = np.add.reduce(cum < delta, axis=0)
    else:
        cum = cost[rows[:, None], order]
        np.cumsum(cum, axis=1, out=cum)
        first = np.count_nonzero(cum < delta[:, None], axis=1)
    # costs are >= 0 (or NaN): the passed breakpoints are a prefix of the sorted ones; the
    # last finite breakpoint stops the step (none: a Farkas row, whatever its k)
    k = order[rows, np.minimum(first, count_last(pos) - 1)]
    # every breakpoint before k (ties with k stay, with a zero multiplier) is passed
    return k, ratio < ratio[rows, k][:, None]
