"""Which half of a bisected box the search takes first: the *dive*.

The buffer is a stack popped ``batch_size`` boxes a round (:mod:`.buffer`); a round pushes
both halves of every box it splits, and the halves pushed last are the next round's.  So
the half put on top decides where the depth-first descent goes.  It never changes what is
proven, only when: how many solutions a search stopped by its limit has certified (issue
30, *anytime search*), and the order in which a complete search meets them.

* :class:`LowerFirst` -- the lower half on top (IBEX's ``CellStack`` order).
* :class:`NewtonSide` (the solver's default) -- the half holding the Newton point
  ``N = c - J(c)^{-1} f(c)`` of the box's midpoint ``c``, computed in floats (a guess,
  not a proof); the lower half where ``N`` is not defined (a singular or non-finite
  ``J(c)``, a non-finite ``f(c)``).  Near a regular solution ``x*``, ``|N - x*|`` is of
  the order of ``|c - x*|^2``: the dive follows the solution into the half that holds
  it.  One float ``f`` and ``J`` program call and one batched LU solve
  (:func:`~.newton.batched_solve`, the certifier's) for the round's boxes: ~3.4 us a box on
  general-19 (2,048 boxes: 1.9 ms, 4.9 ms), ~3 % of a box's
  search there.

A dive is ``upper_first(csys, lo, hi, var, at)``: for each box ``lo, hi`` (``(k, n)``) split
along ``var[i]`` at ``at[i]``, whether its upper half goes on top.
"""

from __future__ import annotations

import numpy as np

from ..expr.compiled import CompiledSystem
from ..interval.core import midpoint
from .newton import batched_solve

__all__ = ["LowerFirst", "NewtonSide"]


class LowerFirst:
    """The lower half on top, always (IBEX's order)."""

    def upper_first(self, csys: CompiledSystem, lo, hi, var, at) -> np.ndarray:
        return np.zeros(lo.shape[0], dtype=bool)


class NewtonSide:
    """The half holding the float Newton point of the box's midpoint on top (module
    docstring); the lower half where that point is not defined."""

    def upper_first(self, csys: CompiledSystem, lo, hi, var, at) -> np.ndarray:
        c = midpoint(lo, hi)
        rows = np.arange(lo.shape[0])
        with np.errstate(all="ignore"):
            f, J = csys.eval_fj_float(c)
            step, _ = batched_solve(J, f)  # NaN where J(c) is singular or not finite
            newton = c[rows, var] - step[rows, var]
        return np.isfinite(newton) & (newton > at)
