"""The pose boxes of a robot known within tolerances (docs/tolerances.md).

    python examples/kinematics/tolerance_boxes.py

The T-platform robot of ``examples/robots/marionet-t-tol.json`` (anchors ±0.05 cm, every
``k`` ±1 %, τ <= 10 N) at three control vectors: the pose box's bounds of the three
distinct attachment points (the rectangles, projected on the x-z plane) with the
attachments of 8 robots drawn from the set (half at random corners of the tolerances) and
solved one by one by the nominal FK (the dots), and the nominal robot's (the crosses), as
offsets from the nominal pose in mm.  Writes ``tolerance-boxes.png`` beside this script
and prints the boxes.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from certsolve.kinematics import forward_kinematics  # noqa: E402
from certsolve.robot import Robot  # noqa: E402

HERE = Path(__file__).resolve().parent
robot = Robot.load(HERE.parent / "robots" / "marionet-t-tol.json")
controls = {
    "u = 0": np.zeros(7),
    "u1 = 3": np.r_[3.0, np.zeros(6)],
    "u4..7 = -2": np.r_[0, 0, 0, -2, -2, -2, -2.0],
}
rng = np.random.default_rng(0)
WIRES = (0, 1, 2)  # the T-platform's three distinct attachment points
fig, axes = plt.subplots(len(WIRES), 3, figsize=(11, 9), constrained_layout=True)
for col, (label, u) in enumerate(controls.items()):
    res = forward_kinematics(robot, u)
    print(f"{label}: {res.status}, {len(res.solutions)} pose box(es), {res.stats.boxes} boxes")
    samples = [forward_kinematics(robot.draw(rng, corner=i % 2 == 0), u) for i in range(8)]
    (nominal,) = forward_kinematics(robot.nominal(), u).solutions
    ref = nominal.platform_points
    pts = np.array([s.platform_points for r in samples for s in r.solutions]) - ref
    for pose in res.solutions:
        lo, hi = (b - ref for b in pose.bounds.platform_points)
        plo, phi = pose.bounds.position
        print("  position bounds (cm):", ", ".join(f"[{a:.3f}, {b:.3f}]" for a, b in zip(plo, phi)))
        for row, i in enumerate(WIRES):
            ax = axes[row, col]
            ax.add_patch(
                Rectangle((10 * lo[i, 0], 10 * lo[i, 2]), 10 * (hi[i, 0] - lo[i, 0]),
                          10 * (hi[i, 2] - lo[i, 2]), fill=False, lw=1.5, color="tab:blue")
            )  # fmt: skip
            ax.plot(10 * pts[:, i, 0], 10 * pts[:, i, 2], ".", ms=5, color="tab:orange")
            ax.plot([0], [0], "x", color="k", ms=7)
            ax.set_xlabel("x - nominal (mm)")
            ax.set_ylabel("z - nominal (mm)")
            ax.set_title(f"{label}: B{i + 1}")
            ax.set_aspect("equal", adjustable="datalim")
            ax.autoscale_view()
fig.suptitle("marionet-t-tol: pose box (blue) and the poses of robots drawn from the set (orange)")
fig.savefig(HERE / "tolerance-boxes.png", dpi=80)
print("wrote", HERE / "tolerance-boxes.png")
