"""Planar seeding of the almost-planar forward kinematics (Merlet 2007, section III-B).

The almost-planar robot moves nearly in the plane of its anchors, so the planar problem
(planar-10, much cheaper) predicts where the spatial solutions are: the paper measured
at most 5.3 cm between corresponding points.  :func:`seeded_forward_kinematics`:

1. builds the planar counterpart of the robot (anchors and attachments projected on the
   anchors' plane, no gravity in it) and solves planar-10 for the same ``u``;
2. lifts each planar solution into a narrow box of the 13-equation system (every chosen
   point within ``radius`` cm of its planar position, in the plane and across it);
3. searches those boxes first;
4. unless ``seeded_only``, searches the rest of the domain -- the exact box difference
   of the domain minus the seed boxes -- continuing the same search (known solutions,
   counters), so the final answer is complete, duplicates are recognised, and the report
   says which solutions came from the seeds.  Otherwise the rest is reported *pending*.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..robot.geometry import rotation_2d
from ..robot.model import Robot
from ..solver import Limits, SearchStatus, resolve_executor, run_search
from ..solver.certify import boxes_minus
from ..solver.search import SearchRun
from .fk_points import PlatformFormulation
from .fk_solver import FKResult, FKSolver

__all__ = ["planar_counterpart", "seeded_forward_kinematics"]


def planar_counterpart(robot: Robot) -> Robot:
    """The dof-3 robot obtained by projecting an almost-planar robot on its anchors' plane.

    Requires anchors in a horizontal plane (equal z) and a planar platform (attachments
    and centre of mass at equal platform-frame z).
    """
    if robot.dof != 6:
        raise ValueError("planar seeding applies to spatial (dof 6) robots")
    if np.ptp(robot.A[:, 2]) > 1e-9 or np.ptp(np.r_[robot.B[:, 2], robot.com[2]]) > 1e-9:
        raise ValueError(
            "planar seeding needs anchors in a horizontal plane and a planar "
            "platform (equal z for attachments and centre of mass)"
        )
    data = robot.spec.model_dump()
    data["dof"] = 3
    data["gravity"] = None
    data["name"] = robot.name + "-planar"
    data["platform"] = {"mass": data["platform"]["mass"]}
    for w in data["wires"]:
        w["base"] = w["base"][:2]
        w["platform"] = w["platform"][:2]
    data["domain"] = {"points": [list(p) for p in robot.domain[:2]]}
    return Robot.load(data)


def seeded_forward_kinematics(
    robot: Robot,
    u,
    *,
    formulation: str = "auto",
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    max_solutions: int | None = None,
    seeded_only: bool = False,
    stable_only: bool = False,
    newton_starts: bool = True,
    radius: float = 6.0,
    progress=None,
    executor: Any = None,
    verify: bool = False,
    cancel: Any = None,
) -> FKResult:
    """Planar-seeded forward kinematics (see the module docstring).

    Both searches (seed boxes, then the rest of the domain) run on ``executor`` with the
    limits, ``progress`` and ``cancel``, as :meth:`.FKSolver.solve`; ``max_boxes`` applies
    to each.  If the seeded search stops early, or with ``seeded_only``, the rest of the
    domain is reported *pending* (status: the limit that stopped it, or ``cancelled``).
    ``stable_only`` and ``newton_starts`` as :class:`.FKSolver` (the planar search is not
    restricted).
    """
    t0 = time.perf_counter()
    u = np.asarray(u, dtype=float)
    planar = planar_counterpart(robot)
    fk2 = FKSolver(planar, "planar-10", eps=eps)
    res2 = fk2.solve(u, timeout=timeout, cancel=cancel)
    t_planar = time.perf_counter() - t0

    fk = FKSolver(robot, formulation, eps=eps, stable_only=stable_only, newton_starts=newton_starts)
    form = fk.form
    if not isinstance(form, PlatformFormulation) or form.n_points != 3:
        raise ValueError("planar seeding needs a 3-point formulation (almost-planar-13)")
    search = fk.search(u)
    if not search.ok:  # nothing to search: the plain solver says so
        return fk.solve(u)
    u, dom, step = search.u, search.domain, search.solver  # the solver for u, on its box
    k, d = 3, 3
    z_plane = float(robot.A[0, 2])
    seeds_lo, seeds_hi = [], []
    for sol in res2.solutions:
        th = np.arctan2(sol.rotation[1, 0], sol.rotation[0, 0])
        R = np.eye(3)
        R[:2, :2] = rotation_2d(th)
        p = np.r_[sol.position, z_plane]
        c = form.coordinates_of(p + form.Q @ R.T)
        lo, hi = dom[:, 0].copy(), dom[:, 1].copy()
        lo[: k * d] = np.maximum(lo[: k * d], c - radius)
        hi[: k * d] = np.minimum(hi[: k * d], c + radius)
        if np.all(lo <= hi):
            seeds_lo.append(lo)
            seeds_hi.append(hi)
    n = step.csys.n
    rest_lo, rest_hi = boxes_minus(dom[:, 0], dom[:, 1], seeds_lo, seeds_hi)

    ex = resolve_executor(executor)

    def limits() -> Limits:
        left = None if timeout is None else max(timeout - (time.perf_counter() - t0), 0.0)
        return Limits(timeout=left, max_boxes=max_boxes, max_solutions=max_solutions)

    run = run_search(
        step,
        np.array(seeds_lo).reshape(-1, n),
        np.array(seeds_hi).reshape(-1, n),
        limits=limits(),
        executor=ex,
        progress=progress,
        cancel=cancel,
    )
    phase1_status = run.status
    n_seeded = run.state.solutions.count("ok")
    t_seeded = time.perf_counter() - t0
    searched_rest = not seeded_only and run.status == SearchStatus.COMPLETE
    if searched_rest:
        run = run_search(
            step,
            rest_lo,
            rest_hi,
            limits=limits(),
            executor=ex,
            progress=progress,
            cancel=cancel,
            previous=run,
        )
    else:  # not searched: pending
        run.state.stack.push(rest_lo, rest_hi)
        status: SearchStatus = (
            SearchStatus.CANCELLED if run.status == SearchStatus.COMPLETE else run.status
        )
        if not len(run.state.stack):
            status = SearchStatus.COMPLETE
        run = SearchRun(status=status, state=run.state, stats=run.stats)
    res = step.result(run)
    if verify:
        from ..solver.verify import verify_solutions  # mpmath: imported when asked

        verify_solutions(step.csys, res.solutions)
    sols = fk.decode_all(res.solutions, u)
    seeding = {
        "planar_solutions": len(res2.solutions),
        "planar_status": str(res2.status),
        "planar_time": t_planar,
        "seed_boxes": len(seeds_lo),
        "seed_radius": radius,
        "solutions_in_seeds": n_seeded,
        "seeded_phase_status": str(phase1_status),
        "time_to_seeded_solutions": t_seeded,
        "rest_of_domain_searched": searched_rest,
        "total_time": time.perf_counter() - t0,
    }
    notes = (
        []
        if searched_rest
        else ["only the seeded boxes were searched: the rest of the domain is pending"]
    )
    return FKResult(
        robot.name, fk.formulation, u, res.status, sols, res, seeding=seeding, notes=notes
    )
