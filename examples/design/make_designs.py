"""Certified designs (Krut et al. 2004, section IV-B) of the robots in examples/robots.

    python examples/design/make_designs.py      # about a minute on the shared 2-core machine

For each spec ``NAME-spec.json`` here: the paving of its parameters (``NAME-design.png``),
the robot at the centre of the best proven box (``NAME-best.json``) and a summary (printed;
kept in ``designs.out``).  The same with the command line:

    certsolve design examples/design/krut3-spec.json --plot krut3.png --emit-robot best.json
"""

import json
from pathlib import Path

import numpy as np

import certsolve
from certsolve.force.plots import plot_design

HERE = Path(__file__).parent

for name, axes in (("krut3", (0, 1)), ("krut4", (0, 1)), ("planar", (1, 2))):
    res = certsolve.design(HERE / f"{name}-spec.json")
    plot_design(res, HERE / f"{name}-design.png", axes=axes)
    shares = ", ".join(
        f"{c} {100 * res.share(c):.1f} % ({len(getattr(res, c))})"
        for c in ("good", "bad", "undecided", "pending")
    )
    print(f"{name}: {res.robot}, f_min >= {res.min_force:g} N on {res.workspace.tolist()} cm")
    print(f"  {res.status}: {shares}")
    print(
        f"  {res.pairs} (parameter, pose) pairs, {res.parameter_boxes} parameter boxes, "
        f"{res.time:.1f} s"
    )
    if res.best is not None:
        box = res.good[res.best]
        print(
            "  best box: "
            + ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in zip(res.names, box))
        )
        print(
            f"  proven: f_min >= {res.min_force + res.margin[res.best]:.2f} N on the "
            f"workspace for every robot of that box"
        )
        (HERE / f"{name}-best.json").write_text(json.dumps(res.best_robot, indent=2) + "\n")
        robot = certsolve.load_robot(res.best_robot)
        axes_ = [np.linspace(lo, hi, 41) for lo, hi in res.workspace]
        grid = np.stack(np.meshgrid(*axes_, indexing="ij"), -1).reshape(-1, len(axes_))
        from certsolve.force import isotropic_values

        f, _ = isotropic_values(robot, grid)
        print(f"  its centre robot on a 41 x 41 grid: f_min from {f.min():.2f} to {f.max():.2f} N")
    print()
