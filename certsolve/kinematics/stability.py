"""Stability of an equilibrium pose: the Hessian of the potential energy, enclosed over a box.

The elastic model (Merlet 2007, eqs. 1-2) makes the forward kinematics a gradient system.
Wire ``i`` stores ``E_i = k_i (L_i - L0_i ln L_i)`` with ``L_i = ρ_i + V_i + K_i u_i``, whose
derivative in ``ρ_i`` is the tension ``τ_i = k_i (L_i - L0_i) / L_i`` (eq. 6); its wrench on
the platform is ``-τ_i ∇ρ_i``.  So the equilibrium equations (eq. 3) are ``∇U = 0`` for

    U(X) = Σ_i E_i(ρ_i(X)) - W·G(X)        (W = m g, G the centre of mass),

and an equilibrium is *stable* when the Hessian of ``U`` is positive definite there (a strict
local minimum), *unstable* when it has a negative eigenvalue.  This holds while every wire is
taut, which the tension limits of the search impose.

**The chart.**  At a pose ``X`` (centre of mass ``G``, levers ``r_i = B_i - G``) we take the
local coordinates ``δ = (δp, δω)`` of the displaced pose ``B_i(δ) = G + δp + exp([δω]×) r_i``
(a translation of the centre of mass and a rotation about it; the gravity term
``-W·(G + δp)`` is then linear and drops out of the Hessian).  Only the 2-jet of the
rotation matters at ``δ = 0``: ``exp([ω]×) r = r + ω × r + ½ ω × (ω × r) + O(|ω|³)`` (in
the plane, ``r + θ r⊥ - ½ θ² r``).  With ``q_i(δ) = |B_i(δ) - A_i|² - ρ_i²`` (``= O(δ)``
at a pose, where ``ρ_i = |B_i - A_i|``), the wire's energy is, to second order,

    E_i = E_i(ρ_i) + (w_i / 2) q_i + (τ'_i - w_i) / (8 ρ_i²) q_i² + O(q_i³),
    w_i = τ_i / ρ_i,  τ'_i = dτ_i/dρ_i = k_i L0_i / L_i²,

so ``H(X)``, the Hessian of ``U(B(δ))`` at ``δ = 0``, is that of the right-hand side: taken
by the expression DAG's symbolic derivatives (:meth:`~certsolve.expr.Graph.derivative`)
and evaluated with interval arithmetic (:class:`~certsolve.expr.Program`) over a box of
the formulation's variables (``δ = [0, 0]``).  ``ρ_i`` is the formulation's own variable
(narrowed by the length equations), and no ``(B_i - A_i) / ρ_i`` is enclosed: over a wide
box this is much tighter than differentiating ``E_i(|B_i(δ) - A_i|)``.  At an equilibrium
``∇U = 0``, so the Hessians of two charts are congruent (``H' = Jᵀ H J``): ``H(X*)``
decides stability at ``X*`` by Sylvester's law of inertia.  If a box holds an equilibrium
``X*``, its ``H(X*)`` is a member of the box's interval Hessian, because ``G`` and ``r_i``
are affine in the chosen points (eq. 8), ``ρ_i = |B_i - A_i|`` there, and the enclosure
is taken over the whole box.

**The verdict** (:func:`classify`, batched over boxes):

* ``stable``: the interval Cholesky factorisation of ``[H] - c I`` (outward rounding)
  succeeds with ``c >= 0``; then every symmetric matrix of ``[H]`` is positive definite
  (each one's exact Cholesky factor lies in the interval one, with positive pivots), and
  ``λ_min >= c``.  ``c`` is the midpoint's smallest eigenvalue less the radius bound
  ``||rad H||_2 <= max row sum`` (Weyl) and a small slack; if that proof fails, ``c = 0`` is
  tried.
* ``unstable``: ``v`` the midpoint's eigenvector of its smallest eigenvalue, and the
  rigorous upper bound of the Rayleigh quotient ``vᵀ H v / vᵀ v`` over ``[H]`` is negative.
* ``undecided`` otherwise (a degenerate equilibrium, or a box too wide).

The enclosure ``[lo, hi]`` of the smallest eigenvalue: ``hi`` the Rayleigh bound above
(``λ_min <= vᵀ H v / vᵀ v`` for any ``v``), ``lo`` the larger of the Cholesky-proven ``c``
and Gershgorin's ``min_i (H_ii - Σ_{j≠i} |H_ij|)``.

:func:`not_positive_definite` is the cheap test of the stable-only search
(:mod:`.stable_only`): a box whose every Hessian has a negative diagonal entry, a negative
2×2 principal minor, or a negative Rayleigh quotient along the midpoint's eigenvector, holds
no stable equilibrium.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ..expr import Expr, Graph, Program, esum, param, sqr, var
from ..interval import arith
from ..interval.linalg import gamma, mr_from_bounds, mr_matmul
from ..interval.rounding import down, up
from .fk_equations import cross, number, tolerance_parameters
from .fk_formulation import FKFormulation

__all__ = [
    "Stability",
    "StabilityVerdict",
    "EnergyHessian",
    "classify",
    "not_positive_definite",
]


class Stability(StrEnum):
    """The verdict on an equilibrium pose."""

    STABLE = "stable"  # the Hessian of U is proven positive definite over the pose's box
    UNSTABLE = "unstable"  # a direction with negative curvature over the whole box
    UNDECIDED = "undecided"


@dataclass(kw_only=True, frozen=True)
class StabilityVerdict:
    """``stability`` and an enclosure ``[eig_lo, eig_hi]`` of the Hessian's smallest
    eigenvalue (N·cm⁻¹ and N·cm per radian units mixed as the chart is: position in the
    robot's length unit, rotation in radians)."""

    stability: Stability
    eig_lo: float
    eig_hi: float

    @classmethod
    def unknown(cls) -> StabilityVerdict:
        return cls(stability=Stability.UNDECIDED, eig_lo=-np.inf, eig_hi=np.inf)

    def to_dict(self) -> dict:
        """Plain JSON: infinite bounds become ``None``."""
        return {
            "stability": str(self.stability),
            "eig_min": [_finite_or_none(self.eig_lo), _finite_or_none(self.eig_hi)],
        }


def _finite_or_none(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


# -- the energy in the chart at a pose ---------------------------------------------------------


def _turn(r: list[Expr], w: list[Expr]) -> list[Expr]:
    """``exp([ω]×) r - r`` to second order (3-D), or the same for the plane rotation by
    ``θ = w[0]``."""
    if len(r) == 3:
        wr = cross(w, r)
        wwr = cross(w, wr)
        return [wr[c] + 0.5 * wwr[c] for c in range(3)]
    th = w[0]
    return [-th * r[1] - 0.5 * sqr(th) * r[0], th * r[0] - 0.5 * sqr(th) * r[1]]


def _energy(form: FKFormulation, dp: list[Expr], dw: list[Expr]) -> Expr:
    """The second-order model of ``U(B(δ))`` at ``δ = (dp, dw)`` (module docstring), less
    its constant and gravity's linear term."""
    robot = form.robot
    d = robot.dim
    G, r = form.levers()
    terms: list[Expr] = []
    for i in range(robot.m):
        rho = var(f"rho{i + 1}")
        k, L0 = number(robot, "k", (i,)), number(robot, "L0", (i,))
        L = rho + number(robot, "V", (i,)) + number(robot, "K", (i,)) * param(f"u{i + 1}")
        w = k * (1.0 - L0 / L) / rho  # τ_i / ρ_i (each number over its tolerance)
        dtau = k * (L0 / sqr(L))  # dτ_i / dρ_i
        t = _turn(r[i], dw)
        move = [dp[c] + t[c] for c in range(d)]  # B_i(δ) - B_i
        arm = [G[c] + r[i][c] - number(robot, "A", (i, c)) for c in range(d)]  # B_i - A_i
        q = esum(2.0 * arm[c] * move[c] + sqr(move[c]) for c in range(d))
        terms.append(0.5 * w * q + (dtau - w) / (8.0 * sqr(rho)) * sqr(q))
    return esum(terms)


class EnergyHessian:
    """The interval Hessian ``H(X)`` of the module docstring, compiled once per formulation.

    :meth:`enclose` evaluates it over a batch of boxes of the formulation's variables (one
    :class:`~certsolve.expr.Program` pass for the batch); :meth:`verdicts` adds the PD proof.
    """

    def __init__(self, form: FKFormulation):
        robot = form.robot
        d = robot.dim
        s = self.size = 3 if d == 2 else 6  # the platform's degrees of freedom
        chart = [f"_dp{c}" for c in range(d)] + [f"_dw{c}" for c in range(s - d)]
        names = list(form.system.variables)
        self.n_vars = n = len(names)
        #: the parameters, in the order :meth:`enclose` takes them
        self.parameters = [f"u{i + 1}" for i in range(robot.m)]
        #: the intervals of a robot's toleranced numbers, parameters after ``u``
        tol = tolerance_parameters(robot)
        self.parameters += list(tol)
        self._tol_lo = np.array([v[0] for v in tol.values()])
        self._tol_hi = np.array([v[1] for v in tol.values()])
        graph = Graph(names + chart, self.parameters)
        # gravity, -W·(G + δp), is linear in δ: no part of the Hessian
        U = graph.add_expr(_energy(form, [var(c) for c in chart[:d]], [var(c) for c in chart[d:]]))
        self.pairs = [(a, b) for a in range(s) for b in range(a, s)]
        zero = graph.const(0.0)

        def second(node, a, b):
            da = graph.derivative(node, a)
            dab = None if da is None else graph.derivative(da, b)
            return zero if dab is None else dab

        self.program = Program(graph, [second(U, n + a, n + b) for a, b in self.pairs])

    def enclose(self, lo, hi, u, u_hi=None) -> tuple[np.ndarray, np.ndarray]:
        """Bounds ``(N, s, s)`` of the Hessian over boxes ``lo, hi`` ``(N, n)`` at control ``u``
        (or any control in ``[u, u_hi]``)."""
        lo = np.atleast_2d(np.asarray(lo, dtype=float))
        hi = np.atleast_2d(np.asarray(hi, dtype=float))
        N = lo.shape[0]
        z = np.zeros((N, self.size))
        ulo = np.asarray(u, dtype=float).ravel()
        uhi = ulo if u_hi is None else np.asarray(u_hi, dtype=float).ravel()
        if ulo.size + self._tol_lo.size == len(self.parameters):  # the numbers' intervals
            ulo, uhi = np.r_[ulo, self._tol_lo], np.r_[uhi, self._tol_hi]
        LO, HI = self.program.eval_interval(np.hstack([lo, z]), np.hstack([hi, z]), ulo, uhi)
        out = self.program.outputs
        s = self.size
        Hlo = np.empty((N, s, s))
        Hhi = np.empty((N, s, s))
        for k, (a, b) in enumerate(self.pairs):
            Hlo[:, a, b] = Hlo[:, b, a] = LO[out[k]]
            Hhi[:, a, b] = Hhi[:, b, a] = HI[out[k]]
        bad = ~(Hlo <= Hhi)  # NaN: an undefined node (a wire of zero length)
        Hlo[bad], Hhi[bad] = -np.inf, np.inf
        return Hlo, Hhi

    def verdicts(self, lo, hi, u) -> list[StabilityVerdict]:
        """One verdict per box (:func:`classify` of :meth:`enclose`)."""
        status, elo, ehi = classify(*self.enclose(lo, hi, u))
        return [
            StabilityVerdict(stability=s, eig_lo=float(a), eig_hi=float(b))
            for s, a, b in zip(status, elo, ehi, strict=True)
        ]


# -- proofs on interval symmetric matrices -------------------------------------------------------


def _cholesky_ok(Hlo: np.ndarray, Hhi: np.ndarray) -> np.ndarray:
    """Interval Cholesky (outward rounding) of symmetric interval matrices ``(N, s, s)``:
    True where every pivot's lower bound is positive, which proves every symmetric member
    positive definite."""
    N, s, _ = Hlo.shape
    Llo = np.zeros((N, s, s))
    Lhi = np.zeros((N, s, s))
    ok = np.all(np.isfinite(Hlo) & np.isfinite(Hhi), axis=(1, 2))
    with np.errstate(all="ignore"):
        for j in range(s):
            plo, phi = Hlo[:, j, j], Hhi[:, j, j]
            for k in range(j):
                qlo, qhi = arith.sqr(Llo[:, j, k], Lhi[:, j, k])
                plo, phi = arith.sub(plo, phi, qlo, qhi)
            ok &= plo > 0.0
            plo = np.where(ok, plo, 1.0)
            phi = np.where(ok, phi, 1.0)
            dlo, dhi = arith.sqrt(plo, phi)
            Llo[:, j, j], Lhi[:, j, j] = dlo, dhi
            if j + 1 == s:
                break
            tlo, thi = Hlo[:, j + 1 :, j], Hhi[:, j + 1 :, j]
            for k in range(j):
                mlo, mhi = arith.mul(
                    Llo[:, j + 1 :, k], Lhi[:, j + 1 :, k], Llo[:, j, k, None], Lhi[:, j, k, None]
                )
                tlo, thi = arith.sub(tlo, thi, mlo, mhi)
            Llo[:, j + 1 :, j], Lhi[:, j + 1 :, j] = arith.div(tlo, thi, dlo[:, None], dhi[:, None])
    return ok


def _shifted(Hlo, Hhi, c):
    """Bounds of ``[H] - c I`` (``c`` per matrix), rounded outward."""
    s = Hlo.shape[1]
    i = np.arange(s)
    lo, hi = Hlo.copy(), Hhi.copy()
    lo[:, i, i] = down(Hlo[:, i, i] - c[:, None])
    hi[:, i, i] = up(Hhi[:, i, i] - c[:, None])
    return lo, hi


def _rayleigh_upper(Hlo, Hhi, v) -> np.ndarray:
    """Rigorous upper bounds of ``max_{H ∈ [H]} vᵀ H v / vᵀ v`` for vectors ``v`` ``(N, s)``."""
    c, r = mr_from_bounds(Hlo, Hhi)
    col = v[:, :, None]
    row = v[:, None, :]
    hc, hr = mr_matmul(c, r, col, None)
    nc, nr = mr_matmul(row, None, hc, hr)
    dc, dr = mr_matmul(row, None, col, None)
    num_lo, num_hi = down(nc - nr)[:, 0, 0], up(nc + nr)[:, 0, 0]
    den_lo, den_hi = down(dc - dr)[:, 0, 0], up(dc + dr)[:, 0, 0]
    with np.errstate(all="ignore"):
        _, q = arith.div(num_lo, num_hi, den_lo, den_hi)
    return np.where(np.isnan(q), np.inf, q)


def _gershgorin_lower(Hlo, Hhi) -> np.ndarray:
    """``min_i (inf H_ii - Σ_{j≠i} mag H_ij)``, rounded down: a lower bound of ``λ_min``."""
    s = Hlo.shape[1]
    i = np.arange(s)
    mag = np.maximum(np.abs(Hlo), np.abs(Hhi))
    mag[:, i, i] = 0.0
    off = up(mag.sum(axis=2) * (1.0 + gamma(s)))
    with np.errstate(invalid="ignore"):
        g = down(Hlo[:, i, i] - off).min(axis=1)
    return np.where(np.isnan(g), -np.inf, g)


def _midpoint_eigen(Hlo, Hhi):
    """Smallest eigenvalue and its eigenvector of each midpoint matrix (finite ones; NaN and
    a zero vector elsewhere)."""
    N, s, _ = Hlo.shape
    fin = np.all(np.isfinite(Hlo) & np.isfinite(Hhi), axis=(1, 2))
    lam = np.full(N, np.nan)
    v = np.zeros((N, s))
    if np.any(fin):
        mid = 0.5 * Hlo[fin] + 0.5 * Hhi[fin]
        w, V = np.linalg.eigh(mid)
        lam[fin] = w[:, 0]
        v[fin] = V[:, :, 0]
    return lam, v, fin


def classify(Hlo, Hhi) -> tuple[list[Stability], np.ndarray, np.ndarray]:
    """Verdicts and ``[lo, hi]`` enclosures of ``λ_min`` for interval Hessians ``(N, s, s)``
    (module docstring)."""
    N = Hlo.shape[0]
    lam, v, fin = _midpoint_eigen(Hlo, Hhi)
    hi = np.where(fin, _rayleigh_upper(Hlo, Hhi, v), np.inf)
    lo = _gershgorin_lower(Hlo, Hhi)
    # Weyl: λ_min(H) >= λ_min(mid) - ||rad||_2; a little below, for the rounding of eigh
    rad = 0.5 * (Hhi - Hlo)
    scale = np.max(np.abs(Hlo) + np.abs(Hhi), axis=(1, 2), initial=0.0)
    with np.errstate(invalid="ignore"):
        c = lam - np.max(rad.sum(axis=2), axis=1, initial=0.0) - 1e-12 * scale
    c = np.where(fin & np.isfinite(c), c, -np.inf)
    try_c = fin & (c > lo)
    proven = np.zeros(N, dtype=bool)
    if np.any(try_c):
        proven[try_c] = _cholesky_ok(*_shifted(Hlo[try_c], Hhi[try_c], c[try_c]))
    lo = np.where(proven, np.maximum(lo, c), lo)
    pd = lo > 0.0
    retry = fin & ~pd & (hi > 0.0)
    if np.any(retry):  # the shifted proof failed or c <= 0: is H itself positive definite?
        pd[retry] = _cholesky_ok(Hlo[retry], Hhi[retry])
        lo = np.where(pd, np.maximum(lo, 0.0), lo)
    status = [
        Stability.STABLE if p else (Stability.UNSTABLE if h < 0.0 else Stability.UNDECIDED)
        for p, h in zip(pd, hi, strict=True)
    ]
    return status, lo, hi


def not_positive_definite(Hlo, Hhi) -> np.ndarray:
    """Boxes whose every Hessian is proven not positive definite: a diagonal entry, a 2×2
    principal minor or the Rayleigh quotient along the midpoint's eigenvector negative."""
    s = Hlo.shape[1]
    i = np.arange(s)
    dlo, dhi = Hlo[:, i, i], Hhi[:, i, i]
    out = np.any(dhi < 0.0, axis=1)
    a, b = np.triu_indices(s, 1)
    with np.errstate(all="ignore"):
        plo, phi = arith.mul(dlo[:, a], dhi[:, a], dlo[:, b], dhi[:, b])
        qlo, qhi = arith.sqr(Hlo[:, a, b], Hhi[:, a, b])
        _, mhi = arith.sub(plo, phi, qlo, qhi)
    out |= np.any(mhi < 0.0, axis=1)
    lam, v, fin = _midpoint_eigen(Hlo, Hhi)
    test = fin & ~out & (lam < 0.0)
    if np.any(test):
        out[test] = _rayleigh_upper(Hlo[test], Hhi[test], v[test]) < 0.0
    return out
