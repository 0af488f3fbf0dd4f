"""Contractors: narrow a batch of boxes without losing any solution (IBEX ``Ctc``).

Each contractor is a small class with two faces:

* the pipeline's protocol (:mod:`.batch`): ``apply(batch)`` on the round's
  :class:`~.batch.Batch` and ``describe()`` for the checkpoint fingerprint;
* its kernel on arrays, ``contract(lo, hi)`` on a batch ``(B, n)`` of boxes, returning
  ``(lo, hi, empty)`` (``empty[k]`` proves box ``k`` holds no solution) -- or, for
  :class:`IntervalNewton`, the whole :class:`NewtonStep` (the proof and the linearisation
  come with the contraction).

* :class:`HC4` -- forward-backward propagation on every equation and constraint at once
  (:meth:`certsolve.expr.compiled.CompiledSystem.hc4_revise`), repeated while it narrows.
* :class:`IntervalNewton` -- one Hansen–Sengupta sweep (:mod:`.newton`); it also keeps the
  :class:`~.newton.Linearization` and runs the Krawczyk test on the input boxes, because
  the proof reuses the same Jacobian and preconditioner for free.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval.core import midpoint
from ..interval.reductions import all_last
from .batch import BISECTION_GAIN, Batch, log_volume_ratio
from .newton import (
    Linearization,
    hansen_sengupta,
    krawczyk,
    linearization_from_bounds,
    linearize,
)

__all__ = [
    "HC4",
    "IntervalNewton",
    "NewtonStep",
    "PartialNewton",
    "informative",
    "log_volume_ratio",
]


class HC4:
    """HC4 propagation, iterated up to ``max_passes`` while some box shrinks by ``ratio``."""

    def __init__(self, csys: CompiledSystem, max_passes: int = 4, ratio: float = 0.1):
        self.csys = csys
        self.max_passes = max_passes
        self.threshold = float(np.log1p(-ratio))

    def contract(self, lo, hi):
        """Repeat HC4-revise on the boxes that keep shrinking (by ``ratio`` of volume)."""
        lo, hi = lo.copy(), hi.copy()
        empty = np.zeros(lo.shape[0], dtype=bool)
        active = np.arange(lo.shape[0])
        for _ in range(self.max_passes):
            nlo, nhi, emp = self.csys.hc4_revise(lo[active], hi[active])
            gain = log_volume_ratio(lo[active], hi[active], nlo, nhi)
            lo[active], hi[active] = nlo, nhi
            empty[active[emp]] = True
            active = active[~emp & (gain < self.threshold)]
            if active.size == 0:
                break
        return lo, hi, empty

    def apply(self, batch: Batch) -> None:
        batch.lo, batch.hi, empty = self.contract(batch.lo, batch.hi)
        batch.empty |= empty

    def describe(self) -> str:
        return f"HC4(passes={self.max_passes}, threshold={self.threshold!r})"


@dataclass
class NewtonStep:
    """Outcome of :meth:`IntervalNewton.contract` on a batch."""

    lin: Linearization  # linearisation of the *input* boxes (mixed Jacobian with groups)
    klo: np.ndarray  # Krawczyk image of the input boxes
    khi: np.ndarray
    proven: np.ndarray  # K(X) ⊂ int X: exactly one solution in the input box
    lo: np.ndarray  # contracted boxes
    hi: np.ndarray
    empty: np.ndarray

    @property
    def regular(self) -> np.ndarray:
        """Preconditioned pivots ``M_ii`` all free of 0: Newton is informative there."""
        return informative(self.lin)


def informative(lin: Linearization) -> np.ndarray:
    """``(B,)``: the linearisation is usable and its preconditioned pivots ``M_ii`` are all
    free of 0 (Newton is informative on the box)."""
    d = np.einsum("bii->bi", lin.Mc)
    r = np.einsum("bii->bi", lin.Mr)
    return lin.ok & all_last(np.abs(d) > r)


class IntervalNewton:
    """Hansen–Sengupta contraction plus the Krawczyk test on the same linearisation.

    ``groups`` (a list of boolean masks partitioning the variables) switches the
    Hansen–Sengupta step to Hansen's *mixed* Jacobian: the columns of group ``k`` are
    enclosed over the box whose groups ``1..k`` span ``X`` and whose later groups sit at the
    midpoint ``c``.  Every zero ``x*`` of ``X`` still satisfies ``0 ∈ f(c) + M (x* - c)``
    (mean value theorem along the path that moves one group at a time from ``c`` to ``x*``),
    so the contraction is sound, and sharper: cross terms with later groups are taken at
    the midpoint.  The Krawczyk *uniqueness* proof keeps the ordinary ``J(X)``.
    """

    def __init__(self, csys: CompiledSystem, groups=None, *, iterations: int = 1):
        if iterations < 1:
            raise ValueError("IntervalNewton needs at least 1 iteration")
        self.csys = csys
        self.groups = None if groups is None else [np.asarray(g, dtype=bool) for g in groups]
        #: Newton steps a box may take in one :meth:`apply` (IBEX's ``CtcNewton`` iterates
        #: until the box stops shrinking); a box takes another while its last step shrank
        #: it as much as a bisection would (:data:`.batch.BISECTION_GAIN`)
        self.iterations = int(iterations)
        if self.groups is not None:  # compile the programs now, not in the search
            csys.prepare_mixed(self.groups)

    def contract(self, lo, hi) -> NewtonStep:
        if self.groups is None:
            lin = linearize(self.csys, lo, hi)
            klo, khi, proven = krawczyk(lin)
        else:
            c = midpoint(lo, hi)
            # f(c) and group k's columns over (X_{1..k}, c_{k+1..}), in one program call
            flo, fhi, mlo, mhi, defined = self.csys.eval_f_mixed(lo, hi, c, self.groups)
            lin = linearization_from_bounds(lo, hi, c, flo, fhi, mlo, mhi, defined)
            # K with the mixed matrix ⊂ int X proves existence only (it is a slope-like
            # enclosure); uniqueness needs J(X): run the full test on those boxes alone
            klo, khi, maybe = krawczyk(lin)
            proven = np.zeros_like(maybe)
            if np.any(maybe):
                k = np.flatnonzero(maybe)
                _, _, jlo, jhi, defined = self.csys.eval_fj(lo[k], hi[k], check_domain=True)
                full = linearization_from_bounds(
                    lo[k], hi[k], c[k], flo[k], fhi[k], jlo, jhi, defined
                )
                fklo, fkhi, fp = krawczyk(full)
                proven[k] = fp
                klo[k] = np.fmax(klo[k], fklo)
                khi[k] = np.fmin(khi[k], fkhi)
        nlo, nhi, empty = hansen_sengupta(lin)
        # a box proven to hold a solution cannot be empty; keep the proof authoritative
        empty &= ~proven
        return NewtonStep(lin, klo, khi, proven, nlo, nhi, empty)

    def apply(self, batch: Batch) -> None:
        """Contract; a box proven to hold exactly one solution is recorded
        (``batch.prove``: existence box ``K(X) ∩ X``, unicity box ``X``) and leaves the
        round; the others keep the linearisation (``batch.jacobian()``, ``batch.regular``).

        With ``iterations > 1`` the boxes whose step shrank them at least as much as a
        bisection (progress gain ``<=`` :data:`.batch.BISECTION_GAIN`,
        :func:`.batch.progress_gain`) take another step on the contracted box, up to
        ``iterations`` steps in all, as IBEX's ``newton()`` loops while it gains: a
        converging box reaches its proof in this round instead of one round (HC4, Newton,
        the hull, CID) per step.  Each step
        is sound on its input box, hence on the round's box; a proof on a later step's box
        ``X' ⊆ X`` proves ``X'`` holds exactly one solution, and ``X \\ X'`` none.  The
        linearisation kept for a row is its last step's (its Jacobian encloses ``J`` over
        the row's box, which lies inside that step's input box).
        """
        lo0, hi0 = batch.lo, batch.hi
        step = self.contract(lo0, hi0)
        self._prove(batch, lo0, hi0, step)
        lo, hi, lin = step.lo, step.hi, step.lin
        empty, proven = step.empty, step.proven
        active = np.flatnonzero(~proven & ~empty)
        xlo, xhi = lo0[active], hi0[active]  # the last step's input boxes of ``active``
        for k in range(1, self.iterations):
            gain = batch.progress(xlo, xhi, lo[active], hi[active])
            active = active[gain <= BISECTION_GAIN]
            if active.size == 0:
                break
            if k == 1:  # the first step's arrays become this round's, rows rewritten
                lo, hi, empty, proven = lo.copy(), hi.copy(), empty.copy(), proven.copy()
            xlo, xhi = lo[active], hi[active]
            sub = self.contract(xlo, xhi)
            self._prove(batch, xlo, xhi, sub)
            lo[active], hi[active] = sub.lo, sub.hi
            empty[active] |= sub.empty
            proven[active] |= sub.proven
            lin = lin.with_rows(active, sub.lin)
            go = ~sub.proven & ~sub.empty
            active, xlo, xhi = active[go], xlo[go], xhi[go]
        batch.lo, batch.hi = lo, hi
        batch.empty = batch.empty | empty
        batch.linearization = lin
        batch.share_jacobian(lin.jlo, lin.jhi)
        batch.regular = informative(lin)
        if np.any(proven):
            batch.keep(~proven)

    @staticmethod
    def _prove(batch: Batch, lo, hi, step: NewtonStep) -> None:
        """Record the boxes ``step`` proved (existence ``K(X) ∩ N(X)``, unicity ``X``)."""
        p = step.proven
        if not np.any(p):
            return
        if batch.prove is None:
            raise RuntimeError("IntervalNewton proves solutions: the batch needs prove")
        elo = np.fmax(step.klo[p], step.lo[p])
        ehi = np.fmin(step.khi[p], step.hi[p])
        batch.prove(elo, ehi, lo[p], hi[p])

    def describe(self) -> str:
        groups = None if self.groups is None else [g.tolist() for g in self.groups]
        steps = f", iterations={self.iterations}" if self.iterations > 1 else ""
        return f"IntervalNewton(groups={groups}{steps})"


class PartialNewton:
    """Hansen–Sengupta on a square sub-system, the other variables as interval parameters.

    For equations ``S`` and variables ``V`` (``|S| = |V|``) and a box ``X``, every zero
    ``x`` of ``f`` in ``X`` satisfies, by the mean value theorem in the ``V`` components
    only,

        0 = f_S(c_V, x_R) + J_SV(ξ) (x_V - c_V),   ξ ∈ X,  x_R ∈ X_R,

    so the interval Gauss–Seidel step with ``f_S(c_V, X_R)`` (``f`` over the box whose
    ``V`` components are the midpoint) and ``J_SV(X)`` contracts ``X_V``.  The remaining
    variables ``R`` may stay wide: this contracts well whenever the sub-Jacobian is
    well conditioned over the box, even if the full one is not (forward kinematics: the
    translation of the platform and the wire lengths, given a box of orientations, are
    fixed by the force balance and the wire lengths).
    """

    def __init__(self, csys: CompiledSystem, equations, variables):
        self.csys = csys
        self.S = np.asarray(equations, dtype=np.int64)
        self.V = np.asarray(variables, dtype=np.int64)
        if self.S.shape != self.V.shape:
            raise ValueError("a partial Newton sub-system must be square")
        csys._column_program(tuple(sorted(int(j) for j in self.V)))

    def contract(self, lo, hi, jlo=None, jhi=None, defined=None):
        """Contract ``X_V``; ``jlo, jhi`` may be a Jacobian enclosure over a superset of X.

        Returns ``(lo, hi, empty)``.
        """
        S, V = self.S, self.V
        if jlo is None:
            _, _, jlo, jhi, defined = self.csys.eval_fj_columns(lo, hi, V)
        c = midpoint(lo[:, V], hi[:, V])
        plo, phi = lo.copy(), hi.copy()
        plo[:, V] = c
        phi[:, V] = c
        flo, fhi = self.csys.eval_f(plo, phi)
        sub_jlo = jlo[:, S][:, :, V]
        sub_jhi = jhi[:, S][:, :, V]
        lin = linearization_from_bounds(
            lo[:, V], hi[:, V], c, flo[:, S], fhi[:, S], sub_jlo, sub_jhi, defined
        )
        vlo, vhi, empty = hansen_sengupta(lin)
        nlo, nhi = lo.copy(), hi.copy()
        nlo[:, V] = vlo
        nhi[:, V] = vhi
        return nlo, nhi, empty

    def apply(self, batch: Batch) -> None:
        batch.lo, batch.hi, empty = self.contract(batch.lo, batch.hi)
        batch.empty |= empty

    def describe(self) -> str:
        return f"PartialNewton(equations={self.S.tolist()}, variables={self.V.tolist()})"
