"""Inverse kinematics of wire robots with elastic wires (Merlet 2007, section II.A).

Given a pose, find the actuator controls ``u`` such that the platform is in equilibrium:
``H(pose) τ(u) + w_g = 0`` with ``τ_i(u_i)`` from eq. (6), tensions within ``[τ_min, τ_max]``
and controls within the strokes ``[u_min, u_max]``.  Three methods,
:func:`inverse_kinematics` ``(robot, pose, method=...)``, one module each (this module only
dispatches and re-exports; the result types are in :mod:`.ik_result`):

``"tension"`` (tension first, :mod:`.ik_first`)
    choose the tensions (max-margin distribution: exact closed form on the line of solutions
    when ``m = w + 1``, the LP otherwise; :mod:`.ik_tension`), then ``u`` by eq. (5).  Limits
    on ``τ`` hold by construction when the pose is wrench-feasible; strokes are *checked* and
    every ``u`` outside its stroke is reported.  No certificate (floating point).
``"alg1"`` (Algorithm 1, :mod:`.ik_alg1`)
    interval branch and prune on the under-constrained system in ``u`` inside the strokes (or a
    window around the last ``u``) and the tension limits, stopping at the first certified
    solution (:mod:`.ik_search`).  Can also *prove* that no solution exists in the box.
``"alg2"`` (Algorithm 2, :mod:`.ik_alg2`)
    fix the control of one wire (default wire 1) from a mid-range tension (eq. 5), solve the
    square system in the others (Newton in the ``τ`` coordinates: one linear solve; or
    classical Newton in ``u`` with ``solve="newton"``), then prove with the Krawczyk test that
    a 1 µm box around the point holds exactly one solution (:mod:`.ik_enclose`).  Tension and
    stroke violations of the result are reported.

**Algorithm 1, design** (details in :mod:`.ik_search`): ``τ_i`` depends on ``u_i`` alone and
is increasing, so boxes of ``u`` and boxes of ``τ`` correspond one to one and the equations are
*linear* in ``τ``.  The branch and prune runs on tension boxes (image of the strokes or window,
intersected with the tension limits): a preconditioned interval Gauss–Seidel contraction
(proves boxes empty), then a certification attempt per box -- the ``m - w`` parametric wires
(left out of the basis by a pivoted QR of ``H``) are fixed at the controls of the box's
mid-tensions, the other controls follow from one linear solve, and the Krawczyk test proves
that exactly one solution of the square system in the other controls lies in a 1e-6 cm box,
inside the strokes/window with tensions within limits -- then bisection.  The fixed controls
are exact floats, so the certified point is an exact solution of the under-constrained system.
For MARIONET the contraction is nearly exact and the root box is certified (or proved empty)
in one round.

A robot known within tolerances (``robot.toleranced``) is answered for **every robot of its
set** by :mod:`.ik_tolerance`: a control interval per wire and the tension bounds of one
distribution (``tension``: fixed tensions; ``alg2``: a fixed control), or the bound that
fails, per wire, by its worst case; ``alg1`` is refused there.

Certificates are proofs about the equations for the pose *as given in floating point*
(position ``p`` and the float rotation matrix ``R``) and the robot's floats: every rounding
error of the geometry, of eq. (6) and of the Krawczyk operator is bounded.

Wire numbers in results and options are **1-based** (``u_1 … u_m`` as in the paper; wire
``i`` is ``wires[i-1]`` in the robot file).  Units: cm, N, degrees at the user boundary.

Robots: dof 6 with 7 wires (MARIONET, T-platform; 1-D null space), dof 3 with 4 wires
(planar; no gravity in the plane, so ``τ = λ v``), dof 6 with 4 wires (almost planar: 6
equations for 4 tensions, over-determined -- a generic pose is *not* an equilibrium and the
result says so; at a pose that is, the tensions are unique), dof 2 (Krut: no elastic model,
tensions only).
"""

from __future__ import annotations

from ..inputs import checked
from ..robot.inputs import IkOptions, as_pose
from .ik_alg1 import ik_algorithm1
from .ik_alg2 import ik_algorithm2
from .ik_first import ik_tension_first
from .ik_inputs import as_robot
from .ik_result import (
    LIMIT_TOL,
    Certificate,
    IKResult,
    IKStatus,
    Violation,
    limit_violations,
)
from .ik_tolerance import check_tolerant_ik, tolerant_inverse_kinematics

__all__ = [
    "IKResult",
    "IKStatus",
    "Certificate",
    "Violation",
    "inverse_kinematics",
    "ik_tension_first",
    "ik_algorithm1",
    "ik_algorithm2",
    "limit_violations",
    "METHODS",
    "LIMIT_TOL",
]

METHODS = ("tension", "alg1", "alg2")


def inverse_kinematics(robot, pose, method: str = "tension", **options) -> IKResult:
    """Controls (and tensions) holding the platform at ``pose``.

    ``robot``: :class:`~certsolve.robot.Robot` (or anything :meth:`Robot.load` accepts);
    ``pose``: :class:`~certsolve.robot.Pose`, a parameter list, tuple or array
    (``x,y,z,yaw,pitch,roll`` in cm and degrees; planar ``x,y,theta``; point ``x,y``) or the
    same as a string.  ``pose`` and ``method`` are checked as the ``ik`` job and
    ``certsolve ik`` check them (:class:`~certsolve.robot.inputs.IkOptions`): a value they
    refuse raises :class:`~certsolve.inputs.InputError` naming it.
    ``method``: ``"tension"`` (options ``distribution``, ``check_lp``), ``"alg1"`` (``u_last``,
    ``window``, ``max_boxes``, ``timeout``, ``eps``, ``box_radius``) or ``"alg2"``
    (``fixed_wire``, ``tau_fixed``, ``u_fixed``, ``solve``, ``u_last``, ``window``,
    ``box_radius``, ``certify``).  Robots without the elastic model support only
    ``"tension"`` (Algorithms 1 and 2 raise :class:`~certsolve.robot.RobotFileError`).
    """
    robot = as_robot(robot)
    pose = as_pose(robot.dof, pose)
    checked(IkOptions, {"pose": pose.params(robot.dof), "method": method})
    if robot.toleranced:  # control intervals for every robot of the set
        check_tolerant_ik(robot, method, options.get("solve", "tau"))
        return tolerant_inverse_kinematics(robot, pose, method, **options)
    if method == "tension":
        return ik_tension_first(robot, pose, **options)
    if method == "alg1":
        return ik_algorithm1(robot, pose, **options)
    if method == "alg2":
        return ik_algorithm2(robot, pose, **options)
    raise ValueError(f"method {method!r}: expected one of {', '.join(METHODS)}")
