"""Contractors: narrow a batch of boxes without losing any solution (IBEX ``Ctc``).

Each contractor is a small class with ``contract(lo, hi) -> (lo, hi, empty)`` acting on a
batch ``(B, n)`` of boxes; ``empty[k]`` proves box ``k`` holds no solution.

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
from .newton import Linearization, hansen_sengupta, krawczyk, linearize

__all__ = ["HC4", "IntervalNewton", "NewtonStep", "log_volume_ratio"]


def log_volume_ratio(lo0, hi0, lo1, hi1) -> np.ndarray:
    """``Σ_i log(w1_i / w0_i)`` per box (0 for degenerate components): < 0 means it shrank."""
    w0 = hi0 - lo0
    w1 = np.maximum(hi1 - lo1, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(w0 > 0.0, w1 / w0, 1.0)
        return np.sum(np.log(np.maximum(r, 1e-300)), axis=1)


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


@dataclass
class NewtonStep:
    """Outcome of :meth:`IntervalNewton.contract` on a batch."""

    lin: Linearization  # linearisation of the *input* boxes
    klo: np.ndarray  # Krawczyk image of the input boxes
    khi: np.ndarray
    proven: np.ndarray  # K(X) ⊂ int X: exactly one solution in the input box
    lo: np.ndarray  # contracted boxes
    hi: np.ndarray
    empty: np.ndarray

    @property
    def regular(self) -> np.ndarray:
        """Preconditioned pivots ``M_ii`` all free of 0: Newton is informative there."""
        lin = self.lin
        d = np.einsum("bii->bi", lin.Mc)
        r = np.einsum("bii->bi", lin.Mr)
        return lin.ok & np.all(np.abs(d) > r, axis=1)


class IntervalNewton:
    """Hansen–Sengupta contraction plus the Krawczyk test on the same linearisation."""

    def __init__(self, csys: CompiledSystem):
        self.csys = csys

    def contract(self, lo, hi) -> NewtonStep:
        lin = linearize(self.csys, lo, hi)
        klo, khi, proven = krawczyk(lin)
        nlo, nhi, empty = hansen_sengupta(lin)
        # a box proven to hold a solution cannot be empty; keep the proof authoritative
        empty &= ~proven
        return NewtonStep(lin, klo, khi, proven, nlo, nhi, empty)
