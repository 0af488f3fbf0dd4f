"""``certsolve ik ROBOT --pose ...``: inverse kinematics (Merlet 2007, section II.A).

``--sweep J=START:STOP:N`` follows the controls by continuation while ``u_J`` takes ``N``
values from ``START`` to ``STOP`` (Fig. 3 of the paper; :mod:`certsolve.kinematics.ik_sweep`).
"""

from __future__ import annotations

import argparse

import numpy as np

from ..kinematics.ik import METHODS, IKResult
from ..kinematics.ik_sweep import IKSweepResult
from ..robot import Robot, load_robot_spec
from .common import CliError, parse_floats, print_json, print_result, validated


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
    p.add_argument(
        "--method", choices=METHODS, default=None, help="default: tension (not with --sweep)"
    )
    p.add_argument(
        "--u-last",
        default=None,
        help="alg1: centre of the search window; alg2: Newton start; --sweep: Newton start "
        "of the first point",
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
    p.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="time limit (s): alg1 (default 10), --sweep (default: none)",
    )
    p.add_argument("--max-boxes", type=int, default=20000, help="alg1: box limit")
    p.add_argument(
        "--distribution",
        choices=("auto", "closed-form", "lp"),
        default="auto",
        help="tension: how to choose the tensions (default auto)",
    )
    p.add_argument(
        "--sweep",
        metavar="J=START:STOP:N",
        default=None,
        help="fix u_J at N values from START to STOP (cm), follow the other controls by "
        "continuation and certify each point (e.g. 1=0.1:10:100)",
    )
    p.add_argument(
        "--plot", metavar="PNG", default=None, help="with --sweep: every u_j against u_J (PNG)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


# the parts of --sweep J=START:STOP:N, as the ik-sweep job's params name them
SWEEP_PARTS = {"joint": "J", "start": "START", "stop": "STOP", "count": "N"}


def parse_sweep(text: str) -> dict[str, int | float]:
    """``"J=START:STOP:N"`` -> ``{"joint", "start", "stop", "count"}``; the syntax is
    checked here, the values by the ik-sweep job's model (:func:`run_sweep`)."""
    form = f"--sweep: expected J=START:STOP:N (e.g. 1=0.1:10:100), got {text!r}"
    head, sep, rest = text.replace(" ", "").partition("=")
    parts = rest.split(":")
    if not sep or len(parts) != 3:
        raise CliError(form)
    try:
        joint = int(head)
    except ValueError:
        raise CliError(f"--sweep: the wire J must be an integer, got {head!r}") from None
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise CliError(form) from None
    try:
        count = int(parts[2])
    except ValueError:
        raise CliError(f"--sweep: N must be an integer, got {parts[2]!r}") from None
    return {"joint": joint, "start": start, "stop": stop, "count": count}


def _check_sweep_options(args: argparse.Namespace) -> None:
    if args.sweep is None:
        if args.plot is not None:
            raise CliError("--plot goes with --sweep")
        return
    if args.method is not None:
        raise CliError("--sweep runs Algorithm 2 with continuation at every point: drop --method")
    for flag, val in (
        ("--window", args.window),
        ("--tau-fixed", args.tau_fixed),
        ("--newton", args.newton or None),
    ):
        if val is not None:
            raise CliError(f"{flag} does not apply to --sweep")


def run(args: argparse.Namespace) -> int:
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.ik import IkParams, run_ik

    _check_sweep_options(args)
    spec = load_robot_spec(args.robot)
    if args.sweep is not None:
        return run_sweep(args, spec)
    method = args.method or "tension"
    values = {
        "pose": parse_floats(args.pose, "--pose"),
        "method": method,
        "u_last": None if args.u_last is None else parse_floats(args.u_last, "--u-last"),
        "solve": "newton" if args.newton else "tau",
        "check_lp": method == "tension",  # the table shows the closed form against the LP
    }
    params = validated(IkParams, args, values, robot=spec, option={"solve": "newton"})
    result = run_ik(params, spec, RunContext())
    if args.json:
        print_json(result.to_dict())
    else:
        print(format_result(result, Robot.from_spec(spec)))
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
    if "set" in details:
        lines.extend(_set_rows(details["set"]))
    lines.extend(f"note: {m}" for m in res.messages)
    return "\n".join(lines)


def _set_rows(s: dict) -> list[str]:
    """The bounds over a robot set (:mod:`certsolve.kinematics.ik_tolerance`), one row a wire."""
    fixed = ", ".join(f"{w}" for w in s["fixed_wires"]) or "none"
    out = [
        f"every robot of the set: {s['fixed']} of wire(s) {fixed} fixed; proven tension "
        f"margin {_num(s['margin_lo'], '.6g')} N",
        f"{'wire':>4} {'tau bounds (N)':>23} {'u bounds (cm)':>25}",
    ]
    u_lo, u_hi = s["u_lo"], s["u_hi"]
    for i, (a, b) in enumerate(zip(s["tau_lo"], s["tau_hi"], strict=True)):
        u = "-" if u_lo is None else f"[{_num(u_lo[i], '.6f')}, {_num(u_hi[i], '.6f')}]"
        out.append(f"{i + 1:>4} {f'[{a:.5f}, {b:.5f}]':>23} {u:>25}")
    return out


def run_sweep(args: argparse.Namespace, spec) -> int:
    """``--sweep``: the options are the ik-sweep job's params, checked by its model."""
    from ..extras import require
    from ..jobs.kinds.base import RunContext
    from ..jobs.kinds.ik_sweep import IkSweepParams, run_ik_sweep

    if args.plot:  # before any work: --plot needs matplotlib
        require("plot", "--plot")

    values = {
        "pose": parse_floats(args.pose, "--pose"),
        **parse_sweep(args.sweep),
        "u_start": None if args.u_last is None else parse_floats(args.u_last, "--u-last"),
    }
    args.options = {
        **getattr(args, "options", {}),
        **{f"sweep_{k}": f"--sweep {v}" for k, v in SWEEP_PARTS.items()},
    }
    option = {"u_start": "u_last", **{k: f"sweep_{k}" for k in SWEEP_PARTS}}
    params = validated(IkSweepParams, args, values, robot=spec, option=option)
    result = run_ik_sweep(params, spec, RunContext(time_limit=params.timeout))
    if args.plot:
        robot = Robot.from_spec(spec)
        from ..kinematics.plots import plot_sweep

        plot_sweep(result, args.plot, tau_limits=(robot.tau_min, robot.tau_max))
    print_result(args.json, result, lambda: format_sweep(result, args.plot), plot=args.plot)
    return 0


def format_sweep(res: IKSweepResult, plot: str | None = None) -> str:
    """One row per point: u_J, the other controls, the tensions, the status and why."""
    names = {6: ("x", "y", "z", "yaw", "pitch", "roll"), 3: ("x", "y", "theta"), 2: ("x", "y")}
    pose = ", ".join(
        f"{n}={v:.6g}" for n, v in zip(names[res.dof], res.pose.params(res.dof), strict=True)
    )
    c = res.counts
    lines = [
        f"{res.robot} (dof {res.dof}): IK sweep of u_{res.joint} from {res.start:g} to "
        f"{res.stop:g} cm ({res.count} points) at {pose}",
        f"status: {res.status}; {c['certified']} certified, {c['uncertified']} uncertified, "
        f"{c['infeasible']} infeasible; {res.time:.3f} s",
    ]
    U, T = res.controls(), res.tensions()
    m = U.shape[1]
    head = " ".join(f"{'u_' + str(j + 1):>10}" for j in range(m))
    head += " " + " ".join(f"{'tau_' + str(j + 1):>9}" for j in range(m))
    lines.append(f"{head}  status")
    for i, p in enumerate(res.points):
        row = " ".join(_num(U[i, j], "10.5f") for j in range(m))
        row += " " + " ".join(_num(T[i, j], "9.4f") for j in range(m))
        note = f"  ({p.reason})" if p.reason else ""
        lines.append(f"{row}  {p.status}{note}")
    if plot:
        lines.append(f"wrote {plot}")
    return "\n".join(lines)
