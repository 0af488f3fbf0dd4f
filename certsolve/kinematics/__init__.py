"""Kinematics of wire-driven robots with elastic wires (Merlet 2007).

* :mod:`.ik` -- inverse kinematics (:func:`inverse_kinematics` dispatches): tension first
  (:mod:`.ik_first`, tensions by :mod:`.ik_tension`), Algorithm 1 (:mod:`.ik_alg1`, the
  interval search :mod:`.ik_search`: first certified solution), Algorithm 2
  (:mod:`.ik_alg2`: fixed wire, Newton, Krawczyk certificate, bounds in :mod:`.ik_enclose`;
  :class:`Algorithm2` is its reusable form, pose after pose);
  results in :mod:`.ik_result`, input checks in :mod:`.ik_inputs`
* :mod:`.fk_systems` -- the table of forward-kinematics formulations (10/13/16/19
  equations, the platform frame, pose parameters): what each owns in
  :mod:`.fk_formulation`, the physics in :mod:`.fk_equations`, the coordinates in
  :mod:`.fk_points` and :mod:`.fk_pose`, the platform's affine frame in :mod:`.fk_geometry`
* :mod:`.fk`         -- all-solutions forward kinematics (:func:`forward_kinematics`)
* :mod:`.seeding`    -- planar seeding of the almost-planar case
* :mod:`.tracking`   -- real-time certified tracking near a known pose

The names below are imported on first use (:mod:`certsolve.lazy`): ``import
certsolve.kinematics.fk`` does not pay for the IK modules (scipy.linalg, scipy.optimize),
which keeps ``certsolve fk`` quick to start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_exports

if TYPE_CHECKING:
    from .fk import FKPose, FKResult, FKSolver, forward_kinematics, with_tau_max
    from .fk_systems import FORMULATIONS, build_formulation
    from .ik import (
        METHODS,
        Certificate,
        IKResult,
        Violation,
        ik_algorithm1,
        ik_algorithm2,
        ik_tension_first,
        inverse_kinematics,
    )
    from .ik_alg2 import Algorithm2
    from .seeding import planar_counterpart, seeded_forward_kinematics
    from .tracking import Tracker, TrackResult, track

_WHERE = {
    "FKPose": ".fk",
    "FKResult": ".fk",
    "FKSolver": ".fk",
    "forward_kinematics": ".fk",
    "with_tau_max": ".fk",
    "FORMULATIONS": ".fk_systems",
    "build_formulation": ".fk_systems",
    "METHODS": ".ik",
    "Algorithm2": ".ik_alg2",
    "Certificate": ".ik",
    "IKResult": ".ik",
    "Violation": ".ik",
    "ik_algorithm1": ".ik",
    "ik_algorithm2": ".ik",
    "ik_tension_first": ".ik",
    "inverse_kinematics": ".ik",
    "planar_counterpart": ".seeding",
    "seeded_forward_kinematics": ".seeding",
    "Tracker": ".tracking",
    "TrackResult": ".tracking",
    "track": ".tracking",
}


__getattr__, __dir__ = lazy_exports(__name__, _WHERE)

__all__ = [
    "FORMULATIONS",
    "METHODS",
    "Algorithm2",
    "Certificate",
    "FKPose",
    "FKResult",
    "FKSolver",
    "IKResult",
    "TrackResult",
    "Tracker",
    "Violation",
    "build_formulation",
    "forward_kinematics",
    "ik_algorithm1",
    "ik_algorithm2",
    "ik_tension_first",
    "inverse_kinematics",
    "planar_counterpart",
    "seeded_forward_kinematics",
    "track",
    "with_tau_max",
]
