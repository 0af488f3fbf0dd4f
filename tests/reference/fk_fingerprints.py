"""Fingerprints of the FK equation systems: graph size and values at random points.

``python tests/reference/fk_fingerprints.py`` rewrites ``fk_fingerprints.json``.  It was
written before the FK builders were refactored, and re-recorded once on purpose when the
affine coefficients of the attachments became exact rationals rounded to nearest instead
of a LAPACK least-squares solve (same poses; the graphs lost the nodes of products by
``1 ± 4e-16``).  ``tests/test_fk_fingerprints.py`` checks that every formulation of every
bundled robot is still built node for node the same (same variables, domain, graph size,
constraint bounds; equation and constraint values to rounding).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from certsolve.expr.compiled import CompiledSystem
from certsolve.kinematics.fk_systems import FORMULATIONS, build_formulation
from certsolve.robot import Robot

HERE = Path(__file__).resolve().parent
ROBOTS = HERE.parent.parent / "examples" / "robots"
OUT = HERE / "fk_fingerprints.json"


def fingerprint(robot: Robot, name: str, seed: int = 0) -> dict | None:
    """The fingerprint of one formulation, or None when it does not apply to the robot."""
    try:
        form = build_formulation(robot, name)
    except ValueError:
        return None
    system = form.system
    csys = CompiledSystem(system)
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, robot.m)
    csys.set_parameters(form.parameters_for(u))
    dom = np.where(np.isfinite(system.domain), system.domain, np.sign(system.domain) * 1e3)
    x = dom[:, 0] + rng.uniform(0.0, 1.0, (3, system.n)) * (dom[:, 1] - dom[:, 0])
    flo, fhi = csys.eval_f_at(x)
    clo, chi = csys.eval_constraints(x, x)
    return {
        "system": system.name,
        "kind": form.kind,
        "variables": list(system.variables),
        "domain": system.domain.tolist(),
        "graph": len(csys.graph),
        "constraints": [[c.lo, c.hi, c.redundant] for c in system.constraints],
        "f": (0.5 * flo + 0.5 * fhi).tolist(),
        "g": (0.5 * clo + 0.5 * chi).tolist(),
    }


def all_fingerprints() -> dict:
    out = {}
    for path in sorted(ROBOTS.glob("*.json")):
        robot = Robot.load(path)
        for name in FORMULATIONS:
            fp = fingerprint(robot, name)
            if fp is not None:
                out[f"{path.stem}/{name}"] = fp
    return out


if __name__ == "__main__":
    OUT.write_text(json.dumps(all_fingerprints(), indent=1) + "\n")
