"""Forward kinematics of the planar robot (examples/robots/planar.json) for the examples of
examples/kinematics/README.md: the number of certified poses for tau_max = 10 N and 60 N at
control vectors a few cm from u = 0.

    python examples/kinematics/planar_examples.py
"""

import numpy as np

from certsolve.kinematics import FKSolver, with_tau_max
from certsolve.robot import Robot

robot = Robot.load("examples/robots/planar.json")
controls = [
    [0.5, 0.5, 0.5, 0.5],
    [0.8, 1.8, -2.5, -3.6],
    [-1.8, 1.3, 0.5, -2.8],
    [2.0, 0.6, 0.9, 0.1],
    [-1.9, -1.6, 2.5, -3.3],
]
solvers = {t: FKSolver(with_tau_max(robot, t)) for t in (10.0, 60.0)}
for u in controls:
    for t, fk in solvers.items():
        res = fk.solve(u, timeout=300)
        poses = "; ".join(
            f"({s.position[0]:.3f}, {s.position[1]:.3f}, {s.euler_deg[0]:.2f} deg, "
            f"max tau {np.max(s.tau):.2f} N)"
            for s in res.solutions
        )
        print(
            f"u = {u}, tau_max = {t:g} N: {res.status}, {len(res.solutions)} pose(s) "
            f"[{res.stats.boxes} boxes, {res.stats.time:.2f} s] {poses}"
        )
