"""A system of equations over a box: the problem handed to the solver (square, or not:
``certsolve.solver.nonsquare``).

``System(variables, domain, equations, constraints)`` means: find every ``x`` in the box
``domain`` with ``f_i(x) = 0`` for all equations (``-inf`` / ``inf`` bounds are allowed: a
Minibex variable declared without a domain).  ``constraints`` are *extra* relations
``lo <= g(x) <= hi`` that every sought solution satisfies (inequalities, or redundant
equations); the solver uses them to contract and discard boxes but never to certify, so a
problem stays square.  A point violating a constraint is not a solution of the problem.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .node import Expr

__all__ = ["Constraint", "System"]


@dataclass(frozen=True)
class Constraint:
    """``lo <= expr <= hi`` (use ``lo == hi`` for an equality).

    A solution of the problem must satisfy every constraint; the solver checks it on each
    certified solution box and reports the solution as undecided when the check is
    inconclusive.  ``redundant=True`` declares a constraint *implied* by the equations and
    the other constraints at every sought solution (e.g. a triple product fixed by the
    distances and its sign): it is used only to contract, never checked.
    """

    expr: Expr
    lo: float = 0.0
    hi: float = 0.0
    redundant: bool = False

    def __post_init__(self):
        if not self.lo <= self.hi:
            raise ValueError(f"constraint bounds [{self.lo}, {self.hi}] are empty")


@dataclass
class System:
    """Equations ``f_i(x) = 0`` in the box ``domain``: as many as variables (:attr:`square`),
    or more or fewer (the solver's over- and under-determined searches).

    ``parameters`` give the values of :func:`~certsolve.expr.node.param` leaves; a compiled
    system can be re-used with new values (:meth:`CompiledSystem.set_parameters`).
    """

    variables: list[str]
    domain: np.ndarray  # shape (n, 2): [lo, hi] per variable (infinite bounds allowed)
    equations: list[Expr]
    constraints: list[Constraint] = field(default_factory=list)
    name: str = ""
    #: parameter name -> value (a float, or ``(lo, hi)`` for an uncertain value)
    parameters: dict = field(default_factory=dict)

    def __post_init__(self):
        self.variables = [str(v) for v in self.variables]
        n = len(self.variables)
        if len(set(self.variables)) != n:
            raise ValueError("variable names must be distinct")
        dom = np.asarray(self.domain, dtype=np.float64)
        if dom.shape != (n, 2):
            raise ValueError(f"domain must have shape ({n}, 2), got {dom.shape}")
        for name, (lo, hi) in zip(self.variables, dom, strict=True):
            if not (lo <= hi and lo < np.inf and hi > -np.inf):
                raise ValueError(f"domain of {name} must be a non-empty interval, got [{lo}, {hi}]")
        self.domain = dom
        known = set(self.variables)
        params = {}
        for name, v in dict(self.parameters).items():
            lo, hi = (v, v) if np.isscalar(v) else v
            if name in known:
                raise ValueError(f"parameter {name!r} has the name of a variable")
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"parameter {name!r} must be finite with lo <= hi")
            params[str(name)] = (float(lo), float(hi))
        self.parameters = params
        exprs = list(self.equations) + [c.expr for c in self.constraints]
        for k, e in enumerate(exprs):
            unknown = e.variables() - known
            if unknown:
                raise ValueError(f"expression {k} uses undeclared variables {sorted(unknown)}")
            missing = e.parameters() - set(params)
            if missing:
                raise ValueError(f"expression {k} uses parameters without values {sorted(missing)}")

    @property
    def n(self) -> int:
        return len(self.variables)

    @property
    def square(self) -> bool:
        """As many equations as variables.  :class:`CompiledSystem` expects a square
        system (it does not check); the solver also takes over- and under-determined ones
        (``certsolve.solver.nonsquare``)."""
        return len(self.equations) == len(self.variables)

    @classmethod
    def build(
        cls,
        domain: dict[str, Sequence[float]],
        equations: Sequence[Expr],
        constraints: Sequence[Constraint] = (),
        name: str = "",
        parameters: dict | None = None,
    ) -> System:
        """Convenience constructor from ``{name: (lo, hi)}`` (insertion order = variable order)."""
        names = list(domain)
        dom = np.array([[float(domain[v][0]), float(domain[v][1])] for v in names])
        return cls(names, dom, list(equations), list(constraints), name, dict(parameters or {}))
