"""``certsolve track ROBOT --trajectory U.csv --start POSE``: follow a control path.

``U.csv`` holds one control vector per row (one column per wire, comma-separated, an
optional header row of names); ``POSE`` is ``x,y,theta`` or ``x,y,z,yaw,pitch,roll`` (cm,
degrees) as ``certsolve ik --pose`` takes it.  The options are the ``trajectory`` job's
params (:class:`~certsolve.jobs.kinds.trajectory.TrajectoryParams`), checked by its model,
and the run is the job's operation (:func:`~certsolve.kinematics.trajectory.
track_trajectory`).  A bad file is one ``error:`` line naming the row and column.
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

from .common import CliError, parse_floats, print_result, validated

#: steps listed by the text report at the start and at the end of a long path
SHOWN = 8


def register(sub) -> None:
    p = sub.add_parser(
        "track",
        description="Follow the equilibrium branch from a start pose through every row of a "
        "control path (Merlet 2007, III-B): each step certified (a Krawczyk box proven to hold "
        "the only equilibrium near it) and joined to the previous one (one equilibrium, moving "
        "continuously, for every u on the segment between the rows).  The path is lost at the "
        "first step where a wire may leave its tension bounds, the Jacobian is singular or a "
        "proof fails; nothing after it is reported.",
    )
    p.add_argument("robot", help="robot file (JSON)")
    p.add_argument(
        "--trajectory",
        required=True,
        metavar="U.csv",
        help="the path: one control vector u per row (cm, one column per wire; an optional "
        "header row)",
    )
    p.add_argument(
        "--start",
        required=True,
        help="a pose near the equilibrium at the first row: x,y,z,yaw,pitch,roll (cm, "
        "degrees) or x,y,theta, as ik --pose.  Use --start=-5,... for a leading minus sign",
    )
    p.add_argument(
        "--half-width", type=float, default=None, help="half-width (cm) of each step's box (0.1)"
    )
    p.add_argument(
        "--tau-max", type=float, default=None, help="override every wire's maximum tension (N)"
    )
    p.add_argument(
        "--formulation", default=None, help="the FK equations (default: the paper's choice)"
    )
    p.add_argument("--plot", metavar="PNG", default=None, help="pose and tensions along the path")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def read_controls(path: str, m: int) -> list[list[float]]:
    """The rows of ``path`` (module docstring): ``m`` finite numbers each.  The first
    non-blank row is a header when none of its cells is a number."""
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise CliError(f"--trajectory: cannot read {path}: {exc.strerror or exc}") from None
    name = Path(path).name
    rows: list[list[float]] = []
    first = True
    for line, raw in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in raw]
        if not any(cells):
            continue
        header = first and not any(_number(c) for c in cells)
        first = False
        if header:
            continue
        values: list[float] = []
        for col, cell in enumerate(cells, start=1):
            v = _number(cell)
            if v is None:
                raise CliError(f"{name} row {line}, column {col}: {cell!r} is not a number")
            if not math.isfinite(v):
                raise CliError(f"{name} row {line}, column {col}: {cell!r} is not finite")
            values.append(v)
        if len(values) != m:
            raise CliError(
                f"{name} row {line}: expected {m} values (one per wire), got {len(values)}"
            )
        rows.append(values)
    if not rows:
        raise CliError(f"{name}: no control rows")
    return rows


def _number(cell: str) -> float | None:
    try:
        return float(cell)
    except ValueError:
        return None


def run(args: argparse.Namespace) -> int:
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.trajectory import TrajectoryParams, run_trajectory
    from ..robot import load_robot_spec

    if args.plot:  # before any work: --plot needs matplotlib
        from ..extras import require

        require("plot", "--plot")
    spec = load_robot_spec(args.robot)
    values = {
        "controls": read_controls(args.trajectory, len(spec.wires)),
        "start": parse_floats(args.start, "--start"),
    }
    params = validated(
        TrajectoryParams, args, values, robot=spec, option={"controls": "trajectory"}
    )
    result = run_trajectory(params, spec, RunContext())  # the trajectory job's operation
    if args.plot:
        from ..kinematics.fk_solver import with_tau_max
        from ..kinematics.plots import plot_trajectory

        robot = with_tau_max(spec, params.tau_max)
        plot_trajectory(result, args.plot, tau_limits=(robot.tau_min, robot.tau_max))
    print_result(args.json, result, lambda: format_result(result, args.plot), plot=args.plot)
    return 0


def format_result(res, plot: str | None = None) -> str:
    """A readable report: the verdict, then the first and last steps (and the lost one)."""
    steps = res.steps
    lines = [
        f"{res.robot} ({res.formulation}), {len(steps)} step(s) reported: {res.status}, "
        f"{res.certified} certified and joined",
    ]
    if res.lost_at is not None:
        lines.append(f"lost at step {res.lost_at}: {res.reason}")
    lines.append(
        f"{res.chunks} chunk(s) proven, {res.chunk_failures} split, {res.halvings} link(s) "
        f"cut, {res.own_proofs} step(s) proven alone; {res.time:.3f} s"
    )
    lines.append(f"{'step':>6} {'cert':>5} {'joined':>6}  pose (cm, deg)  tensions min..max (N)")
    shown = steps if len(steps) <= 2 * SHOWN else [*steps[:SHOWN], None, *steps[-SHOWN:]]
    for s in shown:
        if s is None:
            lines.append(f"{'...':>6}")
            continue
        joined = "-" if s.joined is None else ("yes" if s.joined else "no")
        if s.pose is None:
            lines.append(f"{s.index:>6} {'no':>5} {joined:>6}  (no equilibrium found)")
            continue
        pose = ", ".join(f"{v:.6g}" for v in [*s.pose.position, *s.pose.euler_deg])
        lines.append(
            f"{s.index:>6} {'yes' if s.certified else 'no':>5} {joined:>6}  {pose}  "
            f"{s.pose.tau.min():.4g}..{s.pose.tau.max():.4g}"
        )
    if plot:
        lines.append(f"plot written to {plot}")
    return "\n".join(lines)
