"""Pictures: isotropic-force heat maps (Fig. 9/10 style), certified pavings, the force
polytope at one pose with its isotropic circle and ellipse (Fig. 4 style), and pavings of
design parameters.

matplotlib is imported lazily with the non-interactive ``Agg`` backend.  Heat maps draw the
region ``f_min < 0`` (and degenerate poses) in white as in the paper, the contour
``f_min = 0`` (the wrench-feasible workspace boundary), the anchors, a colorbar in newtons
and equal axes.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..plotting import pyplot, save
from .certified import CertifiedWorkspace
from .design import DesignResult
from .maps import IsotropicMap
from .picture import ForcePicture

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PathOrName = str | Path | None

__all__ = ["plot_map", "plot_maps", "plot_paving", "plot_force_picture", "plot_design"]


def _plt():
    return pyplot()


def _draw_map(ax, res: IsotropicMap, vmax=None, title=None, cmap="jet", colorbar=True):
    plt = _plt()
    # a robot with tolerances: the certified lower bound over its set (NaN where not proven)
    over_set = res.set_force_lo is not None
    values = res.values if res.set_force_lo is None else res.set_force_lo
    v = np.where(values >= 0, values, np.nan)
    masked = np.ma.masked_invalid(v)
    cm = plt.get_cmap(cmap).with_extremes(bad="white")
    dx = (res.xs[-1] - res.xs[0]) / max(len(res.xs) - 1, 1) / 2
    dy = (res.ys[-1] - res.ys[0]) / max(len(res.ys) - 1, 1) / 2
    extent = (res.xs[0] - dx, res.xs[-1] + dx, res.ys[0] - dy, res.ys[-1] + dy)
    vmax = vmax if vmax is not None else (float(np.nanmax(v)) if np.isfinite(v).any() else 1.0)
    im = ax.imshow(
        masked,
        origin="lower",
        extent=extent,
        cmap=cm,
        vmin=0.0,
        vmax=vmax,
        interpolation="nearest",
        aspect="equal",
    )
    finite = np.where(np.isfinite(values), values, -1.0)
    if (finite >= 0).any() and (finite < 0).any() and len(res.xs) > 1 and len(res.ys) > 1:
        ax.contour(res.xs, res.ys, finite, levels=[0.0], colors="k", linewidths=0.8)
    A = res.anchors
    if res.dof == 6:
        ax.plot(A[:, 0], A[:, 1], "k^", ms=6, label="anchors (x, y)")
    else:
        ax.plot(A[:, 0], A[:, 1], "ko", ms=6, label="anchors")
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    pad = 0.05 * max(extent[1] - extent[0], extent[3] - extent[2])
    ax.set_xlim(min(extent[0], A[:, 0].min()) - pad, max(extent[1], A[:, 0].max()) + pad)
    ax.set_ylim(min(extent[2], A[:, 1].min()) - pad, max(extent[3], A[:, 1].max()) + pad)
    if title is None:
        title = f"{res.robot}: maximum isotropic force" + (", every robot" if over_set else "")
        if res.z is not None:
            title += f" (z = {res.z:g} cm)"
    ax.set_title(title)
    if colorbar:
        label = "maximum isotropic force (N)"
        if over_set:
            label = "certified lower bound over the set (N)"
        plt.colorbar(im, ax=ax, label=label, shrink=0.85)
    return im


def plot_map(
    res: IsotropicMap,
    path: PathOrName = None,
    vmax: float | None = None,
    title: str | None = None,
    cmap: str = "jet",
) -> Figure:
    """One heat map; saved as PNG if ``path`` is given.  Returns the figure."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=120)
    _draw_map(ax, res, vmax=vmax, title=title, cmap=cmap)
    fig.tight_layout()
    return save(fig, path)


def plot_maps(
    maps: list[IsotropicMap],
    path: PathOrName = None,
    titles: list[str] | None = None,
    shared_scale: bool = True,
    cmap: str = "jet",
) -> Figure:
    """Several maps side by side with one shared colour scale (the paper's Fig. 10)."""
    plt = _plt()
    vmax = max(
        float(np.nanmax(np.where(v >= 0, v, np.nan)))
        for v in (m.values if m.set_force_lo is None else m.set_force_lo for m in maps)
    )
    fig, axes = plt.subplots(1, len(maps), figsize=(4.6 * len(maps) + 1.0, 4.6), dpi=120)
    axes = np.atleast_1d(axes)
    im = None
    for k, (ax, m) in enumerate(zip(axes, maps)):
        im = _draw_map(
            ax,
            m,
            vmax=vmax if shared_scale else None,
            title=None if titles is None else titles[k],
            cmap=cmap,
            colorbar=not shared_scale,
        )
    if shared_scale and im is not None:
        fig.colorbar(im, ax=list(axes), label="maximum isotropic force (N)", shrink=0.85)
    return save(fig, path, bbox_inches="tight")


def plot_paving(
    ws: CertifiedWorkspace,
    path: PathOrName = None,
    title: str | None = None,
    anchors: np.ndarray | None = None,
    z: float | None = None,
) -> Figure:
    """The paving of a planar box (x, y): inside green, outside grey, boundary orange.

    For dof 6 the picture is the slice ``z = z`` (default: the middle of the box): the boxes
    whose z-range contains it.
    """
    plt = _plt()
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Patch, Rectangle

    fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=120)
    if ws.dof == 6 and z is None:
        z = float(0.5 * (ws.box[2, 0] + ws.box[2, 1]))
    styles = [
        ("outside", "#d9d9d9", "proven f < f_req"),
        ("boundary", "#ff9f1c", "boundary (< eps)"),
        ("pending", "#8ecae6", "not processed"),
        ("inside", "#2a9d8f", "proven f ≥ f_req"),
    ]
    handles = []
    for key, color, label in styles:
        boxes = getattr(ws, key)
        if ws.dof == 6 and len(boxes):
            boxes = boxes[(boxes[:, 2, 0] <= z) & (z <= boxes[:, 2, 1])]
        if len(boxes) == 0:
            continue
        rects = [Rectangle((b[0, 0], b[1, 0]), b[0, 1] - b[0, 0], b[1, 1] - b[1, 0]) for b in boxes]
        pc = PatchCollection(
            rects,
            facecolor=color,
            edgecolor="k" if len(rects) < 3000 else color,
            linewidth=0.15,
        )
        ax.add_collection(pc)
        handles.append(Patch(facecolor=color, edgecolor="k", label=f"{label} ({len(boxes)})"))
    if anchors is not None:
        A = np.asarray(anchors)
        ax.plot(A[:, 0], A[:, 1], "ko", ms=5)
    b = ws.box
    ax.set_xlim(b[0, 0], b[0, 1])
    ax.set_ylim(b[1, 0], b[1, 1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    if title is None:
        title = (
            f"{ws.robot}: f_min ≥ {ws.min_force:g} N, eps {ws.eps:g} cm"
            + (f", slice z = {z:g} cm" if ws.dof == 6 else "")
            + "\n"
            f"inside {ws.inside_measure:.4g} {ws.unit} ({100 * ws.inside_share:.1f} % of the box)"
        )
        if not ws.complete:
            title += f" [{ws.status}: {len(ws.pending)} boxes not processed]"
    ax.set_title(title, fontsize=10)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.12),
        ncol=2,
        fontsize=8,
        frameon=False,
    )
    fig.tight_layout()
    return save(fig, path)


def _fmt_vec(v) -> str:
    return "(" + ", ".join(f"{x + 0.0:.4g}" for x in v) + ")"  # + 0.0: no "-0"


def _panel_points(panel) -> np.ndarray:
    pts = [panel.centre[None], panel.origin[None]]
    if panel.polygon is not None:
        pts.append(panel.polygon)
    if panel.radius is not None:
        pts.append(panel.centre[None] + panel.radius * np.array([[-1, -1], [1, 1]]))
    if panel.ellipse is not None:
        pts.append(panel.ellipse)
    return np.concatenate(pts)


def _draw_panel(ax, pic: ForcePicture, panel, half: float):
    from matplotlib.artist import Artist
    from matplotlib.patches import Circle, Polygon

    handles: list[Artist] = []
    if panel.polygon is not None:
        what = "force polytope" if pic.dof == 2 else "force section F(μ)"
        facets = f", {pic.n_facets} facets" if pic.n_facets is not None else ""
        patch = Polygon(
            panel.polygon, closed=True, facecolor="#cfe3f3", edgecolor="#1f4e79", lw=1.2,
            label=f"{what}{facets}",
        )  # fmt: skip
        ax.add_patch(patch)
        handles.append(patch)
    if panel.radius is not None:
        what = "isotropic force (sphere)" if pic.dof == 6 else "isotropic force"
        circle = Circle(
            panel.centre, panel.radius, fill=False, edgecolor="#c0392b", lw=1.6,
            label=f"{what} {panel.radius:.5g} N",
        )  # fmt: skip
        ax.add_patch(circle)
        handles.append(circle)
    semi = pic.ellipse_semi_axes if pic.dof == 6 else panel.ellipse_semi_axes
    if panel.ellipse is not None and semi is not None:  # set together by force_picture
        what = "ellipsoid" if pic.dof == 6 else "ellipse"
        (line,) = ax.plot(
            panel.ellipse[:, 0], panel.ellipse[:, 1], "--", color="#27ae60", lw=1.3,
            label=f"{what}, semi-axes " + ", ".join(f"{v:.4g}" for v in semi) + " N",
        )  # fmt: skip
        handles.append(line)
    (c,) = ax.plot(
        *panel.centre, "x", color="#c0392b", ms=8, mew=2,
        label=f"centre −w_ext {_fmt_vec(pic.centre)} N",
    )  # fmt: skip
    (o,) = ax.plot(*panel.origin, "+", color="k", ms=9, label="zero force")
    handles += [c, o]
    if panel.polygon is None:
        ax.text(
            0.5, 0.8, "no force polytope to draw:\nempty or flat at this pose",
            transform=ax.transAxes, ha="center", fontsize=9,
        )  # fmt: skip
    mid = 0.5 * (_panel_points(panel).min(axis=0) + _panel_points(panel).max(axis=0))
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_xlabel(f"{panel.axes[0]} (N)")
    ax.set_ylabel(f"{panel.axes[1]} (N)")
    if panel.plane:
        ax.set_title(f"section {panel.plane.replace('-0 N', '0 N')}", fontsize=9)
    return handles


def plot_force_picture(
    pic: ForcePicture, path: PathOrName = None, title: str | None = None
) -> Figure:
    """The force polytope, isotropic circle, centre and ellipse at one pose (Krut Fig. 4).

    Planar robots: one panel; dof 6: the three sections through the centre side by side, on
    one scale.  Values are in the legend.  Saved as PNG if ``path`` is given.  Returns the
    figure.
    """
    plt = _plt()
    n = len(pic.panels)
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 5.4), dpi=120, squeeze=False)
    spans = [np.ptp(_panel_points(p), axis=0).max() for p in pic.panels]
    big = max(spans)
    half = 0.54 * big if big > 1e-6 else 1.0
    handles = []
    for ax, panel in zip(axes[0], pic.panels):
        handles = _draw_panel(ax, pic, panel, half)
    if title is None:
        pose = ", ".join(f"{v + 0.0:g}" for v in pic.pose)
        f = "n/a" if pic.isotropic_force is None else f"{pic.isotropic_force:.5g} N"
        title = f"{pic.robot} at ({pose}): maximum isotropic force {f} [{pic.status}]"
    fig.suptitle(title, fontsize=10)
    fig.legend(
        handles=handles, loc="lower center", ncol=2 if n == 1 else 3, fontsize=8,
        frameon=False,
    )  # fmt: skip
    fig.tight_layout(rect=(0, 0.17 if n == 1 else 0.1, 1, 1))
    return save(fig, path)


def plot_design(
    res: DesignResult,
    path: PathOrName = None,
    axes: tuple[int, int] = (0, 1),
    at: ArrayLike | None = None,
    title: str | None = None,
) -> Figure:
    """The paving of the design parameters: good green, bad grey, undecided orange, pending
    blue, the best box outlined with its centre starred.

    Two parameters: the plane of the parameters.  More: the **section** through the values
    ``at`` (a ``(k,)`` array; default the centre of the best box, or the middle of the
    ranges) of the parameters other than ``axes``: the boxes whose ranges contain them, so
    every point of the picture shows the class of the box holding it.  Saved as PNG if
    ``path`` is given.  Returns the figure.
    """
    plt = _plt()
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Patch, Rectangle

    i, j = axes
    k = len(res.names)
    fig, ax = plt.subplots(figsize=(6.4, 5.8), dpi=120)
    styles = [
        ("bad", "#bdbdbd", "proven bad"),
        ("pending", "#8ecae6", "not processed"),
        ("undecided", "#ff9f1c", "undecided (< eps)"),
        ("good", "#2a9d8f", "proven good"),
    ]
    handles = []
    others = [m for m in range(k) if m not in (i, j)]
    if at is None:
        best = res.best_box
        at = (best if best is not None else res.ranges).mean(axis=1)
    at = np.asarray(at, dtype=float)
    for key, color, label in styles:
        boxes = getattr(res, key)
        for m in others:
            boxes = boxes[(boxes[:, m, 0] <= at[m]) & (at[m] <= boxes[:, m, 1])]
        if len(boxes) == 0:
            continue
        rects = [Rectangle((b[i, 0], b[j, 0]), b[i, 1] - b[i, 0], b[j, 1] - b[j, 0]) for b in boxes]
        pc = PatchCollection(
            rects, facecolor=color, edgecolor="k" if len(rects) < 3000 else color, linewidth=0.2
        )
        ax.add_collection(pc)
        n_all, share = len(getattr(res, key)), 100 * res.share(key)
        handles.append(
            Patch(facecolor=color, edgecolor="k", label=f"{label}: {n_all} ({share:.1f} %)")
        )
    if res.best is not None and all(
        res.good[res.best][m, 0] <= at[m] <= res.good[res.best][m, 1] for m in others
    ):
        b = res.good[res.best]
        ax.add_patch(
            Rectangle(
                (b[i, 0], b[j, 0]), b[i, 1] - b[i, 0], b[j, 1] - b[j, 0], fill=False,
                edgecolor="#c0392b", lw=2.0,
            )
        )  # fmt: skip
        c = 0.5 * (b[:, 0] + b[:, 1])
        (star,) = ax.plot(
            c[i], c[j], "*", color="#c0392b", ms=12,
            label=f"best: margin {res.margin[res.best]:.4g} N "
            f"(f ≥ {res.min_force + res.margin[res.best]:.4g} N)",
        )  # fmt: skip
        handles.append(star)
    ax.set_xlim(*res.ranges[i])
    ax.set_ylim(*res.ranges[j])
    ax.set_xlabel(f"{res.names[i]}  ({res.paths[i]})")
    ax.set_ylabel(f"{res.names[j]}  ({res.paths[j]})")
    ws = ", ".join(f"[{lo:g}, {hi:g}]" for lo, hi in res.workspace)
    if title is None:
        title = f"{res.robot}: f_min ≥ {res.min_force:g} N on the workspace {ws} cm"
        if k > 2:
            where = ", ".join(f"{res.names[m]} = {at[m]:.4g}" for m in others)
            title += f"\nsection at {where}"
        if not res.complete:
            title += f" [{res.status}]"
    ax.set_title(title, fontsize=9)
    ax.legend(
        handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8,
        frameon=False,
    )  # fmt: skip
    fig.tight_layout()
    return save(fig, path)
