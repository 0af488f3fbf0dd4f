"""``certsolve ik ROBOT --pose ...``: inverse kinematics (Merlet 2007, section II.A)."""

from __future__ import annotations

import argparse

import numpy as np

from ..kinematics.ik import METHODS, IKResult, inverse_kinematics
from ..robot import Pose, Robot, load_robot_spec
from .common import CliError, parse_floats, print_json, validated


def register(sub) -> None:
    p = sub.add_parser(
        "ik",
        description="Controls u and wire tensions that hold the platform at a pose. "
        "Methods: 'tension' (max-margin tensions, then u by eq. 5; strokes checked), "
        "'alg1' (interval branch and prune, first certified solution within the strokes or "
        "a window around --u-last), 'alg2' (fix one wire from a mid-range tension, solve, "
        "certify with Krawczyk).  Wire numbers are 1-based.",
    )
    p.add_argument("robot", help="robot file (JSON)")
    p.add_argument(
        "--pose",
        required=True,
        help="x,y,z,yaw,pitch,roll (cm, degrees; Z-Y-X Euler angles); planar robots x,y,theta; "
        "point robots x,y.  Use --pose=-5,... for a leading minus sign",
    )
    p.add_argument("--method", choices=METHODS, default="tension", help="default: tension")
    p.add_argument(
        "--u-last", default=None, help="alg1: centre of the search window; alg2: Newton start"
    )
    p.add_argument(
        "--window",
        type=float,
        default=None,
        help="alg1/alg2: full width (cm) of the window around --u-last (alg1 default 0.1 = 1 mm)",
    )
    p.add_argument("--fixed-wire", type=int, default=1, help="alg2: wire whose u is fixed")
    p.add_argument(
        "--tau-fixed", type=float, default=None, help="alg2: tension of the fixed wire (N)"
    )
    p.add_argument(
        "--newton", action="store_true", help="alg2: classical Newton in u instead of the τ solve"
    )
    p.add_argument("--timeout", type=float, default=10.0, help="alg1: time limit (s)")
    p.add_argument("--max-boxes", type=int, default=20000, help="alg1: box limit")
    p.add_argument(
        "--distribution",
        choices=("auto", "closed-form", "lp"),
        default="auto",
        help="tension: how to choose the tensions (default auto)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _options(args: argparse.Namespace, robot: Robot) -> dict:
    m = robot.m
    u_last = None
    if args.u_last is not None:
        u_last = parse_floats(args.u_last, "--u-last", m)
    if args.window is not None and not args.window > 0:
        raise CliError("--window must be positive (cm)")
    if args.method == "tension":
        for flag, val in (("--u-last", args.u_last), ("--window", args.window)):
            if val is not None:
                raise CliError(f"{flag} applies to --method alg1 or alg2")
        return {"distribution": args.distribution, "check_lp": True}
    if args.method == "alg1":
        if args.timeout is not None and not args.timeout > 0:
            raise CliError("--timeout must be positive")
        if args.max_boxes < 1:
            raise CliError("--max-boxes must be at least 1")
        return {
            "u_last": u_last,
            "window": args.window,
            "timeout": args.timeout,
            "max_boxes": args.max_boxes,
        }
    if not 1 <= args.fixed_wire <= m:
        raise CliError(f"--fixed-wire: the robot has wires 1..{m}")
    return {
        "u_last": u_last,
        "window": args.window,
        "fixed_wire": args.fixed_wire,
        "tau_fixed": args.tau_fixed,
        "solve": "newton" if args.newton else "tau",
    }


def run(args: argparse.Namespace) -> int:
    from ..jobs.kinds.ik import IkParams

    spec = load_robot_spec(args.robot)
    values = parse_floats(args.pose, "--pose")
    params = validated(IkParams, args, {"pose": values}, robot=spec)  # the ik job's checks
    robot = Robot.from_spec(spec)
    pose = Pose.from_params(robot.dof, params.pose)
    result = inverse_kinematics(robot, pose, args.method, **_options(args, robot))
    if args.json:
        print_json(result.to_dict())
    else:
        print(format_result(result, robot))
    return 0


def _num(x, fmt: str = "10.5f") -> str:
    if x is None or not np.isfinite(x):
        return f"{'-':>{fmt.split('.')[0]}}"
    return f"{x:{fmt}}"


def format_result(res: IKResult, robot: Robot) -> str:
    """A readable report: status, certificate, one row per wire, violations, messages."""
    names = {6: ("x", "y", "z", "yaw", "pitch", "roll"), 3: ("x", "y", "theta"), 2: ("x", "y")}
    pose = ", ".join(
        f"{n}={v:.6g}" for n, v in zip(names[res.dof], res.pose.params(res.dof), strict=True)
    )
    feas = "feasible" if res.feasible else "not feasible"
    lines = [f"{res.robot} (dof {res.dof}), method {res.method}: {pose}"]
    head = f"status: {res.status} ({feas})"
    if res.margin is not None:
        head += f", tension margin {res.margin:.6g} N"
    if res.residual is not None:
        head += f", equilibrium residual {res.residual:.3g}"
    head += f", {res.time * 1e3:.3f} ms"
    lines.append(head)
    cert = res.certificate
    if cert.kind != "none":
        lines.append(f"certificate: {cert.kind}: {cert.statement}")
    viol = {(v.wire, v.quantity) for v in res.violations}
    fixed = set(cert.fixed)
    lines.append(
        f"{'wire':>4} {'rho (cm)':>11} {'tau (N)':>10} {'tau range':>15} "
        f"{'u (cm)':>11} {'stroke':>15}  note"
    )
    for i in range(robot.m):
        w = i + 1
        tau = None if res.tau is None else float(res.tau[i])
        u = None if res.u is None else float(res.u[i])
        notes = []
        if w in fixed:
            notes.append("fixed")
        if (w, "tau") in viol:
            notes.append("tension!")
        if (w, "u") in viol:
            notes.append("stroke!")
        if (w, "u-window") in viol:
            notes.append("window!")
        trange = f"[{robot.tau_min[i]:g}, {robot.tau_max[i]:g}]"
        stroke = f"[{robot.u_min[i]:g}, {robot.u_max[i]:g}]" if robot.is_elastic else "-"
        lines.append(
            f"{w:>4} {_num(float(res.rho[i]), '11.4f')} {_num(tau, '10.5f')} {trange:>15} "
            f"{_num(u, '11.6f')} {stroke:>15}  {' '.join(notes)}"
        )
    if res.violations:
        lines.append("violations:")
        lines.extend(f"  {v.describe()}" for v in res.violations)
    details = res.details
    if "lp_check" in details:
        lp = details["lp_check"]
        lines.append(
            f"closed form vs LP: margin difference {lp['margin_difference']:.3g} N, "
            f"largest tension difference {lp['max_tau_difference']:.3g} N"
        )
    if res.method == "alg1" and "boxes" in details:
        lines.append(
            f"search: {details['boxes']} box(es), {details['rounds']} round(s), "
            f"parametric wire(s) {details.get('parametric_wires')}"
        )
    lines.extend(f"note: {m}" for m in res.messages)
    return "\n".join(lines)
