"""Certified solutions early: float Newton from random points of the pending boxes.

A search stopped by its limit reports what it has certified, and branch and prune reaches
the leaves of a wide domain late: on IBEX's CountercurrentReactors2-14 (14 variables in
``[-1e8, 1e8]``) the search had certified 1 solution after 10 s, where ibexsolve had 16, yet
float Newton from 256 random points converges to 31 distinct solutions in 0.15 s.  So the
solver runs :class:`NewtonStarts` once its search is seen not to be short: after
:attr:`~NewtonStarts.after` bisections (64, fewer past 16 variables), and again at 4, 16 ...
times that.

A phase draws :attr:`~NewtonStarts.count` points in the boxes still pending (a box drawn at
random, then a point in it, near 0 where the box reaches that far: :func:`draw_points`),
runs float Newton from them (:meth:`.Certifier.newton_point`; a share of them damped: each
step halved until the residual falls, which brings home points that full steps throw away on
high-degree systems) and hands the points that converged inside the domain to the
certifier's inflated Krawczyk test (:meth:`.Certifier.inflate`) -- the proof the search
itself makes.  A point that proves is a solution like any other: recorded with its unicity
box, which prunes the boxes it holds (:meth:`.certify.SolutionSet.prune`).  Nothing is
trusted: a point that does not prove is forgotten, and the search goes on over the whole
domain as before, so a complete search is still complete, and finds nothing twice.

The phases are a function of the bisection count, so a search resumed from a checkpoint runs
them where the uninterrupted one did (a phase's Newton stops at the search's time limit:
only the last phase of a search stopped by it may be cut short).  Worker tasks run none: the
driver runs a phase when its own rounds, or the bisections a task brings home
(``Solver.merge``), reach it, and the tasks that follow get its solutions with the others.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..interval.reductions import all_last

__all__ = ["NewtonStarts", "draw_points"]

#: a point is drawn within ``[-NEAR, NEAR]`` on each variable where its box reaches that
#: far: equations are written in units where solutions are not huge, and Newton from a
#: point of ``[-1e8, 1e8]`` wanders (CountercurrentReactors2-14, 256 starts: 121 converge
#: drawn within 10, fewer from farther)
NEAR = 10.0


def draw_points(
    lo: np.ndarray, hi: np.ndarray, count: int, rng, near: float | None = NEAR
) -> np.ndarray:
    """``(count, n)`` points, each in a box of ``lo, hi`` drawn at random; on each variable
    uniform in the box's interval met with ``[-near, near]``, or, where they do not meet,
    within one magnitude of the box's bound nearest 0 (``near=None``: uniform in the box,
    for bounded domains in the equations' own units)."""
    k = rng.integers(0, lo.shape[0], size=count)
    blo, bhi = lo[k], hi[k]
    if near is None:
        return np.clip(blo + (bhi - blo) * rng.random(blo.shape), blo, bhi)
    a, b = np.maximum(blo, -near), np.minimum(bhi, near)
    meet = a <= b
    edge = np.where(blo > 0.0, blo, bhi)  # the box lies beyond +near or -near
    a = np.where(meet, a, np.where(blo > 0.0, edge, 2.0 * edge))
    b = np.where(meet, b, np.where(blo > 0.0, 2.0 * edge, edge))
    x = a + (b - a) * rng.random(blo.shape)
    return np.clip(x, blo, bhi)


@dataclass(kw_only=True, frozen=True)
class NewtonStarts:
    """Multistart float Newton, certified (module docstring).

    ``after``: bisections before the first phase for a system of at most 16 variables, and
    ``after * (16 / n)^2`` (at least 1) for ``n`` variables, whose bisections cost more (a
    box's Jacobian holds ``n^2`` entries: Yamamura1-0080sp made 21 bisections in 10 s);
    a search that ends sooner never runs one.  Phases follow at ``spacing``, ``spacing^2``
    ... times that (``phases`` in all).  ``count``: points a draw takes for a system of at
    most 16 variables, fewer for larger ones (a Newton step costs ``n^3``):
    ``max(32, count * 16 / n)`` (:meth:`size`).  ``iterations``: Newton steps from a point at most;
    ``damped``: the share of the points (every ``1/damped``-th) whose steps are halved
    until the residual falls (:meth:`.Certifier.newton_point`); the others take full
    steps, which jump between basins where a damped step settles in a local minimum of
    the residual (both kinds find solutions the other does not).  ``again``, ``draws``: a
    draw whose points prove at least the share ``again`` of its size as new solutions is
    followed by another of the same phase in the next round, up to ``draws`` (IBEX's
    Brent-10 has ~1,000 solutions, and the first draw of 512 points proves 295 of them).
    ``seed``: the draws of phase ``k`` are seeded with ``(seed, k, draw)``.
    """

    after: int = 64
    phases: int = 4
    spacing: int = 4
    count: int = 256
    iterations: int = 30
    damped: float = 0.0
    again: float = 1.0
    draws: int = 1
    seed: int = 0
    near: float | None = NEAR

    def size(self, n: int) -> int:
        """The points a draw takes for ``n`` variables."""
        return max(32, self.count * 16 // max(n, 16))

    def first(self, n: int) -> int:
        """The bisections before the first phase, for ``n`` variables."""
        return max(1, round(self.after * min(1.0, (16 / max(n, 1)) ** 2)))

    def due(self, before: int, now: int, n: int = 16) -> int | None:
        """The phase whose bisection count lies in ``(before, now]``, if any (``n``: the
        system's variables)."""
        first = self.first(n)
        for k in range(self.phases):
            if before < first * self.spacing**k <= now:
                return k
        return None

    def points(
        self,
        certifier,
        domain: np.ndarray,
        lo,
        hi,
        phase: int,
        draw: int = 0,
        *,
        deadline: float | None = None,
    ) -> np.ndarray:
        """Distinct points where float Newton from random points of the boxes ``lo, hi``
        converged inside ``domain`` ((n, 2)): candidates, proven by the caller.  ``draw``:
        the draw of the phase (each its own points).  Newton stops iterating past
        ``deadline`` (:func:`time.monotonic`)."""
        rng = np.random.default_rng([self.seed, phase, draw])
        x0 = draw_points(lo, hi, self.size(domain.shape[0]), rng, self.near)
        dlo, dhi = domain[:, 0], domain[:, 1]
        with np.errstate(all="ignore"):
            x, conv = certifier.newton_point(
                x0,
                np.broadcast_to(dlo, x0.shape),
                np.broadcast_to(dhi, x0.shape),
                iterations=self.iterations,
                damped=np.diff(np.floor(np.arange(x0.shape[0] + 1) * self.damped)) > 0,
                deadline=deadline,
            )
        x = x[conv & all_last((x >= dlo) & (x <= dhi))]
        if x.shape[0] == 0:
            return x
        # one point per solution: equal to 8 significant digits
        scale = 1e-8 * (1.0 + np.abs(x))
        _, first = np.unique(np.round(x / scale).astype(np.int64), axis=0, return_index=True)
        return x[np.sort(first)]
