"""The options of :func:`certsolve.solve` a user sets, checked once for every front end.

:func:`~certsolve.solver.branch_and_prune.solve` validates them with :class:`SolveOptions`;
the ``solve`` job's params (and so ``certsolve solve``) derive from it, so the three refuse
the same values with the same message (:mod:`certsolve.inputs`).  The sizes of the answer
the service lists (``max_undecided``, ``max_pending``) and its bound on ``cid_vars`` are the
service's own limits and stay with the job kind.
"""

from __future__ import annotations

from pydantic import Field

from ..inputs import StrictModel

__all__ = ["SolveOptions"]


class SolveOptions(StrictModel):
    """Stopping rules of a solve: ``eps`` (boxes narrower stop), the limits, ``verify``."""

    eps: float = Field(default=1e-8, gt=0, le=1e9, description="boxes narrower stop")
    timeout: float | None = Field(default=None, gt=0, description="time limit (s)")
    max_boxes: int | None = Field(default=None, ge=1, description="limit on processed boxes")
    max_solutions: int | None = Field(
        default=None, ge=1, le=10**9, description="stop after this many certified solutions"
    )
    verify: bool = Field(default=False, description="re-prove solutions with mpmath")
