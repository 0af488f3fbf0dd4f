"""Branch-and-prune solving with certified solutions (ALIAS / IBEX style), batched.

* :mod:`.newton`          -- linearisation, Krawczyk operator, Hansen–Sengupta sweep
* :mod:`.contractors`     -- :class:`HC4`, :class:`IntervalNewton`
* :mod:`.certify`         -- Krawczyk proofs with inflation, existence boxes, de-duplication
* :mod:`.bisectors`       -- smear-sum-relative and largest-first bisection
* :mod:`.buffer`          -- the box stack
* :mod:`.branch_and_prune`-- :class:`Solver` and :func:`solve`
* :mod:`.parallel`        -- the same search over ``multiprocessing`` workers
* :mod:`.verify`          -- independent re-proof of certificates with ``mpmath.iv``
* :mod:`.result`          -- :class:`SolveResult` and friends (plain, JSON-ready data)
* :mod:`.summary`         -- undecided / pending boxes as bounded lists of hulls with counts
"""

from .branch_and_prune import Progress, SearchState, Solver, solve
from .result import Solution, SolveResult, Stats, Undecided

__all__ = [
    "Progress",
    "SearchState",
    "Solution",
    "SolveResult",
    "Solver",
    "Stats",
    "Undecided",
    "solve",
]
