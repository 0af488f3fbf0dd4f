"""``certsolve design SPEC.json``: certified design of the force index (Krut et al. 2004, IV-B).

The spec names the robot, two or more design parameters (paths into the robot file with
ranges), the workspace box and the required isotropic force
(:mod:`certsolve.force.design_spec`); the search (:mod:`certsolve.force.design`) returns
parameter boxes proven good, proven bad and undecided, optionally drawn (``--plot``), and
the robot at the centre of the best proven box (``--emit-robot``).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Mapping

from ..jobs.jsonutil import plain
from .common import (
    CliError,
    add_checkpoint_options,
    checkpointing,
    parse_floats,
    print_json,
    progress_reporter,
    validated,
)

DEFAULT_EPS = 1 / 16  # = certsolve.force.design_spec.DEFAULT_EPS, without importing it here


def register(sub) -> None:
    p = sub.add_parser(
        "design",
        help="parameter boxes proven to give the isotropic force F over a workspace",
        description="Certified design: pave the box of design parameters into boxes proven "
        "good (isotropic force >= min_force at every pose of the workspace, for every "
        "parameter value of the box), proven bad (every parameter value of the box has a "
        "force < min_force on a common witness box of poses) and undecided (narrower than "
        "eps).  SPEC.json: {robot, parameters: [{name, path, mode, range}], workspace, "
        "min_force[, orientation, eps, workspace_eps]}; see docs/design.md.",
    )
    p.add_argument("spec", help="design specification (JSON)")
    p.add_argument(
        "--eps",
        type=float,
        default=None,
        help=f"parameter boxes stop at this fraction of each range (spec value, else "
        f"{DEFAULT_EPS:g})",
    )
    p.add_argument(
        "--workspace-eps",
        type=float,
        default=None,
        help="pose boxes stop at this width, cm (spec value, else 1/16 of the largest "
        "workspace side)",
    )
    p.add_argument(
        "--timeout", type=float, default=None, help="time limit in seconds (default: none)"
    )
    p.add_argument(
        "--max-boxes",
        type=int,
        default=None,
        help="limit on evaluated (parameter, pose) pairs (default: none)",
    )
    p.add_argument("--plot", metavar="PNG", default=None, help="picture of the paving (PNG)")
    p.add_argument(
        "--axes",
        metavar="I,J",
        default="1,2",
        help="with --plot and more than two parameters: the two parameters drawn (1-based; "
        "the picture is the section through the centre of the best box; default 1,2)",
    )
    p.add_argument(
        "--emit-robot",
        metavar="JSON",
        default=None,
        help="write the robot at the centre of the best proven box (largest margin)",
    )
    add_checkpoint_options(p)
    p.add_argument("--no-boxes", action="store_true", help="omit the box lists from --json")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _axes(text: str, k: int) -> tuple[int, int]:
    vals = parse_floats(text, "--axes", 2)
    if any(v != int(v) for v in vals):
        raise CliError("--axes: expected two parameter numbers, e.g. 1,2")
    i, j = (int(v) for v in vals)
    if not (1 <= i <= k and 1 <= j <= k) or i == j:
        raise CliError(f"--axes: two different parameter numbers in 1..{k}")
    return i - 1, j - 1


# the fields of a design job's params that come from the spec file, not from options
_SPEC_FIELDS = ("parameters", "workspace", "min_force", "orientation")


def run(args: argparse.Namespace) -> int:
    from ..extras import require
    from ..force.design_spec import load_design_spec
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.design import DesignParams, run_design
    from ..robot import RobotFileError, load_robot_spec

    if args.plot:  # before any work: --plot needs matplotlib
        require("plot", "--plot")
    spec = load_design_spec(args.spec)
    try:
        robot = load_robot_spec(spec.robot)
    except RobotFileError as exc:
        raise CliError(f"robot: {exc}".replace("\n", "; ")) from None
    # the options and the spec are the design job's params: one validation (its model)
    values = {name: getattr(spec, name) for name in _SPEC_FIELDS}
    values["parameters"] = [q.model_dump(exclude_none=True) for q in spec.parameters]
    for name in ("eps", "workspace_eps"):
        if getattr(args, name) is None:
            values[name] = getattr(spec, name)
    args.options = {
        **getattr(args, "options", {}),
        **{f"spec_{name}": f"{args.spec}: {name}" for name in _SPEC_FIELDS},
    }
    option = {name: f"spec_{name}" for name in _SPEC_FIELDS}
    params = validated(DesignParams, args, values, robot=robot, option=option)
    axes = _axes(args.axes, len(spec.parameters))
    progress, stop = progress_reporter(not args.json, line=_design_line)
    saving = checkpointing(args, "design")
    try:
        with saving as (checkpoint, cancel):  # Ctrl-C sets cancel: the search stops and saves
            ctx = RunContext(
                time_limit=params.timeout,
                max_boxes=params.max_boxes,
                progress=progress,
                checkpoint=checkpoint,
                cancel=cancel,
            )
            res = run_design(params, spec.robot, ctx)  # the design job's operation
            saving.status = str(res.status)
    finally:
        stop()
    if args.plot:
        from ..force.plots import plot_design

        plot_design(res, args.plot, axes=axes)
    emitted = None
    if args.emit_robot and res.best_robot is not None:
        with open(args.emit_robot, "w") as fh:
            json.dump(res.best_robot, fh, indent=2)
            fh.write("\n")
        emitted = args.emit_robot
    if args.json:
        out = res.to_dict(boxes=not args.no_boxes)
        out.update({"plot": args.plot, "emitted_robot": emitted})
        print_json(out)
    else:
        print(format_design(plain(res.to_dict(boxes=False)), args.plot, args.emit_robot, emitted))
    return saving.exit_code


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def format_design(
    res: Mapping, plot: str | None = None, emit: str | None = None, emitted: str | None = None
) -> str:
    """The report of a design from its JSON form (``to_dict(boxes=False)`` here, the stored
    result of a ``design`` job for ``certsolve result``)."""
    ws = " x ".join(f"[{lo:g}, {hi:g}]" for lo, hi in res["workspace"])
    lines = [
        f"{res['robot']}: isotropic force >= {res['min_force']:g} N on the workspace {ws} cm: "
        f"{res['status']}"
    ]
    names = [p["name"] for p in res["parameters"]]
    for p in res["parameters"]:
        r = p["range"]
        lines.append(f"  parameter {p['name']} ({p['path']}, {p['mode']}) in [{r[0]:g}, {r[1]:g}]")
    c, share = res["counts"], res["shares"]
    lines.append(
        f"  good {c['good']} boxes ({_pct(share['good'])}), bad {c['bad']} "
        f"({_pct(share['bad'])}), undecided {c['undecided']} "
        f"({_pct(share['undecided'])}), pending {c['pending']} ({_pct(share['pending'])})"
    )
    best = res["best"]
    if best is not None:
        box = ", ".join(f"{n} in [{lo:.6g}, {hi:.6g}]" for n, (lo, hi) in zip(names, best["box"]))
        centre = ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, best["centre"]))
        lines.append(
            f"  best box: {box}: f_min >= {best['min_force_bound']:.6g} N proven "
            f"(margin {best['margin']:.4g} N)"
        )
        lines.append(f"  its centre: {centre}")
    else:
        lines.append("  no parameter box is proven good")
    lines.append(
        f"  {res['pairs']} (parameter, pose) pairs, {res['parameter_boxes']} parameter boxes, "
        f"eps {res['eps']:g} of each range, workspace eps {res['workspace_eps']:g} cm, "
        f"{res['time']:.3f} s"
    )
    lines.extend(f"  note: {n}" for n in res["notes"])
    if plot:
        lines.append(f"  wrote {plot}")
    if emit:
        lines.append(
            f"  wrote {emitted}" if emitted else "  no proven box: --emit-robot wrote nothing"
        )
    return "\n".join(lines)


def _design_line(p) -> str:
    """The progress line from the driver's :class:`~certsolve.solver.search.Progress`."""
    x = p.extra
    return (
        f"design: {x['pairs']:.0f} pairs, {p.pending} queued, {x['good']:.0f} good, "
        f"{x['bad']:.0f} bad, {x['undecided']:.0f} undecided, "
        f"{100 * x['good_share']:.1f} % proven good, {p.elapsed:.1f} s"
    )
