"""Merlet (2007), Fig. 3: the controls u_2, u_3, u_4 of a 4-wire planar MARIONET at a fixed
pose while u_1 goes from 0.1 to 10 cm, by continuation, every point certified.

    python examples/kinematics/fig3_sweep.py      # writes fig3-sweep*.png, prints the table

The same sweep from the command line:

    certsolve ik examples/robots/planar.json --pose 85,65,3 --sweep 1=0.1:10:100 --plot fig3.png
"""

from pathlib import Path

import numpy as np

import certsolve
from certsolve.kinematics import with_tau_max
from certsolve.kinematics.plots import plot_sweep

HERE = Path(__file__).parent
POSE = [85.0, 65.0, 3.0]  # cm, cm, degrees: off-centre, so that the four controls differ

planar = certsolve.load_robot("examples/robots/planar.json")
for tau_max, png in ((60.0, "fig3-sweep.png"), (10.0, "fig3-sweep-tau10.png")):
    robot = with_tau_max(planar, tau_max)
    sweep = certsolve.ik_sweep(robot, POSE, joint=1, start=0.1, stop=10.0, count=100)
    plot_sweep(sweep, HERE / png, tau_limits=(robot.tau_min, robot.tau_max))
    t, U, T = sweep.values, sweep.controls(), sweep.tensions()
    print(
        f"tau in [0, {tau_max:g}] N, pose {POSE}: {sweep.status}, {sweep.counts}, "
        f"{1e3 * sweep.time:.0f} ms"
    )
    print(f"{'u_1':>7} {'u_2':>9} {'u_3':>9} {'u_4':>9}   {'tau_1..tau_4 (N)':<30} status")
    for i in range(0, len(t), 11):
        p = sweep.points[i]
        taus = " ".join(f"{x:6.2f}" for x in T[i])
        print(f"{t[i]:7.3f} {U[i, 1]:9.4f} {U[i, 2]:9.4f} {U[i, 3]:9.4f}   {taus:<30} {p.status}")
    ok = np.array([p.status == "certified" for p in sweep.points])
    if ok.sum() >= 2:
        for j in (1, 2, 3):  # "roughly linearly dependent upon u_1": fit a line
            slope, icpt = np.polyfit(t[ok], U[ok, j], 1)
            dev = np.max(np.abs(U[ok, j] - (slope * t[ok] + icpt)))
            print(f"  u_{j + 1} ~ {slope:.4f} u_1 {icpt:+.4f}  (largest deviation {dev:.4f} cm)")
    bad = [p for p in sweep.points if p.status != "certified"]
    if bad:
        print(f"  first non-certified point: u_1 = {bad[0].value:.3f}: {bad[0].reason}")
    print()
