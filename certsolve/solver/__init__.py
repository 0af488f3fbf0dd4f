"""Branch-and-prune solving with certified solutions (ALIAS / IBEX style), batched.

* :mod:`.newton`          -- linearisation, Krawczyk operator, Hansen–Sengupta sweep
* :mod:`.batch`           -- the batch record of a round and the contractor protocol
* :mod:`.contractors`     -- :class:`HC4`, :class:`IntervalNewton`, partial Newton
* :mod:`.shaving`         -- CID on the bisection variable, ACID (:class:`Shave`)
* :mod:`.pipeline`        -- compositions (``Sequence``, ``FixPoint``, ``Inflate``) and the
  default pipeline
* :mod:`.certify`         -- Krawczyk proofs with inflation, existence boxes, de-duplication
* :mod:`.bisectors`       -- smear-sum-relative, smear/curvature mix, prioritized and
  largest-first bisection
* :mod:`.buffer`          -- the box stack
* :mod:`.protocol`        -- what the driver and its checkpoints share (``Step``, counters)
* :mod:`.search`          -- the search driver shared by every branch-and-prune loop (solver,
  forward kinematics, workspace paving, IK search): buffer, limits, cancellation,
  progress, :class:`SearchStatus`, and the serial executor
* :mod:`.executors`       -- the same search on local worker processes (and the choice of an
  executor from ``None`` / a number / ``"auto"`` / a Dask client or address)
* :mod:`.dask_executor`   -- ... and on a Dask cluster (optional extra ``distributed``)
* :mod:`.checkpoint`      -- a search saved as it goes and resumed (:class:`Checkpoint`)
* :mod:`.branch_and_prune`-- :class:`Solver` (the solve step, assembled from parts:
  contractor, certifier, bisector, buffer, :class:`SolverLimits`) and :func:`solve`
* :mod:`.verify`          -- independent re-proof of certificates with ``mpmath.iv``
* :mod:`.result`          -- :class:`SolveResult` and friends (plain, JSON-ready data)
* :mod:`.summary`         -- undecided / pending boxes as bounded lists of hulls with counts

Inside: search <- executors <- dask_executor (imported only when a Dask client or address is
given), and search, executors <- branch_and_prune.  The driver knows nothing about systems:
the solve step, the workspace paving (:mod:`certsolve.force.certified`) and the IK search
(:mod:`certsolve.kinematics.ik_search`) plug into it the same way.
"""

from .branch_and_prune import SearchState, Solver, SolverLimits, solve
from .checkpoint import Checkpoint, CheckpointError
from .executors import ProcessExecutor, available_cores, resolve_executor
from .result import Solution, SolveResult, Stats, Undecided
from .search import Limits, Progress, SearchStatus, SerialExecutor, run_search

__all__ = [
    "Checkpoint",
    "CheckpointError",
    "Limits",
    "ProcessExecutor",
    "Progress",
    "SearchState",
    "SearchStatus",
    "SerialExecutor",
    "Solution",
    "SolveResult",
    "Solver",
    "SolverLimits",
    "Stats",
    "Undecided",
    "available_cores",
    "resolve_executor",
    "run_search",
    "solve",
]
