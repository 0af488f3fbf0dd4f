"""Pictures of kinematics results: an IK sweep as in Merlet (2007), Fig. 3, and the
poses of forward kinematics as in his Figs. 4-8.

:func:`plot_sweep` draws every control ``u_j`` against the swept ``u_J`` (top) and the
tensions with their limits (bottom).  Certified points are filled markers, uncertified ones
hollow, infeasible ones (a limit violated) grey crosses.

:func:`plot_pose` draws one pose of the robot: the base frame and the anchors ``A_i``, each
wire as the segment ``A_i B_i`` coloured by its tension, and the platform as the convex hull
of its distinct attachment points (a solid for MARIONET's 7 points, a triangle for the
T-platform's 3), with its own frame.  Spatial robots are drawn in 3-D, planar ones in the
plane.  :func:`plot_poses` overlays several poses of one robot (Fig. 8: the four poses of
one control vector).  Only the world coordinates of the attachments are drawn, so the
picture shows what the result says, nothing recomputed.  matplotlib is imported lazily
(:mod:`certsolve.plotting`).
"""

from __future__ import annotations

import numpy as np

from ..plotting import pyplot, save
from ..robot.model import Robot
from .ik_sweep import IKSweepResult, PointStatus

__all__ = ["plot_pose", "plot_poses", "plot_sweep", "plot_trajectory"]

_STYLE = {
    PointStatus.CERTIFIED: {"marker": "o", "fill": True},
    PointStatus.UNCERTIFIED: {"marker": "o", "fill": False},
    PointStatus.INFEASIBLE: {"marker": "x", "fill": True},
}


def plot_sweep(res: IKSweepResult, path=None, tau_limits=None, title=None):
    """Controls and tensions along the sweep; saved as PNG if ``path`` is given.

    ``tau_limits``: optional ``(tau_min, tau_max)`` arrays drawn as dashed lines.
    Returns the figure.
    """
    plt = pyplot()
    t = res.values
    U = res.controls()
    T = res.tensions()
    status = np.array([str(p.status) for p in res.points])
    m = U.shape[1]
    fig, (ax_u, ax_t) = plt.subplots(2, 1, figsize=(6.4, 7.2), dpi=120, sharex=True)
    colours = plt.get_cmap("tab10")
    for j in range(m):
        c = colours(j % 10)
        label = f"u_{j + 1}" + (" (swept)" if j + 1 == res.joint else "")
        for ax, Y, name in ((ax_u, U, "u"), (ax_t, T, "tau")):
            ls = ":" if (j + 1 == res.joint and name == "u") else "-"
            ax.plot(t, Y[:, j], ls, color=c, lw=1.2, label=label if name == "u" else None)
            for st, style in _STYLE.items():
                sel = status == str(st)
                if not sel.any():
                    continue
                if st is PointStatus.INFEASIBLE:
                    colour = {"color": "0.5"}
                else:
                    colour = {"facecolors": c if style["fill"] else "none", "edgecolors": c}
                ax.scatter(
                    t[sel], Y[sel, j], s=12, marker=style["marker"], linewidths=0.8, zorder=3,
                    **colour,
                )  # fmt: skip
    if tau_limits is not None:
        lo, hi = (np.asarray(x, dtype=float) for x in tau_limits)
        for v, name in ((np.unique(lo), "tau_min"), (np.unique(hi), "tau_max")):
            for x in v:
                ax_t.axhline(x, color="k", ls="--", lw=0.8)
                ax_t.annotate(
                    f"{name} {x:g} N", (1.0, x), xycoords=("axes fraction", "data"),
                    ha="right", va="bottom", fontsize=7,
                )  # fmt: skip
    counts = res.counts
    ax_u.set_ylabel("controls u_j (cm)")
    ax_t.set_ylabel("tensions τ_j (N)")
    ax_t.set_xlabel(f"u_{res.joint} (cm)")
    ax_u.legend(fontsize=8, ncol=2)
    ax_u.grid(alpha=0.3)
    ax_t.grid(alpha=0.3)
    pose = ", ".join(f"{v:g}" for v in res.pose.params(res.dof))
    if title is None:
        title = (
            f"{res.robot}: IK at pose ({pose}) as u_{res.joint} varies\n"
            f"{counts['certified']} certified (filled), {counts['uncertified']} uncertified "
            f"(hollow), {counts['infeasible']} infeasible (grey x)"
        )
    ax_u.set_title(title, fontsize=9)
    fig.tight_layout()
    return save(fig, path)


# -- poses of forward kinematics (Merlet 2007, Figs. 4-8) ----------------------------------------
def _hull_faces(points: np.ndarray) -> list[np.ndarray]:
    """The faces of the convex hull of ``points`` ``(k, d)``, as index arrays.

    Points spanning 3-D give the hull's triangles; points in a plane (all points of a planar
    robot, the T-platform's three) one polygon in boundary order; collinear points the
    segment between the extreme ones; a single point itself.
    """
    from scipy.spatial import ConvexHull, QhullError

    k = len(points)
    c = points - points.mean(axis=0)
    sv = np.linalg.svd(c, compute_uv=False) if k > 1 else np.zeros(1)
    rank = int(np.sum(sv > 1e-9 * sv[0])) if sv[0] > 0 else 0
    if rank == 0:
        return [np.array([0])]
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    if rank == 1:
        t = c @ vt[0]
        return [np.array([int(np.argmin(t)), int(np.argmax(t))])]
    try:
        if rank == 2:
            return [ConvexHull(c @ vt[:2].T).vertices]  # boundary order
        return list(ConvexHull(points).simplices)
    except QhullError:  # nearly degenerate: the points in their order
        return [np.arange(k)]


def _distinct_attachments(robot: Robot, platform_points: np.ndarray) -> np.ndarray:
    """World coordinates of the distinct attachment points (the T-platform has 3 for 7)."""
    _, idx = robot.attachment_groups()
    first = [int(np.flatnonzero(idx == g)[0]) for g in range(int(idx.max()) + 1)]
    return platform_points[first]


def _arrows(ax, origin, axes_, length: float, labels=None, lw=1.4) -> None:
    """A frame: one arrow per column of ``axes_`` (x red, y green, z blue)."""
    origin = np.asarray(origin, dtype=float)
    for j, colour in enumerate(("#d62728", "#2ca02c", "#1f77b4")[: len(origin)]):
        tip = origin + length * np.asarray(axes_)[:, j]
        if len(origin) == 3:
            ax.quiver(*origin, *(tip - origin), color=colour, lw=lw, arrow_length_ratio=0.2)
        else:
            ax.annotate(
                "", xy=tip, xytext=origin,
                arrowprops={"arrowstyle": "-|>", "color": colour, "lw": lw},
            )  # fmt: skip
        if labels is not None:
            ax.text(*tip, labels[j], color=colour, fontsize=8)


def _draw_platform(ax, points: np.ndarray, colour, alpha: float) -> None:
    faces = _hull_faces(points)
    if points.shape[1] == 3 and len(faces[0]) >= 3:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        ax.add_collection3d(
            Poly3DCollection(
                [points[f] for f in faces], facecolor=colour, edgecolor="k", linewidths=0.5,
                alpha=alpha,
            )
        )  # fmt: skip
    elif len(faces[0]) >= 3:
        ax.fill(*points[faces[0]].T, facecolor=colour, edgecolor="k", lw=0.8, alpha=alpha)
    else:
        ax.plot(*points[faces[0]].T, color=colour, lw=3)
    ax.scatter(*points.T, color="k", s=8, zorder=4)


def _draw_base(ax, robot: Robot, extent: float) -> None:
    """Anchors (labelled), the reference frame, and for spatial robots the box of anchors."""
    A = robot.A
    if robot.dim == 3:  # the edges of the anchors' bounding box: the robot's frame
        lo, hi = A.min(axis=0), A.max(axis=0)
        corners = np.array([[(lo, hi)[(c >> a) & 1][a] for a in range(3)] for c in range(8)])
        for c in range(8):
            for a in range(3):
                if not (c >> a) & 1:
                    ax.plot(*corners[[c, c | (1 << a)]].T, color="0.8", lw=0.8)
    ax.scatter(*A.T, marker="^", color="k", s=30, zorder=4)
    for i, a in enumerate(A):
        ax.text(*a, f" A{i + 1}", fontsize=7)
    names = ("x", "y", "z")[: robot.dim]
    _arrows(ax, np.zeros(robot.dim), np.eye(robot.dim), 0.15 * extent, labels=names)


def _pose_axes(robot: Robot, panels: int = 1):
    plt = pyplot()
    fig = plt.figure(figsize=(5.6 * panels + 1.2, 5.8 if robot.dim == 3 else 5.0), dpi=110)
    kw = {"projection": "3d"} if robot.dim == 3 else {}
    axes = [fig.add_subplot(1, panels, k + 1, **kw) for k in range(panels)]
    if robot.dim == 3:
        for ax in axes:
            ax.view_init(elev=22, azim=-58)
    return plt, fig, axes


def _finish_axes(ax, robot: Robot, points: np.ndarray, pad: float = 0.06) -> None:
    lo, hi = points.min(axis=0), points.max(axis=0)
    margin = pad * float(np.max(hi - lo))
    lo, hi = lo - margin, hi + margin
    for a, b, name in zip(lo, hi, "xyz"):
        getattr(ax, f"set_{name}lim")(a, b)
        getattr(ax, f"set_{name}label")(f"{name} (cm)")
    if robot.dim == 3:
        span = hi - lo
        ax.set_box_aspect(np.maximum(span, 0.15 * span.max()))
    else:
        ax.set_aspect("equal")
        ax.grid(alpha=0.25)


def _fmt(values, digits: str) -> str:
    return ", ".join(f"{v + 0.0:{digits}}".replace("-0.000", "0.000") for v in values)


def _pose_text(pose) -> str:
    ang = np.asarray(pose.euler_deg, dtype=float)
    names = "θ" if ang.size == 1 else "yaw, pitch, roll"
    return f"position ({_fmt(pose.position, '.5g')}) cm, {names} ({_fmt(ang, '.3f')})°"


def plot_pose(robot: Robot, pose, path=None, title=None, number=None):
    """One equilibrium pose (an :class:`~.fk.FKPose`): wires coloured by tension.

    Two panels: the whole robot, and a close-up of the platform with the first part of
    each wire (labelled with its number).  ``number = (k, n)`` says "pose k of n" in the
    title.  Saved as PNG if ``path`` is given (and the figure closed).  Returns the figure.
    """
    plt, fig, (ax, zoom) = _pose_axes(robot, panels=2)
    P = np.asarray(pose.platform_points, dtype=float)
    tau = np.asarray(pose.tau, dtype=float)
    A = robot.A
    extent = float(np.ptp(np.vstack([A, P]), axis=0).max()) or 1.0
    limits = robot.tau_max[np.isfinite(robot.tau_max)]
    top = float(limits.max()) if limits.size and limits.max() > 0 else float(max(tau.max(), 1))
    norm = plt.Normalize(0.0, top)
    cmap = plt.get_cmap("viridis")
    Q = _distinct_attachments(robot, P)
    rotation = np.asarray(pose.rotation, dtype=float)
    has_frame = rotation.shape == (robot.dim, robot.dim)
    # the whole robot
    _draw_base(ax, robot, extent)
    for i in range(robot.m):
        ax.plot(*np.array([A[i], P[i]]).T, color=cmap(norm(tau[i])), lw=1.8)
        ax.text(*(0.5 * (A[i] + P[i])), f"τ{i + 1} {tau[i]:.3g}", fontsize=7, color="0.15")
    _draw_platform(ax, Q, "#f4a261", 0.6)
    _finish_axes(ax, robot, np.vstack([A, P, np.zeros((1, robot.dim))]))
    ax.set_title("robot", fontsize=9)
    # close-up: the platform and where each wire leaves it
    size = float(np.ptp(Q, axis=0).max()) if len(Q) > 1 else 0.05 * extent
    size = max(size, 0.02 * extent)
    ends = []
    for i in range(robot.m):
        d = A[i] - P[i]
        n = float(np.linalg.norm(d))
        end = P[i] + (0.8 * size / n) * d if n > 0 else P[i]
        zoom.plot(*np.array([P[i], end]).T, color=cmap(norm(tau[i])), lw=2.0)
        zoom.text(*end, f"{i + 1}", fontsize=8, color="0.15")
        ends.append(end)
    _draw_platform(zoom, Q, "#f4a261", 0.6)
    if has_frame:
        _arrows(zoom, pose.position, rotation, 0.4 * size, labels=("x'", "y'", "z'"), lw=1.2)
        ends.extend(np.asarray(pose.position) + 0.45 * size * rotation.T)
    _finish_axes(zoom, robot, np.vstack([Q, *ends]), 0.08)
    zoom.set_title("platform (close-up), wires numbered", fontsize=9)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=[ax, zoom], shrink=0.75, pad=0.04, label="wire tension τ (N)")
    if title is None:
        which = "" if number is None else f" pose {number[0]} of {number[1]},"
        cert = f"certificate: {pose.certificate}"
        if getattr(pose, "verified", None):
            cert += " (verified with mpmath)"
        title = f"{robot.name}:{which} {cert}\n{_pose_text(pose)}"
    fig.suptitle(title, fontsize=10)
    return save(fig, path, bbox_inches="tight")


def plot_poses(robot: Robot, poses, path=None, title=None):
    """Several poses of one robot overlaid, one colour each (Merlet's Fig. 8).

    Saved as PNG if ``path`` is given (and the figure closed).  Returns the figure.
    """
    plt, fig, (ax,) = _pose_axes(robot)
    A = robot.A
    pts = [np.asarray(p.platform_points, dtype=float) for p in poses]
    allp = np.vstack([A, np.zeros((1, robot.dim)), *pts])
    extent = float(np.ptp(allp, axis=0).max()) or 1.0
    _draw_base(ax, robot, extent)
    colours = plt.get_cmap("tab10")
    handles = []
    from matplotlib.lines import Line2D

    for k, (pose, P) in enumerate(zip(poses, pts)):
        c = colours(k % 10)
        for i in range(robot.m):
            ax.plot(*np.array([A[i], P[i]]).T, color=c, lw=0.9, alpha=0.8)
        _draw_platform(ax, _distinct_attachments(robot, P), c, 0.45)
        pos = ", ".join(f"{v + 0.0:.4g}" for v in pose.position)
        handles.append(Line2D([], [], color=c, lw=3, label=f"pose {k + 1}: ({pos})"))
    _finish_axes(ax, robot, allp)
    ax.legend(handles=handles, fontsize=8, loc="best")
    if title is None:
        title = f"{robot.name}: {len(poses)} certified pose(s)"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return save(fig, path)


# -- a followed path (certsolve track) ------------------------------------------------------------
def plot_trajectory(result, path=None, tau_limits=None, title=None):
    """Pose components and tensions along a followed path, the lost step marked; saved as
    PNG if ``path`` is given.  Returns the figure.

    ``result``: a :class:`~.trajectory.TrajectoryResult` or its ``to_dict()`` (a stored
    job's result).  Three panels against the step index: the position (cm), the
    orientation angles (degrees), the wires' tensions (N) with ``tau_limits``
    (``(tau_min, tau_max)`` arrays) dashed.  Certified steps are lines with dots; the lost
    step, if any, is a red vertical line with its reason in the title.
    """
    data = result if isinstance(result, dict) else result.to_dict()
    plt = pyplot()
    steps = [s for s in data["steps"] if s.get("pose") is not None]
    idx = np.array([s["index"] for s in steps])
    ok = np.array([bool(s["certified"]) for s in steps], dtype=bool)
    pos = np.array([s["pose"]["position"] for s in steps]).reshape(len(steps), -1)
    ang = np.array([s["pose"]["euler"] for s in steps]).reshape(len(steps), -1)
    tau = np.array([s["tensions"] for s in steps]).reshape(len(steps), -1)
    fig, axes = plt.subplots(3, 1, figsize=(6.4, 8.0), dpi=120, sharex=True)
    colours = plt.get_cmap("tab10")
    panels = (
        (axes[0], pos, ("x", "y", "z"), "position (cm)"),
        (axes[1], ang, ("yaw", "pitch", "roll") if ang.shape[1] == 3 else ("theta",), "angles (°)"),
        (axes[2], tau, tuple(f"τ_{j + 1}" for j in range(tau.shape[1])), "tensions (N)"),
    )
    for ax, Y, names, label in panels:
        for j in range(Y.shape[1]):
            c = colours(j % 10)
            ax.plot(idx[ok], Y[ok, j], "-", color=c, lw=1.0, label=names[j])
            if len(idx) <= 200:
                ax.scatter(idx[ok], Y[ok, j], s=6, color=c, zorder=3)
            if (~ok).any():
                ax.scatter(idx[~ok], Y[~ok, j], s=18, marker="x", color=c, zorder=3)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=4)
    if tau_limits is not None:
        for v in (np.unique(np.asarray(b, dtype=float)) for b in tau_limits):
            for x in v:
                axes[2].axhline(x, color="k", ls="--", lw=0.8)
    lost = data.get("lost_at")
    if lost is not None:
        for ax in axes:
            ax.axvline(lost, color="red", lw=1.2)
        axes[0].annotate(
            f"lost at step {lost}", (lost, 1.0), xycoords=("data", "axes fraction"),
            color="red", ha="right", va="top", fontsize=8, rotation=90,
        )  # fmt: skip
    axes[2].set_xlabel("step")
    if title is None:
        n = sum(1 for s in data["steps"] if s["certified"])
        title = f"{data['robot']}: {data['status']}, {n} step(s) certified and joined"
        if data.get("reason"):
            title += "\n" + _wrap(f"step {data['lost_at']}: {data['reason']}", 80)
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    return save(fig, path)


def _wrap(text: str, width: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))
