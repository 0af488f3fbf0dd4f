"""Tension distributions for the tension-first inverse kinematics (Merlet 2007, section II.A).

At a pose, equilibrium ``H τ + w_g = 0`` has ``w`` equations (the wrench dimension) in the
``m`` wire tensions, with ``τ_min <= τ <= τ_max``.  Which tensions to choose depends on the
shape of ``H`` (rank ``r``):

* ``m = w + 1`` and ``r = w`` (MARIONET: 7 wires, dof 6; the planar robot: 4 wires, dof 3;
  Krut's 3-motor robot): the solutions form the line ``τ = τ_p + λ v`` (``v`` spans the null
  space of ``H``).  The *margin* ``g(λ) = min_i min(τ_i - τ_min,i, τ_max,i - τ_i)`` is the
  minimum of ``2m`` affine functions of ``λ``, concave and piecewise linear; its maximum is
  at a crossing of a line of positive slope with one of negative slope, so evaluating ``g``
  at all such crossings gives the exact max-margin distribution (:func:`closed_form`).  The
  admissible tensions are the segment ``λ ∈ [λ_lo, λ_hi]``.
* ``m > w + 1``: the max-margin LP (:func:`certsolve.robot.statics.max_margin_tensions`).
* ``m = w`` and ``r = w``: the tensions are unique, ``τ = -H⁻¹ w_g``.
* ``m < w`` (the almost-planar robot: 4 wires, 6 equations) or ``r < min(w, m)``: the
  equations are over-determined; least squares gives the best tensions and the pose is an
  *equilibrium* only if the residual vanishes (relative tolerance ``1e-9``).  A generic pose
  of such a robot is not an equilibrium: the 4 controls determine the pose (forward
  kinematics), not the other way round.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..inputs import InputError
from ..robot.statics import max_margin_tensions

__all__ = ["TensionChoice", "closed_form", "distribute_tensions", "margin_of"]

EQ_TOL = 1e-9  # relative residual below which H τ + w_g = 0 is accepted numerically


@dataclass
class TensionChoice:
    """A tension distribution and what is known about it."""

    tau: np.ndarray  # (m,) NaN if no tension satisfies the equations
    margin: float  # min distance to a tension limit (N); negative: some limit violated
    equilibrium: bool  # H τ + w_g = 0 has a solution (always, when rank H = w)
    residual: float  # max |H τ + w_g| (N, N·cm)
    method: str  # "closed-form" | "lp" | "unique" | "least-squares"
    rank: int
    null_dim: int  # m - rank: dimension of the solution set of the equations
    lam_range: tuple[float, float] | None = None  # closed form: admissible λ (empty: lo > hi)
    null_vector: np.ndarray | None = None
    particular: np.ndarray | None = None
    lp_check: dict | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def admissible(self) -> bool:
        return bool(self.equilibrium and self.margin >= -1e-9)


def margin_of(tau: np.ndarray, tau_min: np.ndarray, tau_max: np.ndarray) -> float:
    return float(np.min(np.minimum(tau - tau_min, tau_max - tau)))


def _residual(H, wg, tau) -> float:
    return float(np.max(np.abs(H @ tau + wg))) if np.all(np.isfinite(tau)) else np.inf


def _scale(H, wg, tau) -> float:
    t = np.abs(tau[np.isfinite(tau)]) if tau.size else np.zeros(1)
    return max(1.0, float(np.max(np.abs(wg), initial=0.0)), float(np.max(t, initial=0.0)))


def closed_form(
    tau_p: np.ndarray, v: np.ndarray, tau_min: np.ndarray, tau_max: np.ndarray
) -> tuple[float, float, tuple[float, float]]:
    """Exact max-margin ``λ`` on ``τ = τ_p + λ v`` and the admissible ``λ`` interval.

    Returns ``(lam, margin, (lam_lo, lam_hi))``.  ``g(λ) = min_k (c_k + s_k λ)`` with slopes
    ``s = (v, -v)`` and intercepts ``c = (τ_p - τ_min, τ_max - τ_p)``.
    """
    s = np.concatenate([v, -v])
    c = np.concatenate([tau_p - tau_min, tau_max - tau_p])
    pos = s > 0
    neg = s < 0
    sp, cp = s[pos], c[pos]
    sn, cn = s[neg], c[neg]
    # crossings c_a + s_a λ = c_b + s_b λ
    lam = (cn[None, :] - cp[:, None]) / (sp[:, None] - sn[None, :])
    lam = lam.ravel()
    g = np.min(c[None, :] + s[None, :] * lam[:, None], axis=1)
    k = int(np.argmax(g))
    # admissible interval: every affine function >= 0
    with np.errstate(divide="ignore"):
        bounds = -c / s
    lo = float(np.max(bounds[pos], initial=-np.inf))
    hi = float(np.min(bounds[neg], initial=np.inf))
    zero = s == 0
    if np.any(zero) and np.any(c[zero] < 0):
        lo, hi = np.inf, -np.inf
    return float(lam[k]), float(g[k]), (lo, hi)


def _lstsq(H, wg):
    tau, *_ = np.linalg.lstsq(H, -wg, rcond=None)
    return tau


def distribute_tensions(
    H: np.ndarray,
    wg: np.ndarray,
    tau_min: np.ndarray,
    tau_max: np.ndarray,
    *,
    mode: str = "auto",
    check_lp: bool = False,
) -> TensionChoice:
    """Choose tensions at a pose (see the module docstring).

    ``mode``: ``"auto"`` (closed form when the null space is a line, LP when larger, the
    unique or least-squares solution otherwise), ``"closed-form"`` or ``"lp"``.
    ``check_lp`` also solves the LP when the closed form was used and records both margins
    and the largest tension difference in ``lp_check``.
    """
    if mode not in ("auto", "closed-form", "lp"):
        raise ValueError(f"tension distribution {mode!r}: expected auto, closed-form or lp")
    H = np.asarray(H, dtype=float)
    wg = np.asarray(wg, dtype=float)
    tau_min = np.asarray(tau_min, dtype=float)
    tau_max = np.asarray(tau_max, dtype=float)
    w, m = H.shape
    U, sv, Vt = np.linalg.svd(H)
    rank = int(np.sum(sv > sv[0] * 1e-12)) if sv.size and sv[0] > 0 else 0
    null_dim = m - rank

    if rank == w and null_dim == 1 and mode != "lp":
        v = Vt[-1]
        tau_p = Vt[:w].T @ ((U.T @ -wg) / sv[:w])
        lam, margin, lam_range = closed_form(tau_p, v, tau_min, tau_max)
        tau = tau_p + lam * v
        out = TensionChoice(
            tau,
            margin_of(tau, tau_min, tau_max),
            True,
            _residual(H, wg, tau),
            "closed-form",
            rank,
            null_dim,
            lam_range,
            v,
            tau_p,
        )
        if check_lp:
            lp = max_margin_tensions(H, wg, tau_min, tau_max)
            out.lp_check = {
                "lp_margin": float(lp.margin),
                "closed_form_margin": out.margin,
                "margin_difference": float(abs(lp.margin - out.margin)),
                "max_tau_difference": float(np.max(np.abs(lp.tau - tau))),
            }
        return out
    if mode == "closed-form":
        raise InputError(
            "distribution",
            f"closed-form tensions need a one-dimensional null space (m = w + 1 = {w + 1} "
            f"wires, rank {w}); this pose has {m} wires and rank {rank}",
        )
    if rank == w and null_dim >= 1:
        lp = max_margin_tensions(H, wg, tau_min, tau_max)
        tau = lp.tau
        eq = bool(np.all(np.isfinite(tau)))
        return TensionChoice(
            tau,
            float(lp.margin) if eq else -np.inf,
            eq,
            _residual(H, wg, tau),
            "lp",
            rank,
            null_dim,
        )
    if rank == w == m:
        tau = np.linalg.solve(H, -wg)
        return TensionChoice(
            tau, margin_of(tau, tau_min, tau_max), True, _residual(H, wg, tau), "unique", rank, 0
        )
    # over-determined (m < w) or rank-deficient: least squares, then check the residual
    tau = _lstsq(H, wg)
    res = _residual(H, wg, tau)
    eq = res <= EQ_TOL * _scale(H, wg, tau)
    notes = []
    if not eq:
        notes.append(
            f"the pose is not an equilibrium: {w} equilibrium equations, rank {rank} in the "
            f"{m} tensions; the least-squares tensions leave a residual of {res:.3g}"
        )
    elif null_dim > 0:
        notes.append(f"rank-deficient wrench matrix (rank {rank} < {m}): least-norm tensions")
    return TensionChoice(
        tau,
        margin_of(tau, tau_min, tau_max),
        bool(eq),
        res,
        "least-squares",
        rank,
        null_dim,
        notes=notes,
    )
