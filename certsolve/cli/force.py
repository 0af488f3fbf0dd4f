"""``certsolve isotropic`` and ``certsolve workspace``: force indexes (Krut et al. 2004).

* ``certsolve isotropic ROBOT --at x,y[,z,...] [--plot pose.png] [--ellipse]``: the maximum
  isotropic force at one pose and the force polytope's facets, optionally drawn as in the
  paper's Fig. 4 (:mod:`certsolve.force.picture`);
* ``certsolve isotropic ROBOT --grid xmin,xmax,ymin,ymax[,nx,ny] [--plot map.png]``: the index
  over a grid of positions (fixed orientation), optionally drawn as a heat map;
* ``certsolve workspace ROBOT --min-force F --box ... --eps E [--plot paving.png]``: the
  certified paving of ``{f_min ≥ F}``.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from ..jobs.jsonutil import plain
from ..robot import Robot
from .common import (
    CliError,
    add_checkpoint_options,
    add_executor_options,
    checkpointing,
    count_of,
    describe_run,
    executor_from_args,
    parse_floats,
    print_json,
    print_result,
    progress_reporter,
    validated,
)

if TYPE_CHECKING:
    from ..jobs.kinds.isotropic_map import IsotropicMapParams


def register(sub) -> None:
    p = sub.add_parser(
        "isotropic",
        description="Maximum isotropic force: the radius of the largest ball of forces, "
        "centred at the load's bias (-gravity), inside the force polytope at the moment the "
        "load requires. Negative: the pose cannot balance the load.",
    )
    p.add_argument("robot", help="robot file (JSON)")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument(
        "--at", metavar="POSE", help="x,y (dof 2), x,y[,theta] (dof 3), x,y,z[,yaw,pitch,roll]"
    )
    where.add_argument(
        "--grid", metavar="XMIN,XMAX,YMIN,YMAX[,NX,NY]", help="grid of positions (default 200x200)"
    )
    p.add_argument("--z", type=float, default=None, help="height of the grid (dof 6; cm)")
    p.add_argument(
        "--orientation",
        metavar="ANGLES",
        default=None,
        help="fixed orientation of the grid: theta (dof 3) or yaw,pitch,roll (dof 6), degrees",
    )
    p.add_argument(
        "--algorithm",
        choices=("shifting", "krut"),
        default="shifting",
        help="polytope algorithm at one pose: hyperplane shifting (default) or the paper's six "
        "steps (small robots only)",
    )
    p.add_argument(
        "--external", metavar="WRENCH", default=None, help="extra constant wrench (N, N*cm)"
    )
    p.add_argument(
        "--ellipse", action="store_true", help="with --at: also the largest centred ellipse"
    )
    p.add_argument(
        "--plot",
        metavar="PNG",
        default=None,
        help="with --grid: heat map; with --at: the force polytope, isotropic circle (three "
        "sections through the centre for dof 6), centre and --ellipse (PNG)",
    )
    p.add_argument("--vmax", type=float, default=None, help="top of the colour scale (N)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_isotropic)
    _allow_negative_lists(p)

    w = sub.add_parser(
        "workspace",
        description="Pave a box of positions into boxes proven inside (f_min >= F at every "
        "pose), proven outside (f_min < F at every pose) and boundary boxes narrower than eps.",
    )
    w.add_argument("robot", help="robot file (JSON)")
    w.add_argument("--min-force", type=float, required=True, metavar="F", help="required force (N)")
    w.add_argument(
        "--box",
        required=True,
        metavar="XMIN,XMAX,YMIN,YMAX[,ZMIN,ZMAX]",
        help="box of positions (cm; z for dof 6)",
    )
    w.add_argument("--eps", type=float, required=True, help="width below which boxes stop (cm)")
    w.add_argument(
        "--orientation",
        metavar="ANGLES",
        default=None,
        help="theta (dof 3) or yaw,pitch,roll (dof 6) in degrees; each a number or lo:hi",
    )
    w.add_argument("--eps-angle", type=float, default=1.0, help="angle width to stop (degrees)")
    w.add_argument(
        "--external", metavar="WRENCH", default=None, help="extra constant wrench (N, N*cm)"
    )
    w.add_argument("--timeout", type=float, default=None, help="time limit in seconds")
    w.add_argument("--max-boxes", type=int, default=None, help="limit on processed boxes")
    add_executor_options(w)
    add_checkpoint_options(w)
    w.add_argument("--plot", metavar="PNG", default=None, help="picture of the paving (PNG)")
    w.add_argument("--no-boxes", action="store_true", help="omit the box lists from --json")
    w.add_argument("--json", action="store_true", help="print one JSON object")
    w.set_defaults(func=run_workspace)
    _allow_negative_lists(w)


def _allow_negative_lists(parser: argparse.ArgumentParser) -> None:
    """Let ``--grid -100,100,...`` read as a value, not as an option (argparse only treats
    plain negative numbers that way); ``--grid=-100,...`` works in any case."""
    parser._negative_number_matcher = re.compile(r"^-(\d|\.\d)[\d.eE+,:-]*$")


# -- helpers ------------------------------------------------------------------------------
def _external(robot: Robot, text: str | None):
    if text is None:
        return None
    return parse_floats(text, "--external", robot.wrench_dim)


def _fixed_orientation(robot: Robot, text: str | None):
    if text is None:
        return None
    if robot.dof == 2:
        raise CliError("--orientation: a point robot (dof 2) has no orientation")
    n = 1 if robot.dof == 3 else 3
    vals = parse_floats(text, "--orientation", n)
    return vals


def _orientation_ranges(robot: Robot, text: str | None):
    if text is None:
        return None
    if robot.dof == 2:
        raise CliError("--orientation: a point robot (dof 2) has no orientation")
    n = 1 if robot.dof == 3 else 3
    items = [t for t in text.replace(" ", "").split(",") if t != ""]
    if len(items) != n:
        raise CliError(f"--orientation: expected {n} angle(s), got {len(items)}")
    out: list[float | tuple[float, float]] = []
    for it in items:
        parts = it.split(":")
        try:
            vals = [float(x) for x in parts]
        except ValueError:
            raise CliError(f"--orientation: {it!r} is not a number or lo:hi") from None
        if len(vals) == 1:
            out.append(vals[0])
        elif len(vals) == 2:
            if vals[0] > vals[1]:
                raise CliError(f"--orientation: {it!r} needs lo <= hi")
            out.append((vals[0], vals[1]))
        else:
            raise CliError(f"--orientation: {it!r} is not a number or lo:hi")
    return out[0] if n == 1 else out


# the command line's own grid ceilings: larger than the service's (a map runs here, with no
# time limit, and is not stored); the service keeps MAX_GRID_SIDE and MAX_GRID_POINTS
CLI_GRID_SIDE = 5000
CLI_GRID_DEFAULT = 200


def _grid_params(args: argparse.Namespace, robot: Robot) -> IsotropicMapParams:
    """``--grid``, ``--z``, ``--orientation``, ``--external`` as the map operation's params:
    the syntax is checked here, the values by the job's model with the command line's
    ceilings (``--grid`` up to 5000 x 5000; 200 x 200 when ``nx``, ``ny`` are not given)."""
    from pydantic import Field

    from ..jobs.kinds.isotropic_map import IsotropicMapParams

    class CliGridParams(IsotropicMapParams):
        max_grid_points: ClassVar[int] = CLI_GRID_SIDE * CLI_GRID_SIDE
        nx: int = Field(default=CLI_GRID_DEFAULT, ge=1, le=CLI_GRID_SIDE)
        ny: int = Field(default=CLI_GRID_DEFAULT, ge=1, le=CLI_GRID_SIDE)

    vals = parse_floats(args.grid, "--grid")
    if len(vals) not in (4, 6):
        raise CliError("--grid: expected xmin,xmax,ymin,ymax[,nx,ny]")
    if not all(np.isfinite(vals)):
        raise CliError("--grid: the bounds and sizes must be finite")
    if len(vals) == 6 and (vals[4] != int(vals[4]) or vals[5] != int(vals[5])):
        raise CliError("--grid: nx and ny must be integers")
    if args.algorithm != "shifting":
        raise CliError("--algorithm: maps always use hyperplane shifting")
    if args.ellipse:
        raise CliError("--ellipse goes with --at")
    values = {
        "grid": vals[:4],
        "nx": int(vals[4]) if len(vals) == 6 else None,
        "ny": int(vals[5]) if len(vals) == 6 else None,
        "orientation": _fixed_orientation(robot, args.orientation),
        "external": _external(robot, args.external),
    }
    option = {"nx": "grid", "ny": "grid"}
    return validated(CliGridParams, args, values, robot=robot.spec, option=option)


def _fmt(x) -> str:
    return "n/a" if x is None else f"{x:.6g}"


# -- isotropic ------------------------------------------------------------------------------
def _check_plot(args: argparse.Namespace) -> None:
    """Before any work: --plot needs matplotlib (the 'plot' extra)."""
    if args.plot:
        from ..extras import require

        require("plot", "--plot")


def run_isotropic(args: argparse.Namespace) -> int:
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.isotropic_map import run_isotropic_map

    _check_plot(args)
    robot = Robot.load(args.robot)
    external = _external(robot, args.external)
    if args.at is not None:
        for opt in ("z", "orientation", "vmax"):
            if getattr(args, opt) is not None:
                raise CliError(f"--{opt} goes with --grid (with --at, put angles in the pose)")
        from ..jobs.kinds.isotropic_map import PoseParams, call_isotropic

        values = {"pose": parse_floats(args.at, "--at"), "external": external}
        params = validated(PoseParams, args, values, robot=robot.spec, option={"pose": "at"})
        try:
            res = call_isotropic(params, robot.spec, ellipse=args.ellipse)
        except ValueError as exc:
            raise CliError(f"--algorithm {args.algorithm}: {exc}") from None
        if args.plot:
            from ..force.picture import force_picture
            from ..force.plots import plot_force_picture

            plot_force_picture(force_picture(res), args.plot)
        print_result(args.json, res, lambda: format_isotropic(res, args.plot), plot=args.plot)
        return 0

    grid = _grid_params(args, robot)
    fmap = run_isotropic_map(grid, robot.spec, RunContext())
    if args.plot:
        from ..force.plots import plot_map

        plot_map(fmap, args.plot, vmax=args.vmax)
    print_result(
        args.json,
        fmap,
        lambda: format_map(plain(fmap.to_dict(values=False)), args.plot),
        plot=args.plot,
    )
    return 0


def format_isotropic(res, plot: str | None = None) -> str:
    where = ", ".join(f"{v:g}" for v in res.pose)
    lines = [
        f"{res.robot} at ({where}): maximum isotropic force {_fmt(res.isotropic_force)} N "
        f"[{res.status}]"
    ]
    if res.dof != 2:
        lines.append(
            "  centre (bias -w_ext) "
            + ", ".join(f"{v:.6g}" for v in res.centre)
            + " N; moment "
            + ", ".join(f"{v:.6g}" for v in res.required_moment)
            + " N*cm"
        )
    if res.weakest_direction is not None:
        lines.append(
            "  weakest disturbance direction: "
            + ", ".join(f"{v:.4f}" for v in res.weakest_direction)
        )
    if res.ellipse is not None:
        lines.append(
            "  largest centred ellipse: semi-axes "
            + ", ".join(f"{v:.6g}" for v in res.ellipse.semi_axes)
            + f" N, measure {res.ellipse.measure:.6g}"
        )
    for note in res.notes:
        lines.append(f"  note: {note}")
    poly = res.polytope
    if poly is not None:
        what = "force polytope" if res.dof == 2 else "force section at the required moment"
        lines.append(f"  {what}: {poly.n_facets} facets (n . f <= d; paper form m . v <= 1)")
        v = poly.paper_vectors()
        for k in range(poly.n_facets):
            n = ", ".join(f"{t: .5f}" for t in poly.normals[k])
            vv = "-" if np.isnan(v[k]).any() else ", ".join(f"{t: .6g}" for t in v[k])
            lines.append(f"    n = ({n})  d = {poly.offsets[k]: .6g}  v = ({vv})")
    lines.append(f"  {res.algorithm}, {1e3 * res.time:.2f} ms")
    if plot:
        lines.append(f"  wrote {plot}")
    return "\n".join(lines)


def format_map(res: Mapping, plot: str | None = None) -> str:
    """The report of an isotropic map from its JSON form (``to_dict(values=False)`` here,
    the stored result of an ``isotropic-map`` job for ``certsolve result``)."""
    s = res["summary"]
    lines = [
        f"{res['robot']}: {s['poses']} poses ({count_of(res, 'xs')} x {count_of(res, 'ys')}"
        + (f", z = {res['z']:g}" if res["z"] is not None else "")
        + f"), {s['inside']} inside, {s['outside']} outside, {s['degenerate']} degenerate",
        f"  maximum isotropic force: {_fmt(s['max'])} N"
        + (f" at ({s['argmax'][0]:g}, {s['argmax'][1]:g})" if s["argmax"] else ""),
        f"  {s['time']:.3f} s ({1e6 * s['time'] / max(s['poses'], 1):.2f} us per pose)",
    ]
    lines.extend(f"  note: {note}" for note in res.get("notes", []))
    if plot:
        lines.append(f"  wrote {plot}")
    return "\n".join(lines)


# -- workspace -------------------------------------------------------------------------------
def run_workspace(args: argparse.Namespace) -> int:
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.workspace import WorkspaceParams, run_workspace

    _check_plot(args)
    robot = Robot.load(args.robot)
    vals = parse_floats(args.box, "--box")
    if len(vals) % 2:
        raise CliError("--box: expected lo,hi pairs (xmin,xmax,ymin,ymax[,zmin,zmax])")
    values = {
        "box": [vals[i : i + 2] for i in range(0, len(vals), 2)],
        "orientation": _orientation_ranges(robot, args.orientation),
        "external": parse_floats(args.external, "--external") if args.external else None,
    }
    # the workspace job's own checks (min_force, eps, box, timeout ...)
    params = validated(WorkspaceParams, args, values, robot=robot.spec)
    executor = executor_from_args(args)
    progress, stop = progress_reporter(not args.json, line=_paving_line)
    saving = checkpointing(args, "workspace")
    try:
        with saving as (checkpoint, cancel):
            ctx = RunContext(
                time_limit=params.timeout,
                max_boxes=params.max_boxes,
                progress=progress,
                checkpoint=checkpoint,
                executor=executor,
                cancel=cancel,
            )
            ws = run_workspace(params, robot.spec, ctx)  # the workspace job's operation
            saving.status = str(ws.status)
    finally:
        stop()
    if args.plot:
        from ..force.plots import plot_paving

        plot_paving(ws, args.plot, anchors=robot.A)
    if args.json:
        out = ws.to_dict(boxes=not args.no_boxes)
        if args.plot:
            out["plot"] = args.plot
        print_json(out)
    else:
        print(format_workspace(plain(ws.to_dict(boxes=False)), args.plot))
    return saving.exit_code


def format_workspace(ws: Mapping, plot: str | None = None) -> str:
    """The report of a certified workspace from its JSON form (``to_dict(boxes=False)``
    here, the stored result of a ``workspace`` job for ``certsolve result``)."""
    c = ws["counts"]
    lines = [
        f"{ws['robot']}: certified f_min >= {ws['min_force']:g} N, eps {ws['eps']:g} cm: "
        f"{ws['status']}",
        f"  inside {ws['inside_measure']:.6g} {ws['unit']} ({100 * ws['inside_share']:.2f} % of "
        f"{ws['total_measure']:.6g}), {c['inside']} boxes",
        f"  outside {c['outside']} boxes, boundary {c['boundary']} boxes, pending {c['pending']}",
        f"  {ws['boxes']} boxes processed in {ws['time']:.3f} s, {describe_run(ws['stats'])}",
    ]
    if plot:
        lines.append(f"  wrote {plot}")
    return "\n".join(lines)


def _paving_line(p) -> str:
    return (
        f"paving: {p.boxes} boxes, {p.pending} pending, {p.solutions} inside, "
        f"{100 * p.extra['inside_share']:.1f} % proven, {p.elapsed:.1f} s"
    )
