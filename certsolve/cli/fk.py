"""``certsolve fk ROBOT --u ...``: every equilibrium pose for a control vector."""

from __future__ import annotations

import argparse
from collections.abc import Mapping

from ..jobs.jsonutil import plain
from .common import (
    CliError,
    Deadline,
    add_checkpoint_options,
    add_executor_options,
    checkpointing,
    count_of,
    describe_run,
    executor_from_args,
    parse_floats,
    print_json,
    print_report,
    progress_reporter,
    validated,
)


def register(sub) -> None:
    from ..kinematics.fk_systems import FORMULATIONS

    p = sub.add_parser(
        "fk",
        description="Forward kinematics of an elastic-wire robot (Merlet 2007): every pose in "
        "the search domain where the platform is in equilibrium for the control vector u, "
        "each certified to be the only solution in its box.  With --near, one real-time "
        "tracking step (Newton + Krawczyk certificate) instead.",
    )
    p.add_argument("robot", help="robot JSON file")
    p.add_argument("--u", required=True, help="control vector u1,...,um (cm), one per wire")
    p.add_argument(
        "--formulation",
        default="auto",
        choices=FORMULATIONS,
        help="equation system (default: the paper's choice for the robot)",
    )
    p.add_argument(
        "--tau-max", type=float, default=None, help="override every wire's maximum tension (N)"
    )
    p.add_argument("--eps", type=float, default=1e-8, help="width below which boxes stop")
    p.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="time limit (s) of the whole command, writing the answer included",
    )
    p.add_argument("--max-boxes", type=int, default=None, help="limit on processed boxes")
    p.add_argument(
        "--max-solutions", type=int, default=None, help="stop after this many certified poses"
    )
    add_executor_options(p)
    add_checkpoint_options(p)
    p.add_argument("--verify", action="store_true", help="re-prove solutions with mpmath")
    p.add_argument(
        "--seed-planar",
        action="store_true",
        help="almost-planar robots: search around the planar solutions first (with "
        "--workers/--scheduler and --verify like the plain search)",
    )
    p.add_argument(
        "--no-seed-minima",
        dest="seed_minima",
        action="store_false",
        help="spatial robots: do not search around the energy's local minima (the stable "
        "poses) first (same answer; by default they come first)",
    )
    p.add_argument(
        "--no-newton-starts",
        dest="newton_starts",
        action="store_false",
        help="no float Newton from random points (the poses it reaches proven) during the "
        "search: the search alone (same complete answer; by default the poses come early)",
    )
    p.add_argument(
        "--seeded-only",
        action="store_true",
        help="with --seed-planar: skip the rest of the domain (incomplete answer)",
    )
    p.add_argument(
        "--stable-only",
        action="store_true",
        help="stable equilibria only (Hessian of the energy positive definite); a complete "
        "answer then proves no other stable pose exists",
    )
    p.add_argument(
        "--near",
        default=None,
        help="tracking: a known nearby pose x,y,z[,yaw,pitch,roll] (cm, degrees)",
    )
    p.add_argument(
        "--half-width",
        type=float,
        default=0.1,
        help="tracking: half-width (cm) of the certified uniqueness box",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.fk import FkParams, TrackParams, run_fk
    from ..kinematics.fk import with_tau_max
    from ..robot.geometry import Pose
    from ..robot.model import Robot
    from ..robot.schema import load_robot_spec

    spec = load_robot_spec(args.robot)
    u = parse_floats(args.u, "--u")
    params = validated(FkParams, args, {"u": u}, robot=spec)  # as the fk job checks them
    if args.seeded_only and not args.seed_planar:
        raise CliError("--seeded-only needs --seed-planar")
    if args.near is not None:
        from ..kinematics.tracking import Tracker

        ignored = [
            flag
            for flag, value in (
                ("--seed-planar", args.seed_planar),
                ("--stable-only", args.stable_only),
                ("--verify", args.verify),
                ("--timeout", args.timeout is not None),
                ("--max-boxes", args.max_boxes is not None),
                ("--max-solutions", args.max_solutions is not None),
                ("--workers", args.workers is not None),
                ("--scheduler", args.scheduler is not None),
                ("--checkpoint", args.checkpoint is not None),
            )
            if value
        ]
        if ignored:
            raise CliError(
                f"{', '.join(ignored)}: options of the all-solutions search, not of a "
                "tracking step (--near)"
            )
        near = parse_floats(args.near, "--near")
        track = validated(
            TrackParams, args, {"u": u, "near_pose": near}, robot=spec, option={"near_pose": "near"}
        )
        robot = with_tau_max(Robot.from_spec(spec), params.tau_max)
        pose = Pose.from_params(robot.dof, track.near_pose)
        res = Tracker(robot, params.formulation, stability=True).step(
            track.u, pose, track.half_width
        )
        if args.json:
            print_json(res.to_dict())
        else:
            print(format_track(res))
        return 0
    if args.checkpoint is not None and args.seed_planar:
        raise CliError("--checkpoint: not available with --seed-planar (a search in two phases)")
    executor = executor_from_args(args)
    deadline = Deadline(params.timeout, args.started)
    show, stop = progress_reporter(not args.json)
    saving = checkpointing(args, "fk")
    try:
        with saving as (checkpoint, cancel):
            ctx = RunContext(
                time_limit=deadline.solver_timeout(),
                max_boxes=params.max_boxes,
                progress=deadline.progress(show),
                checkpoint=checkpoint,
                executor=executor,
                cancel=cancel,
                verify=args.verify,
            )
            res = run_fk(params, spec, ctx)  # the fk job's operation
            saving.status = str(res.status)
    finally:
        stop()
    deadline.mark(res)
    print_report(args.json, res.to_dict(), format_result)
    return saving.exit_code


def _pose_lines(s: Mapping) -> list[str]:
    """A pose of an FK result (its JSON form, :meth:`FKPose.to_dict`)."""
    spatial = len(s["position"]) == 3
    pos = ", ".join(f"{v:.6f}" for v in s["position"])
    ang = ", ".join(f"{v:.4f}" for v in s["euler"])
    names = "yaw, pitch, roll" if spatial else "theta"
    lines = [
        f"  position ({'x, y, z' if spatial else 'x, y'}) = ({pos}) cm",
        f"  orientation ({names}) = ({ang}) deg",
        _stability_line(s),
    ]
    if "position_lo" in s:  # a robot with tolerances: bounds over every robot of the set
        return lines + _bounds_lines(s)
    lines.append("  wire      rho (cm)    tau (N)    B_i (world, cm)")
    for i, (rho, tau, point) in enumerate(
        zip(s["rho"], s["tau"], s["platform_points"], strict=True)
    ):
        b = ", ".join(f"{v:9.4f}" for v in point)
        lines.append(f"  {i + 1:4d}  {rho:12.6f}  {tau:9.5f}    ({b})")
    return lines


def _bounds_lines(s: Mapping) -> list[str]:
    """The bounds of a pose box of a robot with tolerances (docs/tolerances.md): the frame's
    origin, and each attachment's interval per axis."""

    def ivl(lo, hi):
        return ", ".join(f"[{a:.4f}, {b:.4f}]" for a, b in zip(lo, hi, strict=True))

    lines = [
        f"  position bounds: ({ivl(s['position_lo'], s['position_hi'])}) cm",
        "  wire   B_i bounds (world, cm)",
    ]
    for i, (lo, hi) in enumerate(
        zip(s["platform_points_lo"], s["platform_points_hi"], strict=True)
    ):
        lines.append(f"  {i + 1:4d}   ({ivl(lo, hi)})")
    return lines


def _stability_line(s: Mapping) -> str:
    """The pose's stability verdict and its enclosure of the smallest Hessian eigenvalue
    (``None`` bounds: unbounded); a stored result from before verdicts has neither."""
    if "stability" not in s:
        return "  stability: not computed"
    lo, hi = s["eig_min"]
    lo_s = "-inf" if lo is None else f"{lo:.6g}"
    hi_s = "inf" if hi is None else f"{hi:.6g}"
    return f"  stability: {s['stability']}, smallest Hessian eigenvalue in [{lo_s}, {hi_s}]"


def format_result(res: Mapping) -> str:
    """The report of an FK result from its JSON form: :meth:`FKResult.to_dict` here, the
    stored result of an ``fk`` job for ``certsolve result``."""
    import numpy as np

    st = res["stats"]
    u = np.array2string(np.asarray(res["u"], dtype=float), precision=4)
    lines = [
        f"{res['robot']}: {res['formulation']}, u = {u}",
        f"{res['status']}: {count_of(res, 'solutions')} certified pose(s), "
        f"{count_of(res, 'undecided')} undecided, {count_of(res, 'pending')} pending; "
        f"{st['boxes']} boxes, {st['time']:.2f} s, {describe_run(st)}",
    ]
    sd = res.get("seeding") or {}
    if sd.get("method") == "energy minima":
        lines.append(
            f"seeds: {sd['minima']} local minim{'um' if sd['minima'] == 1 else 'a'} of the "
            f"energy found in {sd['time']:.2f} s, searched first"
        )
    elif sd:
        lines.append(
            f"planar seeding: {sd['planar_solutions']} planar solution(s), "
            f"{sd['solutions_in_seeds']} found in the seed boxes after "
            f"{sd['time_to_seeded_solutions']:.2f} s; rest of the domain "
            f"{'searched' if sd['rest_of_domain_searched'] else 'NOT searched'}"
        )
    lines.extend(f"note: {n}" for n in res.get("notes", ()) if not n.startswith("compiled"))
    for k, s in enumerate(res["solutions"], 1):
        tag = s["certificate"] + (" (verified)" if s.get("verified") else "")
        lines.append(f"pose {k} [{tag}]")
        lines.extend(_pose_lines(s))
    for k, und in enumerate(res["undecided"], 1):
        lines.append(f"undecided {k} ({und['reason']}): box {und['box']}")
    return "\n".join(lines)


def format_track(res) -> str:
    head = (
        f"tracking step: {'certified' if res.certified else 'NOT certified'}, "
        f"{res.iterations} Newton iteration(s), {1e3 * res.time:.3f} ms"
    )
    if res.certified:
        head += f"; the only solution with every chosen point within ±{res.half_width:g} cm"
    lines = [head]
    if res.message:
        lines.append(f"note: {res.message}")
    if res.pose is not None:
        lines.extend(_pose_lines(plain(res.pose.to_dict())))
    return "\n".join(lines)
