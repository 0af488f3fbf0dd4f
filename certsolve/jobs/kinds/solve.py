"""Kind ``solve``: every solution of a Minibex system (``certsolve.solver.solve``)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, ValidationInfo, field_validator

from ...solver.options import SolveOptions
from ...solver.options_schema import solve_keywords
from .base import Job, Kind, Params, RunContext, trusted

__all__ = ["KIND", "MAX_SYSTEM_CHARS", "MAX_VARIABLES", "SolveJob", "SolveParams", "run_solve"]

MAX_SYSTEM_CHARS = 200_000  # Minibex text of a solve job
MAX_VARIABLES = 100


class SolveParams(SolveOptions, Params):  # the library's options, and the answer's sizes
    max_undecided: int = Field(
        default=1000, ge=0, le=100_000, description="undecided hulls listed in the answer"
    )
    max_pending: int = Field(
        default=1000, ge=1, le=100_000, description="hulls listing the boxes left by a limit"
    )
    cid_vars: Annotated[int, Field(ge=1, le=MAX_VARIABLES)] | Literal["all", "auto"] = Field(
        default="auto",
        description="variables shaved by CID before a bisection: the chosen one (1), the "
        "first k by smear score, all (fewer boxes, more time per box), or auto (default: "
        "the count learnt during the search, as IBEX's ACID)",
    )
    split_at_zero: bool = Field(
        default=True,
        description="split the variables that multiply others at 0 while 0 is well inside "
        "their interval (a sign split; false: at the bisector's ratio everywhere)",
    )
    newton_starts: bool = Field(
        default=True,
        description="certify solutions early: float Newton from random points of the "
        "pending boxes, each point proven as the search proves its solutions (false: the "
        "search alone)",
    )

    @field_validator("cid_vars", mode="before")
    @classmethod
    def _cid_vars(cls, v: Any) -> Any:
        if v in ("all", "auto"):
            return v
        if isinstance(v, str) and v.strip().isdigit():
            v = int(v)
        elif isinstance(v, float) and v.is_integer():
            v = int(v)  # JSON Schema's integers include 3.0
        if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= MAX_VARIABLES:
            raise ValueError(f"must be 'all', 'auto' or an integer in [1, {MAX_VARIABLES}]")
        return v

    def solver_cid_vars(self) -> int | str | None:
        """``cid_vars`` as :class:`~certsolve.solver.Solver` takes it (None: all)."""
        return solve_keywords(self.model_dump())["cid_vars"]


def check_system(text: str) -> str:
    """Parse the Minibex text (errors with line and column); at most MAX_VARIABLES."""
    from ...expr.minibex import MinibexError, parse_minibex

    try:
        system = parse_minibex(text)
    except MinibexError as exc:
        raise ValueError(str(exc)) from None
    if len(system.variables) > MAX_VARIABLES:
        raise ValueError(f"{len(system.variables)} variables; at most {MAX_VARIABLES}")
    return text


class SolveJob(Job):
    kind: Literal["solve"]
    system: str = Field(
        min_length=1, max_length=MAX_SYSTEM_CHARS, description="the system, Minibex text"
    )
    params: SolveParams = Field(default_factory=SolveParams)

    @field_validator("system")
    @classmethod
    def _system(cls, v: str, info: ValidationInfo) -> str:
        return v if trusted(info) else check_system(v)


def solve() -> Any:
    """The library function of kind ``solve``."""
    from ...solver.branch_and_prune import solve

    return solve


def run_solve(p: SolveParams, system: Any, ctx: RunContext) -> Any:
    """Every solution of ``system`` (Minibex text, or a parsed
    :class:`~certsolve.expr.System`): :func:`~certsolve.solver.solve`."""
    from ...expr.minibex import parse_minibex
    from ...solver.branch_and_prune import solve

    return solve(
        parse_minibex(system) if isinstance(system, str) else system,
        timeout=ctx.time_limit,
        max_boxes=ctx.max_boxes,
        executor=ctx.executor,
        cancel=ctx.cancel,
        progress=ctx.progress,
        checkpoint=ctx.checkpoint,
        **solve_keywords(p.model_dump()),
    )


KIND = Kind(
    name="solve",
    model=SolveJob,
    params=SolveParams,
    run=run_solve,
    function=solve,
    summary="all solutions of a Minibex system, certified",
)
