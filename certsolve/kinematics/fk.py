"""Forward kinematics with all solutions, in one call: :func:`forward_kinematics`.

The solver itself is :class:`.fk_solver.FKSolver` (compile a formulation once, solve for
many control vectors); planar seeding of the almost-planar case is :mod:`.seeding`.  This
module only chooses between them, so neither imports the other's caller.
"""

from __future__ import annotations

import time
from typing import Any

from ..inputs import InputError, checked
from ..robot.inputs import FkOptions, check_controls
from ..robot.model import Robot
from ..solver import resolve_executor
from .fk_solver import FKPose, FKResult, FKSolver, with_tau_max
from .fk_tolerance import check_tolerant_options, tolerant_forward_kinematics
from .seeding import seeded_forward_kinematics

__all__ = ["FKPose", "FKResult", "FKSolver", "forward_kinematics", "with_tau_max"]


def forward_kinematics(
    robot: Robot,
    u,
    *,
    formulation: str = "auto",
    eps: float = 1e-8,
    timeout: float | None = None,
    max_boxes: int | None = None,
    max_solutions: int | None = None,
    tau_max: float | None = None,
    seed_planar: bool = False,
    seeded_only: bool = False,
    stable_only: bool = False,
    seed_minima: bool = True,
    newton_starts: bool = True,
    progress=None,
    executor: Any = None,
    verify: bool = False,
    cancel: Any = None,
    workers: int | None = None,
    checkpoint: Any = None,
) -> FKResult:
    """Every equilibrium pose of ``robot`` for the control vector ``u`` (see
    :mod:`.fk_solver`).

    The options are checked as the ``fk`` job and ``certsolve fk`` check them
    (:class:`~certsolve.robot.inputs.FkOptions`, one value of ``u`` per wire): a value
    they refuse raises :class:`~certsolve.inputs.InputError` naming it (``tau_max: must be
    greater than or equal to 0``).

    ``tau_max`` overrides every wire's maximum tension; ``seed_planar`` solves the planar
    counterpart first and searches around its solutions before the rest of the domain
    (:func:`.seeding.seeded_forward_kinematics`); ``seeded_only`` skips the rest (the rest
    is then reported pending).  ``stable_only`` returns the stable equilibria only (and
    those whose verdict is undecided); ``complete`` then means that no other stable
    equilibrium is in the domain (:mod:`.stable_only`).  ``seed_minima`` (spatial robots):
    search first around the local minima of the potential energy, found in floats -- the
    stable poses, where a robot at rest is -- then the whole domain (the same answer, the
    stable poses in the first rounds: :meth:`.FKSolver.seeded_boxes`).  ``newton_starts``:
    float Newton from random points of the pending boxes, the points it reaches proven as
    the search's own poses (:data:`.fk_solver.FK_STARTS`; not with ``stable_only``): every
    equilibrium early, the same complete answer.  ``executor`` (or
    the older ``workers``), ``verify``, the limits, ``progress`` and ``cancel`` apply to
    either search (see :meth:`.Solver.solve`); ``checkpoint``
    (:class:`~certsolve.solver.checkpoint.Checkpoint`) to the one-phase search only (not
    ``seed_planar``).

    A robot with tolerances (:mod:`certsolve.robot.tolerance`) is a set of robots: the
    result's poses are then pose boxes that hold every equilibrium of every robot of the set
    (:func:`.fk_tolerance.tolerant_forward_kinematics`; ``seed_planar``, ``stable_only`` and
    ``checkpoint`` are refused there, naming the field).
    """
    opts = checked(
        FkOptions,
        {
            "u": u,
            "eps": eps,
            "timeout": timeout,
            "max_boxes": max_boxes,
            "max_solutions": max_solutions,
            "tau_max": tau_max,
            "formulation": formulation,
            "seed_planar": seed_planar,
            "seeded_only": seeded_only,
            "stable_only": stable_only,
            "seed_minima": seed_minima,
            "newton_starts": newton_starts,
        },
    )
    check_controls(robot.m, opts.u)
    if seeded_only and not seed_planar:
        raise InputError("seeded_only", "needs seed_planar")
    if checkpoint is not None and seed_planar:
        raise InputError("checkpoint", "not available with seed_planar (a search in two phases)")
    executor = resolve_executor(executor, workers=workers)
    robot = with_tau_max(robot, tau_max)
    if robot.toleranced:  # a set of robots: pose boxes (:mod:`.fk_tolerance`)
        check_tolerant_options(
            robot, formulation, seed_planar=seed_planar, stable_only=stable_only,
            checkpoint=checkpoint is not None,
        )  # fmt: skip
        return tolerant_forward_kinematics(
            robot, u, formulation=formulation, eps=eps, timeout=timeout, max_boxes=max_boxes,
            max_solutions=max_solutions, progress=progress, executor=executor, verify=verify,
            cancel=cancel,
        )  # fmt: skip
    search = {
        "timeout": timeout,
        "max_boxes": max_boxes,
        "max_solutions": max_solutions,
        "progress": progress,
        "executor": executor,
        "verify": verify,
        "cancel": cancel,
        "stable_only": stable_only,
        "newton_starts": newton_starts,
    }
    if seed_planar:
        return seeded_forward_kinematics(
            robot, u, formulation=formulation, eps=eps, seeded_only=seeded_only, **search
        )
    t0 = time.perf_counter()
    fk = FKSolver(
        robot,
        formulation,
        eps=eps,
        stable_only=search.pop("stable_only"),
        seed_minima=seed_minima,
        newton_starts=search.pop("newton_starts"),
    )
    compile_time = time.perf_counter() - t0
    res = fk.solve(u, checkpoint=checkpoint, **search)
    res.notes.append(f"compiled in {compile_time:.3f} s")
    return res
