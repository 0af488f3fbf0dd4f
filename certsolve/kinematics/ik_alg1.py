"""Algorithm 1 of Merlet (2007): the first certified solution of the under-constrained IK system.

Interval branch and prune on the controls ``u`` inside the strokes (or a window around the
last ``u``) and the tension limits (:mod:`.ik_search`), stopping at the first certified
solution; it can also *prove* that no solution exists in the box.  This module turns the
search's answer into an :class:`~.ik_result.IKResult`.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import ArrayLike

from ..robot.geometry import Pose
from ..robot.model import Robot
from .ik_enclose import enclose_pose, is_elastic, tension_mr
from .ik_inputs import check_pose, controls, overdetermined_note, require_elastic, search_window
from .ik_result import (
    IKResult,
    IKStatus,
    Violation,
    box_list,
    limit_violations,
    no_certificate,
    unique_in_box,
)
from .ik_search import Verdict, search_controls
from .ik_tension import margin_of

__all__ = ["ik_algorithm1"]


def ik_algorithm1(
    robot: Robot,
    pose: Pose,
    *,
    u_last: ArrayLike | None = None,
    window: float | None = None,
    max_boxes: int = 20000,
    timeout: float | None = 10.0,
    eps: float = 1e-9,
    box_radius: float = 1e-6,
) -> IKResult:
    """Algorithm 1: first certified solution in the strokes, or in ``u_last ± window/2``.

    ``window`` (cm, full width) defaults to 0.1 (1 mm) when ``u_last`` is given.
    """
    t0 = time.perf_counter()
    if not is_elastic(robot):
        require_elastic(robot, "alg1")
    if u_last is not None and window is None:
        window = 0.1
    ulo, uhi, u_last = search_window(robot, u_last, window)
    with np.errstate(all="ignore"):
        enc = enclose_pose(robot, pose.position, pose.rotation)
    check_pose(pose, enc)
    rho, H, wg = enc.rho, enc.H, enc.wg
    w, m = H.shape
    out = search_controls(
        robot, enc, ulo, uhi, max_boxes=max_boxes, timeout=timeout, eps=eps, box_radius=box_radius
    )
    details = {
        "domain": box_list(ulo, uhi),
        "boxes": out.boxes,
        "rounds": out.rounds,
        "search_time": out.time,
        "parametric_wires": [j + 1 for j in out.params],
    }
    if out.verdict == Verdict.UNKNOWN:
        details["stopped_by"] = str(out.status)
    messages: list[str] = []
    where = "the strokes" if u_last is None else f"the {window:g} cm window around u_last"
    u = tau = margin = res = None
    cert = no_certificate()
    violations: list[Violation] = []
    if out.verdict == Verdict.CERTIFIED:
        u, box_lo, box_hi, enc_lo, enc_hi = out.certified_point()
        tau, _ = tension_mr(robot, enc, u)
        margin = margin_of(tau, robot.tau_min, robot.tau_max)
        res = float(np.max(np.abs(H @ tau + wg)))
        F = np.array(out.params, dtype=np.int64)
        S = np.array([j for j in range(m) if j not in out.params], dtype=np.int64)
        cert = unique_in_box(u, F, S, box_lo[S], box_hi[S], enc_lo[S], enc_hi[S])
        violations = limit_violations(robot, tau, u)
        status = IKStatus.LIMITS_VIOLATED if violations else IKStatus.OK
    elif out.verdict == Verdict.INFEASIBLE:
        status = IKStatus.INFEASIBLE
        messages.append(
            f"proved: no control vector in {where} holds the platform at this pose with "
            "tensions within their limits"
        )
    else:
        status = IKStatus.UNCERTIFIED
        if m < w:
            messages.append(overdetermined_note(robot, w))
        if out.undecided:
            lo, hi = out.undecided[0]
            tau = 0.5 * lo + 0.5 * hi
            u = controls(robot, rho, tau)
            margin = margin_of(tau, robot.tau_min, robot.tau_max)
            res = float(np.max(np.abs(H @ tau + wg)))
            details["undecided_tension_boxes"] = [box_list(a, b) for a, b in out.undecided]
            messages.append(
                f"{len(out.undecided)} undecided box(es) of width < eps: a solution may exist "
                "there (returned: the centre of the first one, not certified)"
            )
        else:
            messages.append(f"search stopped ({out.status}) before a certified solution")
    return IKResult(
        robot=robot.name,
        dof=robot.dof,
        method="alg1",
        pose=pose,
        status=status,
        feasible=status == IKStatus.OK,
        u=u,
        tau=tau,
        rho=rho,
        margin=margin,
        residual=res,
        violations=violations,
        certificate=cert,
        messages=messages,
        details=details,
        time=time.perf_counter() - t0,
    )
