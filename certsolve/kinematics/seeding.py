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
   of the domain minus the seed boxes -- in the same search, so the final answer is
   complete, duplicates are recognised, and the report says which solutions came from
   the seeds.
"""

from __future__ import annotations

import time

import numpy as np

from ..robot.geometry import rotation_2d
from ..robot.model import Robot
from ..solver import SearchState
from ..solver.certify import box_difference
from .fk import FKResult, FKSolver

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


def _subtract(domain_lo, domain_hi, seeds_lo, seeds_hi):
    """Boxes covering ``domain \\ ∪ int(seeds)`` (iterated exact box differences)."""
    pieces = [(domain_lo, domain_hi)]
    for slo, shi in zip(seeds_lo, seeds_hi, strict=True):
        nxt = []
        for plo, phi in pieces:
            if np.all(np.maximum(plo, slo) < np.minimum(phi, shi)):
                nxt.extend(box_difference(plo, phi, slo, shi))
            else:
                nxt.append((plo, phi))
        pieces = nxt
    return pieces


def seeded_forward_kinematics(
    robot: Robot,
    u,
    *,
    formulation: str = "auto",
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    seeded_only: bool = False,
    radius: float = 6.0,
    progress=None,
) -> FKResult:
    t0 = time.perf_counter()
    u = np.asarray(u, dtype=float)
    planar = planar_counterpart(robot)
    fk2 = FKSolver(planar, "planar-10", eps=eps)
    res2 = fk2.solve(u, timeout=timeout)
    t_planar = time.perf_counter() - t0

    fk = FKSolver(robot, formulation, eps=eps)
    if fk.form.kind not in ("points", "frame") or fk.form.n_points != 3:
        raise ValueError("planar seeding needs a 3-point formulation (almost-planar-13)")
    u, ok = fk._prepare(u)
    dom = fk.csys.system.domain
    k, d = 3, 3
    z_plane = float(robot.A[0, 2])
    seeds_lo, seeds_hi = [], []
    for sol in res2.solutions:
        th = np.arctan2(sol.rotation[1, 0], sol.rotation[0, 0])
        R = np.eye(3)
        R[:2, :2] = rotation_2d(th)
        p = np.r_[sol.position, z_plane]
        c = fk.form.coordinates_of(p + fk.form.Q @ R.T)
        lo, hi = dom[:, 0].copy(), dom[:, 1].copy()
        lo[: k * d] = np.maximum(lo[: k * d], c - radius)
        hi[: k * d] = np.minimum(hi[: k * d], c + radius)
        if np.all(lo <= hi):
            seeds_lo.append(lo)
            seeds_hi.append(hi)

    state = SearchState.start(dom, fk.csys.n)
    state.stack.pop(1)
    for lo, hi in zip(seeds_lo, seeds_hi, strict=True):
        state.stack.push(lo[None], hi[None])
    remaining = None if timeout is None else max(timeout - (time.perf_counter() - t0), 0.0)
    fk.solver.run(state, timeout=remaining, max_boxes=max_boxes, progress=progress)
    phase1_status = "complete" if len(state.stack) == 0 else "incomplete"
    n_seeded = state.solutions.count("ok")
    t_seeded = time.perf_counter() - t0
    searched_rest = False
    if not seeded_only and phase1_status == "complete":
        for plo, phi in _subtract(dom[:, 0], dom[:, 1], seeds_lo, seeds_hi):
            state.stack.push(plo[None], phi[None])
        remaining = None if timeout is None else max(timeout - (time.perf_counter() - t0), 0.0)
        fk.solver.run(state, timeout=remaining, max_boxes=max_boxes, progress=progress)
        searched_rest = True
    res = fk.solver.result(state)
    status = res.status if searched_rest else "incomplete"
    if not searched_rest and seeded_only:
        res.status = "incomplete"
    sols = [fk.decode(s.lo, s.hi, u, s) for s in res.solutions]
    seeding = {
        "planar_solutions": len(res2.solutions),
        "planar_status": res2.status,
        "planar_time": t_planar,
        "seed_boxes": len(seeds_lo),
        "seed_radius": radius,
        "solutions_in_seeds": n_seeded,
        "seeded_phase_status": phase1_status,
        "time_to_seeded_solutions": t_seeded,
        "rest_of_domain_searched": searched_rest,
        "total_time": time.perf_counter() - t0,
    }
    notes = (
        [] if searched_rest else ["only the seeded boxes were searched: the answer is not complete"]
    )
    return FKResult(robot.name, fk.formulation, u, status, sols, res, seeding=seeding, notes=notes)
