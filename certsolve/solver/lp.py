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

Box bounds come in pairs (``-d_k <= 0``, ``d_k <= w_k``): with ``pair`` the ratio test is the
*bound-flipping* (long-step) one of the dual simplex method: a bound whose multiplier reaches
zero swaps for its opposite bound, and the step goes on, while the dual objective still
increases.  One iteration then moves a vertex across the whole box where the plain test
needs one pivot per bound; on katsura-6 the median program needs ~7 iterations instead of
~11 (and the plain test cycles on some programs).  With ``cutoff`` the programs of a set stop
as soon as one of them proves it empty (a Farkas ray, or a dual objective past the cutoff).
A :class:`StallRule` (with ``stall``) stops the programs whose objective has stopped moving:
the dual objective only grows, and the last iterations of a program that creeps (degenerate
pivots, or 22 variables where the optimum is ~60 pivots away) buy little bound for their cost.

Nothing here needs to be exact: the caller turns the multipliers into *rigorous* bounds
(any ``y >= 0`` gives a valid bound, Neumaier & Shcherbina 2004), so rounding, cycling or
the iteration cap can only weaken a bound, never make it wrong.  Programs sharing a
constraint set (one box, several objectives) share one ``(M, n)`` matrix: the violations of
all of them come from one batched ``matmul`` per iteration; the other steps work on the
programs still running, a handful of numpy calls each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..interval.reductions import all_last, any_last, count_last, max_last

__all__ = ["LPBatch", "StallRule", "dual_active_set"]


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
    set) or -1; given, the ratio test flips bounds (see the module doc).  ``cutoff``
    ``(L,)``: a program whose dual objective ``c·x`` (a lower bound of its minimum) exceeds
    its cutoff proves its set empty for the caller; the set's other programs then stop, their
    multipliers as they are (valid, only less tight).  ``stall`` with ``scale`` ``(L,)``
    (each program's yardstick, the width of the variable it bounds): programs that creep
    stop (:class:`StallRule`); without them, programs run to optimality or ``max_iter``.
    """
    L, n = c.shape
    S, M, _ = G.shape
    K = L // S
    box = np.repeat(np.arange(S), K)
    norms = np.sqrt(np.einsum("smn,smn->sm", G, G))
    inv_norm = 1.0 / np.where(norms > 0.0, norms, 1.0)
    GT = np.ascontiguousarray(np.swapaxes(G * inv_norm[:, :, None], 1, 2))  # (S, n, M)
    beta_n = beta * inv_norm
    Gf = G.reshape(S * M, n)
    bf = beta.reshape(S * M)
    if pair is not None:
        gap = np.where(pair >= 0, beta + beta[:, np.maximum(pair, 0)], np.inf).reshape(S * M)
    W = W0.copy()
    lam = lam0.astype(float)
    with np.errstate(all="ignore"):
        Ninv = np.linalg.inv(Gf[(box * M)[:, None] + W]) if Ninv0 is None else Ninv0.copy()
        x = np.einsum("lij,lj->li", Ninv, bf[(box * M)[:, None] + W])
    y = np.zeros((L, M))
    infeasible = np.zeros(L, dtype=bool)
    done = ~np.all(np.isfinite(Ninv), axis=(1, 2))
    proven = np.zeros(S, dtype=bool)  # a program of the set proved it empty: all stop
    checked = None  # the objectives at the last stall check
    iterations = 0
    with np.errstate(all="ignore"):
        while iterations < max_iter:
            iterations += 1
            obj = np.einsum("li,li->l", c, x)
            if cutoff is not None:
                proven[box[(obj > cutoff) & ~done]] = True
            done |= proven[box]
            if stall is not None and scale is not None and iterations >= stall.start:
                if (iterations - stall.start) % stall.window == 0:
                    if checked is not None:
                        done |= ~(obj - checked > stall.fraction * scale)
                    checked = obj
            act = np.flatnonzero(~done)
            if act.size == 0:
                break
            if stall is not None and iterations > stall.few_after and act.size < stall.few:
                break
            # normalised violations; the most violated constraint enters
            if 3 * act.size > L:
                V = np.matmul(x.reshape(S, K, n), GT)
                V -= beta_n[:, None, :]
                V = V.reshape(L, M)[act]
            else:
                V = np.matmul(x[act][:, None, :], GT[box[act]])[:, 0, :]
                V -= beta_n[box[act]]
            V[np.arange(act.size)[:, None], W[act]] = -np.inf
            t = np.argmax(V, axis=1)
            vmax = V[np.arange(act.size), t]
            conv = vmax <= tol * (1.0 + max_last(np.abs(x[act])))
            done[act[conv]] = True
            run, t = act[~conv], t[~conv]
            if run.size == 0:
                break
            gs = Gf[box[run] * M + t]
            Ni = Ninv[run]
            alpha = np.einsum("lij,li->lj", Ni, gs)  # g_t = Σ_k α_k g_{W_k}
            lr = lam[run]
            pos = alpha > 1e-12 * max_last(np.abs(alpha))[:, None]
            ratio = lr / alpha
            ratio[~pos] = np.inf
            farkas = ~any_last(pos)
            if pair is None:
                k = np.argmin(ratio, axis=1)
                flip = None
            else:
                delta = vmax[~conv] * norms[box[run], t]  # g_t·x - β_t > 0
                k, flip = _long_step(ratio, pos, alpha, W[run], gap, box[run] * M, delta)
            if np.any(farkas):  # every α_k <= 0: infeasible
                fr = run[farkas]
                rows = np.arange(fr.size)
                fy = np.zeros((fr.size, M))
                fy[rows, t[farkas]] = 1.0
                np.add.at(fy, (rows[:, None], W[fr]), -alpha[farkas])
                y[fr] = np.maximum(fy, 0.0)
                infeasible[fr] = True
                done[fr] = True
                proven[box[fr]] = True
                keep = ~farkas
                run, t, k, gs, Ni, alpha, lr = (
                    run[keep], t[keep], k[keep], gs[keep], Ni[keep], alpha[keep], lr[keep]
                )  # fmt: skip
                if flip is not None:
                    flip = flip[keep]
                if run.size == 0:
                    continue
            Wr = W[run]
            if flip is not None and pair is not None and np.any(flip):
                # the flipped bounds change sides: their row of N, α and λ change sign
                Wr = np.where(flip, pair[Wr], Wr)
                sgn = np.where(flip, -1.0, 1.0)
                Ni *= sgn[:, None, :]  # a copy of Ninv[run]
                alpha *= sgn
                lr = lr * sgn
            ar = np.arange(run.size)
            ak = alpha[ar, k]
            s = lr[ar, k] / ak
            lr = np.maximum(lr - s[:, None] * alpha, 0.0)
            lr[ar, k] = s
            lam[run] = lr
            Wr[ar, k] = t
            W[run] = Wr
            # N' = N + e_k (g_t - g_k)ᵀ  =>  N'^{-1} = N^{-1} - N^{-1} e_k (α - e_k)ᵀ / α_k
            col = Ni[ar, :, k]
            alpha[ar, k] -= 1.0
            Ni -= col[:, :, None] * (alpha / ak[:, None])[:, None, :]
            Ninv[run] = Ni
            xr = np.einsum("lij,lj->li", Ni, bf[(box[run] * M)[:, None] + Wr])
            bad = ~all_last(np.isfinite(xr))
            x[run] = np.where(bad[:, None], x[run], xr)
            done[run[bad]] = True
    feasible = np.flatnonzero(~infeasible)
    np.add.at(y, (feasible[:, None], W[feasible]), np.maximum(lam[feasible], 0.0))
    return LPBatch(y=np.where(np.isfinite(y), y, 0.0), infeasible=infeasible, iterations=iterations)


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
    cost = np.where(pos, alpha * gap[base[:, None] + Wr], np.inf)
    order = np.argsort(ratio, axis=1)
    # costs in breakpoint order, summed down the short axis laid out first (whole rows)
    cum = np.take_along_axis(cost, order, axis=1).T.copy()
    np.cumsum(cum, axis=0, out=cum)
    # costs are >= 0 (or NaN): the passed breakpoints are a prefix of the sorted ones
    first = np.add.reduce(cum < delta, axis=0)
    last = count_last(pos) - 1  # the last finite breakpoint
    p = np.minimum(first, np.maximum(last, 0))
    k = order[np.arange(R), p]
    # every breakpoint before k (ties with k stay, with a zero multiplier) is passed
    return k, ratio < ratio[np.arange(R), k][:, None]
