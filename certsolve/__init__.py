"""certsolve: certified interval analysis for wire-driven parallel robots.

The functions a script needs, with the result dataclasses the CLI prints (each has
``to_dict()`` for JSON); ``docs/python.md`` walks through them:

========================  =============================================================
``load_system``           Minibex text or file -> :class:`~certsolve.expr.system.System`
``solve``                 every solution of a square system, certified
``load_robot``            robot file (path, JSON text or dict) -> :class:`Robot`
``inverse_kinematics``    controls and tensions at a pose (tension-first, Alg. 1, Alg. 2)
``Algorithm2``            reusable IK Algorithm 2: ``Algorithm2(robot).solve(pose)``
``forward_kinematics``    every certified equilibrium pose for a control vector
``track``                 one real-time tracking step near a known pose (one-off form)
``Tracker``               reusable tracker: ``Tracker(robot).step(u, near, half_width=)``
``track_trajectory``      a control path, certified at every step and between steps
``ik_sweep``              controls along a sweep of one control (Merlet 2007, Fig. 3)
``isotropic_force``       maximum isotropic force and force polytope at a pose (Krut 2004)
``certified_workspace``   paving of the poses where the isotropic force is >= F
``design``                parameter boxes proven to give force >= F over a workspace
========================  =============================================================

Importing this package is cheap: each name is imported from its module on first access
(PEP 562), so ``import certsolve`` loads neither numpy nor any solver code.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

#: public name -> "module:attribute" (the attribute may be dotted: a class method)
_EXPORTS = {
    "load_system": "certsolve.expr.minibex:load_system",
    "solve": "certsolve.solver.branch_and_prune:solve",
    "load_robot": "certsolve.robot.model:Robot.load",
    "inverse_kinematics": "certsolve.kinematics.ik:inverse_kinematics",
    "Algorithm2": "certsolve.kinematics.ik_alg2:Algorithm2",
    "forward_kinematics": "certsolve.kinematics.fk:forward_kinematics",
    "track": "certsolve.kinematics.tracking:track",
    "Tracker": "certsolve.kinematics.tracking:Tracker",
    "track_trajectory": "certsolve.kinematics.trajectory:track_trajectory",
    "ik_sweep": "certsolve.kinematics.ik_sweep:ik_sweep",
    "isotropic_force": "certsolve.force.isotropic:isotropic_force",
    "certified_workspace": "certsolve.force.certified:certified_workspace",
    "design": "certsolve.force.design:design",
    # the types of the arguments and results
    "System": "certsolve.expr.system:System",
    "Robot": "certsolve.robot.model:Robot",
    "Pose": "certsolve.robot.geometry:Pose",
    "SolveResult": "certsolve.solver.result:SolveResult",
    "IKResult": "certsolve.kinematics.ik:IKResult",
    "FKResult": "certsolve.kinematics.fk:FKResult",
    "TrackResult": "certsolve.kinematics.tracking:TrackResult",
    "TrajectoryResult": "certsolve.kinematics.trajectory:TrajectoryResult",
    "IKSweepResult": "certsolve.kinematics.ik_sweep:IKSweepResult",
    "IsotropicForceResult": "certsolve.force.isotropic:IsotropicForceResult",
    "CertifiedWorkspace": "certsolve.force.certified:CertifiedWorkspace",
    "DesignResult": "certsolve.force.design:DesignResult",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("certsolve")
        except PackageNotFoundError:  # pragma: no cover - running from a source tree
            return "0+unknown"
    target = _EXPORTS.get(name)
    if target is None:
        raise AttributeError(f"module 'certsolve' has no attribute {name!r}")
    module, _, attr = target.partition(":")
    value: Any = import_module(module)
    for part in attr.split("."):
        value = getattr(value, part)
    return value


def __dir__() -> list[str]:
    return sorted(set(__all__) | {n for n in globals() if n.startswith("__")})
