"""Regenerate the paper's Fig. 4, 9 and 10 (Krut, Company, Pierrot 2004) and extras.

Run from the repository root:  python examples/force/make_figures.py
"""

from pathlib import Path

import numpy as np

from certsolve.force import certified_workspace, force_picture, isotropic_force, isotropic_map
from certsolve.force.plots import plot_force_picture, plot_map, plot_maps, plot_paving
from certsolve.robot import Robot

HERE = Path(__file__).resolve().parent
ROBOTS = HERE.parent / "robots"


def main() -> None:
    xs = np.linspace(-100.0, 100.0, 401)  # 0.5 cm steps, the centre is a grid point
    robots = {n: Robot.load(ROBOTS / f"krut-{n}.json") for n in (3, 4, 5, 6)}
    maps = {n: isotropic_map(r, xs, xs) for n, r in robots.items()}

    # Fig. 9: 3 actuators / 2 dof, f_min < 0 in white
    plot_map(maps[3], HERE / "fig9-krut3.png", title="Fig. 9: 3 actuators, tau in [50, 500] N")
    # Fig. 10: 4, 5, 6 actuators on the same colour scale
    plot_maps(
        [maps[n] for n in (4, 5, 6)],
        HERE / "fig10-krut456.png",
        titles=[f"Fig. 10: {n} actuators" for n in (4, 5, 6)],
    )

    # Fig. 4: the force polytope at one pose, its isotropic circle and centred ellipse; and
    # MARIONET's force section (gravity-shifted centre) cut through the centre three ways
    at = isotropic_force(robots[3], [30.0, 20.0], ellipse=True)
    plot_force_picture(force_picture(at), HERE / "fig4-krut3.png")
    mar = Robot.load(ROBOTS / "marionet.json")
    at6 = isotropic_force(mar, [111.0, 58.0, 107.0], ellipse=True)
    plot_force_picture(force_picture(at6), HERE / "fig4-marionet.png")
    print(
        f"fig. 4: krut-3 at (30, 20): {at.isotropic_force:.4f} N, ellipse semi-axes "
        f"{np.round(at.ellipse.semi_axes, 3)}; marionet at (111, 58, 107): "
        f"{at6.isotropic_force:.4f} N, centre {np.round(at6.centre, 4) + 0.0}"
    )

    # extras: the certified workspace f_min >= 100 N of the 3-motor robot, and MARIONET
    ws = certified_workspace(robots[3], 100.0, [-100, 100, -100, 100], 1.0)
    plot_paving(ws, HERE / "workspace-krut3-100N.png", anchors=robots[3].A)
    m6 = isotropic_map(mar, np.linspace(0, 180, 181), np.linspace(0, 120, 121), z=107.0)
    plot_map(m6, HERE / "marionet-z107.png")
    for n, m in maps.items():
        s = m.summary()
        print(f"krut-{n}: max {s['max']:.4f} N at {s['argmax']}, {m.time:.3f} s")
    print(
        f"krut-3 certified f >= 100 N: {100 * ws.inside_share:.2f} % of the box, "
        f"{ws.boxes} boxes, {ws.time:.3f} s"
    )


if __name__ == "__main__":
    main()
