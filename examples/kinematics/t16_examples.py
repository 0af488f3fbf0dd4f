"""Forward kinematics of the T-platform (examples/robots/marionet-t.json) for the examples
of examples/kinematics/README.md: one pose for tau_max = 10 N at u = 0, four poses for
tau_max = 60 N and u = 2 cm on every wire (complete searches).

    python examples/kinematics/t16_examples.py [--workers 2]
"""

import argparse

import numpy as np

from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.robot import Robot

ap = argparse.ArgumentParser()
ap.add_argument("--workers", type=int, default=1)
args = ap.parse_args()
robot = Robot.load("examples/robots/marionet-t.json")
for tau, u in ((10.0, [0.0] * 7), (60.0, [2.0] * 7)):
    fk = FKSolver(with_tau_max(robot, tau))
    res = fk.solve(u, workers=args.workers)
    print(
        f"tau {tau} u {np.array(u)} {fk.formulation} {res.status} {len(res.solutions)} "
        f"boxes {res.stats.boxes} time {res.stats.time:.1f} s"
    )
    for s in res.solutions:
        print(
            f"  pos {np.round(s.position, 3)} euler {np.round(s.euler_deg, 2)} "
            f"tau {np.round(s.tau, 2)}"
        )
