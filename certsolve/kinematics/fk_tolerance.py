"""Forward kinematics of a robot known within tolerances: pose boxes for every robot of the set.

A robot file with ``tolerances`` (:mod:`certsolve.robot.tolerance`) describes a *set* of
robots.  The FK system of the set is the nominal formulation with every toleranced number
written as its interval constant (:func:`.fk_equations.number`): an interval evaluation of
an equation over a box of the variables then encloses that equation for every robot of
the set at every point of the box.  Every contractor of the FK search stays sound (HC4,
interval Newton: each robot's equilibria in a box stay in its contraction), and so does
the Krawczyk proof: ``K(U) = c - Y f(c) + (I - Y J(U))(U - c)`` with ``f(c)`` and ``J(U)``
enclosed over the numbers' intervals contains, for *every* robot of the set, that robot's
Krawczyk image; so ``K(U) ⊂ int U`` proves that each robot of the set has exactly one
equilibrium in ``U``, and it lies in ``K(U)``.

**The search near a solution set.**  Each robot's equilibrium moves with its numbers, so
the equilibria of the set fill a small region ``S`` of positive width.  A box that holds
part of ``S`` can never be proven empty, and splitting it to ``eps`` would leave thousands
of undecided boxes around every pose.  So the search is done in three steps:

1. the nominal robot's FK (:class:`.FKSolver` without tolerances): its certified poses are
   the seeds;
2. around each seed ``x*``, a box ``U`` where every robot of the set has exactly one
   equilibrium: by epsilon-inflation with the set's Krawczyk test (:class:`SetKrawczyk`,
   :func:`_prove_seeds`), or, where the set spreads over a region too curved for one
   Krawczyk box, by the regularity of ``J_x`` over ``U`` (at most one per robot) and the
   degree argument of :func:`_regular_box` (existence, once step 3 has found no
   equilibrium of any robot on ``∂U``); the existence box ``E`` is then tightened,
   ``E ← K(E) ∩ E``, until it stops shrinking: every equilibrium of every robot of the set
   in ``U`` stays in ``E``;
3. the rest of the search box -- the domain less the interiors of the proven ``U``
   (:func:`.boxes_minus`, closed pieces that meet no ``int U``) -- is searched by the
   set's own FK search (the nominal pipeline on the interval system, with the set's
   Krawczyk operator as one more contractor, :class:`SetNewton`): it proves its own pose
   boxes where a robot of the set has another equilibrium, and reports
   what it cannot decide.  A pose box it proves whose ``E`` lies in a seed's ``U`` is that
   seed's pose (``U`` holds one equilibrium per robot) and is not reported twice.

**What ``complete`` means**: every equilibrium of every robot of the set inside the search
box lies in a reported pose box or in a reported undecided box.  A pose box's
``certificate`` is ``unique`` when every robot of the set is proven to have exactly one
equilibrium in its ``U`` (inside ``E``), ``undecided`` when at most one is proven (a
regular ``U`` whose boundary the search of the rest could not clear).  A seed for which
neither proof holds is not reported as a pose; its neighbourhood is searched in step 3
like the rest (undecided boxes there, if the set's equilibria cannot be separated).

**What a pose box reports** (:class:`PoseBounds`): bounds of every platform point (the
attachments are affine in the variables, eq. 8), of the platform frame's origin and of its
rotation matrix, taken over ``E`` with outward rounding; the pose at ``E``'s midpoint as
the nominal reading; the stability verdict over ``E`` with the interval numbers (the
energy's Hessian, :mod:`.stability`, is written with the same constants).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..expr import System, var
from ..expr.compiled import CompiledSystem
from ..expr.node import Expr
from ..inputs import InputError
from ..interval import arith
from ..interval.core import midpoint
from ..interval.linalg import (
    U,
    gamma,
    krawczyk_image,
    krawczyk_magnitude,
    mr_from_bounds,
    mr_matmul,
    precondition,
)
from ..interval.reductions import all_last, any_last
from ..interval.rounding import down, up
from ..robot.model import Robot
from ..solver.certify import SolutionSet, boxes_minus
from ..solver.result import Solution, SolveResult
from ..solver.search import SearchStatus
from .fk_equations import tolerance_parameters
from .fk_formulation import FKFormulation
from .fk_solver import FKResult, FKSolver

__all__ = [
    "TOLERANT_KINDS",
    "PoseBounds",
    "SetKrawczyk",
    "check_tolerances",
    "check_tolerant_options",
    "tolerant_forward_kinematics",
]

#: the coordinate kinds whose systems write every robot number through
#: :func:`.fk_equations.number` (the pose formulation writes the attachments in its
#: rotation: not yet)
TOLERANT_KINDS = ("frame", "points")
#: the tightening of ``E`` stops when no side shrank by more than this share of its width
_TIGHT = 1e-3
_MAX_TIGHTEN = 60
_MAX_INFLATE = 12
_MAX_GROW = 12


@dataclass(kw_only=True, frozen=True)
class PoseBounds:
    """Bounds of a pose box over every robot of the set: ``platform_points`` ``(m, d)``,
    ``position`` ``(d,)`` (the platform frame's origin) and ``rotation`` ``(d, d)``, each a
    pair ``(lo, hi)`` rounded outward."""

    platform_points: tuple[np.ndarray, np.ndarray]
    position: tuple[np.ndarray, np.ndarray]
    rotation: tuple[np.ndarray, np.ndarray]

    def to_dict(self) -> dict:
        out = {}
        for name in ("platform_points", "position", "rotation"):
            lo, hi = getattr(self, name)
            out[f"{name}_lo"] = lo.tolist()
            out[f"{name}_hi"] = hi.tolist()
        return out


def check_tolerances(robot: Robot, form: FKFormulation) -> None:
    """Refuse, naming the field, what the FK of a set does not handle yet: tolerances on
    the attachments or the centre of mass (they move the chosen points' geometry, eq. 8),
    and formulations other than :data:`TOLERANT_KINDS`."""
    check_tolerant_options(robot, "auto")
    if form.kind not in TOLERANT_KINDS:
        raise InputError(
            "formulation",
            f"{form.name} does not take tolerances; use one of the frame or points "
            "formulations (auto chooses the frame)",
        )


def points_map(form: FKFormulation) -> np.ndarray:
    """``T`` ``(m d, n)``: the attachments ``B_i`` (rows ``i d + c``) as a linear map of the
    variables (eq. 8: ``B_i = Σ_j l_ij P_j``; in the frame ``P_j = P_1 + E_j``)."""
    robot = form.robot
    d, m, n = robot.dim, robot.m, form.system.n
    L = form.platform.L  # type: ignore[attr-defined]
    T = np.zeros((m * d, n))
    for i in range(m):
        for c in range(d):
            for j in range(L.shape[1]):
                T[i * d + c, j * d + c] += L[i, j]
            if form.kind == "frame":  # P_1 carries the whole weight sum_j l_ij = 1
                T[i * d + c, c] = 1.0
    return T


def pose_bounds(
    form: FKFormulation, lo: np.ndarray, hi: np.ndarray, test: SetKrawczyk | None = None
) -> PoseBounds:
    """Bounds of the platform points, the frame's origin and the rotation over the variable
    box ``[lo, hi]`` (:class:`PoseBounds`).

    The chosen points ``P_j`` are read from the box (the frame's ``P_1 + E_j`` in interval
    arithmetic), every attachment is ``Σ_j l_ij P_j`` (eq. 8, midpoint-radius products with
    their rounding error).  The rotation: ``R (Q_j - Q_1) = P_j - P_1``; with the platform
    frame's axes as combinations of the edges (a least-squares inverse of the edge matrix,
    exact for a rigid pose up to its rounding, which the radius covers), and the third axis
    as the cross product of the first two where the edges span a plane.  With the set's
    ``test``, the attachments' bounds are also those of :meth:`SetKrawczyk.linear_image`
    (the intersection of the two is kept)."""
    robot = form.robot
    d, m = robot.dim, robot.m
    k = form.platform.Q.shape[0]  # type: ignore[attr-defined]
    Plo = lo[: k * d].reshape(k, d).copy()
    Phi = hi[: k * d].reshape(k, d).copy()
    if form.kind == "frame":  # P_j = P_1 + E_j
        Plo[1:] = down(Plo[0] + Plo[1:])
        Phi[1:] = up(Phi[0] + Phi[1:])
    Pc, Pr = mr_from_bounds(Plo, Phi)
    L = form.platform.L  # type: ignore[attr-defined]
    Bc, Br = mr_matmul(L, None, Pc, Pr)
    Q = form.platform.Q  # type: ignore[attr-defined]
    e = Q[1:] - Q[0]  # (k-1, d): R e_j = E_j
    if form.kind == "frame":  # the edges are variables
        Elo = lo[d : k * d].reshape(k - 1, d)
        Ehi = hi[d : k * d].reshape(k - 1, d)
    else:
        Elo, Ehi = down(Plo[1:] - Phi[0]), up(Phi[1:] - Plo[0])
    Ec, Er = mr_from_bounds(Elo, Ehi)
    # pinv(e) E = pinv(e) e R^T = Π R^T, Π the projector on the edges' span
    pinv = np.linalg.pinv(e)  # (d, k-1)
    span = int(np.linalg.matrix_rank(e))
    proj = np.diag([1.0] * span + [0.0] * (d - span))
    if span < d and (d != 3 or span != 2 or np.max(np.abs(pinv @ e - proj)) > 1e-9):
        raise ValueError("pose bounds: the chosen points must span the platform frame's xy plane")
    Rc, Rr = mr_matmul(pinv, None, Ec, Er)  # (d, d): row a is R's column a
    Rc, Rr = Rc.T.copy(), Rr.T.copy()
    # pinv is a float inverse: |(pinv e - Π) R^T| <= its row sums, as |R| <= 1 entrywise
    slack = float(up(np.max(np.sum(np.abs(pinv @ e - proj), axis=1))))
    Rr = up(Rr + slack)
    R_lo, R_hi = _cross_column(Rc, Rr) if span < d else (down(Rc - Rr), up(Rc + Rr))
    R_lo, R_hi = np.maximum(R_lo, -1.0), np.minimum(R_hi, 1.0)
    # the frame's origin: P_1 - R Q_1
    Rmc, Rmr = mr_from_bounds(R_lo, R_hi)
    oc, orr = mr_matmul(Rmc, Rmr, Q[0][:, None], None)
    pos_lo, pos_hi = arith.sub(Plo[0], Phi[0], down(oc - orr)[:, 0], up(oc + orr)[:, 0])
    Blo, Bhi = down(Bc - Br).reshape(m, d), up(Bc + Br).reshape(m, d)
    if test is not None:
        ilo, ihi = test.linear_image(lo[None], hi[None], points_map(form))
        Blo, Bhi = np.fmax(Blo, ilo.reshape(m, d)), np.fmin(Bhi, ihi.reshape(m, d))
    return PoseBounds(
        platform_points=(Blo, Bhi),
        position=(pos_lo, pos_hi),
        rotation=(R_lo, R_hi),
    )


def _cross_column(Rc: np.ndarray, Rr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``R`` with its third column ``R_1 × R_2`` (the first two enclosed by ``Rc ± Rr``)."""
    lo, hi = down(Rc - Rr), up(Rc + Rr)
    a = (lo[:, 0], hi[:, 0])
    b = (lo[:, 1], hi[:, 1])

    def prod(i, j):
        return arith.mul(a[0][i], a[1][i], b[0][j], b[1][j])

    out_lo, out_hi = lo.copy(), hi.copy()
    for c, (i, j) in enumerate(((1, 2), (2, 0), (0, 1))):
        p = prod(i, j)
        q = prod(j, i)
        out_lo[c, 2], out_hi[c, 2] = arith.sub(p[0], p[1], q[0], q[1])
    return out_lo, out_hi


class SetNewton:
    """The set's Krawczyk operator as a contractor of the search (the solver's protocol,
    :mod:`certsolve.solver.batch`): ``X ← X ∩ K(X)`` keeps every equilibrium of every
    robot of the set in ``X`` (each lies in its own Krawczyk image, inside ``K(X)``), and
    ``X ∩ K(X) = ∅`` proves that none has one there.  Its image keeps the numbers apart
    (:class:`SetKrawczyk`), where the interval Newton step of the pipeline reads each
    occurrence of a number as independent."""

    def __init__(self, test: SetKrawczyk):
        self.test = test

    def apply(self, batch) -> None:
        idx = np.flatnonzero(~batch.empty)
        if idx.size == 0:
            return
        lo, hi = batch.lo[idx], batch.hi[idx]
        klo, khi, _, usable = self.test.image(lo, hi)
        nlo = np.where(usable[:, None], np.fmax(lo, klo), lo)
        nhi = np.where(usable[:, None], np.fmin(hi, khi), hi)
        empty = any_last(nlo > nhi)
        batch.lo[idx] = np.where(empty[:, None], lo, nlo)
        batch.hi[idx] = np.where(empty[:, None], hi, nhi)
        batch.empty[idx] |= empty

    def describe(self) -> str:
        return f"SetNewton(parameters={self.test.q})"


def check_tolerant_options(
    robot: Robot,
    formulation: str,
    *,
    seed_planar: bool = False,
    stable_only: bool = False,
    checkpoint: bool = False,
) -> None:
    """The cheap checks of an FK request on a robot with tolerances (no expression built):
    :class:`~certsolve.inputs.InputError` naming ``robot.tolerances`` (toleranced
    attachments or centre of mass), ``formulation`` (``pose``) or the option that the FK of
    a set does not take (``seed_planar``, ``stable_only``, ``checkpoint``)."""
    if not robot.toleranced:
        return
    b = robot.bounds()
    for name, path in (("B", "platform"), ("com", "center_of_mass")):
        if not np.all(b.exact(name)):
            raise InputError(
                "robot.tolerances",
                f"forward kinematics within tolerances takes exact {path} coordinates "
                "(anchors, k, K, V, L0 and the mass may be toleranced)",
            )
    if formulation == "pose":
        raise InputError("formulation", "pose does not take tolerances; use auto or frame")
    for name, on in (
        ("seed_planar", seed_planar),
        ("stable_only", stable_only),
        ("checkpoint", checkpoint),
    ):
        if on:
            raise InputError(name, "not available for a robot with tolerances")


def _as_variables(e: Expr, names: set[str], memo: dict[int, Expr]) -> Expr:
    """``e`` with the parameters ``names`` read as variables of the same names."""
    got = memo.get(id(e))
    if got is not None:
        return got
    if e.op == "param" and e.param in names:
        out = var(e.param)
    elif not e.args:
        out = e
    else:
        out = Expr(e.op, tuple(_as_variables(a, names, memo) for a in e.args), e.param)
    memo[id(e)] = out
    return out


class SetKrawczyk:
    """The Krawczyk test of a robot set, with the numbers' intervals ``P`` apart:

        K(X) = c - Y f(c, p0) - (Y J_p(c, P)) (P - p0) + (I - Y J_x(X, P)) (X - c).

    For one robot ``p ∈ P`` the mean-value theorem in ``p`` gives ``f(c, p) ∈ f(c, p0) +
    J_p(c, P)(p - p0)``, and ``J_x(X, p) ⊆ J_x(X, P)``, so that robot's own Krawczyk image
    lies in ``K(X)``: ``K(X) ⊂ int X`` proves that *every* robot of the set has exactly one
    equilibrium in ``X``, inside ``K(X)``.  Writing ``Y f(c, P)`` this way (first order in
    the numbers, the product ``Y J_p`` taken before the radius) instead of enclosing
    ``f(c, P)`` alone keeps the correlations between equations that share a number (a
    wire's ``k`` enters every equilibrium equation): on T-16 at 10 N with ±0.05 cm anchors
    and ±1 % on ``k`` the plain test fails at every size, this one proves a box a few
    tenths of a cm wide.

    The derivatives come from an auxiliary square system in ``(x, p)``: the FK equations
    with the numbers' parameters read as variables, and ``p = p0`` (never solved: it only
    makes the Jacobian's ``J_p`` columns available, :func:`_as_variables`).
    """

    def __init__(self, form: FKFormulation, u: np.ndarray):
        system = form.system
        tol = tolerance_parameters(form.robot)
        names = list(tol)
        self.n, self.q = system.n, len(names)
        lo = np.array([tol[t][0] for t in names])
        hi = np.array([tol[t][1] for t in names])
        self.p_lo, self.p_hi = lo, hi
        self.p0 = midpoint(lo, hi)
        self.dp = np.maximum(up(hi - self.p0), up(self.p0 - lo))
        memo: dict[int, Expr] = {}
        keep = set(names)
        eqs = [_as_variables(e, keep, memo) for e in system.equations]
        eqs += [var(t) - float(c) for t, c in zip(names, self.p0, strict=True)]
        dom = np.vstack([system.domain, np.stack([lo, hi], axis=1)])
        params = {f"u{i + 1}": float(v) for i, v in enumerate(u)}
        aug = System(list(system.variables) + names, dom, eqs, [], name="set", parameters=params)
        self.csys = CompiledSystem(aug)

    def pieces(self, plo: np.ndarray | None, phi: np.ndarray | None, B: int):
        """The parameter boxes ``(B, q)`` of a batch: the whole set's, or the pieces given."""
        if plo is None or phi is None:
            return np.tile(self.p_lo, (B, 1)), np.tile(self.p_hi, (B, 1))
        return plo, phi

    def _linearize(self, lo, hi, plo=None, phi=None):
        """``c``, ``Y``, ``f(c, p0)``, ``J_x(X, P)`` and ``J_p(c, P)`` (midpoint-radius), the
        radius of ``P - p0`` and the mask of boxes where they are usable."""
        n, B = self.n, lo.shape[0]
        c = midpoint(lo, hi)
        P_lo, P_hi = self.pieces(plo, phi, B)
        p0 = midpoint(P_lo, P_hi)
        dp = np.maximum(up(P_hi - p0), up(p0 - P_lo))
        _, _, jlo, jhi, ok = self.csys.eval_fj(
            np.hstack([lo, P_lo]), np.hstack([hi, P_hi]), check_domain=True
        )
        _, _, jplo, jphi, ok_c = self.csys.eval_fj(
            np.hstack([c, P_lo]), np.hstack([c, P_hi]), check_domain=True
        )
        flo, fhi = self.csys.eval_f_at(np.hstack([c, p0]))
        Jc, Jr = mr_from_bounds(jlo[:, :n, :n], jhi[:, :n, :n])
        fc, fr = mr_from_bounds(flo[:, :n], fhi[:, :n])
        pre = precondition(Jc, Jr, fc, fr)
        Pc, Pr = mr_from_bounds(jplo[:, :n, n:], jphi[:, :n, n:])
        return c, pre, (Jc, Jr), (fc, fr), (Pc, Pr), dp, pre.ok & ok & ok_c

    def _parameter_radius(self, Mc, Mr, dp) -> np.ndarray:
        """Radius of ``M (P - p0)`` for ``M ∈ Mc ± Mr`` ``(B, k, q)``, ``|P - p0| <= dp``."""
        B = Mc.shape[0]
        with np.errstate(all="ignore"):
            _, tr = mr_matmul(Mc, Mr, np.zeros((B, self.q, 1)), dp[:, :, None])
        return tr[..., 0]

    def __call__(self, lo: np.ndarray, hi: np.ndarray, plo=None, phi=None):
        """``(klo, khi, proven)`` for boxes ``(B, n)`` of the FK variables, over the whole
        set or, row by row, over the robots of the parameter boxes ``[plo, phi]``."""
        klo, khi, proven, usable = self.image(lo, hi, plo, phi)
        return klo, khi, proven & usable

    def image(self, lo: np.ndarray, hi: np.ndarray, plo=None, phi=None):
        """``(klo, khi, proven, usable)``: ``K(X)``, ``K(X) ⊂ int X``, and where the
        linearisation is usable (elsewhere ``K(X)`` is not an enclosure of anything)."""
        c, pre, _, _, (Pc, Pr), dp, good = self._linearize(lo, hi, plo, phi)
        Y = np.where(pre.ok[:, None, None], pre.Y, 0.0)
        with np.errstate(all="ignore"):
            YPc, YPr = mr_matmul(Y, None, Pc, Pr)
            br = up(pre.br + self._parameter_radius(YPc, YPr, dp))
        mag = krawczyk_magnitude(pre.Mc, pre.Mr)
        klo, khi, proven = krawczyk_image(c, lo, hi, mag, pre.bc, br)
        usable = good & all_last(np.isfinite(br) & np.isfinite(klo) & np.isfinite(khi))
        return klo, khi, proven, usable

    def regular(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Mask of the boxes where every matrix of ``J_x(X, P)`` is nonsingular, proven by
        ``|I - Y J_x(X, P)| w < w`` with ``w`` the box's widths (the spectral radius of the
        bound is then below 1): each robot of the set has at most one equilibrium there."""
        _, pre, _, _, _, _, good = self._linearize(lo, hi)
        mag = krawczyk_magnitude(pre.Mc, pre.Mr)
        w = hi - lo
        with np.errstate(all="ignore"):
            mw = up((mag @ w[..., None])[..., 0] * (1.0 + 2.0 * gamma(self.n + 2)))
        return good & all_last(mw < w) & all_last(w > 0)

    def linear_image(self, lo: np.ndarray, hi: np.ndarray, T: np.ndarray):
        """Bounds ``(B, k)`` of ``T x`` over the equilibria ``x`` in the boxes of every robot
        of the set (``T`` ``(k, n)``; infinite where the linearisation is unusable).

        For an equilibrium ``x ∈ X`` of robot ``p``, ``0 = f(x, p) = f(c, p) + J̃ (x - c)``
        with ``J̃ ∈ J_x(X, P)`` (mean value), so ``x = c - Y f(c, p) + (I - Y J̃)(x - c)``
        and ``T x ∈ T c - (T Y) f(c, p0) - (T Y J_p(c, P))(P - p0) + (T - T Y J_x(X, P))(X -
        c)``: the first-order term keeps the correlation between the coordinates that a
        product of ``T`` with the box ``K(X)`` loses (a platform point is the reference point
        plus an edge vector, which move together)."""
        c, pre, (Jc, Jr), (fc, fr), (Pc, Pr), dp, good = self._linearize(lo, hi)
        Y = np.where(pre.ok[:, None, None], pre.Y, 0.0)
        with np.errstate(all="ignore"):
            TYc, TYr = mr_matmul(T[None], None, Y, None)
            t1c, t1r = mr_matmul(T[None], None, c[..., None], None)
            t2c, t2r = mr_matmul(TYc, TYr, fc[..., None], fr[..., None])
            TPc, TPr = mr_matmul(TYc, TYr, Pc, Pr)
            t3r = self._parameter_radius(TPc, TPr, dp)
            Mc, Mr = mr_matmul(TYc, TYr, Jc, Jr)
            rx = up(np.maximum(hi - c, c - lo))
            D = np.abs(T[None] - Mc)
            t4r = (D + up(Mr + 4.0 * U * D)) @ rx[..., None]
            t4r = up(t4r[..., 0] * (1.0 + 2.0 * gamma(self.n + 2)))  # the product's rounding
            center = t1c[..., 0] - t2c[..., 0]
            rad = up(up(up(t1r[..., 0] + t2r[..., 0]) + t3r) + t4r)
            rad = up(rad + 4.0 * U * np.abs(center))
        rad = np.where(good[:, None] & np.isfinite(rad), rad, np.inf)
        return down(center - rad), up(center + rad)


def _prove_seeds(test: SetKrawczyk, seeds: np.ndarray) -> tuple[np.ndarray, ...]:
    """Unicity and existence boxes around the seed points (module docstring, step 2):
    ``(proven mask, E_lo, E_hi, U_lo, U_hi)``.

    Epsilon-inflation from the seed: ``X`` starts as ``x* ± (2 |Y f(x*, P)| + 0.1 max)`` and
    becomes ``K(X)`` widened by half its radius until ``K(X) ⊂ int X``; the proven ``U`` is
    then grown by factors of 2 while the test still passes (a larger ``U`` leaves less for
    the search to exclude next to the set), and ``E ← K(E) ∩ E`` from the first proven box
    until it stops shrinking."""
    S, n = seeds.shape
    lo, hi = seeds.copy(), seeds.copy()
    klo, khi, _ = test(lo, hi)
    r = 2.0 * np.maximum(khi - seeds, seeds - klo)
    r = r + 0.1 * np.max(r, axis=1, keepdims=True) + 1e-9 * (1.0 + np.abs(seeds))
    lo, hi = seeds - r, seeds + r
    proven = np.zeros(S, dtype=bool)
    elo, ehi = lo.copy(), hi.copy()
    for _ in range(_MAX_INFLATE):
        todo = np.flatnonzero(~proven)
        if todo.size == 0:
            break
        klo, khi, ok = test(lo[todo], hi[todo])
        done = todo[ok]
        proven[done] = True
        elo[done], ehi[done] = klo[ok], khi[ok]
        with np.errstate(invalid="ignore", over="ignore"):
            kc, kr = 0.5 * klo + 0.5 * khi, 0.5 * (khi - klo)
        grow = todo[~ok & all_last(np.isfinite(kr))]
        keep = ~ok & all_last(np.isfinite(kr))
        lo[grow] = np.minimum(kc[keep] - 1.5 * kr[keep], lo[grow])
        hi[grow] = np.maximum(kc[keep] + 1.5 * kr[keep], hi[grow])
    ulo, uhi = lo.copy(), hi.copy()
    active = proven.copy()
    for _ in range(_MAX_GROW):  # U twice as wide around its centre, while proven
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        mid, rad = 0.5 * ulo[idx] + 0.5 * uhi[idx], uhi[idx] - ulo[idx]
        _, _, ok = test(mid - rad, mid + rad)
        ulo[idx[ok]], uhi[idx[ok]] = (mid - rad)[ok], (mid + rad)[ok]
        active[idx[~ok]] = False
    elo, ehi = np.fmax(elo, lo), np.fmin(ehi, hi)
    elo[proven], ehi[proven] = _tighten(test, elo[proven], ehi[proven])
    return proven, elo, ehi, ulo, uhi


def _tighten(test: SetKrawczyk, elo: np.ndarray, ehi: np.ndarray):
    """``E ← K(E) ∩ E`` until no side shrinks by more than :data:`_TIGHT` of its width: every
    equilibrium of every robot of the set in ``E`` stays in ``K(E)`` (Krawczyk's operator
    keeps the zeros of the box, proven or not)."""
    elo, ehi = elo.copy(), ehi.copy()
    for _ in range(_MAX_TIGHTEN):
        if elo.shape[0] == 0:
            break
        klo, khi, _ = test(elo, ehi)
        nlo, nhi = np.fmax(elo, klo), np.fmin(ehi, khi)
        gain = np.max((nlo - elo + ehi - nhi) / (ehi - elo), axis=1)
        elo, ehi = nlo, nhi
        if not np.any(gain > _TIGHT):
            break
    return elo, ehi


def _regular_box(test: SetKrawczyk, seed: np.ndarray, elo: np.ndarray, ehi: np.ndarray):
    """For a seed whose whole-set test failed: a box ``U`` around it where every robot of
    the set has **at most one** equilibrium, and the nominal one's ``[elo, ehi]`` lies in
    ``int U``; ``(U_lo, U_hi)`` or None.

    ``|I - Y J_x(U, P)| w < w`` (:meth:`SetKrawczyk.regular`) proves every matrix of
    ``J_x(U, P)`` nonsingular, so two equilibria of one robot in ``U`` are equal (mean
    value).  *Existence* for every robot then follows from the search of the rest
    (:func:`tolerant_forward_kinematics`): if no robot of the set has an equilibrium on
    ``∂U``, the degree of ``f(·, p)`` on ``U`` is the same for every ``p`` of the (connected)
    parameter box as for the nominal robot, ``±1`` (one regular zero).  ``U`` is
    ``x* ± s r``, ``r`` twice the first-order spread ``|Y J_p| dp``, at the largest scale
    ``s`` that passes."""
    x = seed[None]
    _, pre, _, _, (Pc, _), dp, good = test._linearize(x, x)
    if not good[0]:
        return None
    spread = np.abs(pre.Y[0] @ Pc[0]) @ dp[0]
    r = 2.0 * spread + 0.1 * spread.max() + 1e-9 * (1.0 + np.abs(seed))
    scales = np.array([1.0, 0.9, 0.75, 0.6, 0.5])
    ulo, uhi = seed - scales[:, None] * r, seed + scales[:, None] * r
    ok = test.regular(ulo, uhi) & all_last((ulo < elo) & (uhi > ehi))
    if not np.any(ok):
        return None
    k = int(np.argmax(ok))
    return ulo[k], uhi[k]


def tolerant_forward_kinematics(
    robot: Robot,
    u,
    *,
    formulation: str = "auto",
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    max_solutions: int | None = None,
    progress=None,
    executor: Any = None,
    verify: bool = False,
    cancel: Any = None,
) -> FKResult:
    """Every equilibrium of every robot of ``robot``'s set for the control ``u``, as pose
    boxes (module docstring).  The limits apply to the two searches together (the nominal
    one first); ``executor``, ``verify``, ``progress`` and ``cancel`` as
    :meth:`.FKSolver.solve`."""
    t0 = time.perf_counter()
    nominal = FKSolver(robot.nominal(), formulation, eps=eps)
    fk = FKSolver(robot, formulation, eps=eps)
    check_tolerances(robot, fk.form)
    search = {"progress": progress, "executor": executor, "cancel": cancel}
    first = nominal.solve(u, timeout=timeout, max_boxes=max_boxes, **search)
    u = first.u
    notes = [
        f"nominal robot: {first.status}, {len(first.solutions)} pose(s), "
        f"{first.stats.boxes} boxes (the stats are the set's search)"
    ]
    test = SetKrawczyk(fk.form, u)
    tsearch = fk.search(u, extra=(SetNewton(test),))
    if not tsearch.ok:
        notes.append("no wire length satisfies the tension limits inside the domain")
        res = SolveResult(list(fk.form.system.variables), SearchStatus.COMPLETE)
        return FKResult(robot.name, fk.formulation, u, res.status, [], res, notes=notes)
    solver = tsearch.solver
    seeds = np.array([0.5 * s.lo + 0.5 * s.hi for s in first.solve.solutions]).reshape(-1, solver.n)
    proven, elo, ehi, ulo, uhi = _prove_seeds(test, seeds)
    regular = np.zeros(len(seeds), dtype=bool)
    for i in np.flatnonzero(~proven):  # at most one per robot in U; existence below
        nom = first.solve.solutions[i]
        got = _regular_box(test, seeds[i], nom.lo, nom.hi)
        if got is not None:
            ulo[i], uhi[i] = got
            elo[i], ehi[i] = _tighten(test, ulo[i : i + 1], uhi[i : i + 1])
            regular[i] = True
    held = proven | regular
    if not np.all(held):
        notes.append(
            f"{int(np.sum(~held))} nominal pose(s) not proven for the whole set: "
            "their neighbourhood is searched"
        )
    kinds = solver.certifier.classify(elo[held], ehi[held]) if np.any(held) else []
    known = SolutionSet(solver.n)
    for a, b, c, d, kind in zip(elo[held], ehi[held], ulo[held], uhi[held], kinds):
        known.add(a, b, c, d, kind)
    plo, phi = boxes_minus(tsearch.domain[:, 0], tsearch.domain[:, 1], ulo[held], uhi[held])
    left = None if timeout is None else max(timeout - (time.perf_counter() - t0), 0.0)
    boxes_left = None if max_boxes is None else max(max_boxes - first.stats.boxes, 1)
    rest = solver.solve(
        boxes=(plo, phi),
        timeout=left,
        max_boxes=boxes_left,
        max_solutions=max_solutions,
        verify=verify,
        **search,
    )
    # a regular U holds an equilibrium of every robot when nothing of the rest meets it
    # (:func:`_regular_box`: no robot has one on its boundary)
    exists = proven.copy()
    if np.any(regular):
        clear = rest.status == SearchStatus.COMPLETE and not rest.undecided_dropped
        others = [(b.lo, b.hi) for b in rest.undecided] + [(b.lo, b.hi) for b in rest.solutions]
        for i in np.flatnonzero(regular):
            meets = any(np.all((a <= uhi[i]) & (b >= ulo[i])) for a, b in others)
            exists[i] = clear and not meets
        notes.append(
            f"{int(np.sum(regular))} pose box(es) proven by regularity and the boundary: "
            f"{int(np.sum(exists & regular))} with an equilibrium of every robot"
        )
    # the set's pose boxes: the seeds', then the search's own that are not a seed's
    sols, certs = [], []
    for k, i in enumerate(np.flatnonzero(held)):
        if kinds[k] == "ok":
            sols.append(Solution(lo=elo[i], hi=ehi[i], ulo=ulo[i], uhi=uhi[i]))
            certs.append("unique" if exists[i] else "undecided")
    for kind in set(kinds) - {"ok"}:
        notes.append(
            f"a proven pose box is '{kind}' (outside the domain or a constraint): left out"
        )
    for s in rest.solutions:
        if known.add(s.lo, s.hi, s.ulo, s.uhi, "ok"):
            sols.append(s)
            certs.append("unique")
    if verify and sols[: len(sols) - len(rest.solutions)]:
        from ..solver.verify import verify_solutions

        verify_solutions(solver.csys, sols)
    rest.solutions = sols
    poses = fk.decode_all(sols, u)
    for pose, s, cert in zip(poses, sols, certs, strict=True):
        pose.bounds = pose_bounds(fk.form, s.lo, s.hi, test)
        pose.certificate = cert
    notes.append(f"pieces searched outside the proven boxes: {plo.shape[0]}")
    status = rest.status
    return FKResult(robot.name, fk.formulation, u, status, poses, rest, notes=notes)
