"""The position determined by the orientation: a parametric interval Newton step on the forces.

For a fixed rotation ``R`` (in the platform frame: fixed edge vectors ``E_j``) the potential
energy (:mod:`.stability`)

    U(p; R) = Σ_i E_i(ρ_i(p)) - W·(p + R c),    ρ_i(p) = |p + b_i(E) - A_i|,

is convex in the reference point ``p = P_1``: each ``ρ_i`` is the norm of an affine map of
``p``, each ``E_i`` is convex and nondecreasing in ``ρ_i`` where the wire is taut
(``E_i' = τ_i >= 0``, ``E_i'' = τ_i' = k_i L0_i / L_i² > 0``), and the weight term is
linear.  Its gradient is minus the force balance of eq. (3),

    g(p; E, u) = Σ_i w_i(ρ_i(p)) (A_i - B_i(p)) + W,    w_i = τ_i / ρ_i,

and ``∂g/∂p = -Σ_i [τ_i' n_i n_iᵀ + w_i (I - n_i n_iᵀ)]`` (``n_i`` the unit wire
direction) is negative definite once the taut wires span the space: for each orientation
there is exactly one force-balanced position.  The search's own equations tie the wire
lengths to the pose only through the length equations, with ``ρ_i`` a free variable of the
box; writing ``ρ_i`` as ``|p + b_i - A_i|`` keeps the coupling ``τ_i' n_i n_iᵀ``.

**The step** (:class:`PositionNewton`, batched over boxes): for a box ``X`` of the
formulation's variables with position part ``[p]`` and orientation part ``[E]``, ``c`` the
midpoint of ``[p]``, ``g(c; [E], [u])`` and ``∂g/∂p([p]; [E], [u])`` are enclosed
(:class:`ForceBalance`), and one preconditioned interval Gauss-Seidel sweep
(:func:`.newton.hansen_sengupta`) narrows ``[p]``; an empty image empties the box.  The
wire lengths follow: ``ρ_i ∈ |[B_i - A_i]|`` over the narrowed box (at an equilibrium
``ρ_i = |B_i - A_i|``; T-16 at 60 N, u = IK(P): 259,883 -> 252,808 boxes, 19.2 -> 17.0
CPU s, one run each).  Boxes whose edge vectors are wider than ``max_turn`` (10 cm,
:data:`MAX_TURN`) are left as they are: there ``p*(E)`` moves by more than the enclosure
can refute (leaving a box alone is always sound).

*Soundness*: let ``(p*, E*)`` be an equilibrium in ``X``.  Then ``g(p*; E*) = 0`` and, by
the mean value theorem on the segment from ``c`` to ``p*`` (inside ``[p]``, with ``E*``
fixed), ``0 = g(c; E*) + J (p* - c)`` for some ``J`` in ``∂g/∂p([p]; E*)``, a member of the
enclosure over ``[E]``; so ``p*`` is in the Hansen-Sengupta image, whatever the
orientation in ``[E]``.  Convexity is not used by the proof, only by the tightness: a
regular Jacobian.  The step needs ``g`` differentiable over the box (every ``ρ_i`` and
``L_i`` positive); other boxes are left as they are.

**The enclosures** are written by hand with outward-rounded interval arithmetic
(:mod:`certsolve.interval.arith`), batched over boxes and wires: the expression DAG's
derivative of ``w_i(|a_i|) a_i`` loses the structure (over a 20 cm position box of T-16 at
60 N the diagonal of its Jacobian enclosure is 12-29 times the Jacobian's range, this one's
9-26 times: the rest is the wires' terms summed as independent intervals).  Per wire,
``a_i = B_i - A_i`` ranges over a box ``[a_i]``; ``ρ_i ∈ [|mig a_i|, |mag a_i|]``; each
component of ``n_i = a_i / |a_i|`` is monotone in that component of ``a_i`` and in the
others' magnitude (:func:`unit_vector_bounds`: exact up to rounding); ``τ_i`` (increasing
in ``L_i``) and ``τ_i' = k_i L0_i / L_i²`` (decreasing) come from
``[L_i] = [ρ_i] + V_i + K_i [u_i]``.  With the wire's block of the Hessian
``H_i = [w_i] I + ([τ_i'] - [w_i]) [n_i n_iᵀ]`` (``n_ic²`` as a square),
``∂g/∂p ∈ -Σ_i H_i`` over the box, and ``g(c)`` is enclosed twice and intersected:
directly, ``W - Σ_i [τ_i][n_i]``, and by its mean-value form in the orientation,
``g(c, E_m) + Σ_j ∂g/∂E_j ([E_j] - E_m,j)`` with ``∂g/∂E_j = -Σ_i l_ij H_i`` over
``{c} × [E]`` (``E_m`` the orientation's midpoint; the segment from ``E_m`` to any ``E*``
is in the box), which keeps the wires' first-order coupling: on T-16 at 60 N, u = IK(P),
it is what makes the step refute (docs/fk-cost.md).
``B_i - A_i = P_1 - A_i + Σ_j l_ij E_j`` with the system's own coefficients (the platform
frame of :mod:`.fk_points` writes ``b_i`` with the same floats), and the robot's numbers
as the intervals of :meth:`.Robot.bounds`, so the step covers the system's solutions.  Only
the platform-frame formulations have a position apart from the orientation (``x1, y1, z1``
and the edge vectors ``E_j``).
"""

from __future__ import annotations

import numpy as np

from ..expr import CompiledSystem
from ..interval import arith
from ..interval.core import midpoint
from ..solver.batch import Batch
from ..solver.newton import hansen_sengupta, linearization_from_bounds
from .fk_formulation import FKFormulation

__all__ = [
    "MAX_TURN",
    "ForceBalance",
    "PositionNewton",
    "applies",
    "norm_bounds",
    "symmetric_pairs",
    "unit_vector_bounds",
]

#: the coefficients the platform frame drops from ``b_i = Σ_j l_ij E_j`` (``fk_points``)
_TINY = 1e-14


def _sum(lo: np.ndarray, hi: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """The outward-rounded sum of intervals along ``axis`` (one rounded add a term)."""
    lo, hi = np.moveaxis(lo, axis, 0), np.moveaxis(hi, axis, 0)
    slo, shi = lo[0], hi[0]
    for k in range(1, lo.shape[0]):
        slo, shi = arith.add(slo, shi, lo[k], hi[k])
    return slo, shi


def _magnitudes(alo: np.ndarray, ahi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``mig`` and ``mag`` of intervals: the least and the largest ``|a|``."""
    mag = np.maximum(np.abs(alo), np.abs(ahi))
    mig = np.where((alo <= 0.0) & (ahi >= 0.0), 0.0, np.minimum(np.abs(alo), np.abs(ahi)))
    return mig, mag


def norm_bounds(alo: np.ndarray, ahi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of ``|a|`` over boxes ``[alo, ahi]`` ``(..., d)``: ``[|mig a|, |mag a|]``."""
    mig, mag = _magnitudes(alo, ahi)
    lo = arith.sqrt(*_sum(*arith.sqr(mig, mig), axis=-1))[0]
    hi = arith.sqrt(*_sum(*arith.sqr(mag, mag), axis=-1))[1]
    return lo, hi


def unit_vector_bounds(alo: np.ndarray, ahi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of ``n = a / |a|`` over boxes ``[alo, ahi]`` ``(..., d)`` free of 0.

    ``n_c = a_c / sqrt(a_c² + s²)`` (``s²`` the others' squares) is increasing in ``a_c``,
    and in ``s²`` decreasing where ``a_c > 0``, increasing where ``a_c < 0``: its largest
    value is at ``a_c = hi_c`` with the least ``s²`` if ``hi_c >= 0`` (else the largest),
    its least at ``a_c = lo_c`` likewise.  Each end is a rigorous interval quotient; a box
    holding 0 gives NaN (no bound, no contraction).
    """
    mig, mag = _magnitudes(alo, ahi)
    d = alo.shape[-1]
    rest = np.array([[j for j in range(d) if j != c] for c in range(d)])  # (d, d - 1)
    with np.errstate(all="ignore"):
        qlo, qhi = arith.sqr(mig, mig)
        small = _sum(qlo[..., rest], qhi[..., rest], axis=-1)  # (..., d): the others' sums
        qlo, qhi = arith.sqr(mag, mag)
        large = _sum(qlo[..., rest], qhi[..., rest], axis=-1)
        ends = []
        for end, pick in ((alo, 0), (ahi, 1)):
            toward = (end <= 0.0) if pick == 0 else (end >= 0.0)
            slo = np.where(toward, small[0], large[0])
            shi = np.where(toward, small[1], large[1])
            den = arith.sqrt(*arith.add(*arith.sqr(end, end), slo, shi))
            ends.append(arith.div_nonzero(end, end, *den)[pick])
        empty = np.all(mig == 0.0, axis=-1, keepdims=True)
    nlo = np.where(empty, np.nan, np.maximum(ends[0], -1.0))
    nhi = np.where(empty, np.nan, np.minimum(ends[1], 1.0))
    return nlo, nhi


def symmetric_pairs(d: int) -> tuple[np.ndarray, np.ndarray]:
    """The entries of a symmetric ``d x d`` matrix stored once: ``pairs`` ``(S, 2)`` the
    diagonal ``(c, c)`` first, then ``(c, e)`` for ``c < e``, and ``full`` ``(d, d)`` the
    entry of each ``(c, e)`` (``matrix = stored[..., full]``)."""
    pairs = [(c, c) for c in range(d)] + [(c, e) for c in range(d) for e in range(c + 1, d)]
    full = np.empty((d, d), dtype=np.int64)
    for k, (c, e) in enumerate(pairs):
        full[c, e] = full[e, c] = k
    return np.array(pairs, dtype=np.int64), full


def _pull(tau, nlo, nhi) -> tuple[np.ndarray, np.ndarray]:
    """``[τ_i][n_i]`` ``(B, m, d)``: minus each wire's force on the platform (``n_i`` points
    from ``A_i`` to ``B_i``)."""
    return arith.mul(tau[0][..., None], tau[1][..., None], nlo, nhi)


def applies(form: FKFormulation) -> bool:
    """Whether the formulation has a position apart from the orientation: the platform
    frame's reference point ``x1, y1, z1`` and edge vectors ``E_j`` among its variables."""
    L = getattr(form, "L", None)
    if L is None:
        return False
    names = set(form.system.variables)
    axes = "xyz"[: form.robot.dim]
    wanted = [f"{a}1" for a in axes] + [f"e{a}{j + 1}" for j in range(1, L.shape[1]) for a in axes]
    return all(v in names for v in wanted)


#: :class:`PositionNewton`'s default ``max_turn`` (cm): boxes whose edge vectors are wider are
#: left alone (T-16 tau<=60 u=IK(P): 28.5 % of the boxes the step sees, 13 % of those it
#: empties; the search 252,808 -> 257,034 boxes)
MAX_TURN = 10.0


class ForceBalance:
    """The force balance ``g(p; E, u)`` with ``ρ_i = |B_i - A_i|`` and its Jacobian in the
    position ``p = P_1``, for a platform-frame formulation (module docstring).

    :meth:`enclose` gives ``g`` at the position's midpoint and ``∂g/∂p`` over the box, over
    the box's orientations, for a batch of boxes of the formulation's variables.
    ``centred=False`` leaves out the mean-value form of ``g`` in the orientation (for
    comparison: T-16 at 60 N, u = IK(P), 305,646 boxes against 259,883).
    """

    def __init__(self, form: FKFormulation, centred: bool = True):
        self.centred = centred
        names = list(form.system.variables)
        robot = form.robot
        d = robot.dim
        axes = "xyz"[:d]
        if not applies(form):
            raise ValueError(
                f"formulation: {form.name} has no reference point apart from the orientation "
                "(the position Newton step needs the platform frame)"
            )
        L = form.L  # type: ignore[attr-defined]
        edges = [[f"e{a}{j + 1}" for a in axes] for j in range(1, L.shape[1])]
        self.d, self.m = d, robot.m
        #: the stored entries of the symmetric blocks ``H_i`` (:func:`symmetric_pairs`)
        self.pairs, self.full = symmetric_pairs(d)
        #: the columns of the reference point ``P_1`` ``(d,)`` and of the edge vectors
        #: ``E_2..E_k`` ``(k - 1, d)``
        self.position = np.array([names.index(f"{a}1") for a in axes])
        #: the columns of the wire lengths, in wire order
        self.rho = np.array([names.index(f"rho{i + 1}") for i in range(robot.m)])
        self.edges = np.array([[names.index(v) for v in row] for row in edges], dtype=np.int64)
        coef = np.asarray(L, dtype=float)[:, 1:]
        #: ``l_ij`` of ``b_i = Σ_j l_ij E_j`` ``(m, k - 1)``, as the system writes them
        self.coef = np.where(np.abs(coef) > _TINY, coef, 0.0)
        b = robot.bounds()
        self.A, self.k, self.L0, self.V, self.K = b.A, b.k, b.L0, b.V, b.K
        self.kL0 = arith.mul(*b.k, *b.L0)
        self.W = robot.weight_bounds()
        #: the parameters ``u1..um``, in the order of the formulation's system
        self.u_index = np.array(
            [list(form.system.parameters).index(f"u{i + 1}") for i in range(robot.m)]
        )

    def turns(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``[b_i] = Σ_j l_ij [E_j]`` ``(B, m, d)`` over boxes of the variables: the part of
        ``B_i - A_i`` the orientation gives (the same for every position in the box)."""
        elo, ehi = lo[:, self.edges], hi[:, self.edges]  # (B, k - 1, d)
        c = self.coef[None, :, :, None]
        return _sum(*arith.scale(elo[:, None], ehi[:, None], c), axis=2)  # (B, m, d)

    def arms(self, lo: np.ndarray, hi: np.ndarray, turn=None) -> tuple[np.ndarray, np.ndarray]:
        """``[B_i - A_i]`` ``(B, m, d)`` over boxes of the variables (``turn``: their
        :meth:`turns`, if known)."""
        blo, bhi = self.turns(lo, hi) if turn is None else turn
        plo, phi = lo[:, None, self.position], hi[:, None, self.position]
        return arith.sub(*arith.add(plo, phi, blo, bhi), *self.A)

    def wires(self, lo, hi, ulo, uhi, turn=None):
        """Per wire over the boxes: ``[n_i]`` ``(B, m, d)`` and ``[τ_i]``, ``[τ_i']``,
        ``[w_i]`` ``(B, m)``, and whether every ``ρ_i`` and ``L_i`` is positive."""
        alo, ahi = self.arms(lo, hi, turn)
        nlo, nhi = unit_vector_bounds(alo, ahi)
        rho = norm_bounds(alo, ahi)
        off = arith.add(*self.V, *arith.mul(*self.K, ulo, uhi))
        Llo, Lhi = arith.add(*rho, *off)
        with np.errstate(all="ignore"):
            tau = arith.sub(*self.k, *arith.div_nonzero(*self.kL0, Llo, Lhi))
            dtau = arith.div_nonzero(*self.kL0, *arith.sqr(Llo, Lhi))
            w = arith.div_nonzero(*tau, *rho)
        ok = np.all((rho[0] > 0.0) & (Llo > 0.0), axis=1)
        return (nlo, nhi), tau, dtau, w, ok

    def stiffness(self, lo, hi, ulo, uhi, turn=None):
        """Each wire's ``H_i = w_i I + (τ_i' - w_i) n_i n_iᵀ`` over the boxes ``(B, m, S)``
        (``∂(τ_i n_i)/∂a_i``, symmetric: its ``S = d(d + 1)/2`` entries in the order of
        :func:`symmetric_pairs`), ``[τ_i][n_i]`` ``(B, m, d)``, and where every ``ρ_i`` and
        ``L_i`` is positive."""
        d = self.d
        (nlo, nhi), tau, dtau, w, ok = self.wires(lo, hi, ulo, uhi, turn)
        clo, chi = arith.sub(*dtau, *w)
        rows, cols = self.pairs[:, 0], self.pairs[:, 1]
        # n_ic n_ie for c < e as products, n_ic² as squares (tighter: a square is >= 0)
        olo, ohi = arith.mul(
            nlo[..., rows[d:]], nhi[..., rows[d:]], nlo[..., cols[d:]], nhi[..., cols[d:]]
        )
        qlo, qhi = arith.sqr(nlo, nhi)
        olo, ohi = np.concatenate((qlo, olo), axis=-1), np.concatenate((qhi, ohi), axis=-1)
        hlo, hhi = arith.mul(clo[..., None], chi[..., None], olo, ohi)
        hlo[..., :d], hhi[..., :d] = arith.add(
            hlo[..., :d], hhi[..., :d], w[0][..., None], w[1][..., None]
        )
        return (hlo, hhi), _pull(tau, nlo, nhi), ok

    def balance(self, lo, hi, ulo, uhi):
        """``g = W - Σ_i [τ_i][n_i]`` over the boxes ``(B, d)``, and where it is defined."""
        (nlo, nhi), tau, _, _, ok = self.wires(lo, hi, ulo, uhi)
        return arith.sub(*self.W, *_sum(*_pull(tau, nlo, nhi), axis=1)), ok

    def enclose(self, lo, hi, plo, phi, turn=None):
        """``(c, flo, fhi, jlo, jhi, defined)`` for boxes ``lo, hi`` ``(B, n)`` and parameters
        in ``[plo, phi]``: ``c`` ``(B, d)`` the position's midpoint, ``g(c)`` over the box's
        orientations ``(B, d)``, ``∂g/∂p`` over the box ``(B, d, d)``, and where ``g`` is
        differentiable on the box (every ``ρ_i > 0`` and ``L_i > 0``).

        ``g(c)`` is the intersection of two enclosures: ``W - Σ_i [τ_i][n_i]`` directly, and
        the mean-value form in the orientation, ``g(c, E_m) + Σ_j ∂g/∂E_j ([E_j] - E_m,j)``
        with ``∂g/∂E_j = -Σ_i l_ij H_i`` over ``{c} × [E]`` (``E_m`` the orientation's
        midpoint), which keeps the wires' first-order coupling.  ``turn``: the boxes'
        :meth:`turns`, if known (the box and ``{c} × [E]`` share them)."""
        pos = self.position
        ulo, uhi = plo[self.u_index], phi[self.u_index]
        turn = self.turns(lo, hi) if turn is None else turn
        (hlo, hhi), _, ok = self.stiffness(lo, hi, ulo, uhi, turn)
        jlo, jhi = _sum(hlo, hhi, axis=1)  # Σ_i H_i, its S entries
        jlo, jhi = -jhi[:, self.full], -jlo[:, self.full]  # ∂g/∂p = -Σ_i H_i
        c = midpoint(lo[:, pos], hi[:, pos])
        at_c = lo.copy(), hi.copy()
        for x in at_c:
            x[:, pos] = c
        (klo, khi), pull, okc = self.stiffness(*at_c, ulo, uhi, turn)
        flo, fhi = arith.sub(*self.W, *_sum(*pull, axis=1))  # W - Σ_i [τ_i][n_i]
        if self.centred:
            em = midpoint(lo[:, self.edges], hi[:, self.edges])  # (B, k - 1, d)
            mid = lo.copy()
            mid[:, pos] = c
            mid[:, self.edges] = em
            (glo, ghi), okm = self.balance(mid, mid, ulo, uhi)
            dlo = arith.sub(lo[:, self.edges], lo[:, self.edges], em, em)[0]
            dhi = arith.sub(hi[:, self.edges], hi[:, self.edges], em, em)[1]
            for j in range(self.edges.shape[0]):
                # ∂g/∂E_j [E_j - E_m,j] = -Σ_i l_ij H_i [E_j - E_m,j]
                slo, shi = _sum(*arith.scale(klo, khi, self.coef[None, :, j, None]), axis=1)
                slo, shi = slo[:, self.full], shi[:, self.full]
                tlo, thi = arith.mul(slo, shi, dlo[:, j, None, :], dhi[:, j, None, :])
                glo, ghi = arith.sub(glo, ghi, *_sum(tlo, thi, axis=-1))
            flo, fhi = np.maximum(flo, glo), np.minimum(fhi, ghi)
            okc &= okm
        return c, flo, fhi, jlo, jhi, ok & okc


class PositionNewton:
    """``contract(lo, hi) -> (lo, hi, empty)``: the position narrowed to its Newton image
    over the box's orientations (module docstring); ``empty`` where the image is empty.

    ``u`` (and a robot's toleranced numbers) are read from the compiled system's parameters
    at each call, so the step is built per search on that search's system.
    """

    def __init__(self, forces: ForceBalance, csys: CompiledSystem, max_turn: float = MAX_TURN):
        self.forces = forces
        self.csys = csys
        #: boxes whose edge vectors are wider than this (their widest component) are left
        #: as they are: over a wide orientation the force-balanced position moves more than
        #: the enclosure can refute
        self.max_turn = max_turn

    def apply(self, batch: Batch) -> None:
        """The solver's contractor protocol (:mod:`certsolve.solver.batch`)."""
        batch.lo, batch.hi, empty = self.contract(batch.lo, batch.hi)
        batch.empty |= empty

    def describe(self) -> str:
        """Its entry in the solver's fingerprint."""
        return f"PositionNewton(max_turn={self.max_turn})"

    def contract(self, lo: np.ndarray, hi: np.ndarray):
        edges = self.forces.edges
        turn = np.max(hi[:, edges] - lo[:, edges], axis=(1, 2))
        take = turn <= self.max_turn
        if take.all():
            return self._contract(lo, hi)
        lo, hi = lo.copy(), hi.copy()
        empty = np.zeros(lo.shape[0], dtype=bool)
        if take.any():
            lo[take], hi[take], empty[take] = self._contract(lo[take], hi[take])
        return lo, hi, empty

    def _contract(self, lo: np.ndarray, hi: np.ndarray):
        pos = self.forces.position
        turn = self.forces.turns(lo, hi)
        c, flo, fhi, jlo, jhi, defined = self.forces.enclose(
            lo, hi, self.csys.param_lo, self.csys.param_hi, turn
        )
        lin = linearization_from_bounds(lo[:, pos], hi[:, pos], c, flo, fhi, jlo, jhi, defined)
        plo, phi, empty = hansen_sengupta(lin)
        lo, hi = lo.copy(), hi.copy()
        lo[:, pos] = plo
        hi[:, pos] = phi
        # the wire lengths through the pose: ρ_i ∈ |[B_i - A_i]| over the narrowed box
        rho = self.forces.rho
        live = ~empty
        rlo, rhi = norm_bounds(
            *self.forces.arms(lo[live], hi[live], (turn[0][live], turn[1][live]))
        )
        lo[np.ix_(live, rho)] = np.fmax(lo[np.ix_(live, rho)], rlo)
        hi[np.ix_(live, rho)] = np.fmin(hi[np.ix_(live, rho)], rhi)
        empty |= np.any(lo > hi, axis=1)
        return lo, hi, empty
